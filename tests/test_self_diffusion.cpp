// Short-time self-diffusion of hard-sphere suspensions (issue 13): the accelerated SD solver
// (engine/sd_accelerated.hpp through Hydrodynamics: periodic box, PME, FTS, lubrication) against
// the fit of Abade, Cichocki, Ekiel-Jezewska, Naegele & Wajnryb, J. Chem. Phys. 132, 014503 (2010)
// to exact multipole results, D_s0/D0 = 1 - 1.8315 phi (1 + 0.12 phi - 0.70 phi^2), at small N
// with the finite-size correction made explicit. The full sweep with the extrapolation to
// N -> infinity is bench/validate_diffusion.cpp (docs/benchmarks.md, "Short-time self-diffusion").
//
// Estimator (the same mathematics as the benchmark): D_s0 = kT/(3N) tr M_UF, M_UF the
// translational block of the SD mobility with zero torques and the stresslets of rigid spheres
// solved for (FTS, quiescent fluid). Per Rademacher probe w (+-1 on every force component), with
// the far-field RPY mobility M_ff (F level, PME) as control variate,
//     e = w . M_UF w - c (w . M_ff w - 3N m_self(L)),   E[e] = tr M_UF   for any fixed c,
// m_self(L) = (1 - 2.837297 a/L + (4 pi/3)(a/L)^3)/(6 pi mu a) the periodic RPY self-mobility
// (Hasimoto), c = mu/eta_inf'. Units a = mu = kT = 1, D0 = 1/(6 pi).
//
// Expected value at finite N (Ladd 1990, J. Chem. Phys. 93, 3484): a periodic system of side L
// diffuses more slowly by 2.837297 (a/L) (mu/eta_inf') D0,
//     D_N/D0 = D_Abade(phi) - 2.837297 (a/L) mu/eta_inf'(phi),
// eta_inf'/mu = (1 + 1.5 phi g)/(1 - phi g), g = 1 + phi - 0.189 phi^2 (generalised Saito form
// quoted by Abade et al. 2010; quoted from memory, see the benchmark). The finite-size term here
// is the published one, not a number fitted to this code; the benchmark's fitted slopes are 6-25 %
// smaller in magnitude (-2.03 against -2.17 at phi 0.1, -0.89 against -1.11 at phi 0.3,
// docs/benchmarks.md), a difference of at most 0.02 at N = 100, inside the model term below.
// Terms of O((a/L)^3) are below 0.004 at L >= 11 a.
//
// Tolerance: |D_N - expected| <= 0.05 D_Abade + 3 se. The first term is the accuracy goal of
// issue 13 for SD against the exact multipole results (SD is a model: its pairwise lubrication
// and far-field truncation are not exact); the second is statistical, se = max(se of this run,
// s_full / sqrt(configs)), s_full the configuration-to-configuration standard deviation of the
// estimate at N = 100 in the full benchmark run (128 configurations: 0.009 at phi 0.1, 0.008 at
// phi 0.3; 0.010 used). For a
// Gaussian estimate a correct solver fails the statistical part with probability 0.27 %. The test
// has power: free draining (D = 1 at every phi) and the far field alone (no lubrication, measured
// here too) are outside the band at phi = 0.3.
#include <doctest/doctest.h>

#include "engine/hydrodynamics.hpp"
#include "engine/model.hpp"
#include "trees/placement.hpp"

#include <cmath>
#include <random>
#include <vector>

using namespace stokesian;

namespace {

constexpr double kHasimoto = 2.837297;

double abade_fit(double phi) { return 1.0 - 1.8315 * phi * (1.0 + 0.12 * phi - 0.70 * phi * phi); }

double eta_inf_ratio(double phi) {
  const double g = 1.0 + phi - 0.189 * phi * phi;
  return (1.0 + 1.5 * phi * g) / (1.0 - phi * g);
}

struct Estimate {
  double mean = 0.0, se = 0.0, L = 0.0;
};

// D_s/D0 of N spheres at volume fraction phi: `configs` equilibrium hard-sphere configurations
// (seeds seed0 ...), 2 probes each; the standard error is over the configuration means.
Estimate self_diffusion(long n, double phi, int configs, std::uint64_t seed0, HydroModel level) {
  ResolvedModel m;
  m.level = level;
  m.solver = level == HydroModel::stokesian ? "accelerated_sd" : "";
  m.moments = Moments::FTS;
  m.far_field = "pme";
  ResolvedModel mf;
  mf.level = HydroModel::far_field;
  mf.moments = Moments::F;
  mf.far_field = "pme";
  Estimate est;
  est.L = std::cbrt(double(n) * 4.0 / 3.0 * kPi / phi);
  const double L = est.L, c = 1.0 / eta_inf_ratio(phi);
  const double m_self = (1.0 - kHasimoto / L + 4.0 * kPi / 3.0 / (L * L * L)) / (6.0 * kPi);
  std::vector<double> per_config;
  for (int k = 0; k < configs; ++k) {
    PlacementParams pp;
    pp.count = n;
    pp.seed = seed0 + std::uint64_t(k);
    pp.min_gap = 1e-3;
    pp.equilibration_sweeps = 100;
    const Placement pl = place_particles(pp, Vec3(L, L, L));
    Domain d;
    d.kind = Domain::Kind::periodic;
    d.box = pl.box;
    Hydrodynamics h(m, 1.0, AmbientFlow{}, 1e-4), ff(mf, 1.0, AmbientFlow{}, 1e-4);
    std::mt19937_64 rng(7919 * pp.seed);
    std::bernoulli_distribution coin(0.5);
    const std::vector<Vec3> T(static_cast<std::size_t>(n), Vec3::Zero());
    double sum = 0.0;
    for (int probe = 0; probe < 2; ++probe) {
      std::vector<Vec3> w(static_cast<std::size_t>(n));
      for (auto& v : w)
        for (int i = 0; i < 3; ++i) v[i] = coin(rng) ? 1.0 : -1.0;
      const HydroResult r = h.solve(pl.position, pl.radius, {}, w, T, d);
      const HydroResult rf = ff.solve(pl.position, pl.radius, {}, w, T, d);
      double wu = 0.0, wuf = 0.0;
      for (std::size_t i = 0; i < w.size(); ++i) wu += w[i].dot(r.U[i]), wuf += w[i].dot(rf.U[i]);
      sum += 6.0 * kPi * (wu - c * (wuf - 3.0 * double(n) * m_self)) / (3.0 * double(n));
    }
    per_config.push_back(sum / 2.0);
  }
  for (double v : per_config) est.mean += v / configs;
  double s2 = 0.0;
  for (double v : per_config) s2 += (v - est.mean) * (v - est.mean);
  est.se = std::sqrt(s2 / (configs - 1) / configs);
  return est;
}

}  // namespace

TEST_CASE("short-time self-diffusion at phi 0.1 and 0.3 (N = 100) matches Abade et al. 2010 with Ladd's finite-size term") {
  const long n = 100;
  const int configs = 3;
  const double s_full = 0.010;
  for (const double phi : {0.1, 0.3}) {
    const Estimate e = self_diffusion(n, phi, configs, 500 + std::uint64_t(1000 * phi), HydroModel::stokesian);
    const double fit = abade_fit(phi);
    const double expected = fit - kHasimoto / e.L / eta_inf_ratio(phi);
    const double se = std::max(e.se, s_full / std::sqrt(double(configs)));
    const double tol = 0.05 * fit + 3.0 * se;
    CAPTURE(phi);
    CAPTURE(e.L);
    CAPTURE(e.mean);
    CAPTURE(e.se);
    CAPTURE(expected);
    CAPTURE(tol);
    MESSAGE("phi " << phi << " N " << n << " L " << e.L << ": D_s/D0 = " << e.mean << " +- " << e.se << ", expected "
                   << expected << " +- " << tol);
    CHECK(std::abs(e.mean - expected) <= tol);
    if (phi == 0.3) {
      // Power: without lubrication (far field only, stresslets still solved) or without any
      // interactions (D = 1) the same estimate falls outside the band.
      const Estimate f = self_diffusion(n, phi, configs, 500 + std::uint64_t(1000 * phi), HydroModel::far_field);
      MESSAGE("far field only: D_s/D0 = " << f.mean << " +- " << f.se);
      CHECK(std::abs(f.mean - expected) > tol);
      CHECK(std::abs(1.0 - expected) > tol);
    }
  }
}
