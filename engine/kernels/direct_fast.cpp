// Fast direct far-field product y = M x (open domains): the path mobility_product takes; the
// reference twin is mobility_product_reference (far_field.cpp), one apply_pair per ordered pair.
//
// Mathematics: that of mobility_pair.hpp, regrouped so that a separated pair (r >= a_i + a_j) is
// straight-line arithmetic on its 11 inputs. With u = 1/r, e = (x_i - x_j) u and the scalars of
// separated_scalars (8 pi mu Psi = r + c/r), the responses at i to F, T, S (S = from_vec5(s),
// Se = S e, eSe = e.S.e, eF = e.F, eT = e.T, Txe = T x e) are
//   U += ya F + ybt Txe + 2 ygt Se + [(xa - ya) eF + (xgt - 2 ygt) eSe] e
//   W += yb (F x e) + yc T + (xc - yc) eT e + 2 yht (e x Se)
//   E  = c1 e e + (e G^T + G e^T) + zm S   (isotropic parts dropped: to_vec5 removes them)
//        c1 = (xg - 2 yg) eF + (1.5 xm - 2 ym + 0.5 zm) eSe,   G = yg F + yh Txe + (ym - zm) Se,
// the E <- F, T, S forms of mobility_pair.hpp with the Kim & Karrila projectors expanded
// (d0 = 3/2 (ee - I/3)(ee - I/3), d1, d2 as in apply_pair). to_vec5 of the symmetric P = c1 ee +
// e G^T + G e^T is (r2 = 1/sqrt 2, r6 = 1/sqrt 6)
//   [r2 (P00 - P11), r6 (2 P22 - P00 - P11), 2 r2 P01, 2 r2 P02, 2 r2 P12],
// and to_vec5(S) = s (orthonormal basis, engine/core/sym_traceless.hpp).
//
// Each particle i's row is one loop over all j on structure-of-arrays copies of positions, radii
// and x, vectorised (OpenMP simd, reductions into 11 accumulators). Pairs that are not separated
// (overlapping or nested spheres) and j = i get u = 0, which zeroes all their scalars (each is a
// polynomial in u without a constant term); a second, scalar pass adds them with apply_pair, and
// the self block with apply_self. Rows are split over threads and each row's sums run in an order
// fixed by N and the instruction set: the result does not depend on the thread count. Compiled for
// AVX2 + FMA (chosen at run time when the CPU has them) and for the baseline ISA; the two differ by
// rounding (FMA). tests/test_mobility.cpp compares both with the reference, pair by pair sums of
// apply_pair, and with dense_mobility.
#include "engine/kernels/far_field.hpp"

#include "engine/core/cpu.hpp"
#include "engine/core/parallel.hpp"
#include "engine/kernels/mobility_pair.hpp"

#include <atomic>
#include <cassert>
#include <cmath>
#include <cstring>
#include <vector>


namespace stokesian {
namespace {

std::atomic<int> g_direct{int(DirectKernels::automatic)};

bool use_avx2() { return cpu_has_avx2_fma() && g_direct.load() == int(DirectKernels::automatic); }

// Structure-of-arrays copy of one product's inputs: positions, radii squared, and x by component.
struct Soa {
  int d = 0;
  long n = 0;
  std::vector<double> px, py, pz, a2, a, in;  // in: component c of particle j at in[c * n + j]
  Soa(const std::vector<Vec3>& x, const std::vector<double>& r, const VecX& v, int dof)
      : d(dof), n(long(x.size())), px(n), py(n), pz(n), a2(n), a(r), in(std::size_t(n * dof)) {
    for (long j = 0; j < n; ++j) {
      px[j] = x[std::size_t(j)][0];
      py[j] = x[std::size_t(j)][1];
      pz[j] = x[std::size_t(j)][2];
      a2[j] = r[std::size_t(j)] * r[std::size_t(j)];
      for (int c = 0; c < d; ++c) in[std::size_t(c * n + j)] = v[j * d + c];
    }
  }
};

// y_i += sum over separated j of M_ij x_j (row i of the vectorised pass); returns the number of
// other particles j that are not separated from i.
// Squared distance, rounded the same way in the vectorised loop and the scalar pass (explicit fused
// multiply-adds on the AVX2 + FMA path, none on the baseline path), so that both passes classify
// every pair alike, including pairs at exact contact.
template <bool Fma>
inline __attribute__((always_inline)) double dist2(double dx, double dy, double dz) {
  if constexpr (Fma)
    return std::fma(dx, dx, std::fma(dy, dy, dz * dz));
  else
    return dx * dx + dy * dy + dz * dz;
}

template <int D, bool Fma>
inline __attribute__((always_inline)) long row(const Soa& s, long i, double k, double* y) {
  const long n = s.n;
  const double xi = s.px[i], yi = s.py[i], zi = s.pz[i], ai = s.a[std::size_t(i)], ai2 = s.a2[i];
  const double* __restrict px = s.px.data();
  const double* __restrict py = s.py.data();
  const double* __restrict pz = s.pz.data();
  const double* __restrict pa = s.a.data();
  const double* __restrict pa2 = s.a2.data();
  const double* __restrict in = s.in.data();
  const double r2c = std::sqrt(0.5), r6c = 1.0 / std::sqrt(6.0);
  double u0 = 0, u1 = 0, u2 = 0, w0 = 0, w1 = 0, w2 = 0, e0 = 0, e1 = 0, e2 = 0, e3 = 0, e4 = 0;
  long close = 0;
#pragma omp simd reduction(+ : u0, u1, u2, w0, w1, w2, e0, e1, e2, e3, e4, close)
  for (long j = 0; j < n; ++j) {
    const double dx = xi - px[j], dy = yi - py[j], dz = zi - pz[j];
    const double rr = dist2<Fma>(dx, dy, dz), sum = ai + pa[j];
    const bool sep = rr >= sum * sum && j != i;
    close += sep ? 0 : 1;
    const double u = sep ? 1.0 / std::sqrt(rr) : 0.0;
    const double ex = dx * u, ey = dy * u, ez = dz * u;
    const double uu = u * u, u3 = uu * u;
    const double b2 = pa2[j];
    const double F0 = in[j], F1 = in[n + j], F2 = in[2 * n + j];
    const double cff = (ai2 + b2) * (1.0 / 3.0);
    const double xa = k * (2.0 * u - 2.0 * cff * u3), ya = k * (u + cff * u3);
    const double eF = ex * F0 + ey * F1 + ez * F2;
    double cU = (xa - ya) * eF;
    double U0 = ya * F0, U1 = ya * F1, U2 = ya * F2;
    if constexpr (D >= 6) {
      const double T0 = in[3 * n + j], T1 = in[4 * n + j], T2 = in[5 * n + j];
      const double yb = k * uu, xc = k * u3, yc = -0.5 * k * u3;
      const double eT = ex * T0 + ey * T1 + ez * T2;
      // T x e and F x e
      const double tx0 = T1 * ez - T2 * ey, tx1 = T2 * ex - T0 * ez, tx2 = T0 * ey - T1 * ex;
      const double fx0 = F1 * ez - F2 * ey, fx1 = F2 * ex - F0 * ez, fx2 = F0 * ey - F1 * ex;
      U0 += yb * tx0;
      U1 += yb * tx1;
      U2 += yb * tx2;
      double W0 = yb * fx0 + yc * T0 + (xc - yc) * eT * ex;
      double W1 = yb * fx1 + yc * T1 + (xc - yc) * eT * ey;
      double W2 = yb * fx2 + yc * T2 + (xc - yc) * eT * ez;
      if constexpr (D == 11) {
        const double s0 = in[6 * n + j], s1 = in[7 * n + j], s2 = in[8 * n + j], s3 = in[9 * n + j],
                     s4 = in[10 * n + j];
        const double A00 = r2c * s0 - r6c * s1, A11 = -r2c * s0 - r6c * s1, A22 = 2.0 * r6c * s1;
        const double A01 = r2c * s2, A02 = r2c * s3, A12 = r2c * s4;
        const double S0 = A00 * ex + A01 * ey + A02 * ez, S1 = A01 * ex + A11 * ey + A12 * ez,
                     S2 = A02 * ex + A12 * ey + A22 * ez;
        const double eSe = ex * S0 + ey * S1 + ez * S2;
        const double u4 = uu * uu, u5 = u4 * u;
        const double ctf = ai2 * 0.2 + b2 * (1.0 / 3.0), cft = ai2 * (1.0 / 3.0) + b2 * 0.2, ctt = (ai2 + b2) * 0.2;
        const double xg = k * (-3.0 * uu + 9.0 * ctf * u4), yg = -3.0 * k * ctf * u4;
        const double xgt = -k * (-3.0 * uu + 9.0 * cft * u4), ygt = 3.0 * k * cft * u4;
        const double yh = -1.5 * k * u3;
        const double xm = k * (-6.0 * u3 + 36.0 * ctt * u5), ym = k * (3.0 * u3 - 24.0 * ctt * u5),
                     zm = 6.0 * k * ctt * u5;
        U0 += 2.0 * ygt * S0;
        U1 += 2.0 * ygt * S1;
        U2 += 2.0 * ygt * S2;
        cU += (xgt - 2.0 * ygt) * eSe;
        // e x Se
        W0 += 2.0 * yh * (ey * S2 - ez * S1);
        W1 += 2.0 * yh * (ez * S0 - ex * S2);
        W2 += 2.0 * yh * (ex * S1 - ey * S0);
        const double c1 = (xg - 2.0 * yg) * eF + (1.5 * xm - 2.0 * ym + 0.5 * zm) * eSe;
        const double G0 = yg * F0 + yh * tx0 + (ym - zm) * S0, G1 = yg * F1 + yh * tx1 + (ym - zm) * S1,
                     G2 = yg * F2 + yh * tx2 + (ym - zm) * S2;
        const double P00 = c1 * ex * ex + 2.0 * ex * G0, P11 = c1 * ey * ey + 2.0 * ey * G1,
                     P22 = c1 * ez * ez + 2.0 * ez * G2;
        const double P01 = c1 * ex * ey + ex * G1 + G0 * ey, P02 = c1 * ex * ez + ex * G2 + G0 * ez,
                     P12 = c1 * ey * ez + ey * G2 + G1 * ez;
        e0 += r2c * (P00 - P11) + zm * s0;
        e1 += r6c * (2.0 * P22 - P00 - P11) + zm * s1;
        e2 += 2.0 * r2c * P01 + zm * s2;
        e3 += 2.0 * r2c * P02 + zm * s3;
        e4 += 2.0 * r2c * P12 + zm * s4;
      }
      w0 += W0;
      w1 += W1;
      w2 += W2;
    }
    u0 += U0 + cU * ex;
    u1 += U1 + cU * ey;
    u2 += U2 + cU * ez;
  }
  y[0] += u0;
  y[1] += u1;
  y[2] += u2;
  if constexpr (D >= 6) {
    y[3] += w0;
    y[4] += w1;
    y[5] += w2;
  }
  if constexpr (D == 11) {
    y[6] += e0;
    y[7] += e1;
    y[8] += e2;
    y[9] += e3;
    y[10] += e4;
  }
  return close - 1;  // j = i counted
}

// Rows i0 .. i1 - 1: the vectorised loop over separated pairs, then, in rows that have any, the
// pairs that are not separated (overlapping, nested) by apply_pair, classified as in the loop.
template <int D, bool Fma>
inline __attribute__((always_inline)) void rows(const Soa& s, long i0, long i1, double mu, Moments m, const VecX& in,
                                                double* out) {
  const double k = 1.0 / (8.0 * kPi * mu);
  thread_local std::vector<unsigned char> close;  // 1 where j is not separated from i
  close.resize(std::size_t(s.n));
  unsigned char* __restrict flag = close.data();
  const double* __restrict px = s.px.data();
  const double* __restrict py = s.py.data();
  const double* __restrict pz = s.pz.data();
  const double* __restrict pa = s.a.data();
  for (long i = i0; i < i1; ++i) {
    double* yi = out + i * D;
    if (row<D, Fma>(s, i, k, yi) == 0) continue;
    const double ai = pa[i], xi = px[i], yi0 = py[i], zi = pz[i];
#pragma omp simd
    for (long j = 0; j < s.n; ++j) {
      const double sum = ai + pa[j];
      flag[j] = dist2<Fma>(xi - px[j], yi0 - py[j], zi - pz[j]) < sum * sum ? 1 : 0;
    }
    flag[i] = 0;
    for (long j = 0; j < s.n; ++j) {
      const void* next = std::memchr(flag + j, 1, std::size_t(s.n - j));
      if (!next) break;
      j = static_cast<const unsigned char*>(next) - flag;
      const double dx = xi - px[j], dy = yi0 - py[j], dz = zi - pz[j];
      const double rr = dist2<Fma>(dx, dy, dz);
      const double r = std::sqrt(rr);
      const Vec3 e = r > 0 ? Vec3(Vec3(dx, dy, dz) / r) : Vec3::UnitZ();
      mobility::apply_pair(mobility::pair_scalars(ai, s.a[std::size_t(j)], r, mu, m), e, m, in.data() + j * D, yi);
    }
  }
}

template <int D>
void rows_baseline(const Soa& s, long i0, long i1, double mu, Moments m, const VecX& in, double* out) {
  rows<D, false>(s, i0, i1, mu, m, in, out);
}

template <int D>
STOKESIAN_AVX2_FMA void rows_avx2(const Soa& s, long i0, long i1, double mu, Moments m, const VecX& in, double* out) {
  rows<D, true>(s, i0, i1, mu, m, in, out);
}

template <int D>
void product(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m, const VecX& in,
             VecX& out) {
  const long n = long(x.size());
  const Soa s(x, a, in, D);
  const bool avx2 = use_avx2();
  constexpr long kBlock = 16;
  const long blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(dynamic, 1) if (n >= parallel::kDirectProductParticles)
  for (long b = 0; b < blocks; ++b) {
    const long i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
    for (long i = i0; i < i1; ++i) mobility::apply_self(a[std::size_t(i)], mu, m, in.data() + i * D, out.data() + i * D);
    if (avx2)
      rows_avx2<D>(s, i0, i1, mu, m, in, out.data());
    else
      rows_baseline<D>(s, i0, i1, mu, m, in, out.data());
  }
}

}  // namespace

void force_direct_kernels(DirectKernels k) { g_direct.store(int(k)); }

void mobility_product(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                      const VecX& in, VecX& out) {
  const int d = dof_per_particle(m);
  assert(in.size() == long(x.size()) * d);
  if (g_direct.load() == int(DirectKernels::reference)) return mobility_product_reference(x, a, mu, m, in, out);
  out.setZero(long(x.size()) * d);
  if (x.empty()) return;
  switch (m) {
    case Moments::F: return product<3>(x, a, mu, m, in, out);
    case Moments::FT: return product<6>(x, a, mu, m, in, out);
    case Moments::FTS: return product<11>(x, a, mu, m, in, out);
  }
}

}  // namespace stokesian
