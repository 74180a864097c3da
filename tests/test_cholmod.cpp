// CHOLMOD wrapper: solve and factor product against dense Eigen, symbolic reuse, failure report.
#include <doctest/doctest.h>

#include "engine/core/errors.hpp"
#include "lubrication/cholmod_factor.hpp"
#include "lubrication/near_field.hpp"

#include <random>

using namespace stokesian;
using lubrication::CholmodFactor;
using lubrication::SparseMatrix;

namespace {
// Random sparse SPD matrix: block-banded pattern plus a diagonal shift.
SparseMatrix random_spd(int n, std::uint64_t seed, double shift) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  MatX B = MatX::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = std::max(0, i - 4); j <= i; ++j)
      if (j == i || u(rng) > 0.2) B(i, j) = u(rng);
  MatX A = B * B.transpose() + shift * MatX::Identity(n, n);
  return A.sparseView();
}
}  // namespace

TEST_CASE("CHOLMOD solve and factor product agree with dense linear algebra") {
  for (int n : {5, 60, 300}) {
    const SparseMatrix R = random_spd(n, std::uint64_t(n), 0.1);
    CholmodFactor f;
    f.factorize(R);
    const MatX Rd = MatX(R);
    const VecX b = VecX::LinSpaced(n, -1.0, 2.0);
    // Condition numbers here are < 1e4: solves agree to 1e-10 relative.
    CHECK((f.solve(b) - Rd.ldlt().solve(b)).norm() < 1e-10 * b.norm());
    // psi = P^T L w for every unit w gives the columns of B with B B^T = R.
    MatX Bm(n, n);
    for (int k = 0; k < n; ++k) Bm.col(k) = f.multiply_L(VecX::Unit(n, k));
    CHECK((Bm * Bm.transpose() - Rd).norm() < 1e-12 * Rd.norm());
    CHECK(f.factor_nonzeros() >= R.nonZeros() / 2);
  }
}

TEST_CASE("the symbolic analysis is reused while the pattern is unchanged") {
  SparseMatrix R = random_spd(80, 3, 0.5);
  CholmodFactor f;
  CHECK(!f.factorize(R));
  R.coeffs() *= 2.0;
  CHECK(f.factorize(R));
  CHECK(f.analyses() == 1);
  const VecX b = VecX::Ones(80);
  CHECK((f.solve(b) - MatX(R).ldlt().solve(b)).norm() < 1e-10);
  SparseMatrix R2 = random_spd(80, 4, 0.5);
  f.factorize(R2);
  CHECK(f.analyses() == 2);
}

TEST_CASE("an indefinite matrix is reported, not factorised") {
  SparseMatrix R = random_spd(30, 5, 0.5);
  R.coeffRef(17, 17) = -50.0;
  CholmodFactor f;
  CHECK_THROWS_AS(f.factorize(R), PhysicsError);
  try {
    f.factorize(R);
  } catch (const PhysicsError& e) {
    CHECK(std::string(e.what()).find("not positive definite") != std::string::npos);
  }
}

TEST_CASE("a failed near-field factorisation names the particle and its closest pair") {
  // A deliberately indefinite R (negative diagonal entry of particle 2) must be reported with the
  // particle owning the failing column and its nearest neighbour.
  const std::vector<Vec3> x{Vec3(0, 0, 0), Vec3(5, 0, 0), Vec3(2.05, 0, 0), Vec3(0, 7, 0)};
  const std::vector<double> a{1.0, 1.0, 1.0, 1.0};
  lubrication::NearField nf(Moments::F, 1.0);
  SparseMatrix R = MatX::Identity(12, 12).sparseView();
  R.coeffRef(7, 7) = -1.0;  // column 7 belongs to particle 2 (3 entries per particle)
  lubrication::CholmodFactor f;
  try {
    nf.factorize(R, f, x, a, Domain{});
    FAIL("expected a PhysicsError");
  } catch (const PhysicsError& e) {
    const std::string msg = e.what();
    CHECK(msg.find("particle 2") != std::string::npos);
    CHECK(msg.find("(2, 0)") != std::string::npos);
  }
}
