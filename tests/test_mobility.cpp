// Far-field grand mobility: pair scalars against closed forms, structure of the assembled matrix,
// and the matrix-free product against the dense reference.
#include <doctest/doctest.h>

#include "engine/kernels/far_field.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "support/sanitizer.hpp"
#include "support/threads.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <string>

using namespace stokesian;
using stokesian::test::kSanitized;
using mobility::pair_scalars;
using mobility::PairScalars;

namespace {
constexpr double pi = 3.14159265358979323846;

// Relative difference with a floor: |x - y| / max(|y|, floor).
double rel(double x, double y, double floor = 1e-300) { return std::abs(x - y) / std::max(std::abs(y), floor); }

// Polydisperse far-field scalars in the normalisation of the thesis [T] (times 6 pi mu), its eqs.
// (3.30)-(3.40), with the corrections of docs/mobility.md: + sign of z^m; (3.35)-(3.36) are x^g, y^g. "src" is the particle carrying F/T/S, "res" the responding one.
struct Thesis {
  double xa, ya, yb, xc, yc, xg, yg, yh, xm, ym, zm;
};
Thesis thesis(double res, double src, double r) {
  const double s2 = res * res + src * src;
  return {1.5 / r - 0.5 * s2 / std::pow(r, 3),
          0.75 / r + 0.25 * s2 / std::pow(r, 3),
          0.75 / (r * r),
          0.75 / std::pow(r, 3),
          -0.375 / std::pow(r, 3),
          -2.25 / (r * r) + 2.25 * src * src / std::pow(r, 4) + 1.35 * res * res / std::pow(r, 4),
          -0.75 * src * src / std::pow(r, 4) - 0.45 * res * res / std::pow(r, 4),
          -1.125 / std::pow(r, 3),
          -4.5 / std::pow(r, 3) + 5.4 * s2 / std::pow(r, 5),
          2.25 / std::pow(r, 3) - 3.6 * s2 / std::pow(r, 5),
          0.9 * s2 / std::pow(r, 5)};
}

std::vector<double> as_list(const PairScalars& s) {
  return {s.xa, s.ya, s.yb, s.ybt, s.xc, s.yc, s.xg, s.yg, s.xgt, s.ygt, s.yh, s.yht, s.xm, s.ym, s.zm};
}

struct Config {
  std::vector<Vec3> x;
  std::vector<double> a;
};

// Random polydisperse configuration in a cube of side L; small L gives many overlaps.
Config random_config(int n, double L, double amin, double amax, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Config c;
  for (int i = 0; i < n; ++i) {
    c.x.emplace_back(L * u(rng), L * u(rng), L * u(rng));
    c.a.push_back(amin * std::pow(amax / amin, u(rng)));
  }
  return c;
}
}  // namespace

TEST_CASE("single sphere: Stokes drag, rotation and stresslet mobilities") {
  // Analytic single-sphere values: U = F/(6 pi mu a), Omega = T/(8 pi mu a^3), S = -(20/3) pi mu a^3 E.
  const double a = 1.7, mu = 0.8;
  const PairScalars s = mobility::self_scalars(a, mu);
  CHECK(s.xa == doctest::Approx(1.0 / (6 * pi * mu * a)).epsilon(1e-15));
  CHECK(s.yc == doctest::Approx(1.0 / (8 * pi * mu * a * a * a)).epsilon(1e-15));
  CHECK(s.zm == doctest::Approx(3.0 / (20 * pi * mu * a * a * a)).epsilon(1e-15));
}

TEST_CASE("separated pairs match the polydisperse far-field formulas (thesis eqs. 3.30-3.40, corrected)") {
  // Independent closed forms typed from the thesis; both are exact rational functions, so only
  // rounding separates them: 1e-12 relative.
  for (double lam : {0.01, 0.1, 0.5, 1.0, 2.0, 7.0, 100.0}) {
    const double res = 1.0, src = lam;
    for (double fac : {1.0, 1.0 + 1e-6, 1.01, 1.5, 3.0, 10.0, 1e3}) {
      const double r = fac * (res + src);
      const PairScalars s = pair_scalars(res, src, r, 1.0, Moments::FTS);
      const Thesis t = thesis(res, src, r);
      const double k = 6 * pi;  // thesis normalisation
      CAPTURE(lam);
      CAPTURE(fac);
      CHECK(rel(k * s.xa, t.xa) < 1e-12);
      CHECK(rel(k * s.ya, t.ya) < 1e-12);
      CHECK(rel(k * s.yb, t.yb) < 1e-12);
      CHECK(rel(k * s.xc, t.xc) < 1e-12);
      CHECK(rel(k * s.yc, t.yc) < 1e-12);
      CHECK(rel(k * s.xg, t.xg, 1e-3 * std::abs(2.25 / (r * r))) < 1e-10);
      CHECK(rel(k * s.yg, t.yg) < 1e-12);
      CHECK(rel(k * s.yh, t.yh) < 1e-12);
      CHECK(rel(k * s.xm, t.xm, 1e-3 * 4.5 / std::pow(r, 3)) < 1e-10);
      CHECK(rel(k * s.ym, t.ym, 1e-3 * 2.25 / std::pow(r, 3)) < 1e-10);
      CHECK(rel(k * s.zm, t.zm) < 1e-12);
      // Transposed couplings: U <- T from the source's point of view, U <- S = -(E <- F)^T.
      const PairScalars back = pair_scalars(src, res, r, 1.0, Moments::FTS);
      CHECK(rel(s.ybt, back.yb) < 1e-12);
      CHECK(rel(s.xgt, -back.xg, 1e-3 * std::abs(s.xgt) + 1e-300) < 1e-10);
      CHECK(rel(s.ygt, -back.yg) < 1e-12);
    }
  }
}

TEST_CASE("overlapping pairs: translation matches Zuk et al. (2014) generalized RPY") {
  // Zuk, Wajnryb, Mizerski & Szymczak, J. Fluid Mech. 741 R5 (2014), eqs. 3.5 (|a-b| < r < a+b)
  // and 3.6 (r <= |a-b|). Closed forms, so 1e-12 relative.
  const double mu = 1.0;
  for (double lam : {0.01, 0.3, 1.0, 3.0}) {
    const double a = 1.0, b = lam;
    for (double t : {0.0, 0.1, 0.5, 0.9, 0.999}) {
      const double r = std::abs(a - b) + t * (a + b - std::abs(a - b));
      const PairScalars s = pair_scalars(a, b, r, mu, Moments::F);
      CAPTURE(lam);
      CAPTURE(r);
      if (r <= std::abs(a - b)) {
        CHECK(rel(s.xa, 1.0 / (6 * pi * mu * std::max(a, b))) < 1e-12);
        CHECK(rel(s.ya, 1.0 / (6 * pi * mu * std::max(a, b))) < 1e-12);
        continue;
      }
      const double d2 = (a - b) * (a - b), pre = 1.0 / (6 * pi * mu * a * b);
      const double iso = pre * (16 * r * r * r * (a + b) - std::pow(d2 + 3 * r * r, 2)) / (32 * r * r * r);
      const double rr = pre * 3 * std::pow(d2 - r * r, 2) / (32 * r * r * r);
      CHECK(rel(s.ya, iso) < 1e-12);
      CHECK(rel(s.xa, iso + rr) < 1e-12);
    }
  }
}

TEST_CASE("overlapping equal spheres: rotation couplings match Wajnryb et al. (2013)") {
  // Equal spheres, r < 2a: mu^rr = (1 - 27r/32a + 5r^3/64a^3) I + (9r/32a - 3r^3/64a^3) ee over
  // 8 pi mu a^3; mu^rt = (r/2a - 3r^2/16a^2)/(8 pi mu a^2) eps.e (Wajnryb, Mizerski, Zuk &
  // Szymczak, J. Fluid Mech. 731 R3, 2013).
  const double a = 1.3, mu = 1.0;
  for (double x : {0.05, 0.5, 1.0, 1.5, 1.99}) {
    const double r = x * a;
    const PairScalars s = pair_scalars(a, a, r, mu, Moments::FT);
    const double k3 = 1.0 / (8 * pi * mu * a * a * a), k2 = 1.0 / (8 * pi * mu * a * a);
    const double iso = 1 - 27 * r / (32 * a) + 5 * std::pow(r / a, 3) / 64;
    const double ani = 9 * r / (32 * a) - 3 * std::pow(r / a, 3) / 64;
    CAPTURE(x);
    CHECK(rel(s.yc, k3 * iso) < 1e-11);
    CHECK(rel(s.xc, k3 * (iso + ani)) < 1e-11);
    CHECK(rel(s.yb, k2 * (r / (2 * a) - 3 * r * r / (16 * a * a))) < 1e-11);
  }
}

TEST_CASE("pair scalars are continuous across contact and nesting and tend to the self terms") {
  for (double lam : {0.01, 0.2, 1.0, 4.0}) {
    const double a = 1.0, b = lam;
    for (double rc : {a + b, std::abs(a - b)}) {
      if (rc == 0.0) continue;
      const auto lo = as_list(pair_scalars(a, b, rc * (1 - 1e-9), 1.0, Moments::FTS));
      const auto hi = as_list(pair_scalars(a, b, rc * (1 + 1e-9), 1.0, Moments::FTS));
      const auto sc = as_list(mobility::self_scalars(std::min(a, b), 1.0));
      double scale = 0;
      for (double v : sc) scale = std::max(scale, std::abs(v));
      CAPTURE(lam);
      CAPTURE(rc);
      // The scalars are Lipschitz in r; a 2e-9 relative step changes them by ~1e-8 of the scale.
      for (std::size_t i = 0; i < lo.size(); ++i) CHECK(std::abs(lo[i] - hi[i]) < 1e-7 * scale);
    }
  }
  // Coincident equal spheres are one sphere: the pair block equals the self block.
  const PairScalars s0 = pair_scalars(1.0, 1.0, 1e-6, 1.0, Moments::FTS);
  const PairScalars self = mobility::self_scalars(1.0, 1.0);
  CHECK(rel(s0.xa, self.xa) < 1e-5);
  CHECK(rel(s0.yc, self.yc) < 1e-5);
  CHECK(rel(s0.zm, self.zm) < 1e-5);
  CHECK(std::abs(s0.yb) < 1e-5 * self.xc);
}

TEST_CASE("grand mobility is symmetric positive definite for random polydisperse overlapping configurations") {
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      // Dense packings (L = 4 for 12 spheres of radii 0.1-3) overlap heavily.
      const Config c = random_config(12, seed % 2 ? 4.0 : 12.0, 0.1, 3.0, seed);
      const MatX M = dense_mobility(c.x, c.a, 1.0, m);
      CAPTURE(to_string(m));
      CAPTURE(seed);
      CHECK((M - M.transpose()).norm() < 1e-13 * M.norm());
      Eigen::SelfAdjointEigenSolver<MatX> eig(0.5 * (M + M.transpose()));
      CHECK(eig.eigenvalues().minCoeff() > 1e-10 * eig.eigenvalues().maxCoeff());
    }
  }
}

TEST_CASE("pair mobility of unequal spheres stays positive definite down to full overlap") {
  for (double b : {0.1, 4.0}) {
    for (double r : {1e-3, 0.5, 0.95 * std::abs(1 - b), 1.0, 1.05, 2.0, 1 + b - 1e-6, 1 + b, 1 + b + 1e-3, 10.0}) {
      const std::vector<Vec3> x{Vec3::Zero(), Vec3(r, 0.3 * r, -0.2 * r).normalized() * r};
      const MatX M = dense_mobility(x, {1.0, b}, 1.0, Moments::FTS);
      Eigen::SelfAdjointEigenSolver<MatX> eig(M);
      CAPTURE(b);
      CAPTURE(r);
      CHECK((M - M.transpose()).norm() < 1e-13 * M.norm());
      CHECK(eig.eigenvalues().minCoeff() > 0.0);
    }
  }
}

TEST_CASE("matrix-free product equals the dense reference") {
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    const Config c = random_config(40, 10.0, 0.2, 2.0, 7);
    const MatX M = dense_mobility(c.x, c.a, 1.3, m);
    std::mt19937_64 rng(3);
    std::normal_distribution<double> g;
    VecX v(M.cols());
    for (auto& e : v) e = g(rng);
    VecX y;
    mobility_product(c.x, c.a, 1.3, m, v, y);
    // Same scalars, different tensor contraction code: agreement to rounding.
    CHECK((y - M * v).norm() < 1e-13 * (M * v).norm());
  }
}

TEST_CASE("vectorised direct product equals its reference twin (every path, thread counts, overlaps)") {
  // mobility_product (direct_fast.cpp: AVX2 and baseline loops over separated pairs, apply_pair for
  // overlapping and nested ones) against mobility_product_reference (one apply_pair per ordered
  // pair) and dense_mobility. Configurations: sizes around the row block (16) and the parallel
  // threshold (256); monodisperse without overlaps, polydisperse (radius ratio 10) with overlapping,
  // nested and coincident pairs; separated pairs down to contact.
  struct Case {
    std::string name;
    Config c;
  };
  std::vector<Case> cases;
  cases.push_back({"one sphere", random_config(1, 5.0, 1.0, 1.0, 1)});
  cases.push_back({"polydisperse, 17 in L = 4 (overlaps, nesting)", random_config(17, 4.0, 0.2, 2.0, 2)});
  cases.push_back({"polydisperse, 300 in L = 25", random_config(300, 25.0, 0.3, 3.0, 3)});
  {
    Config c = random_config(40, 12.0, 0.5, 1.5, 4);
    c.x[5] = c.x[4];  // coincident centres (nested), different radii
    c.a[5] = 0.5 * c.a[4];
    c.x[7] = c.x[6] + Vec3(0.3, 0.4, 1.2).normalized() * (c.a[6] + c.a[7]);  // exact contact
    c.x[9] = c.x[8] + Vec3(1, 0, 0) * (c.a[8] + c.a[9]) * (1 + 1e-12);       // just separated
    cases.push_back({"special pairs", c});
  }
  {
    // Monodisperse lattice with gaps of 0.01 (every pair separated): the vectorised loop alone.
    Config c;
    for (int i = 0; i < 7; ++i)
      for (int j = 0; j < 7; ++j)
        for (int k = 0; k < 6; ++k) {
          c.x.emplace_back(2.01 * i, 2.01 * j + 0.3 * (i % 2), 2.01 * k);
          c.a.push_back(1.0);
        }
    cases.push_back({"monodisperse lattice, 294 spheres", c});
  }
  for (const auto& cs : cases)
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      CAPTURE(cs.name);
      CAPTURE(int(m));
      const Config& c = cs.c;
      const int d = dof_per_particle(m);
      std::mt19937_64 rng(5);
      std::normal_distribution<double> g;
      VecX v(long(c.x.size()) * d);
      for (auto& e : v) e = g(rng);
      VecX ref;
      mobility_product_reference(c.x, c.a, 0.7, m, v, ref);
      // The sanitizer job checks the large cases against the reference product only (the dense
      // matrix and the reference-kernel pass over 300 spheres took 150 s at -O0, 2026-11-29).
      const bool large = c.x.size() > 100;
      if (!(kSanitized && large)) {
        const VecX dense = dense_mobility(c.x, c.a, 0.7, m) * v;
        CHECK((ref - dense).norm() <= 1e-13 * dense.norm());
      }
      for (DirectKernels k : {DirectKernels::automatic, DirectKernels::baseline, DirectKernels::reference}) {
        if (kSanitized && large && k == DirectKernels::reference) continue;
        CAPTURE(int(k));
        force_direct_kernels(k);
        VecX y1, y2;
        {
          const test::ThreadCount one(1);
          mobility_product(c.x, c.a, 0.7, m, v, y1);
        }
        {
          const test::ThreadCount several(test::ThreadCount::kSeveral);
          mobility_product(c.x, c.a, 0.7, m, v, y2);
        }
        CHECK((y1 - ref).norm() <= 1e-13 * ref.norm());
        // Largest entry error against the reference, relative to the largest response.
        CHECK((y1 - ref).cwiseAbs().maxCoeff() <= 1e-13 * ref.cwiseAbs().maxCoeff());
        CHECK((y1 - y2).cwiseAbs().maxCoeff() == 0.0);  // bitwise: independent of the thread count
      }
      force_direct_kernels(DirectKernels::automatic);
    }
}

TEST_CASE("scalars from radial derivatives reproduce the monomial evaluation") {
  // Separated pair: 8 pi mu Psi = r + c/r, derivatives exact; both paths must agree to rounding.
  for (double r : {2.5, 4.0, 17.0}) {
    const double a = 1.0, b = 0.5;
    auto derivs = [&](double c) {
      mobility::PsiDerivatives d;
      d.d1 = 1 - c / (r * r);
      d.d2 = 2 * c / (r * r * r);
      d.d3 = -6 * c / std::pow(r, 4);
      d.d4 = 24 * c / std::pow(r, 5);
      return d;
    };
    const auto ff = derivs(2 * (a * a + b * b) / 6), tf = derivs(2 * (a * a / 10 + b * b / 6)),
               ft = derivs(2 * (a * a / 6 + b * b / 10)), tt = derivs(2 * (a * a + b * b) / 10);
    const auto x = as_list(mobility::scalars_from_derivatives(ff, tf, ft, tt, r, 1.0, Moments::FTS));
    const auto y = as_list(pair_scalars(a, b, r, 1.0, Moments::FTS));
    for (std::size_t i = 0; i < x.size(); ++i) CHECK(std::abs(x[i] - y[i]) <= 1e-13 * (std::abs(y[i]) + 1e-3 / (r * r * r)));
  }
}
