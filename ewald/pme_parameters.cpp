// Tolerance -> PME parameters; the error and cost models are stated in pme_parameters.hpp.
#include "ewald/pme_parameters.hpp"

#include "engine/core/quadrature.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/real_space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <tuple>
#include <stdexcept>
#include <utility>
#include <vector>

namespace stokesian::ewald {
namespace {

// Achieved / modelled error: the model is an rms estimate; kSafety places the achieved error
// between tol / 10 and tol. Measured with 0.4 (bench/bench_pme.cpp, 138 rows, N = 10^3-10^6,
// phi 0.1 and 0.4, F and FTS, tol 1e-3-1e-6): achieved / requested 0.13-1.07, the top one F at
// N = 10^4, phi = 0.1, tol 1e-4; 0.34 scales that to about 0.11-0.91 (tests/test_ewald.cpp).
constexpr double kSafety = 0.34;
// Edge-jump error per unit jump (pme_edge_error), measured with probes of the aliasing error
// against the window shape at fixed grid (FT, N = 2000, phi = 0.4; docs/ewald.md s.5).
constexpr double kEdge = 0.065;

// Cost per unit of the model [s] on the reference machine (2-core AMD EPYC VM, one thread), measured
// 2026-11-24: real-space pairs by bench/bench_pme_real.cpp (with and without the per-entry scalar
// cache of real_space.hpp, RealSpaceSum::cache_bytes_for per ordered pair, within the budget);
// window points (spread + interpolate, per particle and P^3) and transforms by timing apply_wave
// at fixed parameters over grids 32^3-192^3 and P = 4-12 (N = 10^4, phi = 0.4).
// Uncached pairs read the pair scalars from tables per pair of radii when there are at most four
// distinct radii (real_space.hpp); equal spheres then take 0.65 / 0.59 / 0.77 of `pair` (F / FT /
// FTS, measured 2026-11-28), but the model keeps
// `pair` for them: pricing the faster pairs moved F, N = 10^6, phi 0.1, tol 1e-4 to a real space
// 1.5x longer (cutoff gap 6.4 -> 9.7 a, grid 250^3 -> 240^3), whose pair data doubled the peak
// memory (6.1 -> 13.2 GB) and tripled the set-up (10-12 -> 30-35 s) for no faster product
// (4.95-5.6 s either way, 2 threads): the model prices neither memory nor, at grids of 10^7 points,
// the memory-bound wave part (docs/benchmarks.md, "Why the PME exponent exceeds 1.1").
struct CostConstants {
  double pair_cached, pair, point;
};
CostConstants cost_constants(Moments m) {
  switch (m) {
    case Moments::F: return {4e-9, 18e-9, 2.5e-9};
    case Moments::FT: return {10e-9, 44e-9, 5.0e-9};
    default: return {32e-9, 75e-9, 5.5e-9};
  }
}
constexpr double kFft = 0.25e-9;  // per point and log2(points), one 3D field, forward or backward
constexpr double kGrid = 2e-9;    // per grid point: Fourier kernel, zeroing, ghost points
// Set-up of a new configuration (PmeFarField::update_positions), one thread, fitted 2026-11-26 to
// bench/bench_pme_setup.cpp (N = 500-10^4, phi 0.05-0.4, F/FT/FTS, 3-230 entries per particle;
// bench/plot_pme_setup.py prints the fit): per particle 0.55 us + 0.12 us per support point
// (windows, slab order, cell binning), per ordered real-space entry 22 / 40 / 48 ns for F / FT / FTS
// (cell search, pair data, scalar cache).
constexpr double kSetupParticle = 0.55e-6, kSetupWindow = 0.12e-6;
double setup_entry(Moments m) { return m == Moments::F ? 22e-9 : m == Moments::FT ? 40e-9 : 48e-9; }

// Gauss-Legendre rules of the model's integrals (engine/core/quadrature.hpp), made once.
using Quadrature = GaussLegendre;
const Quadrature& rule(int n) {
  static const Quadrature q16 = stokesian::gauss_legendre(16), q32 = stokesian::gauss_legendre(32);
  return n == 16 ? q16 : q32;
}
// int_lo^hi f by 32-point Gauss-Legendre on `panels` equal panels.
template <class F>
double integrate(F&& f, double lo, double hi, int panels) {
  const Quadrature& q = rule(32);
  const double h = (hi - lo) / panels;
  double sum = 0.0;
  for (int p = 0; p < panels; ++p) {
    const double c = lo + (p + 0.5) * h;
    for (std::size_t i = 0; i < q.x.size(); ++i) sum += q.w[i] * f(c + 0.5 * h * q.x[i]);
  }
  return 0.5 * h * sum;
}

// R(k)^+ R(k) = alpha I + beta k k^T (pme_parameters.hpp).
struct AlphaBeta {
  double alpha, beta;
};
AlphaBeta response(double k2, double a, Moments m) {
  const double pf = 1.0 - a * a * k2 / 6.0, pt = 1.0 - a * a * k2 / 10.0;
  switch (m) {
    case Moments::F: return {pf * pf, 0.0};
    case Moments::FT: return {pf * pf + 0.25 * k2 * pt * pt, -0.25 * pt * pt};
    default: return {pf * pf + 0.75 * k2 * pt * pt, -pt * pt / 12.0};
  }
}
double g_of(double k2, double xi) { return hasimoto(k2, xi) / k2; }  // mu = 1

}  // namespace

int fft_size(int n) {
  for (int m = std::max(2, n);; ++m) {
    if (m % 2) continue;
    int r = m;
    for (int p : {2, 3, 5})
      while (r % p == 0) r /= p;
    if (r == 1) return m;
  }
}

double pme_self_scale2(double a, Moments m) {
  const mobility::PairScalars s = mobility::self_scalars(a, 1.0);
  double s2 = 3.0 * s.xa * s.xa;
  if (m != Moments::F) s2 += 3.0 * s.xc * s.xc;
  if (m == Moments::FTS) s2 += 5.0 * s.xm * s.xm;
  return s2;
}

double pme_real_error2(double cutoff_gap, double xi, double ai, double aj, double rho, Moments m) {
  const int d = dof_per_particle(m);
  const double r0 = cutoff_gap + ai + aj;
  std::vector<double> B(std::size_t(d) * d);
  auto f = [&](double r) {
    const mobility::PairScalars s = real_scalars(ai, aj, r, xi, 1.0, m);
    mobility::fill_pair_block(s, Vec3::UnitZ(), m, B.data(), d);
    double n2 = 0.0;
    for (double v : B) n2 += v * v;
    return 4.0 * kPi * r * r * n2;
  };
  return rho * integrate(f, r0, r0 + 7.0 / xi, 4);
}

double pme_wave_error2(double k_in, double xi, double a, double rho, Moments m) {
  // Pairs: Parseval over random positions. Self: the truncated modes' own contribution, coherent
  // over k: the direction average of R G R^+ is diag(2/3 P_F^2 I3, 1/6 k^2 P_T^2 I3, 1/5 k^2 P_T^2 I5) g.
  double pair = 0.0, sF = 0.0, sT = 0.0, sS = 0.0;
  const Quadrature& q = rule(32);
  const double lo = k_in, hi = k_in + 14.0 * xi, h = (hi - lo) / 4.0;
  for (int p = 0; p < 4; ++p)
    for (std::size_t i = 0; i < q.x.size(); ++i) {
      const double k = lo + (p + 0.5) * h + 0.5 * h * q.x[i], wk = 0.5 * h * q.w[i];
      const double k2 = k * k, g = g_of(k2, xi), shell = 4.0 * kPi * k2 * wk;
      const AlphaBeta ab = response(k2, a, m);
      pair += shell * g * g * 2.0 * ab.alpha * ab.alpha;
      const double pf = 1.0 - a * a * k2 / 6.0, pt = 1.0 - a * a * k2 / 10.0;
      sF += shell * g * 2.0 / 3.0 * pf * pf;
      sT += shell * g * k2 * pt * pt / 6.0;
      sS += shell * g * k2 * pt * pt / 5.0;
    }
  const double c = 1.0 / std::pow(2.0 * kPi, 3);
  double self = 3.0 * sF * sF;
  if (m != Moments::F) self += 3.0 * sT * sT;
  if (m == Moments::FTS) self += 5.0 * sS * sS;
  return rho * c * pair + c * c * self;
}

double pme_alias_error2(const std::array<int, 3>& M, const Vec3& lengths, const Window1D& w, double xi, double a,
                        double rho, Moments m) {
  // Pairs: Parseval over random positions (header). Self: the alias of a particle on itself is
  // coherent over k, with a phase set by its sub-grid position; per alias (d, m) it is bounded by
  // the integral of ||R(k) G(k) R(k_m)^+||_F |phihat ratio|, and the aliases add in quadrature.
  const Quadrature& q = rule(16);
  double pair = 0.0, self = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double K = 2.0 * kPi * M[d] / lengths[d];
    double Kp = std::numeric_limits<double>::infinity();
    for (int e = 0; e < 3; ++e)
      if (e != d) Kp = std::min(Kp, 2.0 * kPi * M[e] / lengths[e]);
    double bound[2] = {0.0, 0.0};
    // k_d over [-K/2, K/2] (two panels), k_perp over [0, Kp/2] (two panels).
    for (int pd = 0; pd < 2; ++pd)
      for (std::size_t i = 0; i < q.x.size(); ++i) {
        const double kd = 0.25 * K * (q.x[i] + (pd == 0 ? -1.0 : 1.0)), wd = 0.25 * K * q.w[i];
        const double nu = kd / K, main = w.transform(nu);
        double ratio[2];
        for (int s = 0; s < 2; ++s) ratio[s] = std::abs(w.transform(nu + (s == 0 ? -1.0 : 1.0)) / main);
        for (int pp = 0; pp < 2; ++pp)
          for (std::size_t j = 0; j < q.x.size(); ++j) {
            const double kp = 0.125 * Kp * (q.x[j] + (pp == 0 ? 1.0 : 3.0)), wp = 0.125 * Kp * q.w[j];
            const double k2 = kd * kd + kp * kp;
            if (k2 <= 0.0) continue;
            const double g = g_of(k2, xi), vol = wd * wp * 2.0 * kPi * kp;
            const AlphaBeta ab = response(k2, a, m);
            for (int s = 0; s < 2; ++s) {
              const double km = kd + (s == 0 ? -K : K), km2 = km * km + kp * kp;
              const AlphaBeta abm = response(km2, a, m);
              const double perp2 = kp * kp * K * K / k2;  // |P_k k_m|^2
              const double t = std::max(0.0, ab.alpha * (2.0 * abm.alpha + abm.beta * perp2));
              pair += vol * g * g * t * ratio[s] * ratio[s];
              bound[s] += vol * g * std::sqrt(t) * ratio[s];
            }
          }
      }
    self += bound[0] * bound[0] + bound[1] * bound[1];
  }
  const double c = 1.0 / std::pow(2.0 * kPi, 3);
  return 2.0 * (rho * c * pair + c * c * self);
}

double pme_edge_error(const Window1D& w, double grid_density, double a, Moments m) {
  // The windows are truncated at |delta| = P/2, where phi and its derivatives are small but not
  // zero; the gradient and Faxen windows (spread.hpp) jump by the edge values of the first three
  // derivatives there. Those jumps spread broadband errors; measured, their effect on M x relative
  // to S is kEdge times the largest jump weighted as in the windows, c_j (M/L)^j |phi^(j)(P/2)|.
  double e[4];
  w.derivatives(0.5 * w.support() * (1.0 - 1e-12), e);
  const double g = grid_density;
  double worst = std::max(std::abs(e[0]), a * a / 6.0 * g * g * std::abs(e[2]));
  if (m != Moments::F)
    worst = std::max({worst, g * std::abs(e[1]), a * a / 10.0 * g * g * g * std::abs(e[3])});
  return kEdge * worst;
}

namespace {
PmeParameters search(double tol, const Lattice& lattice, int n, double a_min, double a_max, Moments m,
                     const PmeOptions& opt);
}

PmeParameters pme_parameters(double tol, const Lattice& lattice, int n, double a_min, double a_max, Moments m,
                             const PmeOptions& opt) {
  if (!(tol >= 1e-14 && tol <= 0.1)) throw std::invalid_argument("pme_parameters: tolerance outside [1e-14, 0.1]");
  if (opt.fixed) return *opt.fixed;
  // The search costs milliseconds; its inputs repeat for every operator of a run (the grid does not
  // depend on the strain), so results are kept.
  using Key =
      std::tuple<double, double, double, double, bool, int, double, double, int, double, double, int, double, double, double>;
  const Key key{tol,    lattice.A(0, 0), lattice.A(1, 1), lattice.A(2, 2), lattice.strain != 0.0,
                n,      a_min,           a_max,           int(m),          opt.neighbours,
                opt.sigma, int(opt.window), opt.self_scale2, opt.products_per_update, opt.cache_bytes};
  static std::mutex mutex;
  static std::map<Key, PmeParameters> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
  }
  const PmeParameters p = search(tol, lattice, n, a_min, a_max, m, opt);
  std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() > 256) cache.clear();
  cache.emplace(key, p);
  return p;
}

namespace {
PmeParameters search(double tol, const Lattice& lattice, int n, double a_min, double a_max, Moments m,
                     const PmeOptions& opt) {
  PmeParameters best;
  best.tolerance = tol;
  best.window = opt.window;
  best.sheared = lattice.strain != 0.0;
  const Vec3 box = lattice.A.diagonal();  // Lx, Ly, Lz
  // Lattice vector lengths; under shear the longest reduced a_2.
  Vec3 len(box.x(), box.y(), box.z());
  if (best.sheared) len.y() = std::sqrt(box.y() * box.y() + 0.25 * box.x() * box.x());
  const double lmin = box.minCoeff();  // shortest lattice vector for every reduced strain
  // Minimum-image contract of the real-space sum: cutoff_gap + 2 a_max <= L_min / 2, with a margin so
  // that adding 2 a_max back cannot round above L_min / 2.
  const double cap = 0.5 * lmin * (1.0 - 1e-12) - 2.0 * a_max;
  if (!(cap > 0.0)) throw std::invalid_argument("pme_parameters: box smaller than four radii");
  const double rho = std::max(n, 1) / lattice.volume;
  const double S2 = opt.self_scale2 > 0.0 ? opt.self_scale2 : pme_self_scale2(a_max, m);
  const double budget = std::pow(kSafety * tol, 2) * S2 / 3.0;  // per part, in e^2
  const CostConstants cc = cost_constants(m);
  // Set-up per product (0 when the caller prices the product alone).
  const double setup_share = opt.products_per_update > 0.0 ? 1.0 / opt.products_per_update : 0.0;
  if (opt.cache_bytes > 0.0) best.cache_bytes = opt.cache_bytes;
  // Real space: the closest neglected pairs are the smallest spheres (gap-based cutoff).
  auto real_error2 = [&](double gap, double xi) {
    double e = 0.0;
    for (const auto& [ai, aj] : {std::pair{a_min, a_min}, std::pair{a_min, a_max}, std::pair{a_max, a_max}})
      e = std::max(e, pme_real_error2(gap, xi, ai, aj, rho, m));
    return e;
  };

  std::vector<double> neighbours;
  if (opt.neighbours > 0.0) neighbours = {opt.neighbours};
  else
    for (double nb = 4.0; nb <= 600.0; nb *= 1.4) neighbours.push_back(nb);
  std::vector<double> sigmas;
  if (opt.sigma > 0.0) sigmas = {opt.sigma};
  else sigmas = {1.0, 1.1, 1.2, 1.35, 1.5, 1.75, 2.0};

  double best_cost = std::numeric_limits<double>::infinity();
  double last_gap = -1.0;
  for (double nb : neighbours) {
    const double r_target = std::cbrt(3.0 * nb / (4.0 * kPi * rho));
    const double gap = std::min(cap, std::max(r_target - 2.0 * a_max, 0.05 * a_max));
    if (gap == last_gap) continue;
    last_gap = gap;
    // xi: smallest with e_R^2 <= budget (e_R falls with xi); bisection in log xi.
    double lo = 0.05 / (gap + 2.0 * a_max), hi = 50.0 / (gap + 2.0 * a_max);
    if (real_error2(gap, hi) > budget) continue;
    for (int it = 0; it < 24; ++it) {
      const double mid = std::sqrt(lo * hi);
      (real_error2(gap, mid) > budget ? lo : hi) = mid;
    }
    const double xi = hi;
    // k_in: smallest with e_K^2 <= budget.
    double klo = 0.0, khi = 2.0 * xi;
    while (pme_wave_error2(khi, xi, a_max, rho, m) > budget) khi *= 1.5;
    for (int it = 0; it < 30; ++it) {
      const double mid = 0.5 * (klo + khi);
      (pme_wave_error2(mid, xi, a_max, rho, m) > budget ? klo : khi) = mid;
    }
    const double k_in = khi;
    const double pairs = 0.5 * n * std::min(double(n - 1), rho * 4.0 / 3.0 * kPi * std::pow(gap + 2.0 * a_max, 3));
    for (double sigma : sigmas) {
      std::array<int, 3> M;
      for (int d = 0; d < 3; ++d) M[d] = fft_size(int(std::ceil(sigma * k_in * len[d] / kPi)));
      const double G = double(M[0]) * M[1] * M[2];
      const bool cached = RealSpaceSum::cache_bytes_for(2.0 * pairs, m) <= best.cache_bytes;
      const double setup_pairs = (kSetupParticle * n + setup_entry(m) * 2.0 * pairs) * setup_share;
      const double fixed =
          (cached ? cc.pair_cached : cc.pair) * pairs + 6.0 * kFft * G * std::log2(G) + kGrid * G + setup_pairs;
      if (fixed >= best_cost) continue;
      double density_max = 0.0;  // grid points per unit length, largest direction
      for (int d = 0; d < 3; ++d) density_max = std::max(density_max, M[d] / len[d]);
      // Effective upsampling of the grid actually used (fft_size rounds up).
      double sig = std::numeric_limits<double>::infinity();
      for (int d = 0; d < 3; ++d) sig = std::min(sig, M[d] * kPi / (k_in * len[d]));
      for (int P = 3; P <= 32; ++P) {
        const double cost = fixed + 2.0 * cc.point * n * double(P) * P * P + kSetupWindow * n * P * setup_share;
        if (cost >= best_cost) break;
        double best_e = std::numeric_limits<double>::infinity(), best_shape = 0.0;
        if (opt.window == WindowKind::kaiser_bessel) {
          for (double kappa : {0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5}) {
            const double beta = kappa * kPi * P * (1.0 - 0.5 / std::max(sig, 1.0));
            const Window1D w(WindowKind::kaiser_bessel, P, beta);
            const double edge = pme_edge_error(w, density_max, a_max, m);
            const double e = pme_alias_error2(M, len, w, xi, a_max, rho, m) + edge * edge * S2;
            if (e < best_e) best_e = e, best_shape = beta;
          }
        } else {
          // The Gaussian's transform ignores its truncation: the edge value exp(-P^2 / (8 s^2)) is
          // held a decade below the tolerance, which fixes s.
          const double s = P / (2.0 * std::sqrt(2.0 * std::log(10.0 / (kSafety * tol))));
          const Window1D w(WindowKind::gaussian, P, s);
          const double edge = pme_edge_error(w, density_max, a_max, m);
          best_e = pme_alias_error2(M, len, w, xi, a_max, rho, m) + edge * edge * S2;
          best_shape = s;
        }
        if (best_e > budget) continue;
        best_cost = cost;
        best.xi = xi;
        best.cutoff_gap = gap;
        best.grid = M;
        best.support = P;
        best.shape = best_shape;
        best.k_max = k_in * sig;
        best.est_real = std::sqrt(real_error2(gap, xi) / S2);
        best.est_wave = std::sqrt(pme_wave_error2(k_in, xi, a_max, rho, m) / S2);
        best.est_alias = std::sqrt(best_e / S2);
        best.est_cost = cost;
        best.est_setup = kSetupParticle * n + kSetupWindow * n * P + setup_entry(m) * 2.0 * pairs;
        break;
      }
    }
  }
  if (!std::isfinite(best_cost))
    throw std::invalid_argument("pme_parameters: no PME parameters meet tolerance " + std::to_string(tol) +
                                " in this box (window support above 32 points)");
  return best;
}
}  // namespace

}  // namespace stokesian::ewald
