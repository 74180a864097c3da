// Fast real-space Ewald sum; the mathematics and the accuracy contract are in real_space.hpp.
#include "ewald/real_space.hpp"

#include "ewald/ewald_split.hpp"

#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#if defined(__x86_64__) && defined(__GNUC__)
#define STOKESIAN_RS_INLINE inline __attribute__((always_inline))
#define STOKESIAN_RS_AVX2 __attribute__((target("avx2,fma")))
#else
#define STOKESIAN_RS_INLINE inline
#define STOKESIAN_RS_AVX2
#endif

namespace stokesian::ewald {
namespace {

using LD = long double;
constexpr LD kSqrtPiL = 1.772453850905516027298167483341145183L;
constexpr double kR2 = 0.70710678118654752440;  // sqrt(1/2), sym_traceless.hpp basis
constexpr double kR6 = 0.40824829046386301637;  // 1/sqrt(6)

// Below xi r = kSeries the derivatives come from the Taylor series in x = xi r (kTerms terms:
// truncation < 1e-40 at x = 0.5); above it from the closed forms, both in long double.
constexpr LD kSeries = 0.5L;
constexpr int kTerms = 30;

// Derivatives d1..d4 (in r) of the wave functions W0, W1, W2 of ewald_split.hpp at r > 0:
//   W0 = r erf x + e^{-x^2} / (sqrt(pi) xi),  W1 = 2 erf(x) / r + 2 xi e^{-x^2} / sqrt(pi),
//   W2 = -(xi^3 / sqrt(pi)) (20 - 8 x^2) e^{-x^2},  x = xi r.
// Series: W_j = scale_j sum_n s_{j,n} x^(2n), so d_k W_j = scale_j xi^k sum_n s_{j,n} (2n)!/(2n-k)! x^(2n-k).
void wave_derivatives(LD r, LD xi, std::array<std::array<LD, 4>, 3>& d) {
  const LD x = xi * r;
  if (x < kSeries) {
    const LD scale[3] = {1.0L / (kSqrtPiL * xi), 2.0L * xi / kSqrtPiL, -xi * xi * xi / kSqrtPiL};
    for (auto& dj : d) dj.fill(0.0L);
    LD fact = 1.0L, fact_prev = 1.0L, sign = 1.0L;  // n!, (n-1)!, (-1)^n
    for (int n = 0; n <= kTerms; ++n) {
      if (n > 0) {
        fact_prev = fact;
        fact *= n;
        sign = -sign;
      }
      LD s[3];
      s[0] = sign / fact + (n > 0 ? 2.0L * (-sign) / (fact_prev * (2.0L * n - 1.0L)) : 0.0L);
      s[1] = sign / fact * (2.0L / (2.0L * n + 1.0L) + 1.0L);
      s[2] = 20.0L * sign / fact - (n > 0 ? 8.0L * (-sign) / fact_prev : 0.0L);
      LD falling = 1.0L;  // (2n)! / (2n - k)!
      for (int k = 1; k <= 4; ++k) {
        falling *= LD(2 * n - k + 1);
        if (falling == 0.0L) break;
        const LD term = falling * std::pow(x, LD(2 * n - k));
        for (int j = 0; j < 3; ++j) d[j][k - 1] += s[j] * term;
      }
    }
    for (int j = 0; j < 3; ++j) {
      LD xik = 1.0L;
      for (int k = 0; k < 4; ++k) {
        xik *= xi;
        d[j][k] *= scale[j] * xik;
      }
    }
    return;
  }
  const LD E = std::exp(-x * x) / kSqrtPiL, er = std::erf(x);
  const LD x2 = x * x, x3 = x2 * x, x5 = x3 * x2, x7 = x5 * x2, x9 = x7 * x2;
  const LD xi2 = xi * xi, xi3 = xi2 * xi, xi4 = xi3 * xi;
  const LD r2 = r * r, r3 = r2 * r, r4 = r3 * r, r5 = r4 * r;
  d[0] = {er, 2.0L * xi * E, -4.0L * xi3 * r * E, xi3 * (8.0L * x2 - 4.0L) * E};
  d[1] = {-2.0L * er / r2 - 4.0L * r * xi3 * E + 4.0L * xi * E / r,
          4.0L * er / r3 - 4.0L * E * (x3 * (3.0L - 2.0L * x2) + 2.0L * x) / r3,
          -12.0L * er / r4 - 4.0L * E * (4.0L * x7 - 10.0L * x5 - 4.0L * x3 - 6.0L * x) / r4,
          48.0L * er / r5 - 8.0L * E * (-4.0L * x9 + 16.0L * x7 - x5 + 8.0L * x3 + 12.0L * x) / r5};
  d[2] = {-xi4 * (16.0L * x3 - 56.0L * x) * E, -xi4 * xi * (-32.0L * x2 * x2 + 160.0L * x2 - 56.0L) * E,
          -xi4 * xi2 * (64.0L * x5 - 448.0L * x3 + 432.0L * x) * E,
          -xi4 * xi3 * (-128.0L * x3 * x3 + 1216.0L * x2 * x2 - 2208.0L * x2 + 432.0L) * E};
}

// Scalars kept per cached entry (yht = yh): xa ya | yb ybt xc yc | xg yg xgt ygt yh xm ym zm.
constexpr int cached_scalars(Moments m) { return m == Moments::F ? 2 : (m == Moments::FT ? 6 : 14); }

// The pair scalars (record order xa ya | yb ybt xc yc | xg yg xgt ygt yh xm ym zm; the first
// cached_scalars(M)) from w[3k + j] = d_{k+1} W_j / (8 pi mu) (k-major; F uses k < 2), radii squared
// A (this row) and B, u = 1/r, km = 1/(8 pi mu): the derivatives of Psi = B0 + c1 B1 + c2 B2 with
// B0 = r - W0, B1 = 2 / r - W1, B2 = -W2 for each kind pair, then mobility::scalars_from_derivatives
// written with u. Used in double by the general tables' product and in long double to build the
// per-class tables.
template <Moments M, class T>
STOKESIAN_RS_INLINE void scalars_from_w(const T* w, T A, T B, T u, T km, T* out) {
  const T u2 = u * u, u3 = u2 * u, AB = A * B;
  // Products by reciprocals: a division per entry cost its latency in the uncached product.
  constexpr T k6 = T(1) / T(6), k10 = T(1) / T(10), k36 = T(1) / T(36), k60 = T(1) / T(60), k100 = T(1) / T(100);
  {
    const T c1 = (A + B) * k6, c2 = AB * k36;  // ff
    const T D1 = km - w[0] + c1 * (T(-2) * km * u2 - w[1]) - c2 * w[2];
    const T D2 = -w[3] + c1 * (T(4) * km * u3 - w[4]) - c2 * w[5];
    out[0] = T(2) * D1 * u;
    out[1] = D2 + D1 * u;
  }
  if constexpr (M != Moments::F) {
    const T u4 = u2 * u2, u5 = u4 * u;
    const T b0[4] = {km - w[0], -w[3], -w[6], -w[9]};
    const T b1[4] = {T(-2) * km * u2 - w[1], T(4) * km * u3 - w[4], T(-12) * km * u4 - w[7], T(48) * km * u5 - w[10]};
    const T b2[4] = {-w[2], -w[5], -w[8], -w[11]};
    auto derivs = [&](T c1, T c2, T* D) {
      for (int q = 0; q < 4; ++q) D[q] = b0[q] + c1 * b1[q] + c2 * b2[q];
    };
    T tf[4], ft[4], t4[4];
    derivs(A * k10 + B * k6, AB * k60, tf);
    derivs(A * k6 + B * k10, AB * k60, ft);
    derivs((A + B) * k10, AB * k100, t4);
    out[2] = T(-0.5) * tf[2] - tf[1] * u + tf[0] * u2;                                  // yb
    out[3] = T(-0.5) * ft[2] - ft[1] * u + ft[0] * u2;                                  // ybt
    out[4] = (T(-0.5) * t4[2] - t4[1] * u + t4[0] * u2) * u;                            // xc
    out[5] = T(-0.25) * t4[3] - T(0.75) * t4[2] * u + T(0.5) * t4[1] * u2 - T(0.5) * t4[0] * u3;  // yc
    if constexpr (M == Moments::FTS) {
      out[6] = T(3) * (tf[1] - tf[0] * u) * u;                                          // xg
      out[7] = T(0.5) * tf[2];                                                          // yg
      out[8] = T(-3) * (ft[1] - ft[0] * u) * u;                                         // xgt
      out[9] = T(-0.5) * ft[2];                                                         // ygt
      out[10] = T(0.25) * (-t4[3] - t4[2] * u + T(6) * t4[1] * u2 - T(6) * t4[0] * u3);  // yh = yht
      out[11] = T(3) * (-t4[2] * u + T(2) * t4[1] * u2 - T(2) * t4[0] * u3);            // xm
      out[12] = T(-0.5) * t4[3] + T(0.5) * t4[2] * u - T(3) * t4[1] * u2 + T(3) * t4[0] * u3;  // ym
      out[13] = -t4[2] * u;                                                             // zm
    }
  }
}

std::atomic<bool> g_force_general{false};  // RealSpaceSum::force_general_tables

// Four doubles, loaded without an alignment assumption (the tables are std::vector storage).
typedef double v4u __attribute__((vector_size(32), aligned(8)));

// Degree-7 polynomial at t in [-1, 1] by Estrin's scheme (three dependent multiply-adds instead of
// Horner's seven); c[lev * stride] holds the coefficient of t^(7 - lev).
// (Two overloads, not a template: a template argument would drop v4u's alignment attribute; the
// vector one writes through a pointer, since returning a vector by value outside the AVX2 target
// changes the ABI.)
#define STOKESIAN_RS_ESTRIN7                                                                      \
  const double t2 = t * t, t4 = t2 * t2;                                                          \
  const auto q01 = c[7 * stride] + c[6 * stride] * t, q23 = c[5 * stride] + c[4 * stride] * t;  \
  const auto q45 = c[3 * stride] + c[2 * stride] * t, q67 = c[1 * stride] + c[0 * stride] * t;
STOKESIAN_RS_INLINE double estrin7(const double* c, int stride, double t) {
  STOKESIAN_RS_ESTRIN7
  return (q01 + q23 * t2) + (q45 + q67 * t2) * t4;
}
STOKESIAN_RS_INLINE void estrin7(const v4u* c, int stride, double t, v4u* out) {
  STOKESIAN_RS_ESTRIN7
  *out = (q01 + q23 * t2) + (q45 + q67 * t2) * t4;
}
#undef STOKESIAN_RS_ESTRIN7

// Degree-7 Chebyshev interpolation on one interval (t in [-1, 1]): the 8 nodes, and the monomial
// coefficients from the values at the nodes, stored as the kernels read them (out[lev * stride] =
// coefficient of t^(7 - lev)). Shared by the general and the per-class tables.
struct Cheb7 {
  static constexpr int n = 8;
  LD node[n], T[n][n] = {}, cosine[n][n];  // T: monomial coefficients of T_0 .. T_7
  Cheb7() {
    for (int q = 0; q < n; ++q) node[q] = std::cos(LD(kPi) * (q + 0.5L) / n);
    T[0][0] = 1.0L;
    T[1][1] = 1.0L;
    for (int k = 1; k + 1 < n; ++k)
      for (int c = 0; c < n; ++c) T[k + 1][c] = (c > 0 ? 2.0L * T[k][c - 1] : 0.0L) - T[k - 1][c];
    for (int k = 0; k < n; ++k)
      for (int q = 0; q < n; ++q) cosine[k][q] = std::cos(LD(kPi) * k * (q + 0.5L) / n);
  }
  // val(q): the function at node q.
  template <class V>
  void fit(V&& val, double* out, int stride) const {
    LD mono[n] = {};
    for (int k = 0; k < n; ++k) {
      LD sum = 0.0L;
      for (int q = 0; q < n; ++q) sum += val(q) * cosine[k][q];
      const LD cheb = sum * (k == 0 ? 1.0L : 2.0L) / n;
      for (int c = 0; c < n; ++c) mono[c] += cheb * T[k][c];
    }
    for (int c = 0; c < n; ++c) out[(n - 1 - c) * stride] = double(mono[c]);
  }
};
const Cheb7& cheb7() {
  static const Cheb7 c;
  return c;
}

// Smallest self mobility (of the moments in m) of a sphere of radius a.
double self_min(double a, double mu, Moments m) {
  double s = 1.0 / (6.0 * kPi * mu * a);
  if (m != Moments::F) s = std::min(s, 1.0 / (8.0 * kPi * mu * a * a * a));
  if (m == Moments::FTS) s = std::min(s, 3.0 / (20.0 * kPi * mu * a * a * a));
  return s;
}

// y += (block with scalars s, unit vector e) x for one source particle; layout [F T S] / [U W E].
// T is double, or v4a for four entries at once (lane l of every operand belongs to entry l; S then
// holds four entries' scalars per field). The same operations in the same order for both.
template <Moments M, class T, class S>
STOKESIAN_RS_INLINE void apply_block_t(const S& s, const T& ex, const T& ey, const T& ez, const T* x, T* y) {
  const T Fx = x[0], Fy = x[1], Fz = x[2];
  const T eF = ex * Fx + ey * Fy + ez * Fz;
  const T cF = (s.xa - s.ya) * eF;
  y[0] += cF * ex + s.ya * Fx;
  y[1] += cF * ey + s.ya * Fy;
  y[2] += cF * ez + s.ya * Fz;
  if constexpr (M == Moments::F) return;
  else {
    const T Tx = x[3], Ty = x[4], Tz = x[5];
    const T eT = ex * Tx + ey * Ty + ez * Tz;
    const T Txe_x = Ty * ez - Tz * ey, Txe_y = Tz * ex - Tx * ez, Txe_z = Tx * ey - Ty * ex;
    const T Fxe_x = Fy * ez - Fz * ey, Fxe_y = Fz * ex - Fx * ez, Fxe_z = Fx * ey - Fy * ex;
    const T cT = (s.xc - s.yc) * eT;
    y[0] += s.ybt * Txe_x;
    y[1] += s.ybt * Txe_y;
    y[2] += s.ybt * Txe_z;
    y[3] += s.yb * Fxe_x + cT * ex + s.yc * Tx;
    y[4] += s.yb * Fxe_y + cT * ey + s.yc * Ty;
    y[5] += s.yb * Fxe_z + cT * ez + s.yc * Tz;
    if constexpr (M == Moments::FT) return;
    else {
      const T s0 = x[6], s1 = x[7], s2 = x[8], s3 = x[9], s4 = x[10];
      const T Sxx = kR2 * s0 - kR6 * s1, Syy = -kR2 * s0 - kR6 * s1, Szz = 2.0 * kR6 * s1;
      const T Sxy = kR2 * s2, Sxz = kR2 * s3, Syz = kR2 * s4;
      const T Sex = Sxx * ex + Sxy * ey + Sxz * ez, Sey = Sxy * ex + Syy * ey + Syz * ez,
                   Sez = Sxz * ex + Syz * ey + Szz * ez;
      const T eSe = ex * Sex + ey * Sey + ez * Sez;
      const T cU = (s.xgt - 2.0 * s.ygt) * eSe, g2 = 2.0 * s.ygt;
      y[0] += cU * ex + g2 * Sex;
      y[1] += cU * ey + g2 * Sey;
      y[2] += cU * ez + g2 * Sez;
      const T h2 = 2.0 * s.yht;
      y[3] += h2 * (ey * Sez - ez * Sey);
      y[4] += h2 * (ez * Sex - ex * Sez);
      y[5] += h2 * (ex * Sey - ey * Sex);
      // E = alpha e e + e v^T + v e^T + zm S (+ multiples of I, which the 5-basis drops).
      const T alpha = (s.xg - 2.0 * s.yg) * eF + (1.5 * s.xm - 2.0 * s.ym + 0.5 * s.zm) * eSe;
      const T ymz = s.ym - s.zm;
      const T vx = s.yg * Fx + s.yh * Txe_x + ymz * Sex, vy = s.yg * Fy + s.yh * Txe_y + ymz * Sey,
                   vz = s.yg * Fz + s.yh * Txe_z + ymz * Sez;
      const T Mxx = alpha * ex * ex + 2.0 * ex * vx, Myy = alpha * ey * ey + 2.0 * ey * vy,
                   Mzz = alpha * ez * ez + 2.0 * ez * vz;
      const T Mxy = alpha * ex * ey + ex * vy + vx * ey, Mxz = alpha * ex * ez + ex * vz + vx * ez,
                   Myz = alpha * ey * ez + ey * vz + vy * ez;
      y[6] += kR2 * (Mxx - Myy) + s.zm * s0;
      y[7] += kR6 * (2.0 * Mzz - Mxx - Myy) + s.zm * s1;
      y[8] += 2.0 * kR2 * Mxy + s.zm * s2;
      y[9] += 2.0 * kR2 * Mxz + s.zm * s3;
      y[10] += 2.0 * kR2 * Myz + s.zm * s4;
    }
  }
}

template <Moments M>
STOKESIAN_RS_INLINE void apply_block(const mobility::PairScalars& s, double ex, double ey, double ez, const double* x, double* y) {
  apply_block_t<M, double>(s, ex, ey, ez, x, y);
}

// Four doubles in a register (natural alignment, locals only) and four entries' pair scalars.
typedef double v4a __attribute__((vector_size(32)));
struct PairScalars4 {
  v4a xa, ya, yb, ybt, xc, yc, xg, yg, xgt, ygt, yh, yht, xm, ym, zm;
};
STOKESIAN_RS_INLINE void load4(const double* p, v4a* out) { __builtin_memcpy(out, p, sizeof(v4a)); }

}  // namespace

double RealSpaceSum::cache_bytes_for(double entries, Moments m) {
  return entries * cached_scalars(m) * double(sizeof(double));
}

RealSpaceSum::RealSpaceSum(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                           double cutoff_gap, double xi, double mu, Moments m, double tolerance,
                           std::size_t cache_bytes)
    : n_(long(x.size())),
      m_(m),
      domain_(domain),
      cutoff_gap_(cutoff_gap),
      xi_(xi),
      mu_(mu),
      radius_(a),
      cache_bytes_(cache_bytes) {
  if (x.empty() || x.size() != a.size())
    throw std::invalid_argument("RealSpaceSum: " + std::to_string(x.size()) + " positions and " +
                                std::to_string(a.size()) + " radii (need equal, non-zero counts)");
  if (!domain.periodic()) throw std::invalid_argument("RealSpaceSum: the domain must be periodic");
  for (double r : a)
    if (!(r > 0.0 && std::isfinite(r))) throw std::invalid_argument("RealSpaceSum: radius " + std::to_string(r) + " not positive");
  if (!(cutoff_gap > 0.0 && std::isfinite(cutoff_gap)))
    throw std::invalid_argument("RealSpaceSum: cutoff_gap " + std::to_string(cutoff_gap) + " must be positive");
  if (!(xi > 0.0 && std::isfinite(xi))) throw std::invalid_argument("RealSpaceSum: xi " + std::to_string(xi) + " must be positive");
  if (!(mu > 0.0 && std::isfinite(mu))) throw std::invalid_argument("RealSpaceSum: mu " + std::to_string(mu) + " must be positive");
  if (!(tolerance >= 1e-14 && tolerance <= 0.1))
    throw std::invalid_argument("RealSpaceSum: tolerance " + std::to_string(tolerance) + " outside [1e-14, 0.1]");
  const double amax = *std::max_element(a.begin(), a.end());
  const double range = cutoff_gap + 2.0 * amax, lmin = domain.box.minCoeff();
  if (!(lmin > 0.0)) throw std::invalid_argument("RealSpaceSum: periodic box with non-positive edge");
  if (range > 0.5 * lmin)
    throw std::invalid_argument("RealSpaceSum: interaction range " + std::to_string(range) +
                                " exceeds half the smallest box edge " + std::to_string(0.5 * lmin) +
                                "; the minimum-image pair list cannot represent this box");
  build_table(tolerance);
  self0_.resize(3 * a.size());
#pragma omp parallel
  {
    double last = -1.0;  // radius of this thread's previous evaluation (monodisperse: one evaluation)
    mobility::PairScalars sc;
#pragma omp for schedule(static)
    for (long i = 0; i < n_; ++i) {
      if (a[i] != last) {
        sc = self_correction(a[i], xi_, mu_);
        last = a[i];
      }
      self0_[3 * i] = sc.xa;
      self0_[3 * i + 1] = sc.xc;
      self0_[3 * i + 2] = sc.xm;
    }
  }
  set_positions(x);
}

namespace {
std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}
}  // namespace

void RealSpaceSum::build_table(double tolerance) {
  const auto [pmin, pmax] = std::minmax_element(radius_.begin(), radius_.end());
  const double amin = *pmin, amax = *pmax;
  r_lo_ = 2.0 * amin;
  const double r_hi = cutoff_gap_ + 2.0 * amax;
  const int kmax = m_ == Moments::F ? 2 : 4;
  nf_ = 3 * kmax;
  stride_ = m_ == Moments::F ? 8 : 12;  // padded to whole 4-vectors
  // Floor 2e-14: below it the tables cannot be resolved in double precision (the wave functions
  // exceed the real part they are subtracted from by orders of magnitude at short range).
  table_target_ = std::max(1e-4 * tolerance, 2e-14);
  // At most kMaxClasses distinct radii: tables of the pair scalars per pair of radius classes.
  classes_.assign(radius_.begin(), radius_.end());
  std::sort(classes_.begin(), classes_.end());
  classes_.erase(std::unique(classes_.begin(), classes_.end()), classes_.end());
  if (int(classes_.size()) <= kMaxClasses && !g_force_general) {
    build_direct_table();
    return;
  }
  classes_.clear();
  class_tables_.clear();
  direct_ = false;
  const LD kmob = 1.0L / (8.0L * LD(kPi) * LD(mu_));
  static_assert(kCoef == Cheb7::n, "the tables are degree-7 Chebyshev pieces");
  const Cheb7& ch = cheb7();
  std::array<std::array<LD, 4>, 3> d;
  for (int nint = 4;; nint *= 2) {
    const double h = (r_hi - r_lo_) / nint;
    std::vector<double> tab(std::size_t(nint) * kCoef * stride_, 0.0);
    for (int i = 0; i < nint; ++i) {
      LD val[kCoef][12];
      for (int q = 0; q < kCoef; ++q) {
        wave_derivatives(LD(r_lo_) + LD(h) * (i + 0.5L * (ch.node[q] + 1.0L)), LD(xi_), d);
        for (int k = 0; k < kmax; ++k)
          for (int j = 0; j < 3; ++j) val[q][3 * k + j] = kmob * d[j][k];
      }
      for (int f = 0; f < nf_; ++f)
        ch.fit([&](int q) { return val[q][f]; }, tab.data() + std::size_t(i) * kCoef * stride_ + f, stride_);
    }
    // Measured error on 9 points per interval (ends included), evaluated as the kernel does.
    double worst = 0.0;
    for (int i = 0; i < nint; ++i)
      for (int p = 0; p <= 8; ++p) {
        const double t = -1.0 + 0.25 * p, r = r_lo_ + h * (i + 0.5 * (t + 1.0));
        wave_derivatives(LD(r), LD(xi_), d);
        // A separated pair at distance r has a_a + a_b <= r: c1 <= min(r^2, 2 a_max^2) / 6,
        // c2 <= min(r/2, a_max)^4 / 36, and its smaller sphere has radius rho <= min(a_max, r/2).
        const double rho = std::min(amax, 0.5 * r), u = 1.0 / r;
        const double cmax[3] = {1.0, std::min(r * r, 2.0 * amax * amax) / 6.0, rho * rho * rho * rho / 36.0};
        double e[4] = {0.0, 0.0, 0.0, 0.0};  // bound of the error of d_k (k = 1..4) of the pair's Psi
        for (int f = 0; f < nf_; ++f) {
          const double w = estrin7(tab.data() + std::size_t(i) * kCoef * stride_ + f, stride_, t);
          const int k = f / 3, j = f % 3;
          e[k] += std::abs(double(LD(w) - kmob * d[j][k])) * cmax[j];
        }
        // Largest multipliers of d1..d4 in the scalars (scalars_from_derivatives): U <- F uses
        // 2u d1 + d2; the torque/stresslet scalars at most max(3u^2, 6u^3) d1 + max(3u, 6u^2) d2
        // + max(1/2, 3u) d3 + d4 / 2. Each is compared with the matching self mobility at rho.
        const double u2 = u * u, u3 = u2 * u;
        double err = (2.0 * u * e[0] + e[1]) / (1.0 / (6.0 * kPi * mu_ * rho));
        if (m_ != Moments::F)
          err = std::max(err, (std::max(3.0 * u2, 6.0 * u3) * e[0] + std::max(3.0 * u, 6.0 * u2) * e[1] +
                               std::max(0.5, 3.0 * u) * e[2] + 0.5 * e[3]) /
                                  self_min(rho, mu_, m_));
        worst = std::max(worst, err);
      }
    if (worst <= table_target_) {
      intervals_ = nint;
      inv_h_ = 1.0 / h;
      table_ = std::move(tab);
      table_error_ = worst;
      return;
    }
    if (nint >= (1 << 14))
      throw std::runtime_error("RealSpaceSum: real-space table error " + sci(worst) + " above the target " +
                               sci(table_target_) + " with " +
                               std::to_string(nint) + " intervals");
  }
}

void RealSpaceSum::build_direct_table() {
  direct_ = true;
  const int K = int(classes_.size());
  const double amax = classes_.back();
  nf_ = cached_scalars(m_);
  stride_ = (nf_ + 3) / 4 * 4;
  const LD kmob = 1.0L / (8.0L * LD(kPi) * LD(mu_));
  const Cheb7& ch = cheb7();
  class_tables_.assign(std::size_t(K) * K, ClassTable{});
  table_.clear();
  intervals_ = 0;
  table_error_ = 0.0;
  for (int p = 0; p < K; ++p)
    for (int q = 0; q < K; ++q) {
      // Row sphere of radius a_p, neighbour a_q: separated pairs lie in [a_p + a_q, cutoff_gap + a_p + a_q].
      const LD A = LD(classes_[p]) * LD(classes_[p]), B = LD(classes_[q]) * LD(classes_[q]);
      const double r_lo = classes_[p] + classes_[q], r_hi = cutoff_gap_ + r_lo;
      auto exact = [&](LD r, LD* v) {
        std::array<std::array<LD, 4>, 3> d;
        wave_derivatives(r, LD(xi_), d);
        LD w[12];
        for (int k = 0; k < 4; ++k)
          for (int j = 0; j < 3; ++j) w[3 * k + j] = kmob * d[j][k];
        if (m_ == Moments::F) scalars_from_w<Moments::F>(w, A, B, 1.0L / r, kmob, v);
        else if (m_ == Moments::FT) scalars_from_w<Moments::FT>(w, A, B, 1.0L / r, kmob, v);
        else scalars_from_w<Moments::FTS>(w, A, B, 1.0L / r, kmob, v);
      };
      for (int nint = 2;; nint *= 2) {
        const double h = (r_hi - r_lo) / nint;
        std::vector<double> tab(std::size_t(nint) * kCoef * stride_, 0.0);
        for (int i = 0; i < nint; ++i) {
          LD val[kCoef][14];
          for (int q = 0; q < kCoef; ++q) exact(LD(r_lo) + LD(h) * (i + 0.5L * (ch.node[q] + 1.0L)), val[q]);
          for (int f = 0; f < nf_; ++f)
            ch.fit([&](int q) { return val[q][f]; }, tab.data() + std::size_t(i) * kCoef * stride_ + f, stride_);
        }
        // Measured error on 9 points per interval (ends included), evaluated as the kernel does. As for
        // the general tables, each scalar is compared with the matching self mobility of a sphere of
        // radius rho = min(a_max, r/2): U <- F with 1 / (6 pi mu rho), the others with the smallest
        // one of the moments.
        double worst = 0.0;
        for (int i = 0; i < nint; ++i)
          for (int e = 0; e <= 8; ++e) {
            const double t = -1.0 + 0.25 * e, r = r_lo + h * (i + 0.5 * (t + 1.0));
            const double rho = std::min(amax, 0.5 * r);
            const double norm_f = 1.0 / (6.0 * kPi * mu_ * rho), norm_o = self_min(rho, mu_, m_);
            LD v[14];
            exact(LD(r), v);
            for (int f = 0; f < nf_; ++f) {
              const double got = estrin7(tab.data() + std::size_t(i) * kCoef * stride_ + f, stride_, t);
              worst = std::max(worst, std::abs(double(LD(got) - v[f])) / (f < 2 ? norm_f : norm_o));
            }
          }
        if (worst <= table_target_) {
          ClassTable& ct = class_tables_[std::size_t(p) * K + q];
          ct.r_lo = r_lo;
          ct.inv_h = 1.0 / h;
          ct.intervals = nint;
          ct.offset = table_.size();
          table_.insert(table_.end(), tab.begin(), tab.end());
          intervals_ = std::max(intervals_, nint);
          table_error_ = std::max(table_error_, worst);
          break;
        }
        if (nint >= (1 << 14))
          throw std::runtime_error("RealSpaceSum: real-space table error " + sci(worst) + " above the target " +
                                   sci(table_target_) + " with " + std::to_string(nint) + " intervals");
      }
    }
}

void RealSpaceSum::update_positions(const std::vector<Vec3>& x) {
  if (long(x.size()) != n_)
    throw std::invalid_argument("RealSpaceSum::update_positions: " + std::to_string(x.size()) + " positions for " +
                                std::to_string(n_) + " particles");
  set_positions(x);
}

void RealSpaceSum::update_positions(const std::vector<Vec3>& x, const Domain& domain) {
  if (!domain.periodic() || domain.box != domain_.box)
    throw std::invalid_argument("RealSpaceSum::update_positions: the box may change only by its strain");
  if (long(x.size()) != n_)
    throw std::invalid_argument("RealSpaceSum::update_positions: " + std::to_string(x.size()) + " positions for " +
                                std::to_string(n_) + " particles");
  domain_ = domain;
  set_positions(x);
}

void RealSpaceSum::set_positions(const std::vector<Vec3>& x) {
  const long N = n_;
  const double amax = *std::max_element(radius_.begin(), radius_.end());
  const double range = cutoff_gap_ + 2.0 * amax;
  // Cells over fractional coordinates, at least `range` wide between lattice planes
  // (trees/neighbor_list.hpp); at most about 8 per particle (the search visits runs of cells, so empty cells cost little).
  const Vec3& L = domain_.box;
  const double gamma = domain_.reduced_strain();
  const std::array<double, 3> width{L.x() / std::sqrt(1.0 + gamma * gamma), L.y(), L.z()};
  // Cells of width >= range / 2 with a 5-cell stencil per direction when there is room (about 40%
  // fewer candidates than width >= range and 3 cells), else width >= range.
  int sub = 2;
  for (int k = 0; k < 3; ++k)
    if (std::floor(2.0 * width[k] / range) < 5.0) sub = 1;
  std::array<int, 3> nc;
  for (int k = 0; k < 3; ++k) nc[k] = std::max(1, int(std::floor(sub * width[k] / range)));
  const double cap = std::max(27.0, 8.0 * double(N));
  while (double(nc[0]) * nc[1] * nc[2] > cap) {
    int k = 0;
    for (int q = 1; q < 3; ++q)
      if (nc[q] > nc[k]) k = q;
    nc[k] = std::max(1, nc[k] / 2);
  }
  const int ncell = nc[0] * nc[1] * nc[2];
  std::vector<int> cell(N);
  std::vector<long> start(ncell + 1, 0);
  std::vector<Vec3> fw(N);  // wrapped fractional coordinates
  for (long i = 0; i < N; ++i) {
    Vec3 f = domain_.fractional(x[i]);
    int c[3];
    for (int k = 0; k < 3; ++k) {
      f[k] -= std::floor(f[k]);
      c[k] = std::min(nc[k] - 1, std::max(0, int(f[k] * nc[k])));
    }
    fw[i] = f;
    cell[i] = (c[2] * nc[1] + c[1]) * nc[0] + c[0];
    ++start[cell[i] + 1];
  }
  for (int c = 0; c < ncell; ++c) start[c + 1] += start[c];
  order_.resize(N);
  {
    std::vector<long> fill(start.begin(), start.end() - 1);
    for (long i = 0; i < N; ++i) order_[fill[cell[i]]++] = int(i);
  }
  std::vector<Vec3> xs(N);
  std::vector<double> as(N);
  // Wrapped Cartesian positions A s (sorted): with 3 or more cells per direction the image of a
  // stencil cell is A (s + wrap), which gives a cheap pre-test before the exact minimum image.
  const Mat3 lat = domain_.lattice();
  std::vector<double> wx(N), wy(N), wz(N);
  for (long k = 0; k < N; ++k) {
    const Vec3 w = lat * fw[order_[k]];
    wx[k] = w.x();
    wy[k] = w.y();
    wz[k] = w.z();
  }
  const bool pretest = nc[0] > 2 * sub && nc[1] > 2 * sub && nc[2] > 2 * sub;
  const double slack = 1e-9 * (L.maxCoeff() + range);  // far above the rounding of A s
  a2s_.resize(N);
  cls_.resize(direct_ ? N : 0);
  self_f_.resize(N);
  self_t_.resize(N);
  self_s_.resize(N);
  for (long k = 0; k < N; ++k) {
    xs[k] = x[order_[k]];
    as[k] = radius_[order_[k]];
    a2s_[k] = as[k] * as[k];
    if (direct_)
      cls_[k] = std::uint8_t(std::lower_bound(classes_.begin(), classes_.end(), as[k]) - classes_.begin());
    self_f_[k] = self0_[3 * order_[k]];
    self_t_[k] = self0_[3 * order_[k] + 1];
    self_s_[k] = self0_[3 * order_[k] + 2];
  }
  // Stencil offsets per direction: -sub .. sub, or every cell once when there are fewer than 2 sub + 1.
  std::array<std::vector<int>, 3> offs;
  for (int k = 0; k < 3; ++k) {
    if (nc[k] > 2 * sub)
      for (int o = -sub; o <= sub; ++o) offs[k].push_back(o);
    else
      for (int o = 0; o < nc[k]; ++o) offs[k].push_back(o);
  }

  // Rows: each thread fills a contiguous block of rows; blocks are joined in row order, so the
  // pair data do not depend on the thread count.
  std::vector<Block>& blocks = blocks_;  // kept between updates (their capacity is reused)
#pragma omp parallel
  {
    const int nt = omp_get_num_threads(), tid = omp_get_thread_num();
#pragma omp single
    blocks.resize(nt);
    Block& b = blocks[tid];
    for (auto* v : {&b.ex, &b.ey, &b.ez, &b.dist, &b.odist}) v->clear();
    b.nbr.clear();
    b.onbr.clear();
    b.oe.clear();
    const long k0 = N * tid / nt, k1 = N * (tid + 1) / nt;
    if (!row_.empty()) {  // update: about as many entries as last time
      const std::size_t guess = std::size_t(1.1 * double(row_.back()) / nt) + 16;
      for (auto* v : {&b.ex, &b.ey, &b.ez, &b.dist}) v->reserve(guess);
      b.nbr.reserve(guess);
    }
    b.count.assign(k1 - k0, 0);
    b.ocount.assign(k1 - k0, 0);
    for (long k = k0; k < k1; ++k) {
      const int ck = cell[order_[k]];
      const int cx = ck % nc[0], cy = (ck / nc[0]) % nc[1], cz = ck / (nc[0] * nc[1]);
      const int ok = order_[k];
      // The stencil cells of one (dz, dy) row with consecutive indices and the same image shift
      // hold consecutive sorted particles: each such run is one range of l (visited in the same
      // order as cell by cell).
      for (int dz : offs[2])
        for (int dy : offs[1]) {
          const int py = cy + dy, pz = cz + dz;
          const int qy = (py + nc[1]) % nc[1], qz = (pz + nc[2]) % nc[2];
          const int row0 = (qz * nc[1] + qy) * nc[0];
          const int sy = (py > qy) - (py < qy), sz = (pz > qz) - (pz < qz);
          std::size_t t = 0;
          while (t < offs[0].size()) {
            const int px0 = cx + offs[0][t];
            const int qx0 = (px0 + nc[0]) % nc[0], sx = (px0 > qx0) - (px0 < qx0);
            int qx1 = qx0;
            for (++t; t < offs[0].size(); ++t) {
              const int px = cx + offs[0][t], qx = (px + nc[0]) % nc[0];
              if (qx != qx1 + 1 || (px > qx) - (px < qx) != sx) break;
              qx1 = qx;
            }
            const Vec3 shift = lat * Vec3(sx, sy, sz);
            const long l0 = start[row0 + qx0], l1 = start[row0 + qx1 + 1];
            // With the pre-test: a branch-free pass keeps, in order, the particles within the largest
            // possible range of k (cutoff_gap + a_k + a_max plus twice the slack, far above the
            // rounding of the differently ordered sum); the exact tests below run on those only
            // (random accept/reject branches cost more than the distances).
            long nc_l = l1 - l0;
            const int* cand = nullptr;
            if (pretest) {
              if (b.candidates.size() < std::size_t(nc_l)) b.candidates.resize(std::size_t(nc_l));
              int* buf = b.candidates.data();
              const double bound = cutoff_gap_ + as[k] + amax + 2.0 * slack, bound2 = bound * bound;
              const double px = wx[k] - shift.x(), py = wy[k] - shift.y(), pz = wz[k] - shift.z();
              long cnt = 0;
              for (long l = l0; l < l1; ++l) {
                const double dx = px - wx[l], dy = py - wy[l], dz = pz - wz[l];
                buf[cnt] = int(l);
                cnt += (dx * dx + dy * dy + dz * dz <= bound2);
              }
              nc_l = cnt;
              cand = buf;
            }
            for (long t = 0; t < nc_l; ++t) {
              const long l = cand ? cand[t] : l0 + t;
              if (l == k) continue;
              const int ol = order_[l];
              // Same expressions as trees::neighbor_pairs (pair (i, j) with i < j).
              const double lim = ok < ol ? cutoff_gap_ + as[k] + as[l] : cutoff_gap_ + as[l] + as[k];
              Vec3 r;
              double dist;
              if (pretest) {
                // r from the cell image; the exact minimum image of trees::neighbor_pairs only
                // near the cutoff, so the pair set is exactly that of neighbor_pairs (and the
                // geometry equal to it within rounding; r_lk = -r_kl exactly either way).
                r = Vec3(wx[k] - wx[l] - shift.x(), wy[k] - wy[l] - shift.y(), wz[k] - wz[l] - shift.z());
                const double r2 = r.squaredNorm(), hi = lim + slack, lo = lim - slack;
                if (r2 > hi * hi) continue;
                if (r2 >= lo * lo) {
                  r = domain_.minimum_image(xs[k] - xs[l]);
                  if (!(r.norm() < lim)) continue;
                }
                dist = r.norm();
              } else {
                r = domain_.minimum_image(xs[k] - xs[l]);
                dist = r.norm();
                if (!(dist < lim)) continue;
              }
              if (dist >= as[k] + as[l]) {
                ++b.count[k - k0];
                b.nbr.push_back(int(l));
                b.ex.push_back(r.x() / dist);
                b.ey.push_back(r.y() / dist);
                b.ez.push_back(r.z() / dist);
                b.dist.push_back(dist);
              } else {
                ++b.ocount[k - k0];
                b.onbr.push_back(int(l));
                b.oe.push_back(dist > 0.0 ? Vec3(r / dist) : Vec3::UnitZ());  // coincident: isotropic block
                b.odist.push_back(dist);
              }
            }
          }
        }
    }
  }
  row_.assign(N + 1, 0);
  orow_.assign(N + 1, 0);
  {
    long k = 0;
    for (const Block& b : blocks)
      for (std::size_t t = 0; t < b.count.size(); ++t, ++k) {
        row_[k + 1] = row_[k] + b.count[t];
        orow_[k + 1] = orow_[k] + b.ocount[t];
      }
  }
  const long ns = row_[N], no = orow_[N];
  nbr_.resize(ns);
  ex_.resize(ns);
  ey_.resize(ns);
  ez_.resize(ns);
  dist_.resize(ns);
  overlap_j_.resize(no);
  overlap_e_.resize(no);
  overlap_s_.resize(no);
  std::vector<double> odist(no);
  {
    long p = 0, po = 0;
    for (const Block& b : blocks) {
      std::copy(b.nbr.begin(), b.nbr.end(), nbr_.begin() + p);
      std::copy(b.ex.begin(), b.ex.end(), ex_.begin() + p);
      std::copy(b.ey.begin(), b.ey.end(), ey_.begin() + p);
      std::copy(b.ez.begin(), b.ez.end(), ez_.begin() + p);
      std::copy(b.dist.begin(), b.dist.end(), dist_.begin() + p);
      p += long(b.nbr.size());
      std::copy(b.onbr.begin(), b.onbr.end(), overlap_j_.begin() + po);
      std::copy(b.oe.begin(), b.oe.end(), overlap_e_.begin() + po);
      std::copy(b.odist.begin(), b.odist.end(), odist.begin() + po);
      po += long(b.onbr.size());
    }
  }
  // Exact scalars of the overlapping and nested pairs.
#pragma omp parallel for schedule(dynamic, 16)
  for (long k = 0; k < N; ++k)
    for (long t = orow_[k]; t < orow_[k + 1]; ++t)
      overlap_s_[t] = real_scalars(as[k], as[overlap_j_[t]], odist[t], xi_, mu_, m_);
  pairs_ = std::size_t(ns + no) / 2;
  // Scalars of the separated entries, kept when they fit in the budget (the storage is reused by
  // later updates).
  if (cache_bytes_for(double(ns), m_) > double(cache_bytes_)) {
    cache_.clear();
    cache_.shrink_to_fit();
  } else {
    if (m_ == Moments::F)
      fill_cache<Moments::F>();
    else if (m_ == Moments::FT)
      fill_cache<Moments::FT>();
    else
      fill_cache<Moments::FTS>();
  }
}

namespace {
template <Moments M>
STOKESIAN_RS_INLINE void store(const mobility::PairScalars& s, double* c, long stride) {
  c[0] = s.xa;
  c[stride] = s.ya;
  if constexpr (M != Moments::F) {
    c[2 * stride] = s.yb;
    c[3 * stride] = s.ybt;
    c[4 * stride] = s.xc;
    c[5 * stride] = s.yc;
  }
  if constexpr (M == Moments::FTS) {
    c[6 * stride] = s.xg;
    c[7 * stride] = s.yg;
    c[8 * stride] = s.xgt;
    c[9 * stride] = s.ygt;
    c[10 * stride] = s.yh;
    c[11 * stride] = s.xm;
    c[12 * stride] = s.ym;
    c[13 * stride] = s.zm;
  }
}
template <Moments M>
STOKESIAN_RS_INLINE mobility::PairScalars load(const double* c, long stride) {
  mobility::PairScalars s;
  s.xa = c[0];
  s.ya = c[stride];
  if constexpr (M != Moments::F) {
    s.yb = c[2 * stride];
    s.ybt = c[3 * stride];
    s.xc = c[4 * stride];
    s.yc = c[5 * stride];
  }
  if constexpr (M == Moments::FTS) {
    s.xg = c[6 * stride];
    s.yg = c[7 * stride];
    s.xgt = c[8 * stride];
    s.ygt = c[9 * stride];
    s.yh = s.yht = c[10 * stride];
    s.xm = c[11 * stride];
    s.ym = c[12 * stride];
    s.zm = c[13 * stride];
  }
  return s;
}
// The scalars of the four entries of a cache group (entry l's scalar q at c[4 q + l]).
template <Moments M>
STOKESIAN_RS_INLINE void load_group(const double* c, PairScalars4& s) {
  load4(c, &s.xa);
  load4(c + 4, &s.ya);
  if constexpr (M != Moments::F) {
    load4(c + 8, &s.yb);
    load4(c + 12, &s.ybt);
    load4(c + 16, &s.xc);
    load4(c + 20, &s.yc);
  }
  if constexpr (M == Moments::FTS) {
    load4(c + 24, &s.xg);
    load4(c + 28, &s.yg);
    load4(c + 32, &s.xgt);
    load4(c + 36, &s.ygt);
    load4(c + 40, &s.yh);
    s.yht = s.yh;
    load4(c + 44, &s.xm);
    load4(c + 48, &s.ym);
    load4(c + 52, &s.zm);
  }
}
}  // namespace

template <Moments M>
STOKESIAN_RS_INLINE mobility::PairScalars RealSpaceSum::table_scalars(double A, double B, double r) const {
  // 4-wide vectors over the functions (stride 8 for F, 12 otherwise).
  using v4 = v4u;
  constexpr int nv = M == Moments::F ? 2 : 3, nf = 4 * nv;
  const double km = 1.0 / (8.0 * kPi * mu_), u = 1.0 / r;
  const double sidx = (r - r_lo_) * inv_h_;
  const int idx = std::min(intervals_ - 1, std::max(0, int(sidx)));
  const double tt = 2.0 * (sidx - idx) - 1.0;
  const v4* c = reinterpret_cast<const v4*>(table_.data() + std::size_t(idx) * kCoef * nf);
  static_assert(kCoef == 8, "estrin7 is written for degree 7");
  v4 a0, a1, a2 = v4{};
  estrin7(c, nv, tt, &a0);
  estrin7(c + 1, nv, tt, &a1);
  if constexpr (nv > 2) estrin7(c + nv - 1, nv, tt, &a2);
  const double w[12] = {a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], a2[0], a2[1], a2[2], a2[3]};
  double v[14];
  scalars_from_w<M>(w, A, B, u, km, v);
  return load<M>(v, 1);
}

template <Moments M>
STOKESIAN_RS_INLINE mobility::PairScalars RealSpaceSum::direct_scalars(const ClassTable& ct, double r) const {
  using v4 = v4u;
  constexpr int nv = M == Moments::F ? 1 : (M == Moments::FT ? 2 : 4);  // stride_ / 4
  const double sidx = (r - ct.r_lo) * ct.inv_h;
  const int idx = std::min(ct.intervals - 1, std::max(0, int(sidx)));
  const double tt = 2.0 * (sidx - idx) - 1.0;
  const v4* c = reinterpret_cast<const v4*>(table_.data() + ct.offset + std::size_t(idx) * kCoef * (4 * nv));
  alignas(32) double v[4 * nv];
  for (int j = 0; j < nv; ++j) {
    v4 p;
    estrin7(c + j, nv, tt, &p);
    for (int q = 0; q < 4; ++q) v[4 * j + q] = p[q];
  }
  return load<M>(v, 1);
}

// The row kernels below are compiled twice, for the baseline x86-64 target and for AVX2 + FMA, and
// chosen once at run time (same choice for the cache fill and the product, so cached and uncached
// products give the same bits on a given machine).
namespace {
std::atomic<bool> g_force_baseline{false};
}

void RealSpaceSum::force_baseline_kernels(bool on) { g_force_baseline = on; }
void RealSpaceSum::force_general_tables(bool on) { g_force_general = on; }

static bool use_avx2() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return yes && !g_force_baseline;
#else
  return false;
#endif
}

template <Moments M>
STOKESIAN_RS_INLINE void RealSpaceSum::fill_row(long k) {
  constexpr int rec = cached_scalars(M);
  if (direct_) {
    const ClassTable* ct = class_tables_.data() + cls_[k] * classes_.size();
    for (long t = row_[k]; t < row_[k + 1]; ++t)
      store<M>(direct_scalars<M>(ct[cls_[nbr_[t]]], dist_[t]), cache_.data() + (t & ~3L) * rec + (t & 3), 4);
  } else {
    for (long t = row_[k]; t < row_[k + 1]; ++t)
      store<M>(table_scalars<M>(a2s_[k], a2s_[nbr_[t]], dist_[t]), cache_.data() + (t & ~3L) * rec + (t & 3), 4);
  }
}

template <Moments M>
STOKESIAN_RS_INLINE void RealSpaceSum::row(long k, const double* xs, double* ys) const {
  constexpr int d = dof_per_particle(M);
  double y[d];
  const double* xk = xs + k * d;
  for (int c = 0; c < 3; ++c) y[c] = self_f_[k] * xk[c];
  if constexpr (d > 3)
    for (int c = 3; c < 6; ++c) y[c] = self_t_[k] * xk[c];
  if constexpr (d > 6)
    for (int c = 6; c < 11; ++c) y[c] = self_s_[k] * xk[c];
  if (!cache_.empty()) {
    // Cache groups of four consecutive entries (fill_cache): the row's entries before its first
    // whole group and after its last one one at a time, the whole groups four at a time, their
    // lanes summed at the end of the row.
    constexpr int rec = cached_scalars(M);
    const long t1 = row_[k + 1];
    long t = row_[k];
    auto one = [&](long e) {
      apply_block<M>(load<M>(cache_.data() + (e & ~3L) * rec + (e & 3), 4), ex_[e], ey_[e], ez_[e],
                     xs + std::size_t(nbr_[e]) * d, y);
    };
    for (; t < t1 && (t & 3); ++t) one(t);
    if (t + 4 <= t1) {
      v4a acc[d];
      for (int c = 0; c < d; ++c) acc[c] = v4a{0.0, 0.0, 0.0, 0.0};
      for (; t + 4 <= t1; t += 4) {
        PairScalars4 s{};
        load_group<M>(cache_.data() + t * rec, s);
        v4a ex, ey, ez, xv[d];
        load4(ex_.data() + t, &ex);
        load4(ey_.data() + t, &ey);
        load4(ez_.data() + t, &ez);
        const double* x0 = xs + std::size_t(nbr_[t]) * d;
        const double* x1 = xs + std::size_t(nbr_[t + 1]) * d;
        const double* x2 = xs + std::size_t(nbr_[t + 2]) * d;
        const double* x3 = xs + std::size_t(nbr_[t + 3]) * d;
        alignas(32) double g[4 * d];  // the four sources' inputs, transposed
        for (int c = 0; c < d; ++c) {
          g[4 * c] = x0[c];
          g[4 * c + 1] = x1[c];
          g[4 * c + 2] = x2[c];
          g[4 * c + 3] = x3[c];
        }
        __builtin_memcpy(xv, g, sizeof(xv));
        apply_block_t<M, v4a>(s, ex, ey, ez, xv, acc);
      }
      for (int c = 0; c < d; ++c) y[c] += (acc[c][0] + acc[c][1]) + (acc[c][2] + acc[c][3]);
    }
    for (; t < t1; ++t) one(t);
  } else if (direct_ && classes_.size() == 1) {
    // One radius: no class lookup per entry (F 12.3 against 14.3-15.3 ns per pair with it).
    const ClassTable& ct = class_tables_[0];
    for (long t = row_[k]; t < row_[k + 1]; ++t)
      apply_block<M>(direct_scalars<M>(ct, dist_[t]), ex_[t], ey_[t], ez_[t], xs + std::size_t(nbr_[t]) * d, y);
  } else if (direct_) {
    const ClassTable* ct = class_tables_.data() + cls_[k] * classes_.size();
    for (long t = row_[k]; t < row_[k + 1]; ++t)
      apply_block<M>(direct_scalars<M>(ct[cls_[nbr_[t]]], dist_[t]), ex_[t], ey_[t], ez_[t],
                     xs + std::size_t(nbr_[t]) * d, y);
  } else {
    const double A = a2s_[k];
    for (long t = row_[k]; t < row_[k + 1]; ++t)
      apply_block<M>(table_scalars<M>(A, a2s_[nbr_[t]], dist_[t]), ex_[t], ey_[t], ez_[t],
                     xs + std::size_t(nbr_[t]) * d, y);
  }
  for (long t = orow_[k]; t < orow_[k + 1]; ++t) {
    const Vec3& e = overlap_e_[t];
    apply_block<M>(overlap_s_[t], e.x(), e.y(), e.z(), xs + std::size_t(overlap_j_[t]) * d, y);
  }
  for (int c = 0; c < d; ++c) ys[k * d + c] = y[c];
}

template <Moments M>
STOKESIAN_RS_AVX2 void RealSpaceSum::rows_avx2(long k0, long k1, const double* xs, double* ys) const {
  for (long k = k0; k < k1; ++k) row<M>(k, xs, ys);
}
template <Moments M>
void RealSpaceSum::rows_base(long k0, long k1, const double* xs, double* ys) const {
  for (long k = k0; k < k1; ++k) row<M>(k, xs, ys);
}
template <Moments M>
STOKESIAN_RS_AVX2 void RealSpaceSum::fill_avx2(long k0, long k1) {
  for (long k = k0; k < k1; ++k) fill_row<M>(k);
}
template <Moments M>
void RealSpaceSum::fill_base(long k0, long k1) {
  for (long k = k0; k < k1; ++k) fill_row<M>(k);
}

template <Moments M>
void RealSpaceSum::fill_cache() {
  // Groups of four consecutive entries t (not aligned to rows), each scalar four-wide: entry t's
  // scalar q at (t & ~3) rec + 4 q + (t & 3). Every entry is written below.
  cache_.resize(std::size_t((row_[n_] + 3) & ~3L) * cached_scalars(M));
  const bool avx = use_avx2();
  constexpr long chunk = 64;
#pragma omp parallel for schedule(dynamic, 1)
  for (long k0 = 0; k0 < n_; k0 += chunk) {
    if (avx)
      fill_avx2<M>(k0, std::min(n_, k0 + chunk));
    else
      fill_base<M>(k0, std::min(n_, k0 + chunk));
  }
}

template <Moments M>
void RealSpaceSum::apply_rows(const double* xs, double* ys) const {
  const bool avx = use_avx2();
  constexpr long chunk = 32;
#pragma omp parallel for schedule(dynamic, 1)
  for (long k0 = 0; k0 < n_; k0 += chunk) {
    if (avx)
      rows_avx2<M>(k0, std::min(n_, k0 + chunk), xs, ys);
    else
      rows_base<M>(k0, std::min(n_, k0 + chunk), xs, ys);
  }
}

void RealSpaceSum::apply(const VecX& in, VecX& out) const {
  if (in.size() != size())
    throw std::invalid_argument("RealSpaceSum::apply: input of size " + std::to_string(in.size()) + ", expected " +
                                std::to_string(size()));
  const int d = dof_per_particle(m_);
  out.resize(size());
  if (n_ == 0) return;  // default-constructed
  std::vector<double> xs(std::size_t(n_) * d), ys(std::size_t(n_) * d);
#pragma omp parallel for schedule(static)
  for (long k = 0; k < n_; ++k)
    for (int c = 0; c < d; ++c) xs[std::size_t(k) * d + c] = in[Eigen::Index(order_[k]) * d + c];
  if (m_ == Moments::F)
    apply_rows<Moments::F>(xs.data(), ys.data());
  else if (m_ == Moments::FT)
    apply_rows<Moments::FT>(xs.data(), ys.data());
  else
    apply_rows<Moments::FTS>(xs.data(), ys.data());
#pragma omp parallel for schedule(static)
  for (long k = 0; k < n_; ++k)
    for (int c = 0; c < d; ++c) out[Eigen::Index(order_[k]) * d + c] = ys[std::size_t(k) * d + c];
}

}  // namespace stokesian::ewald
