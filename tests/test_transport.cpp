// High-frequency viscosity eta'_inf and sedimentation coefficient K (issue 15) from the accelerated SD
// solver (periodic cube, PME, FTS, lubrication; tests/support/transport.hpp states the estimators):
//   eta'_inf/mu = 1 - sum_i S_xy,i / (V mu gdot)   (HydroResult::S is the stresslet on the fluid,
//                                                   -(20/3) pi mu a^3 E for one sphere),
//   K = <U_z> / (F/(6 pi mu a))                    (same force F e_z on every sphere, Ewald frame =
//                                                   zero volume flux).
// References, independent of this code:
//  - Einstein: eta - 1 = 2.5 phi for phi -> 0. One sphere per periodic cube (simple cubic lattice):
//    the lattice correction is O(phi) relative (measured here 1 - 0.83 phi), inside 1 % for
//    phi <= 0.01, the criterion. Random configurations: the exact second virial coefficient
//    of eta'_inf for hard spheres, 5.0 phi^2 (the expansion of the Abade fit,
//    1 + 2.5 phi (1 + 2 phi + O(phi^2))), i.e. (eta - 1)/(2.5 phi) = 1 + 2 phi, to 1 % + 3 se.
//  - Hasimoto (1959) / Zick & Homsy (1982): a simple cubic array of spheres settling in the frame of
//    zero volume flux, K = 1 - 1.7601 phi^(1/3) + phi - 1.5593 phi^2 + O(phi^(8/3)). The phi^(1/3)
//    term is the Oseen field of the images, the phi term the finite size of the sphere (RPY), both in
//    SD's far field; the phi^2 term comes from the images' quadrupolar field (curvature of the flow at
//    the sphere), which SD's multipole truncation at the stresslet does not have (the stresslet
//    induced by the images vanishes by cubic symmetry). SD must therefore reproduce the series
//    through O(phi): checked to 2e-5 (the O(phi^2) term would be 1.6e-4 at phi 0.01).
//  - Abade, Cichocki, Ekiel-Jezewska, Naegele & Wajnryb (2010, 2011) fits to exact multipole results
//    for random hard spheres (docs/transport.md). Tolerances derived from the full benchmark
//    (bench/validate_transport.cpp, docs/transport.md, commit 745748a): SD's eta'_inf deviates from
//    the fit by at most 3.0 % at phi <= 0.5 (0.4 ... 0.8 % at 0.3), so the band is 3 % of the fit
//    + 3 se, se = max(se of this run, s_full / sqrt(configs)), s_full the configuration-to-
//    configuration standard deviation measured in the full run at the same N (0.062 at phi 0.3,
//    N 125); K agrees with the fit at phi 0.1 after Ladd's finite-size correction (+0.5 % at N 500
//    and 2000), so its band is 3 % + 3 se, s_full = 0.019 (phi 0.1, N 500). At phi >= 0.2 SD's K lies above the fit (docs/transport.md);
//    no test asserts agreement there.
//  - Sierou & Brady (2001, J. Fluid Mech. 448, 115, fig. 9; digitised by A. Townsend, values in
//    tests/data/rheology_references.json): settling velocity of a simple cubic array from their own
//    (accelerated) SD code, an independent implementation of the same model; read-off uncertainty
//    about 1 % of the axis range, so the band is 0.01. Zick & Homsy (1982, J. Fluid Mech. 115, 13,
//    table 2; U/U0 = 1/K_drag) give the exact values, which SD exceeds by 5 % at phi 0.125 and by a
//    factor 2.8 at 0.45: the same excess as for random suspensions (docs/transport.md), i.e. a
//    property of SD's multipole truncation, not of this implementation. Printed, not asserted.
// Power: without lubrication (far field only) eta'_inf at phi 0.3 is 2.15 against 2.65 and fails
// the band (checked below); K in the frame of zero mean fluid velocity instead of zero volume flux
// would be 1/(1 - phi) = 11 % higher at phi 0.1, outside the K band; without the finite-size
// correction K(N = 500) is 7 % low, at the edge of the band (not claimed as power).
#include <doctest/doctest.h>

#include "support/transport.hpp"

#include <algorithm>
#include <cmath>

using namespace stokesian;
using namespace stokesian::transport;

TEST_CASE("dilute limit: eta'_inf - 1 = 2.5 phi within 1 % for a simple cubic lattice and random configurations") {
  for (const double phi : {0.001, 0.002, 0.005, 0.01}) {
    const double L = std::cbrt(4.0 / 3.0 * kPi / phi);
    const Sample s = measure({Vec3(0.3 * L, 0.6 * L, 0.1 * L)}, {1.0}, Vec3(L, L, L), 1e-6);
    const double ratio = (s.eta - 1.0) / (2.5 * phi);
    MESSAGE("simple cubic phi " << phi << ": (eta' - 1)/(2.5 phi) = " << ratio);
    CHECK(std::abs(ratio - 1.0) <= 0.01);
  }
  for (const double phi : {0.005, 0.01}) {
    const Estimate e = estimate(32, phi, 4, 11, 1e-4);
    const double ratio = (e.eta - 1.0) / (2.5 * phi), se = e.se_eta / (2.5 * phi), expected = 1.0 + 2.0 * phi;
    MESSAGE("random N 32 phi " << phi << ": (eta' - 1)/(2.5 phi) = " << ratio << " +- " << se << ", expected "
                               << expected);
    CHECK(std::abs(ratio - expected) <= 0.01 * expected + 3.0 * se);
  }
}

TEST_CASE("settling simple cubic lattice: K = 1 - 1.7601 phi^(1/3) + phi (Hasimoto 1959) through O(phi)") {
  for (const double phi : {0.001, 0.002, 0.005, 0.01}) {
    const double L = std::cbrt(4.0 / 3.0 * kPi / phi);
    const Sample s = measure({Vec3(0.3 * L, 0.6 * L, 0.1 * L)}, {1.0}, Vec3(L, L, L), 1e-6);
    const double series = 1.0 - 1.7601 * std::cbrt(phi) + phi;
    MESSAGE("simple cubic phi " << phi << ": K = " << s.K << ", Hasimoto through O(phi) " << series
                                << ", with -1.5593 phi^2 " << series - 1.5593 * phi * phi);
    CHECK(std::abs(s.K - series) <= 2e-5);
    // Both leading terms matter at this size: without them K would be 1.
    CHECK(1.0 - s.K > 0.15);
  }
}

TEST_CASE("random hard spheres: eta'_inf at phi 0.3 and K at phi 0.1 against the Abade et al. fits") {
  {
    const double phi = 0.3, s_full = 0.062;
    const int configs = 4;
    const Estimate e = estimate(125, phi, configs, 900, 1e-4);
    const double fit = abade_eta(phi), se = std::max(e.se_eta, s_full / std::sqrt(double(configs)));
    const double tol = 0.03 * fit + 3.0 * se;
    MESSAGE("phi 0.3 N 125: eta'/mu = " << e.eta << " +- " << e.se_eta << ", fit " << fit << " +- " << tol);
    CHECK(std::abs(e.eta - fit) <= tol);
    const Estimate f = estimate(125, phi, configs, 900, 1e-4, HydroModel::far_field);
    MESSAGE("far field only: eta'/mu = " << f.eta << " +- " << f.se_eta);
    CHECK(std::abs(f.eta - fit) > tol);
  }
  {
    const double phi = 0.1, s_full = 0.019;
    const int configs = 4;
    const Estimate e = estimate(500, phi, configs, 950, 1e-4);
    const double fit = abade_K(phi), se = std::max(e.se_K, s_full / std::sqrt(double(configs)));
    const double tol = 0.03 * fit + 3.0 * se;
    MESSAGE("phi 0.1 N 500: K = " << e.K << " +- " << e.se_K << ", with the finite-size term " << e.K_inf
                                  << ", fit " << fit << " +- " << tol);
    CHECK(std::abs(e.K_inf - fit) <= tol);
    CHECK(std::abs(e.K_inf / (1.0 - phi) - fit) > tol);  // the other frame would be detected
  }
}

TEST_CASE("settling simple cubic lattice at phi 0.125 ... 0.45: Sierou & Brady 2001 (SD) and Zick & Homsy 1982 (exact)") {
  // 5^3 lattice sites in the periodic box (the box must exceed twice the near-field range).
  const double table[][3] = {// phi, SD U/U0 (Sierou & Brady 2001 fig. 9), exact 1/K (Zick & Homsy 1982 table 2)
                             {0.125, 0.2427, 1.0 / 4.292},
                             {0.216, 0.1603, 1.0 / 7.442},
                             {0.343, 0.1111, 1.0 / 15.4},
                             {0.45, 0.1024, 1.0 / 28.1}};
  for (const auto& row : table) {
    const double phi = row[0], h = std::cbrt(4.0 / 3.0 * kPi / phi);
    const int m = 5;
    std::vector<Vec3> x;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j)
        for (int k = 0; k < m; ++k) x.push_back(Vec3(h * (i + 0.5), h * (j + 0.5), h * (k + 0.5)));
    const Sample s = measure(x, std::vector<double>(x.size(), 1.0), Vec3(m * h, m * h, m * h), 1e-4);
    MESSAGE("simple cubic phi " << phi << ": K = " << s.K << ", Sierou & Brady SD " << row[1] << ", Zick & Homsy exact "
                                << row[2]);
    CHECK(std::abs(s.K - row[1]) <= 0.01);
  }
}
