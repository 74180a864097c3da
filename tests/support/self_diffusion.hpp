#pragma once
// Short-time self-diffusion of hard-sphere suspensions (issue 13), shared by the CI test
// (tests/test_self_diffusion.cpp) and the long validation (bench/validate_diffusion.cpp, whose
// header states the mathematics in full):
//   D_s0/D0 = 6 pi (w . M_UF w) / (3N) per Rademacher probe w, M_UF the translational block of the
//   FTS mobility (torques zero, stresslets of rigid spheres solved for); with the far-field RPY
//   mobility M_ff (F, PME) as control variate, e = w.M_UF w - c (w.M_ff w - 3N m_self(L)), unbiased
//   for any fixed c; c = mu/eta_inf' (generalised Saito form) only sets the variance.
// References: Abade, Cichocki, Ekiel-Jezewska, Naegele & Wajnryb, J. Chem. Phys. 132, 014503 (2010)
// (the fit of D_s0 and the eta_inf' form, quoted as in issue 13, not checked against the paper);
// Hasimoto (1959) for m_self(L); Ladd (1990), J. Chem. Phys. 93, 3484, for the finite-size term.
#include "engine/hydrodynamics.hpp"
#include "engine/model.hpp"
#include "hard_spheres.hpp"  // same folder
#include "trees/placement.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace stokesian::self_diffusion {

inline constexpr double kHasimoto = 2.837297;

// D_s0/D0 = 1 - 1.8315 phi (1 + 0.12 phi - 0.70 phi^2) (Abade et al. 2010).
inline double abade_fit(double phi) { return 1.0 - 1.8315 * phi * (1.0 + 0.12 * phi - 0.70 * phi * phi); }

// High-frequency viscosity eta_inf'/mu, generalised Saito form (quoted from memory; cross-check only).
inline double eta_inf_ratio(double phi) {
  const double g = 1.0 + phi - 0.189 * phi * phi;
  return (1.0 + 1.5 * phi * g) / (1.0 - phi * g);
}

struct Estimate {
  double L = 0.0;                       // box side [a]
  double mean = 0.0, se = 0.0;          // D_s/D0 with the control variate; se over configurations
  double mean_raw = 0.0, se_raw = 0.0;  // plain Hutchinson (no control variate)
  long iterations = 0;                  // Krylov iterations of all solves at `level`
  double seconds_placement = 0.0, seconds_solve = 0.0, seconds_far_field = 0.0;
};

// D_s/D0 of n spheres at volume fraction phi (periodic cube, FTS at `level`, PME, tolerance tol):
// `configs` equilibrium hard-sphere configurations (seeds seed0, seed0 + 1, ...), `probes`
// Rademacher probes each; the standard error is over the configuration means.
inline Estimate estimate(long n, double phi, int configs, int probes, std::uint64_t seed0, double tol,
                         HydroModel level = HydroModel::stokesian) {
  using clock = std::chrono::steady_clock;
  auto since = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  ResolvedModel m;
  m.level = level;
  m.solver = level == HydroModel::stokesian ? "accelerated_sd" : "";
  m.moments = Moments::FTS;
  m.far_field = "pme";
  ResolvedModel mf;  // far-field RPY mobility for the control variate
  mf.level = HydroModel::far_field;
  mf.moments = Moments::F;
  mf.far_field = "pme";
  Estimate est;
  est.L = std::cbrt(double(n) * 4.0 / 3.0 * kPi / phi);
  const double L = est.L, c = 1.0 / eta_inf_ratio(phi);
  const double m_self = (1.0 - kHasimoto / L + 4.0 * kPi / 3.0 / (L * L * L)) / (6.0 * kPi);
  std::vector<double> per_config, raw;
  for (int k = 0; k < configs; ++k) {
    const std::uint64_t seed = seed0 + std::uint64_t(k);
    auto t = clock::now();
    const Placement pl = test::equilibrium_hard_spheres(n, L, seed);
    est.seconds_placement += since(t);
    Domain d;
    d.kind = Domain::Kind::periodic;
    d.box = pl.box;
    Hydrodynamics h(m, 1.0, AmbientFlow{}, tol), ff(mf, 1.0, AmbientFlow{}, tol);
    std::mt19937_64 rng(1000003ULL * seed + std::uint64_t(n));
    std::bernoulli_distribution coin(0.5);
    const std::vector<Vec3> T(static_cast<std::size_t>(n), Vec3::Zero());
    double sum = 0.0, sum_raw = 0.0;
    for (int probe = 0; probe < probes; ++probe) {
      std::vector<Vec3> w(static_cast<std::size_t>(n));
      for (auto& v : w)
        for (int i = 0; i < 3; ++i) v[i] = coin(rng) ? 1.0 : -1.0;
      t = clock::now();
      const HydroResult r = h.solve(pl.position, pl.radius, {}, w, T, d);
      est.seconds_solve += since(t);
      t = clock::now();
      const HydroResult rf = ff.solve(pl.position, pl.radius, {}, w, T, d);
      est.seconds_far_field += since(t);
      est.iterations += r.iterations;
      double wu = 0.0, wuf = 0.0;
      for (std::size_t i = 0; i < w.size(); ++i) wu += w[i].dot(r.U[i]), wuf += w[i].dot(rf.U[i]);
      sum += 6.0 * kPi * (wu - c * (wuf - 3.0 * double(n) * m_self)) / (3.0 * double(n));
      sum_raw += 6.0 * kPi * wu / (3.0 * double(n));
    }
    per_config.push_back(sum / probes);
    raw.push_back(sum_raw / probes);
  }
  auto mean_se = [&](const std::vector<double>& v, double& mean, double& se) {
    mean = 0.0;
    for (double x : v) mean += x / double(v.size());
    double s2 = 0.0;
    for (double x : v) s2 += (x - mean) * (x - mean);
    se = v.size() > 1 ? std::sqrt(s2 / double(v.size() - 1) / double(v.size())) : 0.0;
  };
  mean_se(per_config, est.mean, est.se);
  mean_se(raw, est.mean_raw, est.se_raw);
  return est;
}

}  // namespace stokesian::self_diffusion
