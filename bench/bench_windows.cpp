// Benchmark: which PME window? A 1D study of the Gaussian, the "exponential of semicircle" (ES)
// and the Kaiser-Bessel (KB) windows in the Ewald setting, charted by bench/plot_windows.py and
// discussed in docs/pme_windows.md.
//
// Setting (one lattice direction). Fractional coordinate s in [0, 1), grid of M points (spacing
// 1/M). A window phi(d), d in grid units, of support P points spreads a particle at s onto the P
// grid points g = g0 .. g0 + P - 1, g0 = ceil(M s - P / 2), so |g - M s| <= P / 2. With
// z = 2 d / P and shape parameter beta:
//   Gaussian  phi = exp(-beta z^2)                          (truncated at |z| = 1)
//   ES        phi = exp(beta (sqrt(1 - z^2) - 1))            (Barnett, Magland & af Klinteberg 2019)
//   KB        phi = I0(beta sqrt(1 - z^2)) / I0(beta)
// Deconvolution uses the continuous transform phihat(nu) = int phi(d) exp(-2 pi i nu d) dd:
//   Gaussian  sqrt(2 pi) w exp(-2 pi^2 w^2 nu^2), w^2 = P^2 / (8 beta) (the untruncated Gaussian,
//             as a Gaussian PME does; the truncation is part of the error measured);
//   KB        (P / 2) / I0(beta) * 2 sinh(r) / r, r = sqrt(beta^2 - w^2), w = pi nu P (2 sin(r) / r
//             with r = sqrt(w^2 - beta^2) when w > beta): the standard Kaiser-Bessel pair;
//   ES        no closed form: (P / 2) int_{-1}^{1} phi(z) cos(w z) dz by Gauss-Legendre in theta after
//             z = sin(theta), which removes the square root and makes the integrand smooth and
//             periodic; kQuadNodes nodes (convergence against 2 kQuadNodes is recorded, kind 5).
// Poisson summation gives S(n) = sum_g phi(g - M s) exp(-2 pi i n g / M)
//   = exp(-2 pi i n s) sum_k phihat(n / M + k) exp(-2 pi i k M s),
// so A(n) = conj(S(n)) / phihat(n / M) approximates E(n) = exp(2 pi i n s) up to aliasing (k != 0)
// and, for the Gaussian, truncation. The PME pair sum
//   approx(i, j) = sum_{|n| < M/2, |n| <= n_max} g(n) A_i(n) conj(A_j(n))
// stands for exact(i, j) = sum_{|n| <= n_max} g(n) exp(2 pi i n (s_i - s_j)), with the Ewald-like
// spectrum g(n) = exp(-ln(1/tol) (n / n_max)^2) (tol at n_max, zero beyond) and M = ceil(2 sigma
// n_max). Derivative windows: d/ds_i of A_i is DA_i(n) = -M conj(S'_i(n)) / phihat(n / M), S' the
// same sum with phi'(d); it stands for (2 pi i n) E_i(n). Measured errors (over all K^2 pairs of K
// random particles): |approx - exact| / sum_n |main term| with main term g(n) (value),
// (2 pi n) g(n) (derivative on one side), (2 pi n)^2 g(n) (both sides); max and rms.
//
// Search: for each window, sigma in {1, 1.1, 1.25, 1.5, 2}, tol in {1e-2 .. 1e-10} and P = 2, 3, ..
// the shape t = beta / P minimising the max value error (20 log-spaced t in [0.02, 8], then golden
// section in log t around the best), until the error is below tol / 30 or P = 32.
//
// Cost: 3D spreading + interpolation of 3 fields with a separable window (c_s per particle per
// P^3) and FFTW r2c + c2r of an M^3 grid per field (c_f per M^3 log2 M^3, 3 fields), timed here;
// window evaluation cost per point (exp, exp+sqrt, std::cyl_bessel_i).
//
// Rows (params; "kind" tells them apart):
//   kind 0  error curve: window (0 Gaussian, 1 ES, 2 KB), sigma, tol, P, t, beta, M, n_max,
//           err_max, err_rms, d1_max, d1_rms, d2_max, d2_rms (derivative errors at the value-optimal t)
//   kind 1  minimal support: window, sigma, tol, P (0: none up to 32), t, err_max, P_d1, P_d2
//           (smallest P whose derivative errors at the value-optimal t are <= tol; 0: none)
//   kind 2  spreading cost: P, N, grid, spread, gather (seconds), c_s (s per particle per P^3)
//   kind 3  FFT cost: M, r2c, c2r (seconds per field), c_f (s per M^3 log2 M^3, 3 fields)
//   kind 4  window evaluation: window, P, degree, ns_per_point (formula), poly_ns_per_point,
//           poly_max_dev (piecewise polynomial of that degree)
//   kind 5  checks: what (0 ES quadrature kQuadNodes vs 2 kQuadNodes, 1 KB closed form vs
//           quadrature, 2 FFT grid pipeline vs the direct pair formula), window, value (max rel. diff)
//   kind 6  cost model, per window its cheapest (sigma, P): deriv (0: P of the value window, 1: P
//           meeting tol with derivative windows on both sides too), rho = N / (2 n_max)^3 in {0.01, 0.1, 1, 10}, tol,
//           window, sigma, P, cost (s, 3D, n_max = 32: T = c_s(P) N P^3 + c_f M^3 log2 M^3), c_s, c_f
//   kind 7  edge test: window, sigma, tol, P (= P_d2), eps (distance of the first grid point inside
//           the support edge, grid units), err_max, d1_max, d2_max
//   kind 8  the shape rule t_rule = beta / P = 1.84 - 0.77 / sigma (Gaussian), 3.60 - 1.65 / sigma (ES,
//           KB) at the minimal P and P + 1: window, sigma, tol, P, t_rule, err_max, d2_max
//   bench_windows [--quick] [--out DIR]     (--quick: K = 48 particles, n_max = 16, fewer cases)
#include "bench/harness.hpp"
#include "engine/core/quadrature.hpp"

#include <fftw3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {

using cd = std::complex<double>;
using CMat = Eigen::Matrix<cd, Eigen::Dynamic, Eigen::Dynamic>;
constexpr double kPi = 3.14159265358979323846;
constexpr int kQuadNodes = 200;

enum Kind { kGauss = 0, kES = 1, kKB = 2 };
const char* kNames[] = {"Gaussian", "ES", "KB"};

struct Window {
  int kind;
  int P;
  double beta;
};

// Gauss-Legendre nodes and weights on [-1, 1] (engine/core/quadrature.hpp).
using Quad = stokesian::GaussLegendre;
using stokesian::gauss_legendre;

// Window value on z in [-1, 1] (shape only, no truncation logic).
double shape(const Window& w, double z) {
  const double s2 = 1 - z * z;
  switch (w.kind) {
    case kGauss: return std::exp(-w.beta * z * z);
    case kES: return s2 <= 0 ? 0.0 : std::exp(w.beta * (std::sqrt(s2) - 1));
    default: return s2 <= 0 ? 1 / std::cyl_bessel_i(0.0, w.beta)
                            : std::cyl_bessel_i(0.0, w.beta * std::sqrt(s2)) / std::cyl_bessel_i(0.0, w.beta);
  }
}

// phi(d) and phi'(d) (d in grid units), zero outside |d| <= P/2.
double phi(const Window& w, double d) {
  const double z = 2 * d / w.P;
  if (std::abs(z) > 1) return 0;
  return shape(w, z);
}
double dphi(const Window& w, double d) {
  const double z = 2 * d / w.P, dz = 2.0 / w.P;
  if (std::abs(z) > 1) return 0;
  const double s2 = 1 - z * z;
  switch (w.kind) {
    case kGauss: return -2 * w.beta * z * std::exp(-w.beta * z * z) * dz;
    case kES:
      // singular at |z| = 1 (z / sqrt(1 - z^2)); a point exactly on the edge gets 0
      if (s2 <= 0) return 0;
      return std::exp(w.beta * (std::sqrt(s2) - 1)) * w.beta * (-z / std::sqrt(s2)) * dz;
    default: {
      // d/dz I0(beta sqrt(1-z^2)) = -beta^2 z I1(x) / x, x = beta sqrt(1 - z^2); I1(x)/x -> 1/2
      const double x = w.beta * std::sqrt(std::max(s2, 0.0));
      const double i1x = x < 1e-8 ? 0.5 : std::cyl_bessel_i(1.0, x) / x;
      return -w.beta * w.beta * z * i1x / std::cyl_bessel_i(0.0, w.beta) * dz;
    }
  }
}

// (P/2) int_{-1}^{1} shape(z) cos(omega z) dz by Gauss-Legendre in theta, z = sin(theta).
double transform_quadrature(const Window& w, double nu, const Quad& q) {
  const double omega = kPi * nu * w.P;
  double s = 0;
  for (std::size_t k = 0; k < q.x.size(); ++k) {
    const double th = 0.5 * kPi * q.x[k], z = std::sin(th);
    s += q.w[k] * shape(w, z) * std::cos(omega * z) * std::cos(th);
  }
  return 0.5 * w.P * 0.5 * kPi * s;
}

double phihat(const Window& w, double nu, const Quad& q) {
  switch (w.kind) {
    case kGauss: {
      const double width2 = double(w.P) * w.P / (8 * w.beta);
      return std::sqrt(2 * kPi * width2) * std::exp(-2 * kPi * kPi * width2 * nu * nu);
    }
    case kES: return transform_quadrature(w, nu, q);
    default: {
      const double omega = kPi * nu * w.P, b2 = w.beta * w.beta, o2 = omega * omega;
      double f;
      if (std::abs(b2 - o2) < 1e-12 * b2) f = 2;
      else if (o2 < b2) {
        const double r = std::sqrt(b2 - o2);
        f = 2 * std::sinh(r) / r;
      } else {
        const double r = std::sqrt(o2 - b2);
        f = 2 * std::sin(r) / r;
      }
      return 0.5 * w.P * f / std::cyl_bessel_i(0.0, w.beta);
    }
  }
}

// Particles, modes, spectrum and exact pair sums for one (tol, n_max).
struct Problem {
  int n_max;
  double tol;
  std::vector<double> s;       // K particles
  std::vector<int> modes;      // -n_max .. n_max
  std::vector<double> g;       // spectrum per mode
  double norm0, norm1, norm2;  // sum |g|, sum |2 pi n g|, sum (2 pi n)^2 g
  CMat exact0, exact1, exact2;
};

Problem make_problem(int n_max, double tol, const std::vector<double>& s) {
  Problem pr;
  pr.n_max = n_max;
  pr.tol = tol;
  pr.s = s;
  const int K = int(s.size());
  for (int n = -n_max; n <= n_max; ++n) {
    pr.modes.push_back(n);
    const double x = double(n) / n_max;
    pr.g.push_back(std::exp(-std::log(1 / tol) * x * x));
  }
  const int nm = int(pr.modes.size());
  CMat E(K, nm), DE(K, nm), Eg(K, nm), DEg(K, nm);
  pr.norm0 = pr.norm1 = pr.norm2 = 0;
  for (int m = 0; m < nm; ++m) {
    const double k = 2 * kPi * pr.modes[m];
    pr.norm0 += pr.g[m];
    pr.norm1 += std::abs(k) * pr.g[m];
    pr.norm2 += k * k * pr.g[m];
    for (int i = 0; i < K; ++i) {
      E(i, m) = std::polar(1.0, k * s[i]);
      DE(i, m) = cd(0, k) * E(i, m);
      Eg(i, m) = E(i, m) * pr.g[m];
      DEg(i, m) = DE(i, m) * pr.g[m];
    }
  }
  pr.exact0 = Eg * E.adjoint();
  pr.exact1 = DEg * E.adjoint();
  pr.exact2 = DEg * DE.adjoint();
  return pr;
}

struct Errors {
  double max0, rms0, max1, rms1, max2, rms2;
};

double finite_or_inf(double x) { return std::isfinite(x) ? x : std::numeric_limits<double>::infinity(); }

// Errors of the PME pair sums for window w on grid M (derivatives only if `derivs`).
Errors measure(const Problem& pr, const Window& w, int M, const Quad& q, bool derivs) {
  const int K = int(pr.s.size());
  std::vector<int> use;  // modes with |n| < M/2
  for (std::size_t m = 0; m < pr.modes.size(); ++m)
    if (2 * std::abs(pr.modes[m]) < M) use.push_back(int(m));
  const int nu = int(use.size());
  std::vector<double> ph(nu);
  for (int u = 0; u < nu; ++u) ph[u] = phihat(w, double(pr.modes[use[u]]) / M, q);
  CMat A(K, nu), DA(K, nu), Ag(K, nu), DAg(K, nu);
  std::vector<double> val(w.P), der(w.P);
  std::vector<cd> twiddle(M);  // exp(2 pi i k / M)
  for (int k = 0; k < M; ++k) twiddle[k] = std::polar(1.0, 2 * kPi * k / M);
  for (int i = 0; i < K; ++i) {
    const double x = M * pr.s[i];
    const long g0 = long(std::ceil(x - 0.5 * w.P));
    for (int p = 0; p < w.P; ++p) {
      val[p] = phi(w, double(g0 + p) - x);
      if (derivs) der[p] = dphi(w, double(g0 + p) - x);
    }
    for (int u = 0; u < nu; ++u) {
      const int n = pr.modes[use[u]];
      cd sv = 0, sd = 0;
      for (int p = 0; p < w.P; ++p) {
        // conj of exp(-2 pi i n g / M), from the table at n g mod M
        const long k = ((long(n) * (g0 + p)) % M + M) % M;
        const cd e = twiddle[k];
        sv += val[p] * e;
        if (derivs) sd += der[p] * e;
      }
      A(i, u) = sv / ph[u];
      Ag(i, u) = A(i, u) * pr.g[use[u]];
      if (derivs) {
        DA(i, u) = -double(M) * sd / ph[u];
        DAg(i, u) = DA(i, u) * pr.g[use[u]];
      }
    }
  }
  auto stats = [&](const CMat& approx, const CMat& exact, double norm, double& mx, double& rms) {
    mx = 0;
    double s2 = 0;
    for (int j = 0; j < K; ++j)
      for (int i = 0; i < K; ++i) {
        const double e = finite_or_inf(std::abs(approx(i, j) - exact(i, j)) / norm);
        mx = std::max(mx, e);
        s2 += e * e;
      }
    rms = std::sqrt(s2 / (double(K) * K));
  };
  Errors er{};
  stats(Ag * A.adjoint(), pr.exact0, pr.norm0, er.max0, er.rms0);
  if (derivs) {
    stats(DAg * A.adjoint(), pr.exact1, pr.norm1, er.max1, er.rms1);
    stats(DAg * DA.adjoint(), pr.exact2, pr.norm2, er.max2, er.rms2);
  }
  return er;
}

// The shape t = beta / P minimising the max value error at (P, M).
double best_shape(const Problem& pr, int kind, int P, int M, const Quad& q, double& err) {
  auto f = [&](double logt) {
    const Window w{kind, P, std::exp(logt) * P};
    return measure(pr, w, M, q, false).max0;
  };
  const int n = 20;
  const double lo = std::log(0.02), hi = std::log(8.0), h = (hi - lo) / (n - 1);
  int best = 0;
  double fb = std::numeric_limits<double>::infinity();
  for (int k = 0; k < n; ++k) {
    const double v = f(lo + k * h);
    if (v < fb) fb = v, best = k;
  }
  double a = lo + std::max(best - 1, 0) * h, b = lo + std::min(best + 1, n - 1) * h;
  const double r = 0.5 * (std::sqrt(5.0) - 1);
  double c = b - r * (b - a), d = a + r * (b - a), fc = f(c), fd = f(d);
  for (int it = 0; it < 16; ++it) {
    if (fc < fd) b = d, d = c, fd = fc, c = b - r * (b - a), fc = f(c);
    else a = c, c = d, fc = fd, d = a + r * (b - a), fd = f(d);
  }
  double tbest = lo + best * h;
  if (fc < fb) fb = fc, tbest = c;
  if (fd < fb) fb = fd, tbest = d;
  err = fb;
  return std::exp(tbest);
}

// FFT pipeline on an actual grid (spread j, DFT, multiply by g / phihat^2, inverse DFT, interpolate
// at i) against the direct pair formula used by measure(): max relative difference over pairs.
double fft_pipeline_check(const Window& w, int n_max, int M, double tol, const Quad& q) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> s(6);
  for (double& x : s) x = u(rng);
  const Problem pr = make_problem(n_max, tol, s);
  // direct: the approx matrix via A
  std::vector<int> use;
  for (std::size_t m = 0; m < pr.modes.size(); ++m)
    if (2 * std::abs(pr.modes[m]) < M) use.push_back(int(m));
  fftw_complex* buf = fftw_alloc_complex(M);
  fftw_plan fwd = fftw_plan_dft_1d(M, buf, buf, FFTW_FORWARD, FFTW_ESTIMATE);
  fftw_plan bwd = fftw_plan_dft_1d(M, buf, buf, FFTW_BACKWARD, FFTW_ESTIMATE);
  // direct formula
  const int K = int(s.size()), nu = int(use.size());
  CMat A(K, nu), Ag(K, nu);
  for (int i = 0; i < K; ++i) {
    const double x = M * s[i];
    const long g0 = long(std::ceil(x - 0.5 * w.P));
    for (int uu = 0; uu < nu; ++uu) {
      const int n = pr.modes[use[uu]];
      cd sv = 0;
      for (int p = 0; p < w.P; ++p) sv += phi(w, double(g0 + p) - x) * std::polar(1.0, 2 * kPi * n * double(g0 + p) / M);
      A(i, uu) = sv / phihat(w, double(n) / M, q);
      Ag(i, uu) = A(i, uu) * pr.g[use[uu]];
    }
  }
  const CMat direct = Ag * A.adjoint();
  double worst = 0;
  for (int j = 0; j < K; ++j) {
    for (int k = 0; k < M; ++k) buf[k][0] = buf[k][1] = 0;
    const double xj = M * s[j];
    const long gj = long(std::ceil(xj - 0.5 * w.P));
    for (int p = 0; p < w.P; ++p) {
      const long gg = ((gj + p) % M + M) % M;
      buf[gg][0] += phi(w, double(gj + p) - xj);
    }
    fftw_execute(fwd);  // sum_g rho(g) exp(-2 pi i n g / M)
    for (int k = 0; k < M; ++k) {
      const int n = k <= M / 2 ? k : k - M;
      double factor = 0;
      if (2 * std::abs(n) < M && std::abs(n) <= n_max) {
        const double ph = phihat(w, double(n) / M, q);
        factor = pr.g[n + n_max] / (ph * ph);
      }
      buf[k][0] *= factor;
      buf[k][1] *= factor;
    }
    fftw_execute(bwd);  // sum_n u(n) exp(+2 pi i n g / M)
    for (int i = 0; i < K; ++i) {
      const double xi = M * s[i];
      const long gi = long(std::ceil(xi - 0.5 * w.P));
      cd v = 0;
      for (int p = 0; p < w.P; ++p) {
        const long gg = ((gi + p) % M + M) % M;
        v += phi(w, double(gi + p) - xi) * cd(buf[gg][0], buf[gg][1]);
      }
      // direct(i, j) = sum g A_i conj(A_j) with A = conj(S)/phihat: the grid gives
      // sum_n g/phihat^2 S_j(n) conj(S_i(n)) = direct(i, j)
      worst = std::max(worst, std::abs(v - direct(i, j)) / pr.norm0);
    }
  }
  fftw_destroy_plan(fwd);
  fftw_destroy_plan(bwd);
  fftw_free(buf);
  return worst;
}

// Piecewise polynomial form of a window: on each of the P unit intervals of the support a
// polynomial of degree D in t in [-1, 1], interpolating phi at D + 1 Chebyshev points (power
// coefficients from the small Vandermonde system). A particle whose first grid point is at
// d_0 = -P/2 + u (u in [0, 1)) gets its P weights phi(d_0 + j) from t = 2 u - 1 by P Horner
// sums of D + 1 terms, the same cost for every window.
struct PiecewisePoly {
  int P, D;
  std::vector<double> c;  // c[k * P + j]: coefficient of t^k on interval j
};
PiecewisePoly fit_poly(const Window& w, int D) {
  PiecewisePoly pp{w.P, D, std::vector<double>(std::size_t(w.P) * (D + 1))};
  std::vector<double> t(D + 1);
  Eigen::MatrixXd V(D + 1, D + 1);
  for (int r = 0; r <= D; ++r) {
    t[r] = std::cos(kPi * (r + 0.5) / (D + 1));
    for (int k = 0; k <= D; ++k) V(r, k) = std::pow(t[r], k);
  }
  const auto lu = V.partialPivLu();
  for (int j = 0; j < w.P; ++j) {
    Eigen::VectorXd f(D + 1);
    for (int r = 0; r <= D; ++r) f[r] = phi(w, -0.5 * w.P + j + 0.5 * (t[r] + 1));
    const Eigen::VectorXd cj = lu.solve(f);
    for (int k = 0; k <= D; ++k) pp.c[std::size_t(k) * w.P + j] = cj[k];
  }
  return pp;
}
void eval_poly(const PiecewisePoly& pp, double u, double* out) {
  const double t = 2 * u - 1;
  for (int j = 0; j < pp.P; ++j) out[j] = pp.c[std::size_t(pp.D) * pp.P + j];
  for (int k = pp.D - 1; k >= 0; --k)
    for (int j = 0; j < pp.P; ++j) out[j] = out[j] * t + pp.c[std::size_t(k) * pp.P + j];
}

}  // namespace

int main(int argc, char** argv) {
  using namespace stokesian;
  const bench::Options opt = bench::parse_options(argc, argv);
  const bool quick = opt.quick;
  bench::Results res(quick ? "windows_quick" : "windows");
  const Quad q = gauss_legendre(kQuadNodes), q2 = gauss_legendre(2 * kQuadNodes);

  // --- kind 5: checks ---------------------------------------------------------------------------
  {
    double es = 0, kb = 0;
    for (int P : {2, 6, 12, 24, 32})
      for (double t : {0.5, 1.5, 2.3, 3.0})
        for (double nu : {0.0, 0.1, 0.25, 0.4, 0.5}) {
          const Window e{kES, P, t * P}, k{kKB, P, t * P};
          const double a = transform_quadrature(e, nu, q), b = transform_quadrature(e, nu, q2);
          es = std::max(es, std::abs(a - b) / std::abs(transform_quadrature(e, 0, q2)));
          const double c = phihat(k, nu, q), d = transform_quadrature(k, nu, q2);
          kb = std::max(kb, std::abs(c - d) / std::abs(transform_quadrature(k, 0, q2)));
        }
    std::printf("check: ES transform, %d vs %d Gauss-Legendre nodes: max diff / phihat(0) = %.2e\n", kQuadNodes,
                2 * kQuadNodes, es);
    std::printf("check: KB closed-form transform vs quadrature: max diff / phihat(0) = %.2e\n", kb);
    res.add({{"kind", 5}, {"what", 0}, {"window", kES}, {"value", es}}, {});
    res.add({{"kind", 5}, {"what", 1}, {"window", kKB}, {"value", kb}}, {});
    for (int kind : {kGauss, kES, kKB}) {
      const Window w{kind, 8, (kind == kGauss ? 0.7 : 2.0) * 8};
      const double d = fft_pipeline_check(w, 16, 40, 1e-6, q);
      std::printf("check: %s FFT grid pipeline vs direct pair formula: max diff / sum g = %.2e\n", kNames[kind], d);
      res.add({{"kind", 5}, {"what", 2}, {"window", kind}, {"value", d}}, {});
    }
  }

  // --- kinds 0, 1: error curves and minimal supports --------------------------------------------
  const int K = quick ? 48 : 128;
  const int n_max = quick ? 16 : 40;
  const std::vector<double> sigmas = quick ? std::vector<double>{1.25, 2.0} : std::vector<double>{1.0, 1.1, 1.25, 1.5, 2.0};
  const std::vector<double> tols =
      quick ? std::vector<double>{1e-2, 1e-4} : std::vector<double>{1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> uni(0, 1);
  std::vector<double> s(K);
  for (double& x : s) x = uni(rng);
  // minimal P per (window, sigma, tol) for the cost model
  struct Choice {
    int kind;
    double sigma, tol;
    int P, P_d2;
    double t, t_d2;  // value-optimal shape at P and at max(P, P_d2)
  };
  std::vector<Choice> choices;
  for (double tol : tols) {
    const Problem pr = make_problem(n_max, tol, s);
    for (double sigma : sigmas) {
      const int M = int(std::ceil(2 * sigma * n_max - 1e-9));
      for (int kind : {kGauss, kES, kKB}) {
        int pmin = 0, pd1 = 0, pd2 = 0;
        double tmin = 0, emin = 0;
        std::vector<double> t_at(33, 0.0);
        for (int P = 2; P <= 32; ++P) {
          double err = 0;
          const auto a = std::chrono::steady_clock::now();
          const double t = best_shape(pr, kind, P, M, q, err);
          const Window w{kind, P, t * P};
          const Errors e = measure(pr, w, M, q, true);
          t_at[P] = t;
          const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
          res.add({{"kind", 0}, {"window", kind}, {"sigma", sigma}, {"tol", tol}, {"P", P}, {"t", t},
                   {"beta", t * P}, {"M", M}, {"n_max", n_max}, {"err_max", e.max0}, {"err_rms", e.rms0},
                   {"d1_max", e.max1}, {"d1_rms", e.rms1}, {"d2_max", e.max2}, {"d2_rms", e.rms2}},
                  {{"search", secs}});
          if (!pmin && e.max0 <= tol) pmin = P, tmin = t, emin = e.max0;
          if (!pd1 && e.max1 <= tol) pd1 = P;
          if (!pd2 && e.max2 <= tol) pd2 = P;
          if (e.max0 < tol / 30 && pd1 && pd2) break;
        }
        std::printf("%-8s sigma %.2f tol %.0e: P %2d (beta/P %.3f, err %.2e); derivative windows: P %2d (one side), %2d (both)\n",
                    kNames[kind], sigma, tol, pmin, tmin, emin, pd1, pd2);
        std::fflush(stdout);
        res.add({{"kind", 1}, {"window", kind}, {"sigma", sigma}, {"tol", tol}, {"P", pmin}, {"t", tmin},
                 {"err_max", emin}, {"P_d1", pd1}, {"P_d2", pd2}},
                {});
        const int pall = pd2 ? std::max(pmin, pd2) : 0;
        choices.push_back({kind, sigma, tol, pmin, pall, tmin, pall ? t_at[pall] : 0.0});
      }
    }
  }

  // --- kind 8: the fitted shape rule beta / P = a + b / sigma (docs/pme_windows.md) at the minimal P
  for (double tol : tols) {
    const Problem pr = make_problem(n_max, tol, s);
    for (const Choice& ch : choices) {
      if (ch.tol != tol || ch.P == 0) continue;
      const double t_rule = ch.kind == kGauss ? 1.84 - 0.77 / ch.sigma : 3.60 - 1.65 / ch.sigma;
      const int M = int(std::ceil(2 * ch.sigma * n_max - 1e-9));
      for (int dP : {0, 1}) {
        const Errors e = measure(pr, Window{ch.kind, ch.P + dP, t_rule * (ch.P + dP)}, M, q, true);
        res.add({{"kind", 8}, {"window", ch.kind}, {"sigma", ch.sigma}, {"tol", tol}, {"P", ch.P + dP},
                 {"t_rule", t_rule}, {"err_max", e.max0}, {"d2_max", e.max2}},
                {});
      }
    }
  }

  // --- kind 7: a grid point close to the support edge (ES: phi' ~ 1 / sqrt(distance)) -----------
  // Particle 0 sits so that its first grid point is at distance eps (grid units) inside the edge
  // of the support; derivative errors over its pairs with the K random particles, at the support
  // that meets tol with derivative windows on both sides (P_d2) and its value-optimal shape.
  for (const Choice& ch : choices) {
    if (ch.P_d2 == 0 || (ch.sigma != 2.0 && ch.sigma != 1.25) || (ch.tol != 1e-4 && ch.tol != 1e-8 && !quick)) continue;
    const int M = int(std::ceil(2 * ch.sigma * n_max - 1e-9));
    for (double eps : {1e-1, 1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
      std::vector<double> se = s;
      // first grid point g0 = 3 (after ceil), at distance P/2 - eps from the particle
      se[0] = (3.0 + 0.5 * ch.P_d2 - eps) / M;
      const Problem pe = make_problem(n_max, ch.tol, se);
      const Errors e = measure(pe, Window{ch.kind, ch.P_d2, ch.t_d2 * ch.P_d2}, M, q, true);
      res.add({{"kind", 7}, {"window", ch.kind}, {"sigma", ch.sigma}, {"tol", ch.tol}, {"P", ch.P_d2}, {"eps", eps},
               {"d1_max", e.max1}, {"d2_max", e.max2}, {"err_max", e.max0}},
              {});
      if (eps == 1e-1 || eps == 1e-12)
        std::printf("edge: %-8s sigma %.2f tol %.0e P %2d, grid point %.0e inside the edge: value %.2e, d1 %.2e, d2 %.2e\n",
                    kNames[ch.kind], ch.sigma, ch.tol, ch.P_d2, eps, e.max0, e.max1, e.max2);
    }
  }

  // --- kind 4: window evaluation cost (P = 8, beta = 2.3 P; a Gaussian exp(-beta z^2) for timing) --
  // direct formulas (std::exp, std::sqrt, std::cyl_bessel_i) and the piecewise polynomial of
  // degree D = P + 4 (its max deviation from the formula is recorded).
  {
    const int n = quick ? 200000 : 2000000, P = 8, D = P + 4;
    std::vector<double> z(n), u(n / P);
    for (double& x : z) x = 2 * uni(rng) - 1;
    for (double& x : u) x = uni(rng);
    for (int kind : {kGauss, kES, kKB}) {
      const Window w{kind, P, 2.3 * P};
      volatile double sink = 0;
      const double t = bench::median_time([&] {
        double acc = 0;
        for (int i = 0; i < n; ++i) acc += shape(w, z[i]);
        sink = acc;
      }, 3);
      const PiecewisePoly pp = fit_poly(w, D);
      double out[64];
      const double tp = bench::median_time([&] {
        double acc = 0;
        for (double x : u) {
          eval_poly(pp, x, out);
          for (int j = 0; j < P; ++j) acc += out[j];
        }
        sink = acc;
      }, 3);
      (void)sink;
      double dev = 0;
      for (int i = 0; i < 20000; ++i) {
        const double x = uni(rng);
        eval_poly(pp, x, out);
        for (int j = 0; j < P; ++j) dev = std::max(dev, std::abs(out[j] - phi(w, -0.5 * P + j + x)));
      }
      const double np = double(u.size()) * P;
      std::printf("window evaluation %-8s: %.1f ns per point (formula), %.2f ns (piecewise degree %d, max dev %.1e)\n",
                  kNames[kind], 1e9 * t / n, 1e9 * tp / np, D, dev);
      res.add({{"kind", 4}, {"window", kind}, {"P", P}, {"degree", D}, {"ns_per_point", 1e9 * t / n},
               {"poly_ns_per_point", 1e9 * tp / np}, {"poly_max_dev", dev}},
              {{"time", t}, {"poly_time", tp}});
    }
  }

  // --- kind 2: 3D spread + gather of 3 fields, separable window ---------------------------------
  std::vector<std::pair<int, double>> cs_values;  // (P, c_s)
  {
    const int G = 64;
    const long N = quick ? 4000 : 20000;
    std::vector<double> grid(3L * G * G * G, 0.0);
    std::vector<Eigen::Vector3d> x(N), f(N), out(N);
    for (long i = 0; i < N; ++i) {
      x[i] = Eigen::Vector3d(uni(rng), uni(rng), uni(rng)) * G;
      f[i] = Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
    }
    for (int P : quick ? std::vector<int>{4, 8} : std::vector<int>{3, 4, 6, 8, 12, 16}) {
      const Window w{kES, P, 2.3 * P};
      std::vector<double> wx(3 * P);
      std::vector<int> ix(3 * P);
      auto weights = [&](const Eigen::Vector3d& p) {
        for (int a = 0; a < 3; ++a) {
          const long g0 = long(std::ceil(p[a] - 0.5 * P));
          for (int k = 0; k < P; ++k) {
            wx[a * P + k] = phi(w, double(g0 + k) - p[a]);
            ix[a * P + k] = int(((g0 + k) % G + G) % G);
          }
        }
      };
      const double t_spread = bench::median_time([&] {
        for (long i = 0; i < N; ++i) {
          weights(x[i]);
          for (int a = 0; a < P; ++a)
            for (int b = 0; b < P; ++b) {
              const double wab = wx[a] * wx[P + b];
              const long row = (long(ix[a]) * G + ix[P + b]) * G;
              for (int c = 0; c < P; ++c) {
                const double wt = wab * wx[2 * P + c];
                double* cell = &grid[3 * (row + ix[2 * P + c])];
                cell[0] += wt * f[i][0];
                cell[1] += wt * f[i][1];
                cell[2] += wt * f[i][2];
              }
            }
        }
      }, quick ? 1 : 3);
      const double t_gather = bench::median_time([&] {
        for (long i = 0; i < N; ++i) {
          weights(x[i]);
          double s0 = 0, s1 = 0, s2 = 0;
          for (int a = 0; a < P; ++a)
            for (int b = 0; b < P; ++b) {
              const double wab = wx[a] * wx[P + b];
              const long row = (long(ix[a]) * G + ix[P + b]) * G;
              for (int c = 0; c < P; ++c) {
                const double wt = wab * wx[2 * P + c];
                const double* cell = &grid[3 * (row + ix[2 * P + c])];
                s0 += wt * cell[0];
                s1 += wt * cell[1];
                s2 += wt * cell[2];
              }
            }
          out[i] = Eigen::Vector3d(s0, s1, s2);
        }
      }, quick ? 1 : 3);
      const double cs = (t_spread + t_gather) / (double(N) * P * P * P);
      cs_values.emplace_back(P, cs);
      std::printf("spread+gather 3 fields, P %2d, N %ld on %d^3: %.3f + %.3f s, c_s = %.2f ns per particle per P^3\n",
                  P, N, G, t_spread, t_gather, 1e9 * cs);
      res.add({{"kind", 2}, {"P", P}, {"N", double(N)}, {"grid", G}, {"c_s", cs}},
              {{"spread", t_spread}, {"gather", t_gather}});
    }
  }
  // --- kind 3: FFTW r2c + c2r per field -------------------------------------------------------------
  std::vector<double> cf_values;
  for (int M : quick ? std::vector<int>{64} : std::vector<int>{64, 96, 128}) {
    const long n = long(M) * M * M, nc = long(M) * M * (M / 2 + 1);
    double* r = fftw_alloc_real(n);
    fftw_complex* c = fftw_alloc_complex(nc);
    const unsigned flags = quick ? FFTW_ESTIMATE : FFTW_MEASURE;
    fftw_plan fw = fftw_plan_dft_r2c_3d(M, M, M, r, c, flags);
    fftw_plan bw = fftw_plan_dft_c2r_3d(M, M, M, c, r, flags);
    for (long i = 0; i < n; ++i) r[i] = uni(rng);
    const double t_r2c = bench::median_time([&] { fftw_execute(fw); }, quick ? 2 : 5);
    const double t_c2r = bench::median_time([&] { fftw_execute(bw); }, quick ? 2 : 5);
    const double cf = 3 * (t_r2c + t_c2r) / (double(n) * std::log2(double(n)));
    cf_values.push_back(cf);
    std::printf("FFTW %d^3: r2c %.4f s, c2r %.4f s; c_f = %.3f ns per M^3 log2 M^3 (3 fields, both ways)\n", M,
                t_r2c, t_c2r, 1e9 * cf);
    res.add({{"kind", 3}, {"M", M}, {"c_f", cf}}, {{"r2c", t_r2c}, {"c2r", t_c2r}});
    fftw_destroy_plan(fw);
    fftw_destroy_plan(bw);
    fftw_free(r);
    fftw_free(c);
  }

  // --- kind 6: cheapest (window, sigma, P) per tol and particle density ------------------------------
  {
    // c_s at the nearest measured P (it falls with P: per-particle overhead and the 3 P window
    // evaluations are spread over P^3 grid points); c_f the median over the measured grids
    auto cs_at = [&](int P) {
      auto best = cs_values.front();
      for (const auto& v : cs_values)
        if (std::abs(v.first - P) < std::abs(best.first - P)) best = v;
      return best.second;
    };
    std::sort(cf_values.begin(), cf_values.end());
    const double cf = cf_values[cf_values.size() / 2];
    for (const auto& [P, c] : cs_values)
      std::printf("cost model: P %2d: c_s = %.2f ns, c_f = %.3f ns, c_s / c_f = %.2f\n", P, 1e9 * c, 1e9 * cf, c / cf);
    const int nm3 = 32;  // n_max of the 3D model
    // per window the cheapest (sigma, P) (kind 6 rows, one per window); ES and KB often tie
    for (int deriv : {0, 1})
      for (double rho : {0.01, 0.1, 1.0, 10.0}) {
        const double N = rho * std::pow(2.0 * nm3, 3);
        for (double tol : tols)
          for (int kind : {kGauss, kES, kKB}) {
            const Choice* best = nullptr;
            double bc = std::numeric_limits<double>::infinity();
            for (const Choice& ch : choices) {
              const int P = deriv ? ch.P_d2 : ch.P;
              if (ch.kind != kind || ch.tol != tol || P == 0) continue;
              const double M = std::ceil(2 * ch.sigma * nm3 - 1e-9), M3 = M * M * M;
              const double cost = cs_at(P) * N * std::pow(P, 3) + cf * M3 * std::log2(M3);
              if (cost < bc) bc = cost, best = &ch;
            }
            if (!best) continue;
            const int P = deriv ? best->P_d2 : best->P;
            std::printf("%s rho %5.1f tol %.0e: %-8s cheapest at sigma %.2f P %2d, %.4f s\n",
                        deriv ? "value+derivative" : "value", rho, tol, kNames[kind], best->sigma, P, bc);
            res.add({{"kind", 6}, {"deriv", deriv}, {"rho", rho}, {"tol", tol}, {"window", kind},
                     {"sigma", best->sigma}, {"P", P}, {"cost", bc}, {"c_s", cs_at(P)}, {"c_f", cf}},
                    {});
          }
      }
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
