// Periodic far field (ewald/): the Ewald reference against analytic limits and its own splitting,
// its structure (symmetric positive definite, Lees-Edwards periodic in strain), and the PME
// operator against the reference over a tolerance sweep.
//
// Error metric used throughout (defined once): rel_error(y, y_ref) = ||y - y_ref|| / ||y_ref|| for
// y = M x on random Gaussian x (fixed seeds).
#include <doctest/doctest.h>

#include "support/random.hpp"
#include "support/threads.hpp"

#include "engine/kernels/far_field.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_reference.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/pme.hpp"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

using namespace stokesian;
using stokesian::test::random_vector;
using mobility::PairScalars;

namespace {
constexpr double pi = 3.14159265358979323846;

Domain box(const Vec3& L, double strain = 0.0) { return Domain::periodic_box(L, strain); }
Domain cube(double L, double strain = 0.0) { return box(Vec3(L, L, L), strain); }

double rel_error(const VecX& y, const VecX& ref) { return (y - ref).norm() / ref.norm(); }
double rel_error(const MatX& A, const MatX& B) { return (A - B).norm() / B.norm(); }

struct Config {
  std::vector<Vec3> x;
  std::vector<double> a;
};
// Uniform random centres (overlaps allowed: the regularised kernel must hold) and radii in [amin, amax].
Config random_config(int n, const Vec3& L, double amin, double amax, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Config c;
  for (int i = 0; i < n; ++i) {
    c.x.emplace_back(L.x() * u(rng), L.y() * u(rng), L.z() * u(rng));
    c.a.push_back(amin + (amax - amin) * u(rng));
  }
  return c;
}


std::vector<double> as_list(const PairScalars& s) {
  return {s.xa, s.ya, s.yb, s.ybt, s.xc, s.yc, s.xg, s.yg, s.xgt, s.ygt, s.yh, s.yht, s.xm, s.ym, s.zm};
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Layer 1: the splitting itself.

TEST_CASE("split: self wave term equals its k-space integrals") {
  // Closed forms of the integrals in ewald_split.hpp (sympy): with c the Faxen coefficient,
  //   int P^2 H dk = sqrt(pi) (42 c^2 xi^5 - 10 c xi^3 + 3 xi / 2),
  //   int k^2 P^2 H dk = sqrt(pi) (540 c^2 xi^7 - 84 c xi^5 + 5 xi^3).
  // The series path (r = 0) and the integrals are independent: agreement to rounding, 1e-13.
  const double mu = 0.7, sp = std::sqrt(pi);
  for (double a : {0.3, 1.0, 2.5})
    for (double xi : {0.2, 0.7, 1.3}) {
      const PairScalars w = ewald::wave_scalars(a, a, 0.0, xi, mu, Moments::FTS);
      const double cF = a * a / 6, cT = a * a / 10;
      const double IF = sp * (42 * cF * cF * std::pow(xi, 5) - 10 * cF * std::pow(xi, 3) + 1.5 * xi);
      const double IT = sp * (540 * cT * cT * std::pow(xi, 7) - 84 * cT * std::pow(xi, 5) + 5 * std::pow(xi, 3));
      CAPTURE(a);
      CAPTURE(xi);
      CHECK(w.xa == doctest::Approx(IF / (3 * pi * pi * mu)).epsilon(1e-13));
      CHECK(w.ya == doctest::Approx(IF / (3 * pi * pi * mu)).epsilon(1e-13));
      CHECK(w.xc == doctest::Approx(IT / (12 * pi * pi * mu)).epsilon(1e-13));
      CHECK(w.yc == doctest::Approx(IT / (12 * pi * pi * mu)).epsilon(1e-13));
      CHECK(w.xm == doctest::Approx(IT / (10 * pi * pi * mu)).epsilon(1e-13));
      CHECK(w.ym == doctest::Approx(IT / (10 * pi * pi * mu)).epsilon(1e-13));
      CHECK(w.zm == doctest::Approx(IT / (10 * pi * pi * mu)).epsilon(1e-13));
      CHECK(std::abs(w.yb) + std::abs(w.xg) + std::abs(w.yh) == 0.0);
    }
}

TEST_CASE("split: real + wave = free kernel; series and closed form join continuously") {
  // Separated pairs: real (erfc form) + wave (closed form or series) must rebuild the exact
  // polydisperse kernel; overlapping pairs by construction. Scale: the largest |scalar| of the
  // free pair; 1e-12 leaves room for the cancellation r + 2c/r - R at xi r ~ 5.
  const double mu = 1.3;
  for (double a : {0.5, 1.0})
    for (double b : {0.5, 2.0})
      for (double xi : {0.3, 1.0})
        for (double r : {0.1, 0.9, 1.6, 2.6, 3.0, 5.0}) {
          const PairScalars f = mobility::pair_scalars(a, b, r, mu, Moments::FTS);
          const auto re = as_list(ewald::real_scalars(a, b, r, xi, mu, Moments::FTS));
          const auto wa = as_list(ewald::wave_scalars(a, b, r, xi, mu, Moments::FTS));
          const auto fr = as_list(f);
          double scale = 0;
          for (double v : fr) scale = std::max(scale, std::abs(v));
          for (std::size_t q = 0; q < fr.size(); ++q) {
            CAPTURE(q);
            CAPTURE(r);
            CHECK(std::abs(re[q] + wa[q] - fr[q]) < 1e-12 * scale);
          }
        }
  // Continuity of the wave scalars across the series threshold xi r = 0.5.
  const double xi = 0.8, r0 = 0.5 / xi;
  const auto lo = as_list(ewald::wave_scalars(1.0, 1.7, r0 * (1 - 1e-12), xi, mu, Moments::FTS));
  const auto hi = as_list(ewald::wave_scalars(1.0, 1.7, r0 * (1 + 1e-12), xi, mu, Moments::FTS));
  for (std::size_t q = 0; q < lo.size(); ++q) CHECK(std::abs(lo[q] - hi[q]) < 1e-12 * (1.0 + std::abs(lo[q])));
}

// ---------------------------------------------------------------------------------------------
// Layer 2: the Ewald reference.

TEST_CASE("Ewald: single sphere in a cubic box matches Hasimoto (1959)") {
  // (1/6 pi mu a)(1 - 2.837297 a/L + (4 pi/3)(a/L)^3) (docs/ewald.md). The constant is given to 7
  // digits (error < 5e-7 a/L) and the RPY lattice sum has further terms beyond (a/L)^3 (measured
  // ~(a/L)^6 scale); 2e-6 relative for a/L <= 0.2.
  const double mu = 1.0, a = 1.0;
  for (double L : {5.0, 10.0, 40.0}) {
    const double q = a / L;
    const double expect = (1.0 - 2.837297 * q + 4.0 * pi / 3.0 * q * q * q) / (6 * pi * mu * a);
    const MatX M = ewald::ewald_mobility({Vec3(0.3, 0.1, 0.2)}, {a}, mu, Moments::FTS, cube(L));
    CAPTURE(L);
    for (int i = 0; i < 3; ++i) CHECK(std::abs(M(i, i) - expect) < 2e-6 * expect);
    // Cubic symmetry: translation-rotation and translation-strain couplings vanish for one sphere.
    CHECK(M.block(0, 3, 3, 8).norm() < 1e-14 * M.norm());
  }
}

TEST_CASE("Ewald: independent of the splitting parameter (FTS, polydisperse, overlaps, shear)") {
  // Both sums are truncated at exp(-56), so xi only changes rounding: the sums over ~300 images and
  // wave vectors give ~1e-15; 1e-13 allows for the cancellation in exact - wave at overlaps.
  const Vec3 L(6.0, 6.0, 6.0);
  const Config c = random_config(6, L, 0.5, 1.5, 3);
  for (double strain : {0.0, 0.3}) {
    const MatX M0 = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, strain), {0.25});
    for (double xi : {0.5, 1.0}) {
      const MatX M1 = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, strain), {xi});
      CAPTURE(strain);
      CAPTURE(xi);
      CHECK(rel_error(M1, M0) < 1e-13);
    }
  }
}

TEST_CASE("Ewald: symmetric positive definite") {
  // M is a lattice Gram matrix sum_k R(k) G(k) R(k)^+ (ewald_split.hpp), so it is SPD for every
  // configuration, overlapping ones included. Symmetry is not imposed (both orders are summed):
  // 1e-14 is rounding.
  const Vec3 L(7.0, 6.0, 8.0);
  const Config c = random_config(12, L, 0.4, 1.6, 17);
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    const MatX M = ewald::ewald_mobility(c.x, c.a, 0.9, m, box(L, 0.2));
    CHECK((M - M.transpose()).norm() < 1e-14 * M.norm());
    const Eigen::SelfAdjointEigenSolver<MatX> es(M);
    CAPTURE(to_string(m));
    CHECK(es.eigenvalues().minCoeff() > 0.0);
  }
}

TEST_CASE("Ewald: tends to free space as L grows, with the Hasimoto 1/L correction") {
  // For a pair at distance r << L the periodic sum differs from the free kernel by the uniform
  // lattice term -2.837297 / (6 pi mu L) I plus O(r^2 / L^3): L (M_periodic - M_free) for the
  // translational pair block tends to -2.837297/(6 pi mu) I with error O((r/L)^2) (~4e-3 at L = 50).
  const double mu = 1.0;
  const std::vector<Vec3> x{Vec3(1.0, 2.0, 3.0), Vec3(2.5, 3.2, 1.9)};
  const std::vector<double> a{1.0, 0.6};
  const MatX free = dense_mobility(x, a, mu, Moments::F);
  double prev = 1e300;
  for (double L : {25.0, 50.0, 100.0}) {
    const MatX M = ewald::ewald_mobility(x, a, mu, Moments::F, cube(L));
    const Mat3 D = L * (M.block(0, 3, 3, 3) - free.block(0, 3, 3, 3));
    const double err = (D + 2.837297 / (6 * pi * mu) * Mat3::Identity()).norm() / (2.837297 / (6 * pi * mu));
    CAPTURE(L);
    CHECK(err < 2.0 * std::pow(4.0 / L, 2));
    CHECK(err < prev);
    prev = err;
  }
}

TEST_CASE("Ewald: FTS tends to free space; after the 1/L term the remainder falls as L^-3") {
  // All FTS blocks: M_periodic - M_free = -2.837297/(6 pi mu L) I on the translational blocks +
  // O(L^-3) (the lattice rotlet / stresslet fields and the (4 pi / 3)(a/L)^3-type terms). Measured
  // L^3 ||remainder|| / ||M_free|| = 6.89, 6.96, 6.98, 6.98 at L = 25, 50, 100, 200: check the
  // L^-3 law to 1% between L = 50 and 100.
  const double mu = 1.0;
  const std::vector<Vec3> x{Vec3(1.0, 2.0, 3.0), Vec3(2.5, 3.2, 1.9)};
  const std::vector<double> a{1.0, 0.6};
  const MatX free = dense_mobility(x, a, mu, Moments::FTS);
  double scaled[2];
  int q = 0;
  for (double L : {50.0, 100.0}) {
    MatX D = ewald::ewald_mobility(x, a, mu, Moments::FTS, cube(L)) - free;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) D.block(11 * i, 11 * j, 3, 3) += 2.837297 / (6 * pi * mu * L) * Mat3::Identity();
    scaled[q++] = D.norm() / free.norm() * L * L * L;
  }
  CHECK(scaled[1] == doctest::Approx(scaled[0]).epsilon(0.01));
  CHECK(scaled[1] < 10.0);
}

TEST_CASE("Ewald: Lees-Edwards lattice is periodic and continuous in the strain") {
  // gamma and gamma + Lx/Ly give the same lattice: identical sums up to rounding (1e-13). A small
  // strain change moves the matrix by O(d gamma) (continuity); a generic strain differs from 0.
  const Vec3 L(6.0, 6.0, 7.0);
  const Config c = random_config(5, L, 0.6, 1.2, 23);
  for (double g : {0.15, 0.49}) {
    const MatX M0 = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, g));
    const MatX M1 = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, g + 1.0));
    const MatX M2 = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, g - 2.0));
    const MatX Md = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, g + 0.02));
    const MatX Mz = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, 0.0));
    CHECK(rel_error(M1, M0) < 1e-13);
    CHECK(rel_error(M2, M0) < 1e-13);
    CHECK(rel_error(Md, M0) < 0.02);
    CHECK(rel_error(Mz, M0) > 1e-4);
  }
  // Lx != Ly: the period is Lx / Ly (1.5 here), and gamma + 1 is a different lattice.
  const Vec3 Lr(12.0, 8.0, 10.0);
  const Config r = random_config(6, Lr, 0.4, 1.0, 29);
  const MatX R0 = ewald::ewald_mobility(r.x, r.a, 1.0, Moments::FTS, box(Lr, 0.2));
  CHECK(rel_error(ewald::ewald_mobility(r.x, r.a, 1.0, Moments::FTS, box(Lr, 1.7)), R0) < 1e-13);
  CHECK(rel_error(ewald::ewald_mobility(r.x, r.a, 1.0, Moments::FTS, box(Lr, 1.2)), R0) > 1e-3);
  // Across the remap at gamma = 1/2 (reduced strain jumps from 1/2 to -1/2): continuous.
  const MatX Ma = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, 0.5 - 1e-9));
  const MatX Mb = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, 0.5 + 1e-9));
  CHECK(rel_error(Mb, Ma) < 1e-8);
}

TEST_CASE("Ewald: simple cubic array sedimentation vs Zick & Homsy (1982)") {
  // One sphere per cubic cell of side L, phi = (4 pi / 3)(a/L)^3. Drag coefficient K = F/(6 pi mu a U)
  // = 1 / (6 pi mu a M_11) (T and S vanish by cubic symmetry, so F, FT and FTS agree).
  // Reference K: Zick & Homsy (1982) Table 2, simple cubic, as quoted in two independent public
  // sources that agree where they overlap: the Basilisk test src/test/spheres.c (K at
  // phi = 0.027 ... 0.45) and the rajeshrinet/pystokes example "mobility as a function of volume
  // fraction" (1/K = 0.8251 at phi = 0.001, 0.4980 at 0.027, ...).
  // The far field reproduces Hasimoto's 1/K = 1 - 1.7601 phi^(1/3) + phi and misses the O(phi^2)
  // term of the exact dilute series (Sangani & Acrivos 1982: ... - 1.5593 phi^2 + ...), so its
  // relative error in K grows like 1.56 phi^2 K: 1e-5 at phi = 0.001, 0.2% at 0.027, 1.5% at
  // 0.064; beyond that the far-field model fails (16% at 0.216; docs/ewald.md s.6).
  struct Row {
    double phi, K;
  };
  const Row zh[] = {{0.001, 1.0 / 0.8251}, {0.027, 2.008}, {0.064, 2.810}, {0.125, 4.292},
                    {0.216, 7.442},        {0.343, 15.4},  {0.45, 28.1}};
  const double mu = 1.0, a = 1.0;
  for (const Row& row : zh) {
    const double L = a * std::cbrt(4.0 * pi / (3.0 * row.phi));
    const MatX M = ewald::ewald_mobility({Vec3::Zero()}, {a}, mu, Moments::FTS, cube(L));
    const double K = 1.0 / (6 * pi * mu * a * M(0, 0));
    const double hasimoto = 1.0 / (1.0 - 1.7601 * std::cbrt(row.phi) + row.phi);
    MESSAGE("phi " << row.phi << "  K(far field) " << K << "  K(Zick-Homsy) " << row.K << "  rel.dev "
                   << K / row.K - 1.0);
    CAPTURE(row.phi);
    // The far-field model is Hasimoto's series, up to RPY lattice terms beyond phi (~1e-4 at 0.216).
    if (row.phi < 0.3) CHECK(K == doctest::Approx(hasimoto).epsilon(2e-4));
    // Dilute agreement with the exact values: the 4-digit table (6e-5) plus the missing phi^2 term.
    if (row.phi < 0.01) CHECK(std::abs(K / row.K - 1.0) < 3e-4);
    else if (row.phi < 0.03) CHECK(std::abs(K / row.K - 1.0) < 0.005);
    else if (row.phi < 0.07) CHECK(std::abs(K / row.K - 1.0) < 0.02);
    else CHECK(K < row.K);  // far field under-predicts the drag of dense arrays
  }
}

// ---------------------------------------------------------------------------------------------
// Layer 3: PME against the reference.

TEST_CASE("PME: requested tolerance met from 1e-2 to 1e-10 (F, FT, FTS; polydisperse; sheared)") {
  // The achieved error must not exceed the request (pme_parameters.hpp states the error model).
  struct Case {
    int n;
    Vec3 L;
    double amin, amax, strain;
  };
  // Monodisperse cases also get a lower bound: the error model (pme_parameters.hpp) places the
  // achieved error between tol / 10 and tol; 0.05 tol is asserted to catch wasteful parameters.
  // Polydisperse suspensions are held to the model of their largest sphere and land lower.
  const Case cases[] = {{5, Vec3(8, 8, 8), 1.0, 1.0, 0.0},
                        {60, Vec3(11, 11, 11), 1.0, 1.0, 0.0},
                        {40, Vec3(14, 14, 14), 0.5, 1.5, 0.0},
                        {25, Vec3(12, 10, 11), 0.4, 1.2, 0.37}};
  int which = 0;
  for (const Case& cs : cases) {
    const Config c = random_config(cs.n, cs.L, cs.amin, cs.amax, 100 + which++);
    const Domain dom = box(cs.L, cs.strain);
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      const ewald::EwaldFarField ref(c.x, c.a, 1.0, m, dom);
      const VecX x = random_vector(ref.size(), 7);
      VecX yref;
      ref.apply(x, yref);
      // Parameters priced for many products per configuration (0) and with the set-up priced for
      // one product (far-field dynamics): other parameters, the same accuracy contract.
      for (double ppu : {0.0, 1.0})
        for (double tol : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10}) {
          ewald::PmeOptions o;
          o.products_per_update = ppu;
          const ewald::PmeFarField pme(c.x, c.a, 1.0, m, dom, tol, o);
          VecX y;
          pme.apply(x, y);
          const double err = rel_error(y, yref);
          CAPTURE(cs.n);
          CAPTURE(to_string(m));
          CAPTURE(tol);
          CAPTURE(ppu);
          CHECK(err < tol);
          if (cs.amin == cs.amax) CHECK(err > 0.05 * tol);
          std::printf("pme-sweep n=%d strain=%.2f %s ppu=%g tol=%.0e err=%.2e M=%d P=%d pairs=%zu\n", cs.n, cs.strain,
                      to_string(m), ppu, tol, err, pme.parameters().grid[0], pme.parameters().support,
                      pme.real_pairs());
        }
    }
  }
}

TEST_CASE("PME: single sphere matches Hasimoto (1959)") {
  // PME at tolerance 1e-8 against the formula: the formula's own 2e-6 (see the Ewald case) dominates.
  const double a = 1.0;
  for (double L : {5.0, 10.0}) {
    const double q = a / L;
    const double expect = (1.0 - 2.837297 * q + 4.0 * pi / 3.0 * q * q * q) / (6 * pi * a);
    const ewald::PmeFarField pme({Vec3(1.0, 2.0, 3.0)}, {a}, 1.0, Moments::F, cube(L), 1e-8);
    VecX y;
    pme.apply(Vec3::UnitX(), y);
    CAPTURE(L);
    CHECK(std::abs(y[0] - expect) < 3e-6 * expect);
    CHECK(std::abs(y[1]) + std::abs(y[2]) < 1e-8 * expect);
  }
}

TEST_CASE("PME: Lees-Edwards periodic in strain and continuous across the remap") {
  // gamma and gamma + 1 reduce to the same lattice, grid and window: identical products (1e-14).
  // Across gamma = 1/2 the lattice basis (hence the grid's orientation) changes (reduced strain
  // 1/2 -> -1/2), so the two products differ by at most the PME error on each side: 2 tol.
  const Vec3 L(9.0, 9.0, 9.0);
  const Config c = random_config(20, L, 0.5, 1.0, 31);
  const double tol = 1e-6;
  const VecX x = random_vector(20 * 11, 4);
  VecX y0, y1, ya, yb;
  ewald::PmeFarField(c.x, c.a, 1.0, Moments::FTS, box(L, 0.3), tol).apply(x, y0);
  ewald::PmeFarField(c.x, c.a, 1.0, Moments::FTS, box(L, 1.3), tol).apply(x, y1);
  CHECK(rel_error(y1, y0) < 1e-14);
  ewald::PmeFarField(c.x, c.a, 1.0, Moments::FTS, box(L, 0.5 - 1e-9), tol).apply(x, ya);
  ewald::PmeFarField(c.x, c.a, 1.0, Moments::FTS, box(L, 0.5 + 1e-9), tol).apply(x, yb);
  CHECK(rel_error(yb, ya) < 2 * tol);
}

TEST_CASE("translation invariance: arbitrary shifts (Ewald) and lattice shifts (PME)") {
  // A rigid translation leaves every separation unchanged: the Ewald matrix to rounding (1e-13).
  // PME windows move relative to the grid, so a generic shift changes the product by at most the
  // PME error on each side (2 tol); a shift by the sheared lattice vector a2 (and wrapping out of
  // the box, negative coordinates) leaves fractional coordinates unchanged up to rounding.
  const Vec3 L(9.0, 8.0, 10.0);
  const double strain = 0.3;
  const Config c = random_config(12, L, 0.5, 1.2, 51);
  Config shifted = c, lattice_shifted = c;
  const Vec3 a2(strain * L.y(), L.y(), 0.0);
  for (auto& p : shifted.x) p += Vec3(-13.7, 4.2, 0.35);
  for (auto& p : lattice_shifted.x) p -= 2.0 * a2 + Vec3(L.x(), 0.0, -L.z());
  const MatX M0 = ewald::ewald_mobility(c.x, c.a, 1.0, Moments::FTS, box(L, strain));
  const MatX M1 = ewald::ewald_mobility(shifted.x, shifted.a, 1.0, Moments::FTS, box(L, strain));
  CHECK(rel_error(M1, M0) < 1e-13);
  const double tol = 1e-6;
  const VecX x = random_vector(M0.rows(), 9);
  VecX y0, y1, y2;
  ewald::PmeFarField(c.x, c.a, 1.0, Moments::FTS, box(L, strain), tol).apply(x, y0);
  ewald::PmeFarField(shifted.x, shifted.a, 1.0, Moments::FTS, box(L, strain), tol).apply(x, y1);
  ewald::PmeFarField(lattice_shifted.x, lattice_shifted.a, 1.0, Moments::FTS, box(L, strain), tol).apply(x, y2);
  CHECK(rel_error(y1, y0) < 2 * tol);
  CHECK(rel_error(y2, y0) < 1e-12);
  CHECK(rel_error(y0, M0 * x) < tol);
}

TEST_CASE("coincident and nested centres: finite, and PME matches the reference") {
  // Two distinct spheres at the same centre (nested, regularised kernel) must give finite,
  // symmetric blocks; the overlap correction is in the real-space part of both implementations.
  const Vec3 L(8.0, 8.0, 8.0);
  const std::vector<Vec3> x{Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1.3, 2.1, 2.9), Vec3(5, 5, 5)};
  const std::vector<double> a{1.0, 0.5, 0.3, 1.2};
  const MatX M = ewald::ewald_mobility(x, a, 1.0, Moments::FTS, box(L, 0.1));
  CHECK(M.allFinite());
  CHECK((M - M.transpose()).norm() < 1e-14 * M.norm());
  const VecX v = random_vector(M.rows(), 3);
  VecX y;
  ewald::PmeFarField(x, a, 1.0, Moments::FTS, box(L, 0.1), 1e-8).apply(v, y);
  CHECK(rel_error(y, M * v) < 1e-8);
}

TEST_CASE("PME: update_positions equals a new operator") {
  // Same parameters, grid and plans; windows and pairs rebuilt: bitwise equal products.
  const Vec3 L(10.0, 10.0, 10.0);
  const Config c0 = random_config(30, L, 0.5, 1.0, 61), c1 = random_config(30, L, 0.5, 1.0, 62);
  const VecX x = random_vector(30 * 6, 8);
  ewald::PmeFarField moved(c0.x, c0.a, 1.0, Moments::FT, box(L, 0.2), 1e-5);
  moved.update_positions(c1.x);
  VecX y0, y1;
  moved.apply(x, y0);
  ewald::PmeFarField(c1.x, c0.a, 1.0, Moments::FT, box(L, 0.2), 1e-5).apply(x, y1);
  CHECK((y0 - y1).norm() == 0.0);
}

TEST_CASE("PME: deterministic for a given thread count and independent of it") {
  // Slab colouring fixes every summation order (spread.hpp), so 1 and 2 threads agree bitwise.
  const Vec3 L(12.0, 12.0, 12.0);
  const Config c = random_config(60, L, 0.5, 1.5, 41);
  const VecX x = random_vector(60 * 11, 5);
  const ewald::PmeFarField pme(c.x, c.a, 1.0, Moments::FTS, box(L), 1e-6);
  VecX y1, y2, y3;
  {
    const test::ThreadCount one(1);
    pme.apply(x, y1);
  }
  {
    const test::ThreadCount two(2);
    pme.apply(x, y2);
    pme.apply(x, y3);
  }
  CHECK((y1 - y2).norm() == 0.0);
  CHECK((y2 - y3).norm() == 0.0);
}

// ---------------------------------------------------------------------------------------------
// PME building blocks against plain evaluations.

#include "ewald/interpolate.hpp"
#include "ewald/spread.hpp"
#include "engine/core/sym_traceless.hpp"

TEST_CASE("PME window: transforms match quadrature, derivatives match finite differences") {
  // phihat(nu) = int phi(t) e^{-2 pi i nu t} dt by composite Simpson on [-P/2, P/2] (2e4 panels; the
  // Kaiser-Bessel window jumps to 1/I0(beta) at the edge, which Simpson integrates exactly there).
  for (const auto& [kind, P, shape] : {std::tuple{ewald::WindowKind::kaiser_bessel, 8, 18.0},
                                       std::tuple{ewald::WindowKind::kaiser_bessel, 13, 35.0},
                                       std::tuple{ewald::WindowKind::gaussian, 12, 1.0}}) {
    const ewald::Window1D w(kind, P, shape);
    const int panels = 20000;
    const double h = double(P) / panels;
    for (double nu : {0.0, 0.1, 0.25, 0.5, 0.75, 1.0, 1.5}) {
      double sum = 0.0;
      for (int i = 0; i <= panels; ++i) {
        const double t = -0.5 * P + i * h;
        const double wt = (i == 0 || i == panels) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += wt * w.value(t) * std::cos(2.0 * pi * nu * t);
      }
      sum *= h / 3.0;
      const double tr = w.transform(nu);
      CAPTURE(std::string(ewald::to_string(kind)));
      CAPTURE(nu);
      if (kind == ewald::WindowKind::kaiser_bessel) CHECK(std::abs(tr - sum) < 1e-10 * w.transform(0.0));
      else CHECK(std::abs(tr - sum) < 1e-6 * w.transform(0.0));  // the Gaussian's truncated tails: e^{-P^2/(8 s^2)}
    }
    for (double t : {-0.3 * P, -1.1, 0.0, 0.7, 0.45 * P}) {
      double d[4], dp[4], dm[4];
      const double e = 1e-5;
      w.derivatives(t, d);
      w.derivatives(t + e, dp);
      w.derivatives(t - e, dm);
      for (int j = 0; j < 3; ++j) CHECK(std::abs((dp[j] - dm[j]) / (2 * e) - d[j + 1]) < 1e-6 * (1.0 + std::abs(d[j + 1])));
    }
  }
}

TEST_CASE("PME window table: the polynomial form equals the window's series over the searched range") {
  // Reference twin: Window1D::derivatives (power series of I0, exact to rounding). Every window the
  // parameter search can choose (P = 3..32, beta = kappa pi P (1 - 1/(2 sigma)), kappa 0.9..1.5,
  // sigma 1..2) and Gaussians of the widths it uses; tolerance kFitError of each derivative's largest
  // value, at offsets other than the fitting and checking points.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int checked = 0;
  double worst = 0.0;
  for (int P = 3; P <= 32; ++P)
    for (double kappa : {0.9, 1.2, 1.5})
      for (double sigma : {1.0, 1.35, 2.0}) {
        const ewald::Window1D w(ewald::WindowKind::kaiser_bessel, P, kappa * pi * P * (1.0 - 0.5 / sigma));
        const ewald::WindowTable t(w);
        CAPTURE(P);
        CAPTURE(kappa);
        CAPTURE(sigma);
        REQUIRE(t.fit_error() <= ewald::WindowTable::kFitError);
        std::array<double, 4> scale{};
        for (int i = 0; i <= 64 * P; ++i) {
          double v[4];
          w.derivatives(-0.5 * P + i / 64.0, v);
          for (int d = 0; d < 4; ++d) scale[d] = std::max(scale[d], std::abs(v[d]));
        }
        std::vector<double> out(4 * P);
        for (int r = 0; r < 20; ++r) {
          const double tau = u01(rng);
          t.evaluate(tau, out.data());
          for (int j = 0; j < P; ++j) {
            double v[4];
            w.derivatives(-0.5 * P + j + tau, v);
            for (int d = 0; d < 4; ++d) worst = std::max(worst, std::abs(out[d * P + j] - v[d]) / scale[d]);
          }
        }
        ++checked;
      }
  // Gaussians as the search chooses them (support and width from pme_parameters).
  const ewald::Lattice lat = ewald::Lattice::from_domain(box(Vec3(20.0, 20.0, 20.0)));
  for (double tol : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10}) {
    ewald::PmeOptions o;
    o.window = ewald::WindowKind::gaussian;
    const ewald::PmeParameters p = ewald::pme_parameters(tol, lat, 500, 1.0, 1.0, Moments::FTS, o);
    const ewald::WindowTable t(ewald::Window1D(ewald::WindowKind::gaussian, p.support, p.shape));
    CAPTURE(tol);
    CHECK(t.fit_error() <= ewald::WindowTable::kFitError);
  }
  MESSAGE("window tables: " << checked << " Kaiser-Bessel windows, worst relative error at random offsets " << worst);
  CHECK(checked == 30 * 9);
  CHECK(worst <= 2.0 * ewald::WindowTable::kFitError);
}

// Grid, windows and colouring of a small sheared box with support P (Kaiser-Bessel, beta = 2.3 P).
namespace {
struct SmallGrid {
  ewald::GridGeometry g;
  Config c;
  std::vector<Vec3> s;
  ewald::ParticleWindows win;
  ewald::SlabColouring colouring;
};
SmallGrid small_grid(int P, std::array<int, 3> M, int n, unsigned seed) {
  SmallGrid r;
  ewald::GridGeometry& g = r.g;
  g.M = M;
  g.P = P;
  g.set_window(ewald::Window1D(ewald::WindowKind::kaiser_bessel, g.P, 2.3 * P));
  const Domain dom = box(Vec3(9.0, 8.0, 10.0), 0.3);
  const ewald::Lattice lat = ewald::Lattice::from_domain(dom);
  for (int d = 0; d < 3; ++d) g.J.row(d) = g.M[d] * lat.Ainv.row(d);
  g.lap = g.J * g.J.transpose();
  g.row = ewald::row_length(g.M[2], g.P);
  r.c = random_config(n, Vec3(9.0, 8.0, 10.0), 0.5, 1.5, seed);
  for (const Vec3& x : r.c.x) r.s.push_back(lat.Ainv * x);
  r.win = ewald::make_windows(g, r.s, r.c.a);
  r.colouring = ewald::colour_slabs(g, r.win);
  return r;
}
// Grid fields with ghost points filled from the periodic values, from an unpadded velocity field.
std::vector<double> padded_field(const ewald::GridGeometry& g, const VecX& u) {
  std::vector<double> padded(g.stored() * 3, 0.0);
  for (int a = 0; a < 3; ++a)
    for (int i0 = 0; i0 < g.M[0]; ++i0)
      for (int i1 = 0; i1 < g.M[1]; ++i1)
        for (int i2 = 0; i2 < g.row; ++i2)
          padded[a * g.stored() + ewald::grid_offset(g, i0, i1, i2)] =
              u[a * g.points() + (long(i0) * g.M[1] + i1) * g.M[2] + i2 % g.M[2]];
  return padded;
}
}  // namespace

TEST_CASE("PME spreading and interpolation: fast kernels and generic loops against a plain point-by-point sum") {
  // Reference: for every particle and every grid point of its window, W, grad W and lap W from the
  // 1D derivatives directly (no row coefficients, no ghost points), accumulated on an unpadded grid.
  // Checked for every path (fast kernels with AVX2 where the CPU has it, fast kernels on the
  // baseline ISA, generic loops) and supports P = 3 ... 13 and 31 ... 34, which cover every padded
  // width of the fast kernels' partial vectors and the switch to the generic loops above 32.
  int cases = 0;
  for (int P : {3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 31, 32, 33, 34}) {
    CAPTURE(P);
    const int big = std::max(P + 2, 12);
    SmallGrid sg = small_grid(P, {big, big - 2 + (P % 2), big + 2}, 7, 77);
    const ewald::GridGeometry& g = sg.g;
    const std::vector<Vec3>& s = sg.s;
    ++cases;
    const ewald::ParticleWindows& win = sg.win;
    // The windows from the table equal the series at the particles' offsets (WindowTable::kFitError of
    // each derivative's largest value).
    std::array<double, 4> wscale{};
    for (int i = 0; i <= 64 * g.P; ++i) {
      double v[4];
      g.window.derivatives(-0.5 * g.P + i / 64.0, v);
      for (int k = 0; k < 4; ++k) wscale[k] = std::max(wscale[k], std::abs(v[k]));
    }
    for (long p = 0; p < 7; ++p)
      for (int dir = 0; dir < 3; ++dir) {
        const double pos = (s[p][dir] - std::floor(s[p][dir])) * g.M[dir];
        const int i0 = int(std::ceil(pos - 0.5 * g.P));
        CHECK(win.start[p][dir] == ((i0 % g.M[dir]) + g.M[dir]) % g.M[dir]);
        for (int j = 0; j < g.P; ++j) {
          double v[4];
          g.window.derivatives((i0 + j) - pos, v);
          for (int k = 0; k < 4; ++k)
            CHECK(std::abs(win.at(p, dir, k)[j] - v[k]) <= ewald::WindowTable::kFitError * wscale[k]);
        }
      }
    const auto& colouring = sg.colouring;
    const auto& basis = sym_traceless_basis();
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      const int d = dof_per_particle(m);
      const VecX q = random_vector(7 * d, 3);
      std::vector<double> ref(g.points() * 3, 0.0);
      const VecX u = random_vector(g.points() * 3, 4);  // a velocity field for the interpolation check
      VecX yref = VecX::Zero(7 * d);
      for (long p = 0; p < 7; ++p) {
        const double* qp = q.data() + p * d;
        Mat3 S = Mat3::Zero();
        Vec3 T = Vec3::Zero();
        if (d > 3) T = Vec3(qp[3], qp[4], qp[5]);
        if (d > 6)
          for (int b = 0; b < 5; ++b) S += qp[6 + b] * basis[b];
        for (int j0 = 0; j0 < g.P; ++j0)
          for (int j1 = 0; j1 < g.P; ++j1)
            for (int j2 = 0; j2 < g.P; ++j2) {
              const int jj[3] = {j0, j1, j2};
              double w[3][4];
              for (int dir = 0; dir < 3; ++dir)
                for (int k = 0; k < 4; ++k) w[dir][k] = win.at(p, dir, k)[jj[dir]];
              // Derivatives of W in grid units: D1[i], D2[i][j], D3[l][i][j] (d_l d_i d_j).
              auto der = [&](int n0, int n1, int n2) { return w[0][n0] * w[1][n1] * w[2][n2]; };
              auto order = [](int i, int j, int l, int dir) { return int(i == dir) + int(j == dir) + int(l == dir); };
              double W = der(0, 0, 0), lap = 0.0;
              Vec3 grad, gradlap = Vec3::Zero();
              for (int i = 0; i < 3; ++i) grad[i] = der(i == 0, i == 1, i == 2);
              for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                  lap += g.lap(i, j) * der((i == 0) + (j == 0), (i == 1) + (j == 1), (i == 2) + (j == 2));
                  for (int l = 0; l < 3; ++l)
                    gradlap[l] += g.lap(i, j) * der(order(i, j, l, 0), order(i, j, l, 1), order(i, j, l, 2));
                }
              const double WF = W + win.cF[p] * lap;
              const Vec3 gT = g.J.transpose() * (grad + win.cT[p] * gradlap);  // physical gradient of W^T
              const Vec3 f = WF * Vec3(qp[0], qp[1], qp[2]) + 0.5 * gT.cross(T) - S * gT;
              const int i0 = (win.start[p][0] + j0) % g.M[0], i1 = (win.start[p][1] + j1) % g.M[1],
                        i2 = (win.start[p][2] + j2) % g.M[2];
              const long t = (long(i0) * g.M[1] + i1) * g.M[2] + i2;
              for (int a = 0; a < 3; ++a) ref[a * g.points() + t] += f[a];
              // Interpolation reference: U = sum W^F u, D = sum gT u^T, Omega = -(1/2) eps : D, E = -B : D.
              const Vec3 uv(u[t], u[g.points() + t], u[2 * g.points() + t]);
              double* y = yref.data() + p * d;
              for (int a = 0; a < 3; ++a) y[a] += WF * uv[a];
              if (d > 3) {
                const Mat3 D = gT * uv.transpose();
                y[3] += -0.5 * (D(1, 2) - D(2, 1));
                y[4] += -0.5 * (D(2, 0) - D(0, 2));
                y[5] += -0.5 * (D(0, 1) - D(1, 0));
                if (d > 6)
                  for (int b = 0; b < 5; ++b) y[6 + b] += -(basis[b].cwiseProduct(D)).sum();
              }
            }
      }
      const std::vector<double> padded = padded_field(g, u);
      for (ewald::GridKernels path :
           {ewald::GridKernels::automatic, ewald::GridKernels::baseline, ewald::GridKernels::generic}) {
        CAPTURE(int(path));
        ewald::force_grid_kernels(path);
        std::vector<double> fast(g.stored() * 3);
        ewald::spread(g, win, colouring, m, q, fast.data());
        double err = 0.0, norm = 0.0, ghost = 0.0;
        for (int a = 0; a < 3; ++a)
          for (int i0 = 0; i0 < g.M[0]; ++i0)
            for (int i1 = 0; i1 < g.M[1]; ++i1)
              for (int i2 = 0; i2 < g.row; ++i2) {
                const long t = (long(i0) * g.M[1] + i1) * g.M[2] + i2;
                const long f = a * g.stored() + ewald::grid_offset(g, i0, i1, i2);
                if (i2 < g.M[2]) {
                  err = std::max(err, std::abs(fast[f] - ref[a * g.points() + t]));
                  norm = std::max(norm, std::abs(ref[a * g.points() + t]));
                } else {
                  ghost = std::max(ghost, std::abs(fast[f]));  // folded back and cleared
                }
              }
        CAPTURE(to_string(m));
        CHECK(err < 1e-13 * norm);
        CHECK(ghost == 0.0);
        VecX y;
        ewald::interpolate(g, win, colouring, m, padded.data(), y);
        CHECK(rel_error(y, yref) < 1e-13);
        ewald::force_grid_kernels(ewald::GridKernels::automatic);
      }
    }
  }
  CHECK(cases == 15);
}

TEST_CASE("PME spreading and interpolation: fast kernels equal the generic loops on larger grids, independent of the thread count") {
  // 400 polydisperse particles (a = 0.5 ... 1.5) in the sheared box, supports 4 ... 16 and 24:
  // fast (AVX2 where available, and baseline) against the generic loops within 1e-13 of the
  // largest value; each path bitwise equal on 1 and 2 threads.
  const int threads = omp_get_max_threads();
  for (int P : {4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 24}) {
    CAPTURE(P);
    SmallGrid sg = small_grid(P, {P + 20, P + 22, P + 19}, 400, 5 + P);
    const ewald::GridGeometry& g = sg.g;
    const VecX u = random_vector(g.points() * 3, 9);
    const std::vector<double> padded = padded_field(g, u);
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      CAPTURE(to_string(m));
      const VecX q = random_vector(400 * dof_per_particle(m), 8);
      std::vector<double> grid[3][2];
      VecX y[3][2];
      const ewald::GridKernels paths[3] = {ewald::GridKernels::generic, ewald::GridKernels::automatic,
                                           ewald::GridKernels::baseline};
      for (int k = 0; k < 3; ++k)
        for (int t = 0; t < 2; ++t) {
          ewald::force_grid_kernels(paths[k]);
          omp_set_num_threads(t == 0 ? 1 : 2);
          grid[k][t].resize(g.stored() * 3);
          ewald::spread(g, sg.win, sg.colouring, m, q, grid[k][t].data());
          ewald::interpolate(g, sg.win, sg.colouring, m, padded.data(), y[k][t]);
        }
      omp_set_num_threads(threads);
      ewald::force_grid_kernels(ewald::GridKernels::automatic);
      double gmax = 0.0;
      for (double v : grid[0][0]) gmax = std::max(gmax, std::abs(v));
      for (int k = 0; k < 3; ++k) {
        CHECK(grid[k][0] == grid[k][1]);
        CHECK((y[k][0] - y[k][1]).norm() == 0.0);
        double e = 0.0;
        for (std::size_t i = 0; i < grid[0][0].size(); ++i) e = std::max(e, std::abs(grid[k][0][i] - grid[0][0][i]));
        CHECK(e <= 1e-13 * gmax);
        CHECK((y[k][0] - y[0][0]).cwiseAbs().maxCoeff() <= 1e-13 * y[0][0].cwiseAbs().maxCoeff());
      }
    }
  }
}

TEST_CASE("PME under shear: a new strain keeps the parameters and FFT plans and equals a new operator") {
  // Parameters of a sheared box do not depend on the strain (pme_parameters.hpp), so
  // set_configuration with only the strain changed keeps grid and plans; the product must equal
  // that of an operator built at the new strain, bitwise.
  const Vec3 L(10.0, 9.0, 11.0);
  const Config c = random_config(30, L, 0.5, 1.0, 71);
  const VecX x = random_vector(30 * 11, 12);
  ewald::PmeFarField moving(MobilitySpec{Moments::FTS, 1.0, 1e-5});
  moving.set_configuration(Configuration{c.x, c.a, box(L, 0.3)});
  const auto before = moving.parameters();
  moving.set_configuration(Configuration{c.x, c.a, box(L, 0.31)});
  CHECK(moving.parameters().grid == before.grid);
  CHECK(moving.parameters().xi == before.xi);
  VecX y0, y1;
  moving.apply(x, y0);
  ewald::PmeFarField(c.x, c.a, 1.0, Moments::FTS, box(L, 0.31), 1e-5).apply(x, y1);
  CHECK((y0 - y1).norm() == 0.0);
  // The unsheared box gets its own (smaller or equal) grid.
  const ewald::PmeFarField still(c.x, c.a, 1.0, Moments::FTS, box(L, 0.0), 1e-5);
  for (int d = 0; d < 3; ++d) CHECK(still.parameters().grid[d] <= before.grid[d]);
  // Back at strain 0 the sheared operator keeps its grid (the parameters hold at every strain) and
  // agrees with the unsheared one to the tolerance (each is within 1e-5 of the exact product).
  moving.set_configuration(Configuration{c.x, c.a, box(L, 0.0)});
  CHECK(moving.parameters().grid == before.grid);
  VecX y2, y3, yref;
  moving.apply(x, y2);
  still.apply(x, y3);
  CHECK((y2 - y3).norm() <= 2e-5 * y3.norm());
  // And against the dense Ewald sum at strain 0 (the independent reference): within the tolerance.
  ewald::EwaldFarField(c.x, c.a, 1.0, Moments::FTS, box(L, 0.0)).apply(x, yref);
  CHECK((y2 - yref).norm() <= 1e-5 * yref.norm());
}

TEST_CASE("PME at N = 1e4: achieved error below the request (F and FTS, phi = 0.1, tol 1e-4)") {
  // The benchmark case that exceeded its tolerance (1.07 tol, F) with kSafety = 0.4
  // (pme_parameters.cpp). Reference: the PME at tolerance 1e-12, whose accuracy against the Ewald
  // sum the small-N sweep above establishes.
  const int n = 10000;
  const double L = std::cbrt(n * 4.0 * pi / 3.0 / 0.1);
  const Config c = random_config(n, Vec3(L, L, L), 1.0, 1.0, 2024);
  for (Moments m : {Moments::F, Moments::FTS}) {
    const VecX x = random_vector(n * dof_per_particle(m), 21);
    VecX y, yref;
    ewald::PmeFarField(c.x, c.a, 1.0, m, cube(L), 1e-12).apply(x, yref);
    ewald::PmeFarField(c.x, c.a, 1.0, m, cube(L), 1e-4).apply(x, y);
    const double err = rel_error(y, yref);
    CAPTURE(to_string(m));
    CHECK(err < 1e-4);
    CHECK(err > 0.05e-4);
    std::printf("pme-1e4 %s err=%.2e\n", to_string(m), err);
  }
}

#include "engine/core/quadrature.hpp"

TEST_CASE("Gauss-Legendre rule (engine/core/quadrature.hpp): exact up to degree 2n - 1") {
  // int_{-1}^{1} x^k dx = 2 / (k + 1) for even k, 0 for odd k. Degree 2n is no longer exact: its
  // error is 2^{2n+1} (n!)^4 / ((2n+1) ((2n)!)^2) (Abramowitz & Stegun 25.4.30, whose ((2n)!)^3 in the
  // denominator meets f^(2n) = (2n)!),
  // 0.0116 for n = 4 (for n = 16, 32 it is below rounding).
  for (int n : {4, 16, 32}) {
    const GaussLegendre q = gauss_legendre(n);
    for (int k = 0; k <= 2 * n; ++k) {
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += q.w[std::size_t(i)] * std::pow(q.x[std::size_t(i)], k);
      const double exact = k % 2 ? 0.0 : 2.0 / (k + 1);
      CAPTURE(n);
      CAPTURE(k);
      if (k < 2 * n) CHECK(std::abs(sum - exact) < 1e-14);
      else if (n == 4) CHECK(std::abs(std::abs(sum - exact) - 512.0 * std::pow(24.0, 4) / (9.0 * std::pow(40320.0, 2))) < 1e-12);
    }
  }
}

TEST_CASE("PME error model: the aliasing-and-edge estimate follows the measured error over the window shape") {
  // pme_alias_error2 (pme_parameters.cpp) models the sampled window's deviation from its ideal
  // transform, aliases and the truncation's edge jumps together. Reference: the measured error of
  // the wave part with support P against the same grid with support P + 6 (whose deviation is
  // negligible), with the real-space part made negligible (xi = 1, cutoff gap 4.5: e^{-(xi r)^2} < 1e-18)
  // and the wave truncation negligible (grid resolving k = 2 pi M / L / 2 >= 9 xi). Unit-variance input;
  // error per particle relative to S (pme_self_scale2). The Kaiser-Bessel shape spans the edge-dominated
  // (beta / (pi P) = 0.6, 0.7) and the alias-dominated (0.9-1.4) regimes. The model is first order
  // in the deviation: rows whose estimate exceeds 0.1 S are printed, not checked. Measured here
  // (2026-11-29): 0.61-1.60 of the estimate (the 1.4-1.6 rows at beta / (pi P) = 0.9-1.1, P = 8, on this
  // grid of k a up to 11, finer than the search chooses); the engine's grids gave 0.33-1.04 (docs/ewald.md s.5).
  const int n = 1000;
  const double phi = 0.3, L = std::cbrt(n * 4.0 * pi / 3.0 / phi);
  const Config c = random_config(n, Vec3(L, L, L), 1.0, 1.0, 77);
  const double rho = n / (L * L * L);
  for (Moments m : {Moments::F, Moments::FTS}) {
    VecX x = random_vector(n * dof_per_particle(m), 5);  // uniform in [-1, 1]: variance 1/3
    const double S = std::sqrt(ewald::pme_self_scale2(1.0, m) / 3.0);
    for (int P : {5, 8}) {
      ewald::PmeParameters p;
      p.xi = 1.0;
      p.cutoff_gap = 4.5;
      const int M = ewald::fft_size(int(std::ceil(9.0 * p.xi * L / pi)));
      p.grid = {M, M, M};
      p.k_max = pi * M / L;
      ewald::PmeParameters wide = p;
      wide.support = P + 6;
      wide.shape = 0.9 * pi * wide.support;
      ewald::PmeOptions ow;
      ow.fixed = wide;
      VecX yw, yw4;
      ewald::PmeFarField(c.x, c.a, 1.0, m, cube(L), 1e-6, ow).apply_wave(x, yw);
      // The reference's own deviation, measured against support P + 10: below 1 % of the smallest
      // deviation checked below.
      ewald::PmeParameters wider = wide;
      wider.support = P + 10;
      wider.shape = 0.9 * pi * wider.support;
      ewald::PmeOptions ow4;
      ow4.fixed = wider;
      ewald::PmeFarField(c.x, c.a, 1.0, m, cube(L), 1e-6, ow4).apply_wave(x, yw4);
      const double reference_error = (yw - yw4).norm() / std::sqrt(double(n)) / S;
      double smallest = std::numeric_limits<double>::infinity();
      for (double shape : {0.6, 0.7, 0.9, 1.1, 1.4}) {
        p.support = P;
        p.shape = shape * pi * P;
        ewald::PmeOptions o;
        o.fixed = p;
        VecX y;
        ewald::PmeFarField(c.x, c.a, 1.0, m, cube(L), 1e-6, o).apply_wave(x, y);
        const double measured = (y - yw).norm() / std::sqrt(double(n)) / S;
        const ewald::Window1D w(ewald::WindowKind::kaiser_bessel, P, p.shape);
        const double model =
            std::sqrt(ewald::pme_alias_error2(p.grid, Vec3(L, L, L), w, p.xi, 1.0, rho, m) / (3.0 * S * S));
        CAPTURE(to_string(m));
        CAPTURE(P);
        CAPTURE(shape);
        CAPTURE(measured);
        CAPTURE(model);
        smallest = std::min(smallest, measured);
        if (model < 0.1) {
          CHECK(measured < 2.0 * model);
          CHECK(measured > 0.4 * model);
        }
        std::printf("pme-alias-model %s P=%d beta/(pi P)=%.1f measured=%.2e model=%.2e ratio=%.2f\n", to_string(m), P,
                    shape, measured, model, measured / model);
      }
      CAPTURE(reference_error);
      CAPTURE(smallest);
      CHECK(reference_error < 0.01 * smallest);
    }
  }
}

TEST_CASE("PME error model: the pairs' part of |M x| against the dense Ewald matrix") {
  // pme_pair_scale2 is the random-position mean of sum_{j != i} ||M_ij||_F^2 (what the tolerance is
  // relative to, with the self part). Reference: the off-diagonal blocks of the dense Ewald matrix
  // (ewald_mobility), averaged over particles and 4 configurations of 150 spheres at random centres
  // (overlaps allowed, as the model assumes), in cubes and in a 2 : 1 : 1/2 box of the same volume.
  // Agreement within 10 % (configuration-to-configuration scatter of the mean: about 3 %).
  const int n = 150;
  for (const Vec3& aspect : {Vec3(1, 1, 1), Vec3(2, 1, 0.5)})
  for (double phi : {0.1, 0.4})
    for (Moments m : {Moments::F, Moments::FTS}) {
      const Vec3 L = aspect * std::cbrt(n * 4.0 * pi / 3.0 / phi);
      const int d = dof_per_particle(m);
      double sum = 0.0;
      const int configurations = 4;
      for (int c = 0; c < configurations; ++c) {
        const Config cfg = random_config(n, L, 1.0, 1.0, 300 + c);
        const MatX M = ewald::ewald_mobility(cfg.x, cfg.a, 1.0, m, box(L));
        double off = M.squaredNorm();
        for (int i = 0; i < n; ++i) off -= M.block(i * d, i * d, d, d).squaredNorm();
        sum += off / n;
      }
      const double measured = sum / configurations;
      const double model = ewald::pme_pair_scale2(L, 1.0, n / (L.x() * L.y() * L.z()), m);
      CAPTURE(aspect.x());
      CAPTURE(phi);
      CAPTURE(to_string(m));
      CAPTURE(measured);
      CAPTURE(model);
      CHECK(std::abs(model / measured - 1.0) < 0.1);
      std::printf("pme-pair-scale %s box %.0f:%.0f:%.1f phi=%.1f measured=%.4e model=%.4e ratio=%.3f\n", to_string(m),
                  aspect.x(), aspect.y(), aspect.z(), phi, measured, model, model / measured);
    }
}
