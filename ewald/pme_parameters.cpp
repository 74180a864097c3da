// Tolerance -> PME parameters; the error model is stated in pme_parameters.hpp.
#include "ewald/pme_parameters.hpp"

#include "ewald/ewald_split.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace stokesian::ewald {
namespace {
}

int fft_size(int n) {
  for (int m = std::max(2, n);; ++m) {
    if (m % 2) continue;
    int r = m;
    for (int p : {2, 3, 5})
      while (r % p == 0) r /= p;
    if (r == 1) return m;
  }
}

PmeParameters pme_parameters(double tol, const Lattice& lattice, int n, double a_min, double a_max, Moments m,
                             const PmeOptions& opt) {
  if (opt.neighbours <= 0.0) {
    // Automatic cost balance: P hardly depends on the cutoff, so one trial fixes it.
    PmeOptions trial = opt;
    trial.neighbours = 200.0;
    const int P = pme_parameters(tol, lattice, n, a_min, a_max, m, trial).support;
    trial.neighbours = std::clamp(P * P * P / 8.0, 50.0, 400.0);
    return pme_parameters(tol, lattice, n, a_min, a_max, m, trial);
  }
  if (!(tol >= 1e-14 && tol <= 0.1)) throw std::invalid_argument("pme_parameters: tolerance outside [1e-14, 0.1]");
  PmeParameters p;
  p.tolerance = tol;
  // Margins: the sums over particles and the k-factors of dipoles and Faxen terms multiply each
  // bound by O(10); measured in tests/test_ewald.cpp (tolerance sweep).
  const double L = std::log(1.0 / tol) + std::log(10.0);

  // 1. Real space.
  const double lmin = std::min(lattice.A.diagonal().minCoeff(), lattice.shortest_vector());  // as neighbor_pairs
  const double cap = 0.5 * lmin - 2.0 * a_max;
  if (!(cap > 0.0)) throw std::invalid_argument("pme_parameters: box smaller than four radii");
  const double density = std::max(n, 1) / lattice.volume;
  const double r_target = std::cbrt(3.0 * opt.neighbours / (4.0 * kPi * density));
  p.cutoff_gap = std::min(cap, std::max(r_target - 2.0 * a_max, 0.5 * a_max));
  p.cutoff_gap = std::min(p.cutoff_gap, cap);
  // xi: the smallest value for which every real-space scalar of a neglected pair, at the closest
  // distance cutoff_gap + a_i + a_j, is below exp(-L) times the smallest self mobility (radius
  // a_max). The blocks carry polynomials up to (xi a)^3 x^4 exp(-x^2) (x = xi r), so a closed
  // form in L alone is not enough for torques and stresslets; the scalars themselves are used.
  const double mu = 1.0;  // every term scales as 1/mu
  double scale = 1.0 / (6.0 * kPi * mu * a_max);
  if (m != Moments::F) scale = std::min(scale, 1.0 / (8.0 * kPi * mu * a_max * a_max * a_max));
  if (m == Moments::FTS) scale = std::min(scale, 3.0 / (20.0 * kPi * mu * a_max * a_max * a_max));
  auto real_error = [&](double xi) {
    double worst = 0.0;
    for (const auto& [ai, aj] : {std::pair{a_min, a_min}, std::pair{a_min, a_max}, std::pair{a_max, a_max}}) {
      const mobility::PairScalars s = real_scalars(ai, aj, p.cutoff_gap + ai + aj, xi, mu, m);
      for (double v : {s.xa, s.ya, s.yb, s.ybt, s.xc, s.yc, s.xg, s.yg, s.xgt, s.ygt, s.yh, s.yht, s.xm, s.ym, s.zm})
        worst = std::max(worst, std::abs(v));
    }
    return worst / scale;
  };
  p.xi = std::sqrt(L) / (p.cutoff_gap + 2.0 * a_min);
  while (real_error(p.xi) > std::exp(-L)) p.xi *= 1.01;

  // 2. Wave space: (1 + q) exp(-q) = tol / 10, by fixed point q = L + ln(1 + q).
  double q = L;
  for (int it = 0; it < 20; ++it) q = L + std::log(1.0 + q);
  p.k_max = 2.0 * p.xi * std::sqrt(q);
  for (int d = 0; d < 3; ++d) {
    const double nmax = p.k_max * lattice.A.col(d).norm() / (2.0 * kPi);
    p.grid[d] = fft_size(int(std::ceil(2.0 * opt.beta * nmax)) + 1);
  }

  // 3-4. Window. Aliasing errors of all grid modes add with random phases, so their bound is
  // raised by sqrt(M0 M1 M2); the Faxen factors (1 - a^2 k^2 / 6) amplify the modes near k_max.
  const double modes = double(p.grid[0]) * p.grid[1] * p.grid[2];
  const double amp = 1.0 + a_max * a_max * p.k_max * p.k_max / 6.0;
  // The wave part carries a fraction ~ 2 (xi a)^3 of the torque/stresslet self terms (less for F).
  const double xa = p.xi * a_max;
  const double share = std::max(1.0, 2.0 * xa * xa * xa);
  const double La = L + 0.5 * std::log(modes) + std::log(amp) + std::log(share) + std::log(10.0);
  const double b2 = opt.beta * opt.beta;
  const double t = b2 * La * (1.0 - std::sqrt(1.0 - 1.0 / b2));
  p.width = std::sqrt(t) / kPi;
  // Truncation at P points: one window per particle, so no sum over modes; the Faxen Laplacian
  // term of the window, c lap W ~ (a^2/6) Gt_dd (delta / s^2)^2 W, raises the edge value.
  const Mat3 metric = lattice.Ainv * lattice.Ainv.transpose();
  double g_max = 0.0;
  for (int d = 0; d < 3; ++d) g_max = std::max(g_max, metric(d, d) * p.grid[d] * p.grid[d]);
  const double Lt0 = L + std::log(share) + std::log(10.0);
  double Lt = Lt0;
  for (int it = 0; it < 3; ++it) {
    const double half = p.width * std::sqrt(2.0 * Lt);  // (P/2) for this Lt
    const double edge = 1.0 + a_max * a_max / 6.0 * g_max * half * half / std::pow(p.width, 4);
    Lt = Lt0 + std::log(edge);
  }
  p.support = std::max(3, int(std::ceil(2.0 * p.width * std::sqrt(2.0 * Lt))));
  return p;
}

}  // namespace stokesian::ewald
