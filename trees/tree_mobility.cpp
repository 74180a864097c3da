#include "trees/tree_mobility.hpp"

#include "engine/core/sym_traceless.hpp"
#include "engine/kernels/mobility_pair.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace stokesian::trees {

namespace {

int derivative_order(Moments m) { return m == Moments::FTS ? 3 : 2; }

constexpr double kPi = 3.14159265358979323846;

// The two hot loops (near pairs, conversions) are also compiled for x86-64-v3 (AVX2, FMA) and the
// version is chosen at run time (GCC function multiversioning); elsewhere one portable version.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
#define STOKESIAN_TREE_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define STOKESIAN_TREE_CLONES
#endif
// Potentials per expansion (phi_x, phi_y, phi_z, psi), stored interleaved: E[index * kPot + pot].
constexpr int kPot = 4;

// Positions in a multi-index set of order >= 3 of the first, second and third unit derivatives.
struct DerivativeIndex {
  int i1[3], i2[3][3], i3[3][3][3];
  explicit DerivativeIndex(const MultiIndexSet& set) {
    for (int a = 0; a < 3; ++a) {
      int e[3] = {0, 0, 0};
      e[a] = 1;
      i1[a] = set.index(e[0], e[1], e[2]);
      for (int b = 0; b < 3; ++b) {
        int f[3] = {e[0], e[1], e[2]};
        ++f[b];
        i2[a][b] = set.index(f[0], f[1], f[2]);
        for (int c = 0; c < 3; ++c) {
          int g[3] = {f[0], f[1], f[2]};
          ++g[c];
          i3[a][b][c] = set.index(g[0], g[1], g[2]);
        }
      }
    }
  }
};

// y (times 8 pi mu) += the responses [U, Omega, E] of a sphere of radius ai at offset R from the
// potentials' origin, from the derivatives P[pot * nb + beta] (pot: phi_x, phi_y, phi_z, psi) of
// the four potentials (the formulas of the header).
void add_responses(const double* P, int nb, const DerivativeIndex& ix, const Vec3& R, double ai, Moments m,
                   double* y) {
  auto phi = [&](int j, int b) { return P[j * nb + b]; };
  auto psi = [&](int b) { return P[3 * nb + b]; };
  for (int a = 0; a < 3; ++a) {
    double u = phi(a, 0) + psi(ix.i1[a]);
    double divgrad = 0;
    for (int j = 0; j < 3; ++j) {
      u -= R[j] * phi(j, ix.i1[a]);
      divgrad += phi(j, ix.i2[a][j]);
    }
    y[a] += u - (ai * ai / 3.0) * divgrad;
  }
  if (!has_torque(m)) return;
  Mat3 G;  // G(k, a) = d_k u_a
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) {
      double g = phi(a, ix.i1[k]) - phi(k, ix.i1[a]) + psi(ix.i2[a][k]);
      for (int j = 0; j < 3; ++j) g -= R[j] * phi(j, ix.i2[a][k]);
      G(k, a) = g;
    }
  y[3] += 0.5 * (G(1, 2) - G(2, 1));
  y[4] += 0.5 * (G(2, 0) - G(0, 2));
  y[5] += 0.5 * (G(0, 1) - G(1, 0));
  if (!has_stresslet(m)) return;
  Mat3 E = 0.5 * (G + G.transpose());
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      double t = 0;
      for (int j = 0; j < 3; ++j) t += phi(j, ix.i3[a][b][j]);
      E(a, b) -= (ai * ai / 5.0) * t;
    }
  const Vec5 e5 = to_vec5(E);
  for (int r = 0; r < 5; ++r) y[6 + r] += e5[r];
}

// y_i += exact pair blocks of the sources j in [begin, end) of `order` (j != i).
void add_pairs(const std::vector<int>& order, int begin, int end, int i, const std::vector<Vec3>& x,
               const std::vector<double>& a, double mu, Moments m, const VecX& in, double* yi, long& count) {
  const int d = dof_per_particle(m);
  for (int q = begin; q < end; ++q) {
    const int j = order[std::size_t(q)];
    if (j == i) continue;
    const Vec3 rij = x[std::size_t(i)] - x[std::size_t(j)];
    const double r = rij.norm();
    const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
    mobility::apply_pair(mobility::pair_scalars(a[std::size_t(i)], a[std::size_t(j)], r, mu, m), e, m,
                         in.data() + long(j) * d, yi);
    ++count;
  }
}

// Near pairs of the fmm path (the hot loop): sources in tree order as separate
// coordinate arrays, so that the loop over a source leaf vectorises. Separated pairs (r >= a_i + a_j)
// use the closed forms of engine/kernels/mobility_pair.cpp (separated_scalars), with d = x_i - x_j,
// u = 1/r, c = (a_i^2 + a_j^2)/3 and k = 1/(8 pi mu), for F and FT
//   U_i += k [u (1 + c u^2) F + u^3 (1 - 3 c u^2) (d.F) d + u^3 T x d],
//   W_i += k [u^3 F x d - u^3/2 T + 3/2 u^5 (d.T) d],
// and for FTS every block of mobility::apply_pair written out with its separated scalars;
// the other pairs (overlapping, nested; rare) go through mobility::pair_scalars. The sum over
// [begin, end) skips the target's own position qi.
STOKESIAN_TREE_CLONES
void add_pairs_sorted(const SortedSources& src, int begin, int end, int qi, double ai, double mu, Moments m,
                      double* yi, long& count) {
  const double xi = src.x[std::size_t(qi)], yc = src.y[std::size_t(qi)], zi = src.z[std::size_t(qi)];
  const double ai2 = ai * ai, k = 1.0 / (8.0 * kPi * mu);
  const double* X = src.x.data();
  const double* Y = src.y.data();
  const double* Z = src.z.data();
  const double* A = src.a.data();
  const double *F0 = src.in[0].data(), *F1 = src.in[1].data(), *F2 = src.in[2].data();
  double u0 = 0, u1 = 0, u2 = 0;
  double sum_rest[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // Omega and E (FT, FTS), before the factor k
  int close = 0;
  if (m == Moments::F) {
#pragma omp simd reduction(+ : u0, u1, u2) reduction(+ : close)
    for (int q = begin; q < end; ++q) {
      const double dx = xi - X[q], dy = yc - Y[q], dz = zi - Z[q];
      const double r2 = dx * dx + dy * dy + dz * dz, sum = ai + A[q];
      const bool sep = r2 >= sum * sum;
      close += !sep && q != qi;
      const double u = sep ? 1.0 / std::sqrt(r2) : 0.0, uu = u * u;
      const double c = (ai2 + A[q] * A[q]) * (1.0 / 3.0) * uu;
      const double b = u * uu * (1.0 - 3.0 * c) * (dx * F0[q] + dy * F1[q] + dz * F2[q]);
      const double f = u * (1.0 + c);
      u0 += f * F0[q] + b * dx;
      u1 += f * F1[q] + b * dy;
      u2 += f * F2[q] + b * dz;
    }
  } else if (m == Moments::FTS) {
    // The separated scalars of engine/kernels/mobility_pair.cpp (over k) with e = d u and the
    // stresslet as a symmetric traceless matrix; the strain rate accumulates as a symmetric matrix.
    const double *T0 = src.in[3].data(), *T1 = src.in[4].data(), *T2 = src.in[5].data();
    const double *S0 = src.in[6].data(), *S1 = src.in[7].data(), *S2 = src.in[8].data(), *S3 = src.in[9].data(),
                 *S4 = src.in[10].data();
    const double r2h = std::sqrt(0.5), r6 = 1.0 / std::sqrt(6.0);
    double w0 = 0, w1 = 0, w2 = 0, e00 = 0, e11 = 0, e22 = 0, e01 = 0, e02 = 0, e12 = 0;
#pragma omp simd reduction(+ : u0, u1, u2, w0, w1, w2, e00, e11, e22, e01, e02, e12, close)
    for (int q = begin; q < end; ++q) {
      const double dx = xi - X[q], dy = yc - Y[q], dz = zi - Z[q];
      const double r2 = dx * dx + dy * dy + dz * dz, sum = ai + A[q];
      const bool sep = r2 >= sum * sum;
      close += !sep && q != qi;
      const double u = sep ? 1.0 / std::sqrt(r2) : 0.0, uu = u * u, u3 = u * uu, u4 = uu * uu, u5 = u4 * u;
      const double aj2 = A[q] * A[q];
      const double cff = (ai2 + aj2) / 3.0, ctf = ai2 / 5.0 + aj2 / 3.0, cft = ai2 / 3.0 + aj2 / 5.0, ctt = (ai2 + aj2) / 5.0;
      const double xa = 2.0 * u - 2.0 * cff * u3, ya = u + cff * u3, yb = uu, xc = u3, yc2 = -0.5 * u3;
      const double xg = -3.0 * uu + 9.0 * ctf * u4, yg = -3.0 * ctf * u4, xgt = 3.0 * uu - 9.0 * cft * u4,
                   ygt = 3.0 * cft * u4, yh = -1.5 * u3;
      const double xm = -6.0 * u3 + 36.0 * ctt * u5, ym = 3.0 * u3 - 24.0 * ctt * u5, zm = 6.0 * ctt * u5;
      const double ex = dx * u, ey = dy * u, ez = dz * u;
      const double f0 = F0[q], f1 = F1[q], f2 = F2[q], t0 = T0[q], t1 = T1[q], t2 = T2[q];
      const double sxx = r2h * S0[q] - r6 * S1[q], syy = -r2h * S0[q] - r6 * S1[q], szz = 2.0 * r6 * S1[q];
      const double sxy = r2h * S2[q], sxz = r2h * S3[q], syz = r2h * S4[q];
      const double eF = ex * f0 + ey * f1 + ez * f2, eT = ex * t0 + ey * t1 + ez * t2;
      const double se0 = sxx * ex + sxy * ey + sxz * ez, se1 = sxy * ex + syy * ey + syz * ez,
                   se2 = sxz * ex + syz * ey + szz * ez;
      const double eSe = ex * se0 + ey * se1 + ez * se2;
      const double tx0 = t1 * ez - t2 * ey, tx1 = t2 * ex - t0 * ez, tx2 = t0 * ey - t1 * ex;  // T x e
      // U = xa eF e + ya (F - eF e) + yb T x e + xgt eSe e + ygt (2 Se - 2 eSe e)
      const double ue = (xa - ya) * eF + (xgt - 2.0 * ygt) * eSe;
      u0 += ue * ex + ya * f0 + yb * tx0 + 2.0 * ygt * se0;
      u1 += ue * ey + ya * f1 + yb * tx1 + 2.0 * ygt * se1;
      u2 += ue * ez + ya * f2 + yb * tx2 + 2.0 * ygt * se2;
      // W = yb F x e + xc eT e + yc (T - eT e) + 2 yh e x Se
      const double we = (xc - yc2) * eT;
      w0 += yb * (f1 * ez - f2 * ey) + we * ex + yc2 * t0 + 2.0 * yh * (ey * se2 - ez * se1);
      w1 += yb * (f2 * ex - f0 * ez) + we * ey + yc2 * t1 + 2.0 * yh * (ez * se0 - ex * se2);
      w2 += yb * (f0 * ey - f1 * ex) + we * ez + yc2 * t2 + 2.0 * yh * (ex * se1 - ey * se0);
      // E = xg (ee - I/3) eF + yg (e F + F e - 2 eF ee) + yh (e Txe + Txe e) + 1.5 xm (ee - I/3) eSe
      //   + ym (e Se + Se e - 2 eSe ee) + zm/2 (2 S + I eSe - 2 (e Se + Se e) + ee eSe)
      const double cee = xg * eF - 2.0 * yg * eF + 1.5 * xm * eSe - 2.0 * ym * eSe + 0.5 * zm * eSe;
      const double cid = -xg * eF / 3.0 - 0.5 * xm * eSe + 0.5 * zm * eSe;
      const double cse = ym - zm;  // on e Se + Se e
      const double g0 = yg * f0 + yh * tx0 + cse * se0, g1 = yg * f1 + yh * tx1 + cse * se1,
                   g2 = yg * f2 + yh * tx2 + cse * se2;  // symmetric part e g + g e
      e00 += cee * ex * ex + cid + 2.0 * ex * g0 + zm * sxx;
      e11 += cee * ey * ey + cid + 2.0 * ey * g1 + zm * syy;
      e22 += cee * ez * ez + cid + 2.0 * ez * g2 + zm * szz;
      e01 += cee * ex * ey + ex * g1 + ey * g0 + zm * sxy;
      e02 += cee * ex * ez + ex * g2 + ez * g0 + zm * sxz;
      e12 += cee * ey * ez + ey * g2 + ez * g1 + zm * syz;
    }
    const double rest[8] = {w0, w1, w2, r2h * (e00 - e11), r6 * (2.0 * e22 - e00 - e11),
                            r2h * 2.0 * e01, r2h * 2.0 * e02, r2h * 2.0 * e12};  // E as to_vec5
    std::copy(rest, rest + 8, sum_rest);
  } else {
    const double *T0 = src.in[3].data(), *T1 = src.in[4].data(), *T2 = src.in[5].data();
    double w0 = 0, w1 = 0, w2 = 0;
#pragma omp simd reduction(+ : u0, u1, u2, w0, w1, w2) reduction(+ : close)
    for (int q = begin; q < end; ++q) {
      const double dx = xi - X[q], dy = yc - Y[q], dz = zi - Z[q];
      const double r2 = dx * dx + dy * dy + dz * dz, sum = ai + A[q];
      const bool sep = r2 >= sum * sum;
      close += !sep && q != qi;
      const double u = sep ? 1.0 / std::sqrt(r2) : 0.0, uu = u * u, u3 = u * uu;
      const double c = (ai2 + A[q] * A[q]) * (1.0 / 3.0) * uu;
      const double b = u3 * (1.0 - 3.0 * c) * (dx * F0[q] + dy * F1[q] + dz * F2[q]);
      const double f = u * (1.0 + c);
      const double t = 1.5 * u3 * uu * (dx * T0[q] + dy * T1[q] + dz * T2[q]);
      // T x d and F x d
      u0 += f * F0[q] + b * dx + u3 * (T1[q] * dz - T2[q] * dy);
      u1 += f * F1[q] + b * dy + u3 * (T2[q] * dx - T0[q] * dz);
      u2 += f * F2[q] + b * dz + u3 * (T0[q] * dy - T1[q] * dx);
      w0 += u3 * (F1[q] * dz - F2[q] * dy) - 0.5 * u3 * T0[q] + t * dx;
      w1 += u3 * (F2[q] * dx - F0[q] * dz) - 0.5 * u3 * T1[q] + t * dy;
      w2 += u3 * (F0[q] * dy - F1[q] * dx) - 0.5 * u3 * T2[q] + t * dz;
    }
    sum_rest[0] = w0;
    sum_rest[1] = w1;
    sum_rest[2] = w2;
  }
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

// L_beta += sum_gamma M_gamma D_(beta + gamma) for the four potentials, the terms of beta being
// terms[begin[beta] .. begin[beta + 1]) = (gamma, beta + gamma); then psi about the target's centre:
// + (c_S - c_T)_j phi_j = - R_j phi_j. Compiled for AVX2/FMA too (chosen at run time).
STOKESIAN_TREE_CLONES
void convert(const double* M, const double* D, const Vec3& R, const std::array<int, 2>* terms, const int* begin, int nl,
             double* L) {
  // the four potentials of an index as one 4-wide vector (GCC/Clang vector extension)
  typedef double Pot4 __attribute__((vector_size(32)));
  const double r0 = R[0], r1 = R[1], r2 = R[2];
  for (int b = 0; b < nl; ++b) {
    const int k0 = begin[b], k1 = begin[b + 1];
    if (k0 == k1) continue;
    Pot4 acc = {0, 0, 0, 0}, acc2 = {0, 0, 0, 0};  // two chains hide the add latency
    int k = k0;
    for (; k + 1 < k1; k += 2) {
      Pot4 m, m2;
      std::memcpy(&m, M + kPot * terms[k][0], sizeof m);
      std::memcpy(&m2, M + kPot * terms[k + 1][0], sizeof m2);
      acc += m * D[terms[k][1]];
      acc2 += m2 * D[terms[k + 1][1]];
    }
    if (k < k1) {
      Pot4 m;
      std::memcpy(&m, M + kPot * terms[k][0], sizeof m);
      acc += m * D[terms[k][1]];
    }
    acc += acc2;
    double* l = L + kPot * b;
    l[0] += acc[0];
    l[1] += acc[1];
    l[2] += acc[2];
    l[3] += acc[3] - (r0 * acc[0] + r1 * acc[1] + r2 * acc[2]);
  }
}

}  // namespace

namespace {

// Terms of one conversion after the harmonic reduction: gamma with gamma_z <= 1 and |gamma| <= p
// (2m + 1 of order m), beta with beta_z <= 1 and |beta + gamma| <= p + k.
double conversion_terms(int p, int k) {
  double t = 0;
  for (int m = 0; m <= p; ++m) t += (2.0 * m + 1) * (p + k - m + 1) * (p + k - m + 1);
  return t;
}

// Unit costs on one thread (measured with bench-like uniform clouds, N = 3e4, 2026-11-25; docs/tree.md):
// a near pair (the vectorised closed forms of F, FT, FTS) and one
// conversion (0.22 us of derivatives and bookkeeping + 1.37 ns per term).
double pair_seconds(Moments m) { return m == Moments::F ? 8.5e-9 : (m == Moments::FT ? 17e-9 : 35e-9); }
double conversion_seconds(int p, Moments m) { return 0.22e-6 + 1.37e-9 * conversion_terms(p, derivative_order(m)); }

}  // namespace

double tree_error_model(const TreeParameters& p, Moments m) {
  const double geometric = std::pow(p.theta, p.order + 1);
  return m == Moments::FTS ? 0.05 * (p.order + 1) * geometric : 0.1 * geometric;
}

namespace {

// Modelled seconds per particle of one product (fmm), one thread.
double cost_per_particle(const TreeParameters& p, Moments m) {
  const double x = p.theta / 0.5;
  return 1770 * std::pow(x, -2.5) * pair_seconds(m) + 10.8 * std::pow(x, -2.05) * conversion_seconds(p.order, m);
}

}  // namespace

long tree_auto_from(double tolerance, Moments m) {
  (void)m;  // one rule for F, FT and FTS (FTS breaks even earlier, so the rule is conservative there)
  if (!(tolerance > 0)) return 0;
  if (tolerance >= 1e-3) return 1000;
  return long(std::ceil(std::pow(10.0, 3.0 + (-3.0 - std::log10(tolerance)) / 3.0)));
}

double tree_product_seconds(const TreeParameters& p, Moments m, double n) { return n * cost_per_particle(p, m); }

double tree_memory_bytes(const TreeParameters& p, Moments m, double n) {
  const double nodes = std::max(1.0, n / 4);
  const double expansion = 4.0 * (multi_index_count(p.order) + multi_index_count(p.order + derivative_order(m)));
  const double lists = 10.8 * std::pow(p.theta / 0.5, -2.05) * n + 2 * nodes;  // conversion and pair lists
  return nodes * (8.0 * expansion + sizeof(OctreeNode) + 16.0) + 4.0 * lists + (4.0 + 32.0) * n;
}

TreeParameters tree_parameters(double tolerance, Moments m) {
  if (!(tolerance >= 1e-14 && tolerance <= 0.5))
    throw std::invalid_argument("tree far field: tolerance " + std::to_string(tolerance) + " outside [1e-14, 0.5]");
  TreeParameters best;
  double best_cost = -1;
  for (int step = 0; step <= 9; ++step) {
    TreeParameters p;
    p.theta = 0.15 + 0.05 * step;
    p.leaf_size = 0;  // tuned per configuration
    p.evaluation = TreeEvaluation::fmm;
    for (p.order = 0; p.order <= 20 && tree_error_model(p, m) > tolerance; ++p.order) {
    }
    if (p.order > 20) continue;
    const double cost = cost_per_particle(p, m);
    if (best_cost < 0 || cost < best_cost) {
      best = p;
      best_cost = cost;
    }
  }
  return best;
}

TreeFarField::TreeFarField(const MobilitySpec& spec) : TreeFarField(spec, tree_parameters(spec.tolerance, spec.moments)) {}

TreeFarField::TreeFarField(const MobilitySpec& spec, const TreeParameters& parameters)
    : m_(spec.moments),
      mu_(spec.viscosity),
      p_(parameters),
      moment_set_(parameters.order),
      deriv_set_(parameters.order + derivative_order(spec.moments)),
      beta_set_(derivative_order(spec.moments)) {
  if (!(p_.theta > 0 && p_.theta < 1))
    throw std::invalid_argument("tree far field: theta " + std::to_string(p_.theta) + " outside (0, 1)");
  if (p_.order < 0 || p_.order > 30)
    throw std::invalid_argument("tree far field: order " + std::to_string(p_.order) + " outside [0, 30]");
  if (p_.leaf_size < 0) throw std::invalid_argument("tree far field: leaf size < 0");
  const int ng = moment_set_.size(), nb = beta_set_.size();
  sum_index_.resize(std::size_t(ng * nb));
  for (int g = 0; g < ng; ++g)
    for (int b = 0; b < nb; ++b) {
      const auto& al = moment_set_[g];
      const auto& be = beta_set_[b];
      sum_index_[std::size_t(g * nb + b)] = deriv_set_.index(al[0] + be[0], al[1] + be[1], al[2] + be[2]);
    }
  // Local expansions have order q = p + k (k the highest target derivative), so that every
  // response is accurate to the order of the moments.
  const int nl = deriv_set_.size();
  for (int b = 0; b < nl; ++b) {
    shift_begin_.push_back(int(shift_terms_.size()));
    const auto& be = deriv_set_[b];
    for (int g = 0; g < nl; ++g) {
      const auto& al = deriv_set_[g];
      const int sum = deriv_set_.index(al[0] + be[0], al[1] + be[1], al[2] + be[2]);
      if (sum >= 0) shift_terms_.push_back({b, g, sum});
    }
  }
  shift_begin_.push_back(int(shift_terms_.size()));
  // Harmonic reduction of the conversion (every D_alpha is harmonic in alpha: D_(alpha + 2e_z) =
  // -D_(alpha + 2e_x) - D_(alpha + 2e_y)). Moments with gamma_z >= 2 are folded onto gamma - 2e_z +
  // 2e_x and gamma - 2e_z + 2e_y (same order, highest gamma_z first); only locals with beta_z <= 1
  // are converted, the others rebuilt by the same identity (lowest beta_z first). Both are exact
  // for the truncated sums (the folded indices have the same order), and cut the terms of one
  // conversion from ~p^6/36 to ~p^4/3 (conversion_terms).
  for (int g = ng - 1; g >= 0; --g) {
    const auto& al = moment_set_[g];
    if (al[2] >= 2)
      moment_fold_.push_back({g, moment_set_.index(al[0] + 2, al[1], al[2] - 2), moment_set_.index(al[0], al[1] + 2, al[2] - 2)});
  }
  std::stable_sort(moment_fold_.begin(), moment_fold_.end(), [&](const auto& u, const auto& v) {
    return moment_set_[u[0]][2] > moment_set_[v[0]][2];
  });
  for (int b = 0; b < nl; ++b) {
    const auto& be = deriv_set_[b];
    if (be[2] >= 2)
      local_rebuild_.push_back({b, deriv_set_.index(be[0] + 2, be[1], be[2] - 2), deriv_set_.index(be[0], be[1] + 2, be[2] - 2)});
  }
  std::stable_sort(local_rebuild_.begin(), local_rebuild_.end(), [&](const auto& u, const auto& v) {
    return deriv_set_[u[0]][2] < deriv_set_[v[0]][2];
  });
  m2l_term_begin_.push_back(0);
  for (int b = 0; b < nl; ++b) {
    const auto& be = deriv_set_[b];
    if (be[2] <= 1)
      for (int g = 0; g < ng; ++g) {
        const auto& al = moment_set_[g];
        const int sum = deriv_set_.index(al[0] + be[0], al[1] + be[1], al[2] + be[2]);
        if (al[2] <= 1 && sum >= 0) m2l_terms_.push_back({g, sum});
      }
    m2l_term_begin_.push_back(int(m2l_terms_.size()));
  }
}

void TreeFarField::set_configuration(const Configuration& c) {
  if (c.domain.periodic()) throw std::invalid_argument("tree far field: the domain is periodic (use ewald or pme)");
  x_ = c.x;
  a_ = c.a;
  // Leaf size: given, or tuned (fmm): the candidates' trees and lists are built and the one of least
  // modelled cost (pairs x pair_seconds + conversions x conversion_seconds) is kept; re-tuned when N
  // changes and every kRetune configurations. Deterministic (counts, not timings).
  constexpr long kRetune = 32;
  if (p_.leaf_size > 0 || p_.evaluation != TreeEvaluation::fmm) {
    leaf_size_ = p_.leaf_size > 0 ? p_.leaf_size : 32;
  } else if (x_.size() != tuned_n_ || ++since_tuned_ >= kRetune) {
    double best = -1;
    for (int leaf : {32, 64, 128}) {
      tree_ = build_octree(x_, a_, leaf);
      build_interaction_lists();
      double pairs = 0;
      for (std::size_t t = 0; t + 1 < p2p_begin_.size(); ++t)
        for (int k = p2p_begin_[t]; k < p2p_begin_[t + 1]; ++k)
          pairs += double(tree_.nodes[t].size()) * tree_.nodes[std::size_t(p2p_source_[std::size_t(k)])].size();
      const double cost = pairs * pair_seconds(m_) + double(m2l_source_.size()) * conversion_seconds(p_.order, m_);
      if (best < 0 || cost < best) {
        best = cost;
        leaf_size_ = leaf;
      }
    }
    tuned_n_ = x_.size();
    since_tuned_ = 0;
  }
  tree_ = build_octree(x_, a_, leaf_size_);
  const std::size_t n = x_.size();
  sorted_.x.resize(n);
  sorted_.y.resize(n);
  sorted_.z.resize(n);
  sorted_.a.resize(n);
  for (std::size_t q = 0; q < n; ++q) {
    const std::size_t i = std::size_t(tree_.order[q]);
    sorted_.x[q] = x_[i].x();
    sorted_.y[q] = x_[i].y();
    sorted_.z[q] = x_[i].z();
    sorted_.a[q] = a_[i];
  }
  moments_.assign(tree_.nodes.size() * kPot * std::size_t(moment_set_.size()), 0.0);
  if (p_.evaluation == TreeEvaluation::fmm) {
    locals_.assign(tree_.nodes.size() * kPot * std::size_t(deriv_set_.size()), 0.0);
    build_interaction_lists();
  }
}

// Dual-tree traversal from (root, root): a well-separated pair is converted, two leaves are summed
// pair by pair, otherwise the node with the larger radius (a non-leaf) is split. Lists are built
// serially, in a fixed order, per target node.
void TreeFarField::build_interaction_lists() {
  const int nn = int(tree_.nodes.size());
  parent_.assign(std::size_t(nn), -1);
  for (int k = 0; k < nn; ++k)
    for (int c = 0; c < tree_.nodes[std::size_t(k)].child_count; ++c)
      parent_[std::size_t(tree_.nodes[std::size_t(k)].first_child + c)] = k;
  std::vector<std::vector<int>> m2l(static_cast<std::size_t>(nn)), p2p(static_cast<std::size_t>(nn));
  if (nn > 0) {
    std::vector<std::pair<int, int>> stack{{0, 0}};
    while (!stack.empty()) {
      const auto [t, s] = stack.back();
      stack.pop_back();
      const OctreeNode& T = tree_.nodes[std::size_t(t)];
      const OctreeNode& S = tree_.nodes[std::size_t(s)];
      const double dist = (T.centre - S.centre).norm();
      const double rr = T.radius + S.radius;
      if (t != s && rr < p_.theta * dist && dist - rr > T.a_max + S.a_max) {
        m2l[std::size_t(t)].push_back(s);
        continue;
      }
      if (T.leaf() && S.leaf()) {
        p2p[std::size_t(t)].push_back(s);
        continue;
      }
      const bool split_target = S.leaf() || (!T.leaf() && T.radius >= S.radius);
      // pushed in reverse so that children are visited in their stored order
      if (split_target) {
        for (int c = T.child_count - 1; c >= 0; --c) stack.push_back({T.first_child + c, s});
      } else {
        for (int c = S.child_count - 1; c >= 0; --c) stack.push_back({t, S.first_child + c});
      }
    }
  }
  auto flatten = [&](const std::vector<std::vector<int>>& lists, std::vector<int>& begin, std::vector<int>& flat) {
    begin.assign(1, 0);
    flat.clear();
    for (const auto& l : lists) {
      flat.insert(flat.end(), l.begin(), l.end());
      begin.push_back(int(flat.size()));
    }
  };
  flatten(m2l, m2l_begin_, m2l_source_);
  flatten(p2p, p2p_begin_, p2p_source_);
}

// Moments of the four potentials of every node, summed from its particles (the source terms of
// the header). M[pot][g] multiplies d^g G(x - c).
void TreeFarField::compute_moments(const VecX& in) const {
  const int d = dof_per_particle(m_);
  const int ng = moment_set_.size();
  const long nodes = long(tree_.nodes.size());
  const bool torque = has_torque(m_), stresslet = has_stresslet(m_);
#pragma omp parallel
  {
    std::vector<double> w(static_cast<std::size_t>(ng));
#pragma omp for schedule(dynamic, 4)
    for (long k = 0; k < nodes; ++k) {
      const OctreeNode& node = tree_.nodes[std::size_t(k)];
      double* M = moments_.data() + std::size_t(k) * kPot * std::size_t(ng);
      std::fill(M, M + kPot * ng, 0.0);
      for (int q = node.begin; q < node.end; ++q) {
        const std::size_t i = std::size_t(tree_.order[std::size_t(q)]);
        const double* src = in.data() + long(i) * d;
        const Vec3 s = x_[i] - node.centre;
        const Vec3 F(src[0], src[1], src[2]);
        Mat3 D = Mat3::Zero();
        Mat3 S = Mat3::Zero();
        if (torque) {
          const Vec3 T(src[3], src[4], src[5]);
          // D_jl = -1/2 eps_jlm T_m
          D(0, 1) = -0.5 * T.z();
          D(1, 0) = 0.5 * T.z();
          D(0, 2) = 0.5 * T.y();
          D(2, 0) = -0.5 * T.y();
          D(1, 2) = -0.5 * T.x();
          D(2, 1) = 0.5 * T.x();
        }
        if (stresslet) {
          Vec5 s5;
          for (int r = 0; r < 5; ++r) s5[r] = src[6 + r];
          S = from_vec5(s5);
          D += S;
        }
        const double a2 = a_[i] * a_[i];
        const Vec3 psi_dipole = D.transpose() * s + (a2 / 3.0) * F;  // (s_j D_jl + a^2/3 F_l)
        const double psi_charge = s.dot(F);
        const Mat3 Q = (a2 / 5.0) * S;
        scaled_powers(s, moment_set_, w.data());
        for (int g = 0; g < ng; ++g) {
          const double wg = w[std::size_t(g)];
          for (int j = 0; j < 3; ++j) M[g * kPot + j] += F[j] * wg;
          M[g * kPot + 3] += psi_charge * wg;
          // dipoles: coefficient -moment_l w_g at g + e_l
          for (int l = 0; l < 3; ++l) {
            const int gl = moment_set_.plus(g, l);
            if (gl < 0) continue;
            for (int j = 0; j < 3; ++j) M[gl * kPot + j] -= D(j, l) * wg;
            M[gl * kPot + 3] -= psi_dipole[l] * wg;
            if (stresslet)
              for (int jj = 0; jj < 3; ++jj) {
                const int gjl = moment_set_.plus(gl, jj);
                if (gjl >= 0) M[gjl * kPot + 3] += Q(jj, l) * wg;
              }
          }
        }
      }
    }
  }
}

void TreeFarField::apply(const VecX& in, VecX& out) const {
  const int d = dof_per_particle(m_);
  const long n = long(x_.size());
  if (in.size() != n * d)
    throw std::invalid_argument("tree far field: input of size " + std::to_string(in.size()) + ", expected " +
                                std::to_string(n * d));
  out.setZero(n * d);
  if (n == 0) return;
  const double t0 = omp_get_wtime();
  compute_moments(in);
  const double t1 = omp_get_wtime();
  if (p_.evaluation == TreeEvaluation::fmm)
    apply_fmm(in, out);
  else
    apply_barnes_hut(in, out);
  stats_.upward_seconds = t1 - t0;
  stats_.downward_seconds = omp_get_wtime() - t1;
}

void TreeFarField::apply_fmm(const VecX& in, VecX& out) const {
  stats_ = TreeProductStats{};
  {
    const std::size_t ng = std::size_t(moment_set_.size()), nodes = tree_.nodes.size();
    for (std::size_t k = 0; k < nodes; ++k) {
      double* M = moments_.data() + k * kPot * ng;
      for (const auto& f : moment_fold_)
        for (int pot = 0; pot < kPot; ++pot) {
          M[kPot * f[1] + pot] -= M[kPot * f[0] + pot];
          M[kPot * f[2] + pot] -= M[kPot * f[0] + pot];
          M[kPot * f[0] + pot] = 0;
        }
    }
  }
  {
    const int d = dof_per_particle(m_);
    const std::size_t n = x_.size();
    for (int c = 0; c < d; ++c) sorted_.in[c].resize(n);
    for (std::size_t q = 0; q < n; ++q)
      for (int c = 0; c < d; ++c) sorted_.in[c][q] = in[long(tree_.order[q]) * d + c];
  }
  pair_count_ = 0;
  long m2l_count = 0;
  for (std::size_t k = 0; k + 1 < m2l_begin_.size(); ++k) m2l_count += m2l_begin_[k + 1] - m2l_begin_[k];
#pragma omp parallel
#pragma omp single
  downward(0, in, out);
  stats_.m2l = m2l_count;
  stats_.pair_interactions = pair_count_;
}

// Local expansion of node t: shifted from its parent's, plus the conversions of its list; a leaf
// then evaluates its targets (expansion + exact pairs); children are tasks.
void TreeFarField::downward(int t, const VecX& in, VecX& out) const {
  const int ng = moment_set_.size(), nl = deriv_set_.size();
  const OctreeNode& T = tree_.nodes[std::size_t(t)];
  double* L = locals_.data() + std::size_t(t) * kPot * std::size_t(nl);
  std::fill(L, L + kPot * nl, 0.0);
  std::vector<double> tmp(static_cast<std::size_t>(nl));
  // conversions of the list (locals with beta_z <= 1), psi about the target's centre:
  // + (c_S - c_T)_j phi_j
  std::vector<double> D(static_cast<std::size_t>(nl));
  for (int q = m2l_begin_[std::size_t(t)]; q < m2l_begin_[std::size_t(t) + 1]; ++q) {
    const int s = m2l_source_[std::size_t(q)];
    const OctreeNode& S = tree_.nodes[std::size_t(s)];
    const double* M = moments_.data() + std::size_t(s) * kPot * std::size_t(ng);
    const Vec3 R = T.centre - S.centre;
    inverse_distance_derivatives(R, deriv_set_, D.data());
    convert(M, D.data(), R, m2l_terms_.data(), m2l_term_begin_.data(), nl, L);
  }
  if (m2l_begin_[std::size_t(t)] < m2l_begin_[std::size_t(t) + 1])
    for (const auto& r : local_rebuild_)
      for (int pot = 0; pot < kPot; ++pot) L[kPot * r[0] + pot] = -L[kPot * r[1] + pot] - L[kPot * r[2] + pot];
  if (parent_[std::size_t(t)] >= 0) {
    const int par = parent_[std::size_t(t)];
    const double* LP = locals_.data() + std::size_t(par) * kPot * std::size_t(nl);
    const Vec3 shift = T.centre - tree_.nodes[std::size_t(par)].centre;
    // L_beta += sum_delta LP_(beta + delta) shift^delta / delta!  (scaled_powers takes -shift),
    // then psi about the child's centre: + (c_parent - c_child)_j phi_j
    scaled_powers(-shift, deriv_set_, tmp.data());
    std::vector<double> Ls(static_cast<std::size_t>(kPot * nl), 0.0);
    for (const auto& term : shift_terms_) {
      const double w = tmp[std::size_t(term[1])];
      const double* lp = LP + kPot * term[2];
      double* l = Ls.data() + kPot * term[0];
      for (int pot = 0; pot < kPot; ++pot) l[pot] += lp[pot] * w;
    }
    for (int b = 0; b < nl; ++b) {
      const double* l = Ls.data() + kPot * b;
      L[kPot * b] += l[0];
      L[kPot * b + 1] += l[1];
      L[kPot * b + 2] += l[2];
      L[kPot * b + 3] += l[3] - (shift[0] * l[0] + shift[1] * l[1] + shift[2] * l[2]);
    }
  }
  if (!T.leaf()) {
    for (int c = 0; c < T.child_count; ++c) {
      const int child = T.first_child + c;
#pragma omp task default(shared) firstprivate(child) if (tree_.nodes[std::size_t(child)].size() > 24)
      downward(child, in, out);
    }
#pragma omp taskwait
    return;
  }
  // targets of the leaf
  const int d = dof_per_particle(m_);
  const int nb = beta_set_.size();
  const DerivativeIndex ix(beta_set_);
  std::vector<double> P(static_cast<std::size_t>(4 * nb));
  const double scale = 1.0 / (8.0 * kPi * mu_);
  long pairs = 0;
  for (int q = T.begin; q < T.end; ++q) {
    const int i = tree_.order[std::size_t(q)];
    const double ai = a_[std::size_t(i)];
    double* yi = out.data() + long(i) * d;
    mobility::apply_self(ai, mu_, m_, in.data() + long(i) * d, yi);
    const Vec3 R = x_[std::size_t(i)] - T.centre;
    scaled_powers(-R, deriv_set_, tmp.data());  // R^delta / delta!
    std::fill(P.begin(), P.end(), 0.0);
    for (int b = 0; b < nb; ++b) {
      const auto& be = beta_set_[b];
      const int bb = deriv_set_.index(be[0], be[1], be[2]);
      for (int k = shift_begin_[std::size_t(bb)]; k < shift_begin_[std::size_t(bb) + 1]; ++k) {
        const auto& term = shift_terms_[std::size_t(k)];
        const double w = tmp[std::size_t(term[1])];
        for (int pot = 0; pot < kPot; ++pot) P[std::size_t(pot * nb + b)] += L[kPot * term[2] + pot] * w;
      }
    }
    double y[11] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    add_responses(P.data(), nb, ix, R, ai, m_, y);
    for (int r = 0; r < d; ++r) yi[r] += scale * y[r];
    for (int k = p2p_begin_[std::size_t(t)]; k < p2p_begin_[std::size_t(t) + 1]; ++k) {
      const OctreeNode& S = tree_.nodes[std::size_t(p2p_source_[std::size_t(k)])];
      add_pairs_sorted(sorted_, S.begin, S.end, q, ai, mu_, m_, yi, pairs);
    }
  }
#pragma omp atomic
  pair_count_ += pairs;
}

void TreeFarField::apply_barnes_hut(const VecX& in, VecX& out) const {
  const int d = dof_per_particle(m_);
  const long n = long(x_.size());
  const int ng = moment_set_.size(), nb = beta_set_.size(), nd = deriv_set_.size();
  const double scale = 1.0 / (8.0 * kPi * mu_);
  const double theta2 = p_.theta * p_.theta;
  const DerivativeIndex ix(beta_set_);
  long node_count = 0, pair_count = 0;
#pragma omp parallel reduction(+ : node_count, pair_count)
  {
    std::vector<double> D(static_cast<std::size_t>(nd));
    std::vector<double> P(static_cast<std::size_t>(4 * nb));  // d^beta of the 4 potentials
    std::vector<int> stack;
    stack.reserve(256);
#pragma omp for schedule(dynamic, 32)
    for (long q = 0; q < n; ++q) {
      const int i = tree_.order[std::size_t(q)];
      const Vec3 xi = x_[std::size_t(i)];
      const double ai = a_[std::size_t(i)];
      double* yi = out.data() + long(i) * d;
      mobility::apply_self(ai, mu_, m_, in.data() + long(i) * d, yi);
      double y[11] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
      stack.clear();
      stack.push_back(0);
      while (!stack.empty()) {
        const int k = stack.back();
        stack.pop_back();
        const OctreeNode& node = tree_.nodes[std::size_t(k)];
        const Vec3 R = xi - node.centre;
        const double R2 = R.squaredNorm();
        const bool far = node.radius * node.radius < theta2 * R2 && std::sqrt(R2) - node.radius > ai + node.a_max;
        if (!far) {
          if (node.leaf())
            add_pairs(tree_.order, node.begin, node.end, i, x_, a_, mu_, m_, in, yi, pair_count);
          else
            for (int c = 0; c < node.child_count; ++c) stack.push_back(node.first_child + c);
          continue;
        }
        ++node_count;
        inverse_distance_derivatives(R, deriv_set_, D.data());
        const double* M = moments_.data() + std::size_t(k) * kPot * std::size_t(ng);
        std::fill(P.begin(), P.end(), 0.0);
        for (int g = 0; g < ng; ++g) {
          const double m0 = M[kPot * g], m1 = M[kPot * g + 1], m2 = M[kPot * g + 2], m3 = M[kPot * g + 3];
          const int* si = sum_index_.data() + std::size_t(g * nb);
          for (int b = 0; b < nb; ++b) {
            const double dv = D[std::size_t(si[b])];
            P[std::size_t(b)] += m0 * dv;
            P[std::size_t(nb + b)] += m1 * dv;
            P[std::size_t(2 * nb + b)] += m2 * dv;
            P[std::size_t(3 * nb + b)] += m3 * dv;
          }
        }
        add_responses(P.data(), nb, ix, R, ai, m_, y);
      }
      for (int r = 0; r < d; ++r) yi[r] += scale * y[r];
    }
  }
  stats_ = TreeProductStats{};
  stats_.node_interactions = node_count;
  stats_.pair_interactions = pair_count;
}

}  // namespace stokesian::trees
