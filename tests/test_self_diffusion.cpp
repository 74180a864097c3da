// Short-time self-diffusion of hard-sphere suspensions (issue 13): the accelerated SD solver
// (engine/sd_accelerated.hpp through Hydrodynamics: periodic box, PME, FTS, lubrication) against
// the fit of Abade, Cichocki, Ekiel-Jezewska, Naegele & Wajnryb, J. Chem. Phys. 132, 014503 (2010)
// to exact multipole results, D_s0/D0 = 1 - 1.8315 phi (1 + 0.12 phi - 0.70 phi^2), at small N
// with the finite-size correction made explicit. The full sweep with the extrapolation to
// N -> infinity is bench/validate_diffusion.cpp (docs/benchmarks.md, "Short-time self-diffusion").
//
// Estimator (tests/support/self_diffusion.hpp, shared with the benchmark): D_s0 = kT/(3N) tr M_UF, M_UF the
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

#include "support/self_diffusion.hpp"

#include <algorithm>
#include <cmath>

using namespace stokesian;
using namespace stokesian::self_diffusion;

TEST_CASE("short-time self-diffusion at phi 0.1 and 0.3 (N = 100) matches Abade et al. 2010 with Ladd's finite-size term") {
  const long n = 100;
  const int configs = 3;
  const double s_full = 0.010;
  for (const double phi : {0.1, 0.3}) {
    const Estimate e = estimate(n, phi, configs, 2, 500 + std::uint64_t(1000 * phi), 1e-4, HydroModel::stokesian);
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
      const Estimate f = estimate(n, phi, configs, 2, 500 + std::uint64_t(1000 * phi), 1e-4, HydroModel::far_field);
      MESSAGE("far field only: D_s/D0 = " << f.mean << " +- " << f.se);
      CHECK(std::abs(f.mean - expected) > tol);
      CHECK(std::abs(1.0 - expected) > tol);
    }
  }
}
