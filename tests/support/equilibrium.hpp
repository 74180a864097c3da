#pragma once
// Brownian equilibrium with full hydrodynamic interactions (issue 13), shared by
// tests/test_equilibrium.cpp (short, CI) and bench/validate_equilibrium.cpp (long form).
//
// Mathematics. Overdamped Brownian motion dx = R^{-1}(x) F dt + kT div(R^{-1}) dt + sqrt(2 kT) R^{-1/2} dW
// with conservative F = -grad U has the Boltzmann density p(x) ~ exp(-U(x)/kT) whatever the
// configuration-dependent resistance R(x): with the drift the probability flux
// J = R^{-1} (F p - kT grad p) vanishes for that p. Without the drift (Euler-Maruyama with noise
// dt R^{-1} xi alone) the flux is R^{-1}(F p - kT grad p) - kT div(R^{-1}) p, whose zero in one
// dimension is p ~ exp(-U/kT) / M(x), M = R^{-1}: weight piles up where the mobility is small
// (near contact, where lubrication makes M ~ gap). The two scenes below therefore separate the
// two schemes: sampled with the drift (FixmanIntegrator) the Boltzmann law must hold, without it
// (EulerIntegrator, which for SD adds dt R^{-1} xi and nothing else) it must not.
//
//  Dimer (open domain): spheres of radii 1 and 2, a harmonic spring on the surface gap
//    U = (k/2)(h - h0)^2 (engine/pair_forces.hpp) plus a Hertz contact U = (2/5) k_H delta^{5/2}
//    for safety. The separation r of a free pair in three dimensions has density
//    p(r) ~ r^2 exp(-U(r)) (the Jacobian of the relative coordinate), normalised numerically on
//    [r_lo, a1 + a2 + h_c] (the spring is cut at h_c, where it holds 100 kT: beyond that the
//    weight is below e^-100 and is ignored; r_lo where the Hertz energy exceeds 100 kT).
//  Wall (periodic box): a square layer of fixed spheres in the plane z = z_w, one mobile sphere
//    above under gravity U = g z. The accessible lateral area fraction A(z) < 1 while the sphere
//    can touch a wall sphere (z - z_w < a + a_w) and A(z) = 1 above; up to the periodic image of
//    the layer, z < z_w + L_z - (a + a_w). We compare only the conditional law of z above
//    z_full = z_w + a + a_w, which is exactly the truncated exponential
//      p(z | z_full <= z <= z_max) = g exp(-g (z - z_full)) / (1 - exp(-g (z_max - z_full))),
//    so no numerical area factor is needed (the excluded volume of the bumps is irrelevant there,
//    and the Hertz contact is zero there). The samples below z_full are simply not compared.
//
// Statistics. One long trajectory; the integrated autocorrelation time tau_int of the observable
// (Sokal's window: tau_int = 1/2 + sum_{t=1}^{M} rho(t), M the first lag with M >= 5 tau_int) is
// estimated from the series, and the samples used are taken every `stride` steps with
// stride >= 3 tau_int (residual correlation ~ e^-3 for exponential decay). The Kolmogorov-Smirnov
// statistic D = sup |F_n - F| of those samples against the Boltzmann CDF F gives the p-value
// Q_KS((sqrt(n) + 0.12 + 0.11/sqrt(n)) D) (Stephens 1970; Press et al., Numerical Recipes s. 14.3).
#include "engine/core/random.hpp"
#include "engine/integrators.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace stokesian::equilibrium {

// ---- Scenes -----------------------------------------------------------------------------------

struct DimerParams {
  double a1 = 1.0, a2 = 2.0;
  double k = 1000.0;      // spring stiffness [kT/a^2]
  double h0 = 0.1;        // rest gap [a] (within 0.1 a of contact)
  double hertz = 1e4;     // Hertz contact stiffness [kT/a^{5/2}]
  double dt = 2e-3;
  std::uint64_t seed = 1;
};

inline std::string dimer_toml(const DimerParams& p) {
  std::ostringstream o;
  o.precision(17);
  o << "[fluid]\nkT = 1.0\n"
    << "[particles]\npositions = [[0,0,0],[" << (p.a1 + p.a2 + p.h0) << ",0,0]]\nradii = [" << p.a1 << ", " << p.a2
    << "]\n"
    << "[[forces.pair]]\nkind = \"harmonic\"\nstiffness = " << p.k << "\nrest_gap = " << p.h0 << "\n"
    << "[[forces.pair]]\nkind = \"hertz\"\nstiffness = " << p.hertz << "\n"
    << "[hydrodynamics]\nmodel = \"stokesian\"\n"
    << "[brownian]\nseed = " << p.seed << "\n"
    << "[time]\ndt = " << p.dt << "\nsteps = 1\n";
  return o.str();
}

struct WallParams {
  int n = 3;              // n x n fixed spheres
  double a = 1.0;         // radius of the mobile and the wall spheres [a]
  double spacing = 2.1;   // lattice spacing of the wall [a]
  double Lz = 8.0;        // box height [a]
  double zw = 1.0;        // height of the wall's centres [a]
  double g = 3.0;         // weight [kT/a]
  double hertz = 1e4;     // Hertz contact stiffness
  double lub_cutoff = 3.0;  // lubrication s_cut (the box must be at least twice the near-field range)
  double dt = 5e-3;
  // Hydrodynamic tolerance: the Boltzmann law does not depend on the mobility's accuracy, only on
  // the noise and the drift coming from the same smooth R(x); 1e-3 makes the dense Ewald sum
  // (70 % of a step at the default 1e-6) about 3x cheaper.
  double tolerance = 1e-3;
  std::string model = "stokesian";  // "free_draining": constant mobility, no drift needed (checks the law)
  std::uint64_t seed = 1;
  double L() const { return n * spacing; }
  double z_full() const { return zw + 2.0 * a; }
  double z_max() const { return zw + Lz - 2.0 * a; }
};

inline std::string wall_toml(const WallParams& p) {
  std::ostringstream o;
  o.precision(17);
  o << "[fluid]\nkT = 1.0\n[domain]\nkind = \"periodic\"\nbox = [" << p.L() << ", " << p.L() << ", " << p.Lz << "]\n";
  o << "[particles]\npositions = [";
  for (int i = 0; i < p.n; ++i)
    for (int j = 0; j < p.n; ++j) o << "[" << (i + 0.5) * p.spacing << "," << (j + 0.5) * p.spacing << "," << p.zw << "],";
  // The mobile sphere starts above the middle of a hollow, at z_full + 1/g.
  o << "[" << p.spacing << "," << p.spacing << "," << p.z_full() + 1.0 / p.g << "]]\n";
  o << "radii = [";
  for (int k = 0; k <= p.n * p.n; ++k) o << p.a << (k < p.n * p.n ? "," : "]\n");
  o << "fixed = [";
  for (int k = 0; k <= p.n * p.n; ++k) o << (k < p.n * p.n ? "true," : "false]\n");
  o << "[forces]\ngravity = [0, 0, " << -p.g << "]\n"
    << "[[forces.pair]]\nkind = \"hertz\"\nstiffness = " << p.hertz << "\n"
    << "[hydrodynamics]\nmodel = \"" << p.model << "\"\n";
  if (p.model == "stokesian") o << "lubrication_cutoff = " << p.lub_cutoff << "\ntolerance = " << p.tolerance << "\n";
  o
    << "[brownian]\nseed = " << p.seed << "\n"
    << "[time]\ndt = " << p.dt << "\nsteps = 1\n";
  return o.str();
}

// ---- Driving the Simulation with a chosen integrator --------------------------------------------

// Steps the state `steps` times with `integ` (FixmanIntegrator: with the drift; EulerIntegrator:
// without), exactly as Simulation::advance does apart from the integrator: the noise of step n is
// RandomStream (seed, brownian, n), positions are wrapped in periodic boxes. observe(s) after
// every step.
inline void run(Simulation& sim, State& s, Integrator& integ, long steps, const std::function<void(const State&)>& observe) {
  for (long n = 0; n < steps; ++n) {
    Rng rng = RandomStream::for_purpose(sim.scene().seed, Purpose::brownian, std::uint64_t(s.step));
    const Evaluation ev = sim.evaluate(s, s.position);
    StepResult r = integ.step(s, ev, sim, rng);
    s.position = std::move(r.x);
    s.time += r.dt_used;
    s.step += 1;
    s.dt = r.dt_next;
    wrap_positions(s, s.domain.shear_strain);
    observe(s);
  }
}

// ---- Boltzmann references (written out here, independently of the engine's pair laws) ----------

// CDF of p(r) ~ r^2 exp(-U(r)) on a fine grid (trapezoid rule on 2e5 intervals; U is smooth
// apart from the contact kink, which lies on a grid node).
class DimerBoltzmann {
 public:
  explicit DimerBoltzmann(const DimerParams& p) {
    const double s = p.a1 + p.a2;
    const double hc = p.h0 + std::sqrt(200.0 / p.k);  // the spring's default cut-off (100 kT)
    const double dlo = std::pow(100.0 / (0.4 * p.hertz), 0.4) + p.h0 + 0.1;  // Hertz + spring >> 100 kT there
    lo_ = s - dlo;
    hi_ = s + hc;
    const int n = 200000;
    // Contact (h = 0) on a node: uniform spacing on [lo, s] and [s, hi] separately.
    const int n1 = int(std::lround(n * dlo / (dlo + hc)));
    r_.resize(n + 1);
    for (int i = 0; i <= n1; ++i) r_[i] = lo_ + (s - lo_) * i / n1;
    for (int i = n1 + 1; i <= n; ++i) r_[i] = s + (hi_ - s) * (i - n1) / double(n - n1);
    auto w = [&](double r) {
      const double h = r - s;
      double U = 0.5 * p.k * (h - p.h0) * (h - p.h0);
      if (h < 0) U += 0.4 * p.hertz * std::pow(-h, 2.5);
      return r * r * std::exp(-U);
    };
    F_.assign(n + 1, 0.0);
    for (int i = 1; i <= n; ++i) F_[i] = F_[i - 1] + 0.5 * (w(r_[i]) + w(r_[i - 1])) * (r_[i] - r_[i - 1]);
    const double Z = F_[n];
    for (double& f : F_) f /= Z;
  }
  double cdf(double r) const {
    if (r <= lo_) return 0.0;
    if (r >= hi_) return 1.0;
    const auto it = std::upper_bound(r_.begin(), r_.end(), r);
    const std::size_t i = std::size_t(it - r_.begin());
    const double t = (r - r_[i - 1]) / (r_[i] - r_[i - 1]);
    return F_[i - 1] + t * (F_[i] - F_[i - 1]);
  }
  // Density p(r) by finite difference of the CDF (for charts).
  double pdf(double r) const { return (cdf(r + 1e-5) - cdf(r - 1e-5)) / 2e-5; }

 private:
  double lo_, hi_;
  std::vector<double> r_, F_;
};

// Truncated exponential of the wall scene above z_full.
struct WallBoltzmann {
  double g, z0, z1;
  explicit WallBoltzmann(const WallParams& p) : g(p.g), z0(p.z_full()), z1(p.z_max()) {}
  double cdf(double z) const {
    if (z <= z0) return 0.0;
    if (z >= z1) return 1.0;
    return -std::expm1(-g * (z - z0)) / -std::expm1(-g * (z1 - z0));
  }
  double pdf(double z) const { return z < z0 || z > z1 ? 0.0 : g * std::exp(-g * (z - z0)) / -std::expm1(-g * (z1 - z0)); }
};

// Full law of the wall scene's height, hollows and soft contacts included:
//   p(z) ~ exp(-g z) A(z),  A(z) = (1/s^2) int_cell exp(-sum_j U_H(|r - r_j|)) dx dy,
// U_H the Hertz energy against the wall spheres r_j of the layer at z_w and of its periodic image
// at z_w + L_z (the lattice has period s, so one cell [0, s]^2 with its 3 x 3 neighbouring sites
// is the whole lateral integral). A(z) = 1 exactly between the two contact zones, where p is the
// analytic exponential; inside them A is tabulated at dz = 1e-3 (midpoint rule on 256 x 256
// lateral points, error well below 1e-4 of the CDF) and the CDF is the trapezoid rule there.
class WallHeightLaw {
 public:
  explicit WallHeightLaw(const WallParams& p) : g_(p.g) {
    const double c = 2.0 * p.a;  // contact distance (equal radii)
    const double dmax = std::pow(100.0 / (0.4 * p.hertz), 0.4);  // overlap at which U_H = 100 kT
    lo_ = p.zw + std::sqrt(std::max(0.0, c * c - 0.5 * p.spacing * p.spacing)) - dmax;  // below the hollow's floor
    z0_ = p.z_full();
    z1_ = p.z_max();
    hi_ = p.zw + p.Lz - (lo_ - p.zw);
    const int M = 256;
    auto area = [&](double z) {
      double sum = 0.0;
      for (int i = 0; i < M; ++i)
        for (int j = 0; j < M; ++j) {
          const double x = (i + 0.5) * p.spacing / M, y = (j + 0.5) * p.spacing / M;
          double U = 0.0;
          for (int u = -1; u <= 1; ++u)
            for (int v = -1; v <= 1; ++v)
              for (double zl : {p.zw, p.zw + p.Lz}) {
                const double dx = x - (u + 0.5) * p.spacing, dy = y - (v + 0.5) * p.spacing, dz = z - zl;
                const double delta = c - std::sqrt(dx * dx + dy * dy + dz * dz);
                if (delta > 0.0) U += 0.4 * p.hertz * std::pow(delta, 2.5);
              }
          sum += std::exp(-U);
        }
      return sum / double(M * M);
    };
    auto table = [&](double a, double b, std::vector<double>& z, std::vector<double>& w) {
      const int n = std::max(2, int(std::ceil((b - a) / 1e-3)));
      for (int k = 0; k <= n; ++k) {
        z.push_back(a + (b - a) * k / n);
        w.push_back(std::exp(-g_ * (z.back() - z0_)) * area(z.back()));
      }
    };
    table(lo_, z0_, zb_, wb_);
    table(z1_, hi_, zt_, wt_);
    auto cumulate = [](const std::vector<double>& z, const std::vector<double>& w, std::vector<double>& F) {
      F.assign(z.size(), 0.0);
      for (std::size_t k = 1; k < z.size(); ++k) F[k] = F[k - 1] + 0.5 * (w[k] + w[k - 1]) * (z[k] - z[k - 1]);
    };
    cumulate(zb_, wb_, Fb_);
    cumulate(zt_, wt_, Ft_);
    mid_ = -std::expm1(-g_ * (z1_ - z0_)) / g_;  // int_{z0}^{z1} exp(-g (z - z0)) dz
    Z_ = Fb_.back() + mid_ + Ft_.back();
  }
  double cdf(double z) const {
    if (z <= lo_) return 0.0;
    if (z >= hi_) return 1.0;
    if (z <= z0_) return interp(zb_, Fb_, z) / Z_;
    if (z <= z1_) return (Fb_.back() - std::expm1(-g_ * (z - z0_)) / g_) / Z_;
    return (Fb_.back() + mid_ + interp(zt_, Ft_, z)) / Z_;
  }
  // Probability of z < z_full (the hollows and contacts).
  double below_z_full() const { return Fb_.back() / Z_; }
  double lo() const { return lo_; }

 private:
  static double interp(const std::vector<double>& z, const std::vector<double>& F, double x) {
    const auto it = std::upper_bound(z.begin(), z.end(), x);
    const std::size_t i = std::min<std::size_t>(std::max<std::size_t>(std::size_t(it - z.begin()), 1), z.size() - 1);
    const double t = (x - z[i - 1]) / (z[i] - z[i - 1]);
    return F[i - 1] + t * (F[i] - F[i - 1]);
  }
  double g_, lo_, z0_, z1_, hi_, mid_ = 0.0, Z_ = 1.0;
  std::vector<double> zb_, wb_, Fb_, zt_, wt_, Ft_;
};

// ---- Statistics ---------------------------------------------------------------------------------

// Integrated autocorrelation time of x (in units of the series' spacing), Sokal's window c = 5.
inline double tau_int(const std::vector<double>& x) {
  const std::size_t n = x.size();
  if (n < 10) return 1.0;
  double m = 0.0;
  for (double v : x) m += v;
  m /= double(n);
  double c0 = 0.0;
  for (double v : x) c0 += (v - m) * (v - m);
  c0 /= double(n);
  if (!(c0 > 0.0)) return 1.0;
  double tau = 0.5;
  for (std::size_t t = 1; t < n / 2; ++t) {
    double c = 0.0;
    for (std::size_t i = 0; i + t < n; ++i) c += (x[i] - m) * (x[i + t] - m);
    tau += c / (double(n - t) * c0);
    if (double(t) >= 5.0 * tau) break;
  }
  return std::max(tau, 0.5);
}

// Kolmogorov's Q_KS(lambda) = 2 sum_{j>=1} (-1)^{j-1} exp(-2 j^2 lambda^2).
inline double q_ks(double lambda) {
  if (lambda < 0.2) return 1.0;
  double sum = 0.0, sign = 1.0;
  for (int j = 1; j <= 200; ++j) {
    const double term = sign * std::exp(-2.0 * j * j * lambda * lambda);
    sum += term;
    if (std::abs(term) < 1e-300 || std::abs(term) <= 1e-16 * std::abs(sum)) break;
    sign = -sign;
  }
  return std::clamp(2.0 * sum, 0.0, 1.0);
}

struct KsResult {
  long n = 0;
  double D = 0.0;  // sup |F_n - F|
  double p = 0.0;  // asymptotic p-value
};

inline KsResult ks_test(std::vector<double> x, const std::function<double(double)>& cdf) {
  std::sort(x.begin(), x.end());
  KsResult k;
  k.n = long(x.size());
  const double n = double(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double F = cdf(x[i]);
    k.D = std::max({k.D, F - double(i) / n, double(i + 1) / n - F});
  }
  const double sn = std::sqrt(n);
  k.p = q_ks((sn + 0.12 + 0.11 / sn) * k.D);
  return k;
}

// Every stride-th entry of x starting at `from`.
inline std::vector<double> subsample(const std::vector<double>& x, std::size_t from, std::size_t stride) {
  std::vector<double> y;
  for (std::size_t i = from; i < x.size(); i += stride) y.push_back(x[i]);
  return y;
}

}  // namespace stokesian::equilibrium
