#include "trees/near_pairs.hpp"

#include "engine/kernels/mobility_pair.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace stokesian::trees {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

namespace {

typedef double V4 __attribute__((vector_size(32)));
// inlined into each clone of add_pairs_sorted, so that they are compiled for its instruction set
#define NEAR_INLINE inline __attribute__((always_inline))
#define NEAR_INLINE_LAMBDA __attribute__((always_inline))

// The loop bodies are written once for a scalar (T = double: the remainder of a leaf) and for four
// sources at a time (T = V4).
template <class T>
T ld(const double* p);
template <>
NEAR_INLINE double ld<double>(const double* p) {
  return *p;
}
template <>
NEAR_INLINE V4 ld<V4>(const double* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// 1 where separated (r2 >= s2), else 0
NEAR_INLINE double separated(double r2, double s2) { return r2 >= s2 ? 1.0 : 0.0; }
NEAR_INLINE V4 separated(V4 r2, V4 s2) { return __builtin_convertvector(-(r2 >= s2), V4); }
// sep / r (0 for overlapping pairs and the target itself, where r2 may be 0)
NEAR_INLINE double inverse_distance(double r2, double sep) { return sep / std::sqrt(std::max(r2, 1e-300)); }
NEAR_INLINE V4 inverse_distance(V4 r2, V4 sep) {
  V4 r;
  for (int l = 0; l < 4; ++l) r[l] = std::sqrt(std::max(r2[l], 1e-300));
  return sep / r;
}

struct Inputs {
  const double *x, *y, *z, *a, *f0, *f1, *f2, *t0, *t1, *t2, *s[5];
};
struct Target {
  double x, y, z, a, a2;
};

// acc: U (3), then Omega (3, FT and FTS), E as a symmetric matrix (xx, yy, zz, xy, xz, yz; FTS),
// and last the count of non-separated sources (the target itself included).
template <class T>
NEAR_INLINE void pair_f(const Inputs& P, int q, const Target& t, T* acc) {
  const T dx = t.x - ld<T>(P.x + q), dy = t.y - ld<T>(P.y + q), dz = t.z - ld<T>(P.z + q), aj = ld<T>(P.a + q);
  const T r2 = dx * dx + dy * dy + dz * dz, sum = t.a + aj;
  const T sep = separated(r2, sum * sum);
  acc[3] += 1.0 - sep;
  const T u = inverse_distance(r2, sep), uu = u * u;
  const T f0 = ld<T>(P.f0 + q), f1 = ld<T>(P.f1 + q), f2 = ld<T>(P.f2 + q);
  const T c = (t.a2 + aj * aj) * (1.0 / 3.0) * uu;
  const T b = u * uu * (1.0 - 3.0 * c) * (dx * f0 + dy * f1 + dz * f2);
  const T f = u * (1.0 + c);
  acc[0] += f * f0 + b * dx;
  acc[1] += f * f1 + b * dy;
  acc[2] += f * f2 + b * dz;
}

template <class T>
NEAR_INLINE void pair_ft(const Inputs& P, int q, const Target& t, T* acc) {
  const T dx = t.x - ld<T>(P.x + q), dy = t.y - ld<T>(P.y + q), dz = t.z - ld<T>(P.z + q), aj = ld<T>(P.a + q);
  const T r2 = dx * dx + dy * dy + dz * dz, sum = t.a + aj;
  const T sep = separated(r2, sum * sum);
  acc[6] += 1.0 - sep;
  const T u = inverse_distance(r2, sep), uu = u * u, u3 = u * uu;
  const T f0 = ld<T>(P.f0 + q), f1 = ld<T>(P.f1 + q), f2 = ld<T>(P.f2 + q);
  const T t0 = ld<T>(P.t0 + q), t1 = ld<T>(P.t1 + q), t2 = ld<T>(P.t2 + q);
  const T c = (t.a2 + aj * aj) * (1.0 / 3.0) * uu;
  const T b = u3 * (1.0 - 3.0 * c) * (dx * f0 + dy * f1 + dz * f2);
  const T f = u * (1.0 + c);
  const T tt = 1.5 * u3 * uu * (dx * t0 + dy * t1 + dz * t2);
  // T x d and F x d
  acc[0] += f * f0 + b * dx + u3 * (t1 * dz - t2 * dy);
  acc[1] += f * f1 + b * dy + u3 * (t2 * dx - t0 * dz);
  acc[2] += f * f2 + b * dz + u3 * (t0 * dy - t1 * dx);
  acc[3] += u3 * (f1 * dz - f2 * dy) - 0.5 * u3 * t0 + tt * dx;
  acc[4] += u3 * (f2 * dx - f0 * dz) - 0.5 * u3 * t1 + tt * dy;
  acc[5] += u3 * (f0 * dy - f1 * dx) - 0.5 * u3 * t2 + tt * dz;
}

// The separated scalars of engine/kernels/mobility_pair.cpp (over k) with e = d u and the
// stresslet as a symmetric traceless matrix; the strain rate accumulates as a symmetric matrix.
template <class T>
NEAR_INLINE void pair_fts(const Inputs& P, int q, const Target& t, T* acc) {
  const double r2h = std::sqrt(0.5), r6 = 1.0 / std::sqrt(6.0), ai2 = t.a2;
  const T dx = t.x - ld<T>(P.x + q), dy = t.y - ld<T>(P.y + q), dz = t.z - ld<T>(P.z + q), aj = ld<T>(P.a + q);
  const T r2 = dx * dx + dy * dy + dz * dz, sum = t.a + aj;
  const T sep = separated(r2, sum * sum);
  acc[12] += 1.0 - sep;
  const T u = inverse_distance(r2, sep), uu = u * u, u3 = u * uu, u4 = uu * uu, u5 = u4 * u;
  const T s0 = ld<T>(P.s[0] + q), s1 = ld<T>(P.s[1] + q), s2 = ld<T>(P.s[2] + q), s3 = ld<T>(P.s[3] + q),
          s4 = ld<T>(P.s[4] + q);
  const T aj2 = aj * aj;
  const T cff = (ai2 + aj2) / 3.0, ctf = ai2 / 5.0 + aj2 / 3.0, cft = ai2 / 3.0 + aj2 / 5.0, ctt = (ai2 + aj2) / 5.0;
  const T xa = 2.0 * u - 2.0 * cff * u3, ya = u + cff * u3, yb = uu, xc = u3, yc2 = -0.5 * u3;
  const T xg = -3.0 * uu + 9.0 * ctf * u4, yg = -3.0 * ctf * u4, xgt = 3.0 * uu - 9.0 * cft * u4,
               ygt = 3.0 * cft * u4, yh = -1.5 * u3;
  const T xm = -6.0 * u3 + 36.0 * ctt * u5, ym = 3.0 * u3 - 24.0 * ctt * u5, zm = 6.0 * ctt * u5;
  const T ex = dx * u, ey = dy * u, ez = dz * u;
  const T f0 = ld<T>(P.f0 + q), f1 = ld<T>(P.f1 + q), f2 = ld<T>(P.f2 + q), t0 = ld<T>(P.t0 + q), t1 = ld<T>(P.t1 + q), t2 = ld<T>(P.t2 + q);
  const T sxx = r2h * s0 - r6 * s1, syy = -r2h * s0 - r6 * s1, szz = 2.0 * r6 * s1;
  const T sxy = r2h * s2, sxz = r2h * s3, syz = r2h * s4;
  const T eF = ex * f0 + ey * f1 + ez * f2, eT = ex * t0 + ey * t1 + ez * t2;
  const T se0 = sxx * ex + sxy * ey + sxz * ez, se1 = sxy * ex + syy * ey + syz * ez,
               se2 = sxz * ex + syz * ey + szz * ez;
  const T eSe = ex * se0 + ey * se1 + ez * se2;
  const T tx0 = t1 * ez - t2 * ey, tx1 = t2 * ex - t0 * ez, tx2 = t0 * ey - t1 * ex;  // T x e
  // U = xa eF e + ya (F - eF e) + yb T x e + xgt eSe e + ygt (2 Se - 2 eSe e)
  const T ue = (xa - ya) * eF + (xgt - 2.0 * ygt) * eSe;
  acc[0] += ue * ex + ya * f0 + yb * tx0 + 2.0 * ygt * se0;
  acc[1] += ue * ey + ya * f1 + yb * tx1 + 2.0 * ygt * se1;
  acc[2] += ue * ez + ya * f2 + yb * tx2 + 2.0 * ygt * se2;
  // W = yb F x e + xc eT e + yc (T - eT e) + 2 yh e x Se
  const T we = (xc - yc2) * eT;
  acc[3] += yb * (f1 * ez - f2 * ey) + we * ex + yc2 * t0 + 2.0 * yh * (ey * se2 - ez * se1);
  acc[4] += yb * (f2 * ex - f0 * ez) + we * ey + yc2 * t1 + 2.0 * yh * (ez * se0 - ex * se2);
  acc[5] += yb * (f0 * ey - f1 * ex) + we * ez + yc2 * t2 + 2.0 * yh * (ex * se1 - ey * se0);
  // E = xg (ee - I/3) eF + yg (e F + F e - 2 eF ee) + yh (e Txe + Txe e) + 1.5 xm (ee - I/3) eSe
  //   + ym (e Se + Se e - 2 eSe ee) + zm/2 (2 S + I eSe - 2 (e Se + Se e) + ee eSe)
  const T cee = xg * eF - 2.0 * yg * eF + 1.5 * xm * eSe - 2.0 * ym * eSe + 0.5 * zm * eSe;
  const T cid = -xg * eF / 3.0 - 0.5 * xm * eSe + 0.5 * zm * eSe;
  const T cse = ym - zm;  // on e Se + Se e
  const T g0 = yg * f0 + yh * tx0 + cse * se0, g1 = yg * f1 + yh * tx1 + cse * se1,
               g2 = yg * f2 + yh * tx2 + cse * se2;  // symmetric part e g + g e
  acc[6] += cee * ex * ex + cid + 2.0 * ex * g0 + zm * sxx;
  acc[7] += cee * ey * ey + cid + 2.0 * ey * g1 + zm * syy;
  acc[8] += cee * ez * ez + cid + 2.0 * ez * g2 + zm * szz;
  acc[9] += cee * ex * ey + ex * g1 + ey * g0 + zm * sxy;
  acc[10] += cee * ex * ez + ex * g2 + ez * g0 + zm * sxz;
  acc[11] += cee * ey * ez + ey * g2 + ez * g1 + zm * syz;
}

// Sums the kernel over [begin, end): four sources at a time, then the remainder.
template <int K, class Kernel>
NEAR_INLINE void sum_pairs(const Inputs& P, int begin, int end, const Target& t, Kernel kernel, double* out) {
  V4 acc4[K];
  for (int r = 0; r < K; ++r) acc4[r] = V4{0, 0, 0, 0};
  int q = begin;
  for (; q + 4 <= end; q += 4) kernel(P, q, t, acc4);
  double acc[K];
  for (int r = 0; r < K; ++r) acc[r] = (acc4[r][0] + acc4[r][1]) + (acc4[r][2] + acc4[r][3]);
  for (; q < end; ++q) kernel(P, q, t, acc);
  for (int r = 0; r < K; ++r) out[r] = acc[r];
}

}  // namespace

// The formulas: trees/near_pairs.hpp. The sum over [begin, end) skips the target's own position qi.
STOKESIAN_TREE_CLONES
void add_pairs_sorted(const SortedSources& src, int begin, int end, int qi, double ai, double mu, Moments m,
                      double* yi, long& count) {
  Inputs P;
  P.x = src.x.data();
  P.y = src.y.data();
  P.z = src.z.data();
  P.a = src.a.data();
  P.f0 = src.in[0].data();
  P.f1 = src.in[1].data();
  P.f2 = src.in[2].data();
  P.t0 = src.in[3].data();
  P.t1 = src.in[4].data();
  P.t2 = src.in[5].data();
  for (int r = 0; r < 5; ++r) P.s[r] = src.in[6 + r].data();
  const Target t{src.x[std::size_t(qi)], src.y[std::size_t(qi)], src.z[std::size_t(qi)], ai, ai * ai};
  const double xi = t.x, yc = t.y, zi = t.z;
  const double* X = src.x.data();
  const double* Y = src.y.data();
  const double* Z = src.z.data();
  const double* A = src.a.data();
  const double k = 1.0 / (8.0 * kPi * mu);
  double u0 = 0, u1 = 0, u2 = 0;
  double sum_rest[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // Omega and E (FT, FTS), before the factor k
  double nonseparated = 0;
  if (m == Moments::F) {
    double acc[4];
    sum_pairs<4>(P, begin, end, t, [](const Inputs& p, int q, const Target& tt, auto* a) NEAR_INLINE_LAMBDA { pair_f(p, q, tt, a); }, acc);
    u0 = acc[0], u1 = acc[1], u2 = acc[2], nonseparated = acc[3];
  } else if (m == Moments::FT) {
    double acc[7];
    sum_pairs<7>(P, begin, end, t, [](const Inputs& p, int q, const Target& tt, auto* a) NEAR_INLINE_LAMBDA { pair_ft(p, q, tt, a); }, acc);
    u0 = acc[0], u1 = acc[1], u2 = acc[2], nonseparated = acc[6];
    std::copy(acc + 3, acc + 6, sum_rest);
  } else {
    double acc[13];
    sum_pairs<13>(P, begin, end, t, [](const Inputs& p, int q, const Target& tt, auto* a) NEAR_INLINE_LAMBDA { pair_fts(p, q, tt, a); },
                  acc);
    u0 = acc[0], u1 = acc[1], u2 = acc[2], nonseparated = acc[12];
    const double r2h = std::sqrt(0.5), r6 = 1.0 / std::sqrt(6.0);
    const double w0 = acc[3], w1 = acc[4], w2 = acc[5], e00 = acc[6], e11 = acc[7], e22 = acc[8], e01 = acc[9],
                 e02 = acc[10], e12 = acc[11];
    const double rest[8] = {w0, w1, w2, r2h * (e00 - e11), r6 * (2.0 * e22 - e00 - e11),
                            r2h * 2.0 * e01, r2h * 2.0 * e02, r2h * 2.0 * e12};  // E as to_vec5
    std::copy(rest, rest + 8, sum_rest);
  }
  // the target itself is among the non-separated sources when it lies in [begin, end)
  const int close = int(nonseparated + 0.5) - (qi >= begin && qi < end ? 1 : 0);
  // y_i += k [U, Omega, E] (the first three entries from u0..u2, the rest from sum_rest)
  const int dof = dof_per_particle(m);
  yi[0] += k * u0;
  yi[1] += k * u1;
  yi[2] += k * u2;
  for (int r = 3; r < dof; ++r) yi[r] += k * sum_rest[r - 3];
  count += end - begin - (qi >= begin && qi < end ? 1 : 0);
  if (!close) return;
  for (int q = begin; q < end; ++q) {
    if (q == qi) continue;
    const Vec3 rij(xi - X[q], yc - Y[q], zi - Z[q]);
    const double r = rij.norm();
    if (r >= ai + A[q]) continue;
    const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
    double xj[11];
    for (int c = 0; c < dof; ++c) xj[c] = src.in[c][std::size_t(q)];
    mobility::apply_pair(mobility::pair_scalars(ai, A[q], r, mu, m), e, m, xj, yi);
  }
}

}  // namespace stokesian::trees
