// Conventional (dense) Stokesian dynamics: two-sphere exactness from near contact to far field,
// sparse/dense near-field twins, symmetry and positive definiteness, unequal spheres.
#include <doctest/doctest.h>

#include "engine/kernels/far_field.hpp"
#include "engine/sd_dense.hpp"
#include "lubrication/near_field.hpp"

#include "engine/core/parallel.hpp"

#include <Eigen/Eigenvalues>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace stokesian;

namespace {
// n spheres with radii uniform in [amin, amax) at centres uniform in [0, L)^3, surfaces at least
// 1e-3 apart (plain distances), drawn from rng in order.
std::pair<std::vector<Vec3>, std::vector<double>> random_cloud(std::mt19937_64& rng, std::size_t n, double L,
                                                                double amin, double amax) {
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> x;
  std::vector<double> a;
  while (x.size() < n) {
    const Vec3 p(L * u(rng), L * u(rng), L * u(rng));
    const double ai = amin + (amax - amin) * u(rng);
    bool ok = true;
    for (std::size_t k = 0; k < x.size(); ++k) ok &= (p - x[k]).norm() > ai + a[k] + 1e-3;
    if (ok) {
      x.push_back(p);
      a.push_back(ai);
    }
  }
  return {x, a};
}

// Mobility of the pair from SD: inverse of R = M_inf^{-1} + R_nf, and the exact two-sphere
// mobility: inverse of the exact resistance (lubrication/resistance_functions).
struct PairMobilities {
  MatX sd, exact;
};
PairMobilities pair_mobilities(double a1, double a2, double gap, Moments m, const Vec3& dir) {
  const double r = a1 + a2 + gap;
  const std::vector<Vec3> x{Vec3::Zero(), Vec3(r * dir.normalized())};
  DenseStokesianDynamics sd(m, 1.0, AmbientFlow{});
  const MatX R = sd.resistance(x, {a1, a2});
  lubrication::NearField nf(m, 1.0);
  const MatX Rex = nf.exact_pair(x[1] - x[0], a1, a2);
  return {R.inverse(), Rex.inverse()};
}
}  // namespace

TEST_CASE("two-sphere SD equals the exact two-sphere resistance inside the cutoff, far field outside") {
  // Inside the cutoff (s < 4) R = R2B_exact by construction, so the only error is that of the
  // tabulated resistance functions (<= 1e-6 relative): 1e-5. Beyond the cutoff SD is the far
  // field alone; its error against the exact mobility (measured: at most 1.0e-2 at s = 4.5 and
  // 2e-3 at s = 7, FTS with lambda = 4 the worst) must fall with distance: 2e-2 at s = 4.5,
  // 4e-3 at s = 7.
  const Vec3 dir(0.3, -0.5, 0.8);
  for (auto [a1, a2] : {std::pair{1.0, 1.0}, std::pair{1.0, 4.0}, std::pair{1.0, 0.1}}) {
    for (double gap_rel : {1e-3, 1e-2, 0.1, 0.5, 1.0, 1.9, 2.5, 5.0}) {
      const double gap = gap_rel * 0.5 * (a1 + a2);  // symmetric gap xi = gap_rel
      for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
        const PairMobilities p = pair_mobilities(a1, a2, gap, m, dir);
        const double err = (p.sd - p.exact).norm() / p.exact.norm();
        CAPTURE(a1);
        CAPTURE(a2);
        CAPTURE(gap_rel);
        CAPTURE(dof_per_particle(m));
        MESSAGE("lambda " << a2 / a1 << " xi " << gap_rel << " dof " << dof_per_particle(m) << " error " << err);
        CHECK(err < (gap_rel < 2.0 ? 1e-5 : gap_rel < 3.0 ? 2e-2 : 4e-3));
      }
    }
  }
}

TEST_CASE("sparse near-field assembly equals the dense twin; R is symmetric positive definite") {
  std::mt19937_64 rng(17);
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    // Polydisperse cloud with many close pairs, no overlaps.
    const auto [x, a] = random_cloud(rng, 25, 9.0, 0.4, 1.6);
    lubrication::NearField nf(m, 1.0);
    lubrication::NearFieldStats st;
    const MatX sparse = MatX(nf.assemble(x, a, Domain{}, &st));
    const MatX dense = nf.assemble_dense(x, a);
    CHECK(st.pairs > 10);
    CHECK((sparse - dense).norm() <= 1e-12 * dense.norm());
    CHECK((dense - dense.transpose()).norm() <= 1e-10 * dense.norm());
    DenseStokesianDynamics sd(m, 1.0, AmbientFlow{});
    const MatX R = sd.resistance(x, a);
    Eigen::SelfAdjointEigenSolver<MatX> eig(R);
    CHECK(eig.eigenvalues().minCoeff() > 0.0);
  }
}

TEST_CASE("near-field pair block from two-sphere scalars equals its reference twin (direct 2d x 2d inversion)") {
  // NearField::pair_block takes R2B_inf as two-sphere scalars (lubrication/far_pair_inverse.hpp);
  // pair_block_reference inverts the two-body far-field mobility in the global frame. Size ratios
  // 1/16 ... 16, symmetric gaps from below the regularised minimum to the largest automatic cutoff,
  // random orientations. The block is a difference of two resistances of similar size at large gaps,
  // so the difference is measured against the size of those parts (|R2B_exact|). Measured: 7e-16.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  double worst = 0.0;
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    lubrication::NearFieldParams np;
    np.cutoff = 8.0;
    const lubrication::NearField nf(m, 1.7, np);
    for (double lambda : {1.0, 1.0 / 16, 0.37, 2.5, 16.0})
      for (double xi : {1e-7, 1e-4, 1e-2, 0.3, 1.0, 2.0, 3.9, 5.9})
        for (int k = 0; k < 5; ++k) {
          const double a1 = 0.8, a2 = 0.8 * lambda;
          const Vec3 dir = Vec3(g(rng), g(rng), g(rng)).normalized();
          const Vec3 r = dir * (0.5 * (a1 + a2) * (2.0 + xi));
          const MatX fast = nf.pair_block(r, a1, a2), ref = nf.pair_block_reference(r, a1, a2);
          const double err = (fast - ref).norm() / nf.exact_pair(r, a1, a2).norm();
          worst = std::max(worst, err);
          CAPTURE(dof_per_particle(m));
          CAPTURE(lambda);
          CAPTURE(xi);
          CHECK(err < 1e-13);
        }
  }
  MESSAGE("largest relative difference " << worst);
}

TEST_CASE("symmetric block matrix: product, lookup and both triangles against a dense matrix") {
  // A random symmetric pattern with empty block rows, rows with only a diagonal, and rows whose
  // partners cross every slice; values random. Reference: the dense matrix built block by block.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int d : {3, 6, 11}) {
    const long n = 57;
    std::vector<char> diag(std::size_t(n), 0);
    std::vector<std::vector<int>> upper(static_cast<std::size_t>(n));
    for (long i = 0; i < n; ++i)
      for (long j = i + 1; j < n; ++j)
        if (u(rng) > 0.6 && i % 7 != 3 && j % 7 != 3) {
          upper[std::size_t(i)].push_back(int(j));
          diag[std::size_t(i)] = diag[std::size_t(j)] = 1;
        }
    diag[10] = 1;  // a diagonal block without partners
    lubrication::SymmetricBlockMatrix A;
    A.reset(n, d, diag, upper);
    MatX dense = MatX::Zero(n * d, n * d);
    for (long i = 0; i < n; ++i)
      for (long b = A.row_begin(i); b < A.row_end(i); ++b) {
        const long j = A.col(b);
        CHECK(A.find(i, j) == b);
        double* B = A.block(b);
        for (int v = 0; v < d; ++v)
          for (int w = 0; w < d; ++w) B[v * d + w] = u(rng);
        if (i == j)  // a symmetric diagonal block
          for (int v = 0; v < d; ++v)
            for (int w = 0; w < v; ++w) B[v * d + w] = B[w * d + v];
        for (int v = 0; v < d; ++v)
          for (int w = 0; w < d; ++w) {
            dense(i * d + w, j * d + v) = B[v * d + w];
            dense(j * d + v, i * d + w) = B[v * d + w];
          }
      }
    CHECK(A.find(3, 4) == -1);
    CHECK(A.find(0, 3) == -1);
    CHECK((MatX(A.to_sparse()) - dense).norm() == 0.0);
    const VecX x = VecX::Random(n * d);
    const int before = omp_get_max_threads();
    omp_set_num_threads(1);
    VecX y1;
    A.multiply(x, y1);
    omp_set_num_threads(2);
    VecX y2;
    A.multiply(x, y2);
    omp_set_num_threads(before);
    CHECK((y1 - dense * x).norm() <= 1e-14 * (dense * x).norm());
    CHECK(std::equal(y1.data(), y1.data() + y1.size(), y2.data()));
  }
}

TEST_CASE("near-field block assembly and its product are bitwise independent of the thread count") {
  // Pair blocks in parallel, diagonal blocks summed per particle in pair order (near_field.cpp);
  // the product over fixed slices (block_matrix.hpp).
  std::mt19937_64 rng(23);
  const auto [x, a] = random_cloud(rng, 120, 10.0, 0.5, 1.2);
  const Domain box = Domain::periodic_box(Vec3(10, 10, 10));
  for (Moments m : {Moments::F, Moments::FTS}) {
    const lubrication::NearField nf(m, 1.0);
    const int before = omp_get_max_threads();
    const VecX z = VecX::Random(long(x.size()) * dof_per_particle(m));
    omp_set_num_threads(1);
    lubrication::NearFieldStats s1, s2;
    lubrication::SymmetricBlockMatrix one, two;
    nf.assemble(x, a, box, one, &s1);
    VecX y1;
    one.multiply(z, y1);
    omp_set_num_threads(2);
    nf.assemble(x, a, box, two, &s2);
    VecX y2;
    two.multiply(z, y2);
    omp_set_num_threads(before);
    CHECK(s1.pairs > parallel::kNearFieldPairs);
    CHECK(s1.pairs == s2.pairs);
    REQUIRE(one.stored_blocks() == two.stored_blocks());
    const long nv = one.stored_blocks() * dof_per_particle(m) * dof_per_particle(m);
    CHECK(std::equal(one.block(0), one.block(0) + nv, two.block(0)));
    CHECK(std::equal(y1.data(), y1.data() + y1.size(), y2.data()));
  }
}

TEST_CASE("sparse near-field assembly over many chunks of pairs equals a plain triplet sum") {
  // More pairs than one chunk of the assembly (16384): 800 spheres, phi 0.25, cutoff 8, F, periodic.
  // Reference: every pair by minimum image, pair_block_reference times the switch, summed by
  // Eigen's triplets. Then once more into the same matrix (storage reused) and on one thread.
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(0, 1);
  const double L = std::cbrt(800 * 4.18879 / 0.25);
  const Domain box = Domain::periodic_box(Vec3(L, L, L));
  std::vector<Vec3> x;
  while (x.size() < 800) {
    const Vec3 p(L * u(rng), L * u(rng), L * u(rng));
    bool ok = true;
    for (const Vec3& q : x) ok &= box.minimum_image(p - q).norm() > 2.01;
    if (ok) x.push_back(p);
  }
  const std::vector<double> a(x.size(), 1.0);
  lubrication::NearFieldParams np;
  np.cutoff = 8.0;
  np.taper = 1.0;
  const lubrication::NearField nf(Moments::F, 1.0, np);
  std::vector<Eigen::Triplet<double>> t;
  long pairs = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = i + 1; j < x.size(); ++j) {
      const Vec3 r = box.minimum_image(x[j] - x[i]);
      const double w = nf.weight(r.norm());
      if (w <= 0.0) continue;
      ++pairs;
      const MatX B = w * nf.pair_block_reference(r, 1.0, 1.0);
      const long idx[2] = {long(i), long(j)};
      for (int p = 0; p < 2; ++p)
        for (int q = 0; q < 2; ++q)
          for (int u2 = 0; u2 < 3; ++u2)
            for (int v = 0; v < 3; ++v) t.emplace_back(int(3 * idx[p] + u2), int(3 * idx[q] + v), B(3 * p + u2, 3 * q + v));
    }
  Eigen::SparseMatrix<double> ref(3 * 800, 3 * 800);
  ref.setFromTriplets(t.begin(), t.end());
  lubrication::NearFieldStats st;
  const lubrication::SparseMatrix R = nf.assemble(x, a, box, &st);
  CHECK(st.pairs == pairs);
  CHECK(pairs > 2 * 16384);
  const double scale = ref.norm();
  CHECK((Eigen::SparseMatrix<double>(R) - ref).norm() <= 1e-12 * scale);
  // The blocks themselves, their product against the reference's, storage reuse and one thread.
  lubrication::SymmetricBlockMatrix B;
  nf.assemble(x, a, box, B);
  const long nv = B.stored_blocks() * 9;
  const std::vector<double> first(B.block(0), B.block(0) + nv);
  const VecX z = VecX::Random(3 * 800);
  VecX y;
  B.multiply(z, y);
  const VecX yref = ref * z;
  CHECK((y - yref).norm() <= 1e-12 * yref.norm());
  nf.assemble(x, a, box, B);  // into the same storage
  CHECK(std::equal(first.begin(), first.end(), B.block(0)));
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  lubrication::SymmetricBlockMatrix one;
  nf.assemble(x, a, box, one);
  omp_set_num_threads(before);
  CHECK(std::equal(first.begin(), first.end(), one.block(0)));
}

TEST_CASE("unequal-sphere pair resistance of SD is symmetric positive definite down to the minimum gap") {
  for (double b : {4.0, 0.1}) {
    for (double xi : {1e-6, 1e-5, 1e-3, 0.1, 1.0, 3.0}) {
      const double r = 0.5 * (1.0 + b) * (2.0 + xi);
      DenseStokesianDynamics sd(Moments::FTS, 1.0, AmbientFlow{});
      const MatX R = sd.resistance({Vec3::Zero(), Vec3(0, r, 0)}, {1.0, b});
      Eigen::SelfAdjointEigenSolver<MatX> eig(R);
      CAPTURE(b);
      CAPTURE(xi);
      CHECK(eig.eigenvalues().minCoeff() > 0.0);
    }
  }
}

namespace {
// Stimson & Jeffery (1926), Proc. R. Soc. A 111, 110: two equal spheres (radius a, centres 2d
// apart, cosh(alpha) = d/a) translating together along their line of centres feel the drag
// 6 pi mu a U * lambda with
//   lambda = 4/3 sinh(alpha) sum_{n>=1} n(n+1)/((2n-1)(2n+3)) *
//            [1 - (4 sinh^2((n+1/2) alpha) - (2n+1)^2 sinh^2(alpha)) /
//                 (2 sinh((2n+1) alpha) + (2n+1) sinh(2 alpha))].
// An exact bispherical-coordinate solution, independent of the twin-multipole series.
double stimson_jeffery(double d_over_a) {
  const double al = std::acosh(d_over_a);
  double sum = 0;
  for (int n = 1; n < 400; ++n) {
    const double num = 4 * std::pow(std::sinh((n + 0.5) * al), 2) - std::pow((2 * n + 1) * std::sinh(al), 2);
    const double den = 2 * std::sinh((2 * n + 1) * al) + (2 * n + 1) * std::sinh(2 * al);
    const double term = double(n) * (n + 1) / ((2.0 * n - 1) * (2.0 * n + 3)) * (1 - num / den);
    sum += term;
    if (std::abs(term) < 1e-17 * std::abs(sum) || !std::isfinite(den)) break;
  }
  return 4.0 / 3.0 * std::sinh(al) * sum;
}
}  // namespace

TEST_CASE("two equal spheres settling along their line of centres: SD vs Stimson & Jeffery (1926)") {
  // Within the cutoff SD is exact up to the resistance functions: measured 3.8e-6 at gap 0.01 a
  // (X^A_11 and X^A_12 ~ 1/(4 xi) cancel to O(1) here, amplifying their ~1e-7 error), 9e-8 at
  // 0.05 a, 1e-13 beyond; allowed 1e-5. Outside the cutoff (gap > 2 a) only the far field acts:
  // measured 4.2e-3 (F, FT) and 2.5e-4 (FTS) at gap 3 a, falling with distance; allowed 5e-3 and
  // 5e-4.
  for (double gap : {0.01, 0.05, 0.2, 1.0, 3.0, 5.0, 10.0}) {
    const double r = 2.0 + gap;
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      DenseStokesianDynamics sd(m, 1.0, AmbientFlow{});
      const Vec3 F(0, 0, -1);
      const HydroResult h = sd.mobility_problem({Vec3::Zero(), Vec3(0, 0, r)}, {1.0, 1.0}, {}, {F, F}, {});
      const double lambda_sd = 1.0 / (6 * M_PI * std::abs(h.U[0].z()));
      const double lambda_exact = stimson_jeffery(0.5 * r);
      const double err = std::abs(lambda_sd / lambda_exact - 1);
      CAPTURE(gap);
      CAPTURE(dof_per_particle(m));
      MESSAGE("gap " << gap << " dof " << dof_per_particle(m) << " lambda_SD " << lambda_sd << " exact " << lambda_exact << " rel err " << err);
      CHECK(err < (gap < 2.0 ? 1e-5 : m == Moments::FTS ? 5e-4 : 5e-3));
    }
  }
}

TEST_CASE("SD resistance problem: single sphere analytic values and inverse of the mobility problem") {
  // One sphere: F = 6 pi mu a (U - u_inf), T = 8 pi mu a^3 (Omega - Omega_inf), S = -(20/3) pi mu a^3 E
  // (Batchelor 1970), whatever the near field (none).
  FlowParams fp;
  fp.kind = FlowParams::Kind::simple_shear;
  fp.rate = 0.4;
  const AmbientFlow flow = ambient_flow(fp);
  const double a = 1.5;
  DenseStokesianDynamics sd(Moments::FTS, 2.0, flow);
  const Vec3 x(0.5, 1.0, 0.0), U(0.1, -0.2, 0.3), W(0.0, 0.05, 0.1);
  const HydroResult r = sd.resistance_problem({x}, {a}, {U}, {W});
  CHECK((r.F[0] - 6 * M_PI * 2.0 * a * (U - flow.velocity(x))).norm() < 1e-12);
  CHECK((r.T[0] - 8 * M_PI * 2.0 * a * a * a * (W - flow.Omega)).norm() < 1e-12);
  CHECK((from_vec5(r.S[0]) + 20.0 / 3.0 * M_PI * 2.0 * a * a * a * flow.E).norm() < 1e-12);

  // Several spheres near contact: the resistance problem inverts the mobility problem.
  const std::vector<Vec3> xs{Vec3(0, 0, 0), Vec3(2.05, 0, 0), Vec3(1.0, 1.8, 0.1), Vec3(-0.5, -1.2, 1.7)};
  const std::vector<double> as{1.0, 1.0, 0.8, 1.2};
  std::vector<Vec3> F{Vec3(0, 0, -1), Vec3(0.2, 0, -1), Vec3(0, 0.3, 0), Vec3(0, 0, 0)};
  std::vector<Vec3> T{Vec3(0, 0, 0.1), Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.2, 0)};
  const HydroResult mob = sd.mobility_problem(xs, as, {}, F, T);
  const HydroResult res = sd.resistance_problem(xs, as, mob.U, mob.Omega);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    // Both go through the same dense R; the Cholesky solve is accurate to ~1e-12 here.
    CHECK((res.F[i] - F[i]).norm() < 1e-9);
    CHECK((res.T[i] - T[i]).norm() < 1e-9);
    CHECK((res.S[i] - mob.S[i]).norm() < 1e-9);
  }
}
