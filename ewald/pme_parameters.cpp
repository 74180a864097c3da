// Tolerance -> PME parameters; the error and cost models are stated in pme_parameters.hpp.
#include "ewald/pme_parameters.hpp"

#include "engine/core/quadrature.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/real_space.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <map>
#include <mutex>
#include <tuple>
#include <stdexcept>
#include <utility>
#include <vector>

namespace stokesian::ewald {
namespace {

// Achieved / modelled error: kSafety places the achieved error between tol / 10 and tol. With 0.7
// (2026-11-29): 0.40-0.51 tol at N = 10^4 (bench_pme_parts), 0.44-0.85 tol for 5-60 monodisperse
// spheres, 0.08-0.31 polydisperse and 0.005-0.21 polydisperse sheared (tests/test_ewald.cpp,
// "requested tolerance met"; the model takes the worse radius for each part).
constexpr double kSafety = 0.7;

// Cost per unit of the model [s] on the reference machine (2-core AMD EPYC VM, one thread), measured
// 2026-11-24: real-space pairs by bench/bench_pme_real.cpp (with and without the per-entry scalar
// cache of real_space.hpp, RealSpaceSum::cache_bytes_for per ordered pair, within the budget; the
// cached pairs re-measured 2026-11-29 with the four-wide groups: 2.6-3.4 / 7.5-8.6 / 18-24 ns for
// F / FT / FTS at N = 10648, phi 0.1 and 0.4, tol 1e-4 and 1e-6);
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
    case Moments::F: return {3e-9, 18e-9, 2.5e-9};
    case Moments::FT: return {8e-9, 44e-9, 5.0e-9};
    default: return {20e-9, 75e-9, 5.5e-9};
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

double pme_pair_scale2(const Vec3& box, double a, double rho, Moments m) {
  // (rho / V) sum_{k != 0} 2 alpha(k)^2 / k^4 with the full Faxen functions, j0(ka) (force kind) and
  // 3 j1(ka) / (ka) (torque kind), in place of their truncations: the lattice sum for |k| < k_c, the
  // continuum rho / (2 pi)^3 int 4 pi k^2 (...) dk beyond, k_c = 6 times the smallest reciprocal
  // spacing (at most 13 modes per axis; the sphere lies inside that block of modes).
  auto f = [&](double k2) {
    const double k = std::sqrt(k2), x = k * a;
    const double gf = x < 1e-4 ? 1.0 - x * x / 6.0 : std::sin(x) / x;
    const double gt = x < 1e-3 ? 1.0 - x * x / 10.0 : 3.0 * (std::sin(x) - x * std::cos(x)) / (x * x * x);
    double alpha = gf * gf;
    if (m == Moments::FT) alpha += 0.25 * k2 * gt * gt;
    if (m == Moments::FTS) alpha += 0.75 * k2 * gt * gt;
    return 2.0 * alpha * alpha / (k2 * k2);
  };
  const double V = box.x() * box.y() * box.z();
  const Vec3 dk(2.0 * kPi / box.x(), 2.0 * kPi / box.y(), 2.0 * kPi / box.z());
  const double kc = 6.0 * dk.minCoeff();
  const int n0 = int(kc / dk.x()), n1 = int(kc / dk.y()), n2 = int(kc / dk.z());
  double lattice = 0.0;
  for (int i = -n0; i <= n0; ++i)
    for (int j = -n1; j <= n1; ++j)
      for (int l = -n2; l <= n2; ++l) {
        const double k2 = std::pow(i * dk.x(), 2) + std::pow(j * dk.y(), 2) + std::pow(l * dk.z(), 2);
        if (k2 > 0.0 && k2 < kc * kc) lattice += f(k2);
      }
  const double tail = integrate([&](double k) { return 4.0 * kPi * k * k * f(k * k); }, kc, kc + 40.0 / a, 16);
  return rho / V * lattice + rho / std::pow(2.0 * kPi, 3) * tail;
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

namespace {

// Per-axis deviation of the sampled window from the ideal one (pme_parameters.hpp, "aliasing and
// edges"): for nu in cycles per grid spacing, D_q(nu, tau) = A_q(nu, tau) - I_q(nu) with
//   A_q = sum_p phi^(q)(delta_p) e^{-2 pi i nu delta_p},  delta_p = -P/2 + p + tau,  I_q = (2 pi i nu)^q phihat(nu),
// and out[q][q'] = mean over tau in [0, 1) of conj(D_q) D_q' (32-point Gauss-Legendre in tau: A_q is
// smooth inside the interval; the support's jump sits at its ends).
class WindowDeviation {
 public:
  explicit WindowDeviation(const Window1D& w) : w_(w), P_(w.support()) {
    const Quadrature& q = rule(32);
    const std::size_t nt = q.x.size();
    tau_.resize(nt);
    wt_.resize(nt);
    phi_.resize(nt * 4 * std::size_t(P_));
    for (std::size_t t = 0; t < nt; ++t) {
      tau_[t] = 0.5 * (q.x[t] + 1.0);
      wt_[t] = 0.5 * q.w[t];
      for (int p = 0; p < P_; ++p) {
        double v[4];
        w.derivatives(-0.5 * P_ + p + tau_[t], v);
        for (int d = 0; d < 4; ++d) phi_[(t * 4 + std::size_t(d)) * std::size_t(P_) + std::size_t(p)] = v[d];
      }
    }
  }
  void moments(double nu, std::complex<double> out[4][4]) const {
    using C = std::complex<double>;
    const C iw(0.0, 2.0 * kPi * nu);
    C ideal[4];
    ideal[0] = w_.transform(nu);
    for (int q = 1; q < 4; ++q) ideal[q] = ideal[q - 1] * iw;
    for (int q = 0; q < 4; ++q)
      for (int r = 0; r < 4; ++r) out[q][r] = 0.0;
    const C step = std::polar(1.0, -2.0 * kPi * nu);
    for (std::size_t t = 0; t < tau_.size(); ++t) {
      C e = std::polar(1.0, -2.0 * kPi * nu * (-0.5 * P_ + tau_[t])), A[4] = {0.0, 0.0, 0.0, 0.0};
      const double* f = &phi_[t * 4 * std::size_t(P_)];
      for (int p = 0; p < P_; ++p, e *= step)
        for (int q = 0; q < 4; ++q) A[q] += f[q * P_ + p] * e;
      for (int q = 0; q < 4; ++q) A[q] -= ideal[q];
      for (int q = 0; q < 4; ++q)
        for (int r = 0; r < 4; ++r) out[q][r] += wt_[t] * std::conj(A[q]) * A[r];
    }
  }
  double transform(double nu) const { return w_.transform(nu); }

 private:
  Window1D w_;
  int P_;
  std::vector<double> tau_, wt_, phi_;
};

// Quadrature nodes of the aliasing model with everything that does not depend on the window
// (pme_parameters.hpp): per axis d, k_d over [-K_d/2, K_d/2] (two 16-point panels) and k_perp over
// [0, K_perp/2] (two 16-point panels, cylindrical about e_d). Per node: the volume weight, g, alpha,
// and t_qq' = tr(P_k Rt_q^+ Rt_q') J^(q+q'), Rt_q the coefficient of k_d^q in R(k) (R is a cubic
// polynomial in k_d at fixed k_perp). t comes from Q(x, y) = tr(P_k R(k_perp + x e_d)^+ R(k_perp + y e_d)),
// in closed form per moment level, at four nodes in x and y and the inverse Vandermonde matrix.
class AliasModel {
 public:
  AliasModel(const std::array<int, 3>& M, const Vec3& lengths, double xi, double a, double rho, Moments m)
      : rho_(rho) {
    const Quadrature& q = rule(16);
    for (int d = 0; d < 3; ++d) {
      // Axes with the same grid spacing and the same perpendicular grid are the same integral.
      bool same = false;
      for (Axis& prev : axis_)
        if (prev.M == M[d] && prev.length == lengths[d] && prev.perp == perp_key(M, lengths, d)) {
          ++prev.weight;
          same = true;
          break;
        }
      if (same) continue;
      axis_.emplace_back();
      Axis& ax = axis_.back();
      ax.M = M[d];
      ax.length = lengths[d];
      ax.perp = perp_key(M, lengths, d);
      ax.weight = 1;
      ax.K = 2.0 * kPi * M[d] / lengths[d];
      const double J = M[d] / lengths[d];
      double Kp = std::numeric_limits<double>::infinity();
      for (int e = 0; e < 3; ++e)
        if (e != d) Kp = std::min(Kp, 2.0 * kPi * M[e] / lengths[e]);
      // Vandermonde nodes in x = k_d and its inverse.
      const double s = 0.5 * ax.K;
      const double xs[4] = {-s, -s / 3.0, s / 3.0, s};
      Eigen::Matrix4d V;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) V(i, j) = std::pow(xs[i], j);
      const Eigen::Matrix4d Vi = V.inverse();
      for (int pd = 0; pd < 2; ++pd)
        for (std::size_t i = 0; i < q.x.size(); ++i) {
          const double kd = 0.25 * ax.K * (q.x[i] + (pd == 0 ? -1.0 : 1.0)), wd = 0.25 * ax.K * q.w[i];
          ax.nu.push_back(kd / ax.K);
          for (int pp = 0; pp < 2; ++pp)
            for (std::size_t j = 0; j < q.x.size(); ++j) {
              const double kp = 0.125 * Kp * (q.x[j] + (pp == 0 ? 1.0 : 3.0)), wp = 0.125 * Kp * q.w[j];
              const double k2 = kd * kd + kp * kp;
              Node n;
              n.vol = wd * wp * 2.0 * kPi * kp;
              n.g = g_of(k2, xi);
              n.alpha = response(k2, a, m).alpha;
              Eigen::Matrix4d Qm;
              for (int ix = 0; ix < 4; ++ix)
                for (int iy = 0; iy < 4; ++iy) Qm(ix, iy) = pair_trace(kd, kp, xs[ix], xs[iy], a, m);
              const Eigen::Matrix4d t = Vi * Qm * Vi.transpose();
              for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) n.t[r][c] = t(r, c) * std::pow(J, r + c);
              ax.node.push_back(n);
            }
        }
      ax.per_nu = 2 * q.x.size();
    }
  }

  // e_A^2 for window w (pme_parameters.hpp).
  double error2(const Window1D& w) const {
    using C = std::complex<double>;
    const WindowDeviation dev(w);
    // i^q (-i)^q' of conj(D_q) D_q' with D_q multiplied by (-i)^q (the k_d^q coefficients).
    C phase[4][4];
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) phase[r][c] = std::pow(C(0.0, 1.0), r) * std::pow(C(0.0, -1.0), c);
    double pair = 0.0, self = 0.0;
    for (const Axis& ax : axis_) {
      double bound = 0.0, pair_axis = 0.0;
      for (std::size_t i = 0; i < ax.nu.size(); ++i) {
        C v[4][4];
        dev.moments(ax.nu[i], v);
        const double main = dev.transform(ax.nu[i]);
        C w4[4][4];
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) w4[r][c] = v[r][c] * phase[r][c] / (main * main);
        for (std::size_t j = 0; j < ax.per_nu; ++j) {
          const Node& n = ax.node[i * ax.per_nu + j];
          double X = 0.0;
          for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) X += (w4[r][c] * n.t[r][c]).real();
          X = std::max(X, 0.0) * n.alpha;
          pair_axis += n.vol * n.g * n.g * X;
          bound += n.vol * n.g * std::sqrt(X);
        }
      }
      pair_axis *= ax.weight;
      pair += pair_axis;
      self += ax.weight * bound * bound;
    }
    const double c = 1.0 / std::pow(2.0 * kPi, 3);
    return 2.0 * (rho_ * c * pair + c * c * self);
  }

 private:
  // tr(P_k R(k1)^+ R(k2)) with k = (kp, 0, kd), k1 = (kp, 0, x), k2 = (kp, 0, y) in a frame whose third
  // axis is e_d: P_F1 P_F2 tr P_k + P_T1 P_T2 [2 c_a k1.k2 + c_b (k1.k2 - (k.k1)(k.k2)/k^2)], from
  // R(k1)^+ R(k2) = P_F1 P_F2 I + P_T1 P_T2 [(1/4)(k1.k2 I - k2 k1^T) (rotation rows)
  //                 + (1/2)(k1.k2 I + k2 k1^T) - (1/3) k1 k2^T (strain rows)]  (ewald_split.hpp).
  static double pair_trace(double kd, double kp, double x, double y, double a, Moments m) {
    const double kp2 = kp * kp, k2 = kd * kd + kp2;
    const double k12 = kp2 + x * y, kk1 = kp2 + kd * x, kk2 = kp2 + kd * y;
    const double a2 = a * a, q1 = kp2 + x * x, q2 = kp2 + y * y;
    const double pf = (1.0 - a2 * q1 / 6.0) * (1.0 - a2 * q2 / 6.0);
    double out = 2.0 * pf;
    if (m == Moments::F) return out;
    const double pt = (1.0 - a2 * q1 / 10.0) * (1.0 - a2 * q2 / 10.0);
    const double perp = k12 - kk1 * kk2 / k2;
    if (m == Moments::FT) return out + pt * (0.5 * k12 - 0.25 * perp);
    return out + pt * (1.5 * k12 - perp / 12.0);
  }
  struct Node {
    double vol, g, alpha;
    double t[4][4];
  };
  static std::array<double, 2> perp_key(const std::array<int, 3>& M, const Vec3& lengths, int d) {
    std::array<double, 2> k{};
    int i = 0;
    for (int e = 0; e < 3; ++e)
      if (e != d) k[std::size_t(i++)] = M[e] / lengths[e];
    if (k[0] > k[1]) std::swap(k[0], k[1]);
    return k;
  }
  struct Axis {
    int M = 0, weight = 0;
    double length = 0.0;
    std::array<double, 2> perp{};
    double K = 0.0;
    std::vector<double> nu;
    std::vector<Node> node;  // [nu][k_perp]
    std::size_t per_nu = 0;
  };
  std::vector<Axis> axis_;  // distinct axes, each with its multiplicity
  double rho_;
};

}  // namespace

double pme_alias_error2(const std::array<int, 3>& M, const Vec3& lengths, const Window1D& w, double xi, double a,
                        double rho, Moments m) {
  return AliasModel(M, lengths, xi, a, rho, m).error2(w);
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
  // The size of (M x)_i: the self part and the pairs' (pme_parameters.hpp).
  const double S2 = (opt.self_scale2 > 0.0 ? opt.self_scale2 : pme_self_scale2(a_max, m)) +
                    pme_pair_scale2(box, a_max, rho, m);
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

  // Wave truncation: the worse of the smallest and the largest sphere (see the aliasing below).
  auto wave_error2 = [&](double k_in, double xi) {
    const double e = pme_wave_error2(k_in, xi, a_max, rho, m);
    return a_min < a_max ? std::max(e, pme_wave_error2(k_in, xi, a_min, rho, m)) : e;
  };

  std::vector<double> neighbours;
  if (opt.neighbours > 0.0) neighbours = {opt.neighbours};
  else
    for (double nb = 4.0; nb <= 600.0; nb *= 1.4) neighbours.push_back(nb);
  // Candidate grids for resolving k_in: with a fixed sigma every axis gets the smallest FFT size
  // above sigma k_in L_d / pi. Otherwise every FFT size of every axis between sigma = 1 and 2 gives a
  // candidate sigma, so that axes of different lengths (a sheared a_2 is up to 12 % longer) are not
  // all rounded up together: a 1e5-sphere sheared cube got 128 x 144 x 128 from a list of seven
  // sigmas where 120 x 144 x 120 meets the tolerance.
  auto grid_candidates = [&](double k_in) {
    std::vector<std::array<int, 3>> grids;
    std::vector<double> sigmas;
    if (opt.sigma > 0.0) sigmas = {opt.sigma};
    else
      for (int d = 0; d < 3; ++d) {
        const double need = k_in * len[d] / kPi;  // grid points at sigma = 1
        for (int M = fft_size(int(std::ceil(need))); M <= 2.0 * need; M = fft_size(M + 1)) sigmas.push_back(M / need);
      }
    std::sort(sigmas.begin(), sigmas.end());
    for (double sigma : sigmas) {
      std::array<int, 3> M;
      // The relative margin keeps an axis whose size defined sigma from rounding up a size.
      for (int d = 0; d < 3; ++d) M[d] = fft_size(int(std::ceil(sigma * k_in * len[d] / kPi * (1.0 - 1e-12))));
      if (grids.empty() || grids.back() != M) grids.push_back(M);
    }
    return grids;
  };

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
    while (wave_error2(khi, xi) > budget) khi *= 1.5;
    for (int it = 0; it < 30; ++it) {
      const double mid = 0.5 * (klo + khi);
      (wave_error2(mid, xi) > budget ? klo : khi) = mid;
    }
    const double k_in = khi;
    const double pairs = 0.5 * n * std::min(double(n - 1), rho * 4.0 / 3.0 * kPi * std::pow(gap + 2.0 * a_max, 3));
    for (const std::array<int, 3>& M : grid_candidates(k_in)) {
      const double G = double(M[0]) * M[1] * M[2];
      const bool cached = RealSpaceSum::cache_bytes_for(2.0 * pairs, m) <= best.cache_bytes;
      const double setup_pairs = (kSetupParticle * n + setup_entry(m) * 2.0 * pairs) * setup_share;
      const double fixed =
          (cached ? cc.pair_cached : cc.pair) * pairs + 6.0 * kFft * G * std::log2(G) + kGrid * G + setup_pairs;
      if (fixed >= best_cost) continue;
      // The largest sphere's Faxen factors damp the modes near k = sqrt(6) / a_max where the smallest
      // sphere's do not: both radii are modelled and the worse one kept.
      const AliasModel alias_max(M, len, xi, a_max, rho, m);
      std::optional<AliasModel> alias_min;
      if (a_min < a_max) alias_min.emplace(M, len, xi, a_min, rho, m);
      auto alias_error2 = [&](const Window1D& w) {
        return std::max(alias_max.error2(w), alias_min ? alias_min->error2(w) : 0.0);
      };
      // Effective upsampling of the grid actually used (fft_size rounds up).
      double sig = std::numeric_limits<double>::infinity();
      for (int d = 0; d < 3; ++d) sig = std::min(sig, M[d] * kPi / (k_in * len[d]));
      auto cost_of = [&](int P) {
        return fixed + 2.0 * cc.point * n * double(P) * P * P + kSetupWindow * n * P * setup_share;
      };
      // Smallest aliasing-and-edge error over the window shape at support P: a coarse scan, then
      // (when the best is within 4x of the budget, where the answer may change) two halvings of the
      // step around the best.
      struct Shaped {
        double e = std::numeric_limits<double>::infinity(), shape = 0.0;
      };
      auto shaped = [&](int P) {
        auto shape_of = [&](double f) {
          return opt.window == WindowKind::kaiser_bessel
                     ? f * kPi * P * (1.0 - 0.5 / std::max(sig, 1.0))  // beta = kappa pi P (1 - 1 / (2 sigma))
                     // Gaussian: widths around the one whose edge value exp(-P^2 / (8 s^2)) is a decade
                     // below the tolerance; the model counts the truncation (its edge jumps) exactly.
                     : f * P / (2.0 * std::sqrt(2.0 * std::log(10.0 / (kSafety * tol))));
        };
        Shaped out;
        double best_f = 0.0;
        auto try_shape = [&](double f) {
          const double shape = shape_of(f);
          const double e = alias_error2(Window1D(opt.window, P, shape));
          if (e < out.e) out.e = e, out.shape = shape, best_f = f;
        };
        const bool kb = opt.window == WindowKind::kaiser_bessel;
        for (int i = 0; i < (kb ? 7 : 6); ++i) try_shape((kb ? 0.9 : 0.6) + 0.1 * i);
        for (double step = 0.05; step > 0.02 && out.e > budget && out.e < 4.0 * budget; step *= 0.5) {
          const double f0 = best_f;
          try_shape(f0 - step);
          try_shape(f0 + step);
        }
        return out;
      };
      // The cost grows with P and the error falls with it: the largest P that could still beat the
      // best so far, then bisection for the smallest P meeting the budget (about six evaluations; a
      // grid that fails at its largest P costs one, where a scan from P = 3 cost up to thirty).
      int Pmax = 2;
      while (Pmax < 32 && cost_of(Pmax + 1) < best_cost) ++Pmax;
      if (Pmax < 3) continue;
      Shaped at_hi = shaped(Pmax);
      if (at_hi.e > budget) continue;
      int lo = 3, hi = Pmax;
      while (lo < hi) {
        const int mid = (lo + hi) / 2;
        const Shaped s_mid = shaped(mid);
        if (s_mid.e <= budget) hi = mid, at_hi = s_mid;
        else lo = mid + 1;
      }
      {
        const int P = hi;
        const double cost = cost_of(P);
        best_cost = cost;
        best.xi = xi;
        best.cutoff_gap = gap;
        best.grid = M;
        best.support = P;
        best.shape = at_hi.shape;
        best.k_max = k_in * sig;
        best.est_real = std::sqrt(real_error2(gap, xi) / S2);
        best.est_wave = std::sqrt(wave_error2(k_in, xi) / S2);
        best.est_alias = std::sqrt(at_hi.e / S2);
        best.est_cost = cost;
        best.est_setup = kSetupParticle * n + kSetupWindow * n * P + setup_entry(m) * 2.0 * pairs;
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
