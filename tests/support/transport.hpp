#pragma once
// High-frequency dynamic viscosity eta'_inf and sedimentation coefficient K of hard-sphere
// suspensions (issue 15), shared by the CI test (tests/test_transport.cpp) and the long validation
// (bench/validate_transport.cpp, whose header states the mathematics and references in full).
// Units a = mu = 1. Per configuration (periodic cube of side L, N spheres, V = L^3), two FTS solves
// of the deterministic solver (no Brownian motion):
//   shear: force- and torque-free rigid spheres in simple shear u = (gdot y, 0, 0), gdot = 1:
//          eta'_inf/mu = 1 - sum_i S_xy,i / (V mu gdot),  S_i the stresslets (HydroResult::S, the
//          stresslet exerted on the fluid, whose sign is opposite to Batchelor's particle stresslet);
//   settling: the same force F = e_z on every sphere, zero torques, no ambient flow:
//          K = (1/N) sum_i U_z,i / (|F| / (6 pi mu a)),  U in the frame of the Ewald sum (zero
//          volume flux: the k = 0 mode, the mean of the velocity field over the cell, is absent).
// Finite size (Ladd 1990, J. Chem. Phys. 93, 3484; the D_s0 law of tests/support/self_diffusion.hpp
// with the collective sum over pairs, which weights it by the structure factor S(0)):
//   K_N = K_inf - 2.837297 (a/L) S(0) mu/eta'_inf,   S(0) = (1-phi)^4/(1+4phi+4phi^2-4phi^3+phi^4)
// (Carnahan-Starling compressibility); eta'_inf here is the value measured in the same run.
#include "engine/hydrodynamics.hpp"
#include "engine/model.hpp"
#include "hard_spheres.hpp"  // same folder
#include "trees/placement.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

namespace stokesian::transport {

inline constexpr double kHasimoto = 2.837297;  // -(self-mobility deficit) x L/a of a periodic cube

// Abade, Cichocki, Ekiel-Jezewska, Naegele & Wajnryb (2010, 2011) fits to exact multipole results
// for equilibrium hard spheres (docs/transport.md names which paper gives which).
inline double abade_eta(double phi) {
  const double s = phi * (1.0 + 0.95 * phi - 2.15 * phi * phi);
  return 1.0 + 2.5 * phi * (1.0 + s) / (1.0 - phi * (1.0 + s));
}
inline double abade_K(double phi) {
  const double p = phi;
  return 1.0 - 6.5464 * p * (1.0 - 3.348 * p + 7.426 * p * p - 10.034 * p * p * p + 5.882 * p * p * p * p);
}
// Structure factor at q -> 0 of hard spheres, Carnahan-Starling: kT (d rho / d p).
inline double structure_factor_0(double phi) {
  const double p = phi;
  return std::pow(1.0 - p, 4) / (1.0 + 4.0 * p + 4.0 * p * p - 4.0 * p * p * p + p * p * p * p);
}
// Ladd's finite-size term: K_inf = K_N + k_finite_size(...).
inline double k_finite_size(double L, double phi, double eta) { return kHasimoto / L * structure_factor_0(phi) / eta; }

struct Sample {
  double eta = 1.0, K = 1.0;
  long iterations = 0;
};

// One configuration: both solves (FTS at `level`, PME far field, tolerance tol).
// solver: the Stokesian-dynamics solver at level stokesian ("accelerated_sd", or "dense_sd" with the
// dense Ewald far field).
inline Sample measure(const std::vector<Vec3>& x, const std::vector<double>& a, const Vec3& box, double tol,
                      HydroModel level = HydroModel::stokesian, const char* solver = "accelerated_sd") {
  ResolvedModel m;
  m.level = level;
  m.solver = level == HydroModel::stokesian ? solver : "";
  m.moments = Moments::FTS;
  m.far_field = m.solver == "dense_sd" ? "ewald" : "pme";
  Domain d;
  d.kind = Domain::Kind::periodic;
  d.box = box;
  const std::size_t n = x.size();
  const std::vector<Vec3> zero(n, Vec3::Zero());
  Sample s;
  {
    FlowParams fp;
    fp.kind = FlowParams::Kind::simple_shear;
    fp.rate = 1.0;
    Hydrodynamics h(m, 1.0, ambient_flow(fp), tol);
    const HydroResult r = h.solve(x, a, {}, zero, zero, d);
    // HydroResult::S is the stresslet the particle exerts on the fluid, -(20/3) pi mu a^3 E for an
    // isolated rigid sphere (tests/test_hydrodynamics.cpp): Batchelor's particle stress is -sum S / V.
    double sxy = 0.0;
    for (const Vec5& S : r.S) sxy += from_vec5(S)(0, 1);
    s.eta = 1.0 - sxy / (box[0] * box[1] * box[2]);
    s.iterations += r.iterations;
  }
  {
    Hydrodynamics h(m, 1.0, AmbientFlow{}, tol);
    const std::vector<Vec3> F(n, Vec3(0.0, 0.0, 1.0));
    const HydroResult r = h.solve(x, a, {}, F, zero, d);
    double uz = 0.0;
    for (const Vec3& u : r.U) uz += u[2];
    s.K = 6.0 * kPi * uz / double(n);
    s.iterations += r.iterations;
  }
  return s;
}

struct Estimate {
  double L = 0.0;                  // box side [a]
  double eta = 0.0, se_eta = 0.0;  // eta'_inf/mu, standard error over configurations
  double K = 0.0, se_K = 0.0;      // K at this N
  double K_inf = 0.0;              // K + k_finite_size(L, phi, eta)
  long iterations = 0;             // Krylov iterations of all solves
  double seconds_placement = 0.0, seconds_solve = 0.0;
  std::vector<Sample> samples;     // per configuration
};

// n spheres at volume fraction phi: `configs` equilibrium hard-sphere configurations of
// trees/placement.hpp (seeds seed0, seed0 + 1, ...; min gap 1e-3 a, 100 sweeps at full size).
inline Estimate estimate(long n, double phi, int configs, std::uint64_t seed0, double tol,
                         HydroModel level = HydroModel::stokesian) {
  using clock = std::chrono::steady_clock;
  auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  Estimate est;
  est.L = std::cbrt(double(n) * 4.0 / 3.0 * kPi / phi);
  for (int k = 0; k < configs; ++k) {
    auto t = clock::now();
    const Placement pl = test::equilibrium_hard_spheres(n, est.L, seed0 + std::uint64_t(k));
    est.seconds_placement += since(t);
    t = clock::now();
    const Sample s = measure(pl.position, pl.radius, pl.box, tol, level);
    est.seconds_solve += since(t);
    est.iterations += s.iterations;
    est.samples.push_back(s);
  }
  auto mean_se = [&](double Sample::*f, double& mean, double& se) {
    const double m = double(est.samples.size());
    mean = 0.0;
    for (const Sample& s : est.samples) mean += s.*f / m;
    double s2 = 0.0;
    for (const Sample& s : est.samples) s2 += (s.*f - mean) * (s.*f - mean);
    se = m > 1 ? std::sqrt(s2 / (m - 1.0) / m) : 0.0;
  };
  mean_se(&Sample::eta, est.eta, est.se_eta);
  mean_se(&Sample::K, est.K, est.se_K);
  est.K_inf = est.K + k_finite_size(est.L, phi, est.eta);
  return est;
}

}  // namespace stokesian::transport
