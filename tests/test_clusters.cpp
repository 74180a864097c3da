// Cluster detection (trees/clusters.hpp) against its plain twin, and cluster shapes against exact
// values: chains and cubic blocks of spheres (radius of gyration, Feret diameter, fractal dimension
// 1 and 3), unwrapping across periodic boundaries, clusters that span the box.
#include "trees/clusters.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace stokesian;
using trees::Clusters;
using trees::ClusterShape;

namespace {

Domain open_domain() { return Domain{}; }

// A straight chain of n spheres of radius a along `dir`, centre spacing s, starting at x0.
void add_chain(std::vector<Vec3>& x, std::vector<double>& a, const Vec3& x0, const Vec3& dir, int n, double radius,
               double s) {
  for (int k = 0; k < n; ++k) {
    x.push_back(x0 + k * s * dir.normalized());
    a.push_back(radius);
  }
}

// A k x k x k simple cubic block of spheres of radius 1, spacing s, corner at x0.
void add_block(std::vector<Vec3>& x, std::vector<double>& a, const Vec3& x0, int k, double s) {
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j)
      for (int l = 0; l < k; ++l) {
        x.push_back(x0 + s * Vec3(i, j, l));
        a.push_back(1.0);
      }
}

}  // namespace

TEST_CASE("find_clusters equals its plain twin: open, periodic and sheared boxes, polydisperse, several bond gaps") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int box_kind = 0; box_kind < 3; ++box_kind)
    for (double gap : {0.0, 0.05, 0.3, 1.0}) {
      const Vec3 L(18.0, 14.0, 16.0);
      const Domain d = box_kind == 0 ? open_domain() : Domain::periodic_box(L, box_kind == 2 ? 0.37 : 0.0);
      std::vector<Vec3> x;
      std::vector<double> a;
      for (int i = 0; i < 300; ++i) {
        x.push_back(Vec3(u(rng) * L.x(), u(rng) * L.y(), u(rng) * L.z()));
        a.push_back(0.5 + 0.7 * u(rng));
      }
      std::vector<char> skip(x.size(), 0);
      for (std::size_t i = 0; i < skip.size(); i += 17) skip[i] = 1;
      for (const std::vector<char>* sk : std::vector<const std::vector<char>*>{nullptr, &skip}) {
        CAPTURE(box_kind);
        CAPTURE(gap);
        const Clusters fast = trees::find_clusters(x, a, d, gap, sk);
        const Clusters ref = trees::find_clusters_reference(x, a, d, gap, sk);
        CHECK(fast.label == ref.label);
        CHECK(fast.members == ref.members);
        CHECK(fast.bonds.size() == ref.bonds.size());
        // Sizes non-increasing; every bond inside one cluster; a skipped sphere in none.
        for (std::size_t k = 1; k < fast.members.size(); ++k)
          CHECK(fast.members[k].size() <= fast.members[k - 1].size());
        for (const auto& b : fast.bonds) CHECK(fast.label[std::size_t(b.i)] == fast.label[std::size_t(b.j)]);
        if (sk)
          for (std::size_t i = 0; i < skip.size(); ++i)
            if (skip[i]) CHECK(fast.label[i] == -1);
      }
    }
}

TEST_CASE("bonds by surface gap: a chain holds together at its spacing, breaks below it; histogram") {
  std::vector<Vec3> x;
  std::vector<double> a;
  add_chain(x, a, Vec3(0, 0, 0), Vec3(1, 0, 0), 5, 1.0, 2.08);   // gaps 0.08
  add_chain(x, a, Vec3(0, 10, 0), Vec3(0, 0, 1), 2, 1.0, 2.04);  // a doublet, gap 0.04
  x.push_back(Vec3(30, 30, 30));                                 // a single sphere
  a.push_back(2.0);
  const Clusters c = trees::find_clusters(x, a, open_domain(), 0.1);
  REQUIRE(c.members.size() == 3);
  CHECK(c.members[0] == std::vector<int>{0, 1, 2, 3, 4});
  CHECK(c.members[1] == std::vector<int>{5, 6});
  CHECK(c.members[2] == std::vector<int>{7});
  CHECK(trees::size_histogram(c) == std::vector<long>{0, 1, 1, 0, 0, 1});
  CHECK(trees::find_clusters(x, a, open_domain(), 0.07).members.size() == 7);  // the chain breaks up
  CHECK(trees::find_clusters(x, a, open_domain(), 0.03).members.size() == 8);  // and the doublet
  // Friends of friends by centre distance: 2.09 links the chain and the doublet, 2.06 the doublet.
  CHECK(trees::link_by_centres(x, open_domain(), 2.09).members.size() == 3);
  CHECK(trees::link_by_centres(x, open_domain(), 2.06).members.size() == 7);
}

TEST_CASE("radius of gyration, Feret diameter and velocity of chains and pairs are exact") {
  for (int n : {1, 2, 7, 40}) {
    std::vector<Vec3> x;
    std::vector<double> a;
    const double s = 2.02;
    add_chain(x, a, Vec3(1.0, -2.0, 0.5), Vec3(1, 2, -2), n, 1.0, s);
    const Clusters c = trees::find_clusters(x, a, open_domain(), 0.05);
    REQUIRE(c.members.size() == 1);
    const ClusterShape sh = trees::cluster_shapes(c, x, a, open_domain()).at(0);
    // Centres k s, k = 0..n-1: variance s^2 (n^2 - 1) / 12, plus 3/5 a^2 of each sphere.
    CHECK(sh.radius_of_gyration == doctest::Approx(std::sqrt(s * s * (n * n - 1) / 12.0 + 0.6)).epsilon(1e-12));
    CHECK(sh.feret == doctest::Approx((n - 1) * s + 2.0).epsilon(1e-12));
    CHECK(sh.mass == doctest::Approx(n));
  }
  // Two spheres of radii 1 and 2: Feret |r| + 3; mass-weighted centre and velocity (weights 1 : 8).
  const std::vector<Vec3> x{Vec3(0, 0, 0), Vec3(3.05, 0, 0)};
  const std::vector<double> a{1.0, 2.0};
  const std::vector<Vec3> v{Vec3(9, 0, 0), Vec3(0, 0, -9)};
  const Clusters c = trees::find_clusters(x, a, open_domain(), 0.1);
  const ClusterShape sh = trees::cluster_shapes(c, x, a, open_domain(), v).at(0);
  CHECK(sh.feret == doctest::Approx(6.05));
  CHECK(sh.centre.x() == doctest::Approx(8.0 * 3.05 / 9.0));
  CHECK((sh.velocity - Vec3(1, 0, -8)).norm() == doctest::Approx(0.0).epsilon(1e-14));
  // A small sphere inside a large one's caliper (overlapping, bonded): D_F = 2 a of the large one.
  const std::vector<Vec3> y{Vec3(0, 0, 0), Vec3(4.0, 0, 0)};
  const std::vector<double> b{0.1, 5.0};
  CHECK(trees::cluster_shapes(trees::find_clusters(y, b, open_domain(), 0.2), y, b, open_domain()).at(0).feret ==
        doctest::Approx(10.0));
}

TEST_CASE("fractal dimension: chains give 1, compact cubic blocks give 3") {
  std::vector<Vec3> x;
  std::vector<double> a;
  double z = 0.0;
  for (int n : {50, 80, 130, 200, 320}) {
    add_chain(x, a, Vec3(0, 0, z), Vec3(1, 0, 0), n, 1.0, 2.02);
    z += 10.0;
  }
  auto fit = [](const std::vector<Vec3>& x, const std::vector<double>& a) {
    const Clusters c = trees::find_clusters(x, a, open_domain(), 0.05);
    return trees::fractal_dimension(trees::cluster_shapes(c, x, a, open_domain()), 1.0, 4);
  };
  const trees::FractalFit chains = fit(x, a);
  CHECK(chains.clusters == 5);
  // R_g^2 = s^2 (n^2 - 1)/12 + 3/5 differs from s^2 n^2 / 12 by < 1e-4 relative at n >= 50.
  CHECK(chains.dimension == doctest::Approx(1.0).epsilon(2e-4));
  CHECK(chains.prefactor == doctest::Approx(std::sqrt(12.0) / 2.02).epsilon(1e-3));
  x.clear();
  a.clear();
  double off = 0.0;
  for (int k : {6, 8, 10, 13, 16}) {
    add_block(x, a, Vec3(off, 0, 0), k, 2.02);
    off += 2.02 * k + 10.0;
  }
  // Blocks: R_g^2 = 3 s^2 (k^2 - 1)/12 + 3/5, n = k^3: slope within 1 % of 3 for k >= 6.
  const trees::FractalFit blocks = fit(x, a);
  CHECK(blocks.clusters == 5);
  CHECK(blocks.dimension == doctest::Approx(3.0).epsilon(0.01));
  // Too few clusters, or too narrow a range of sizes: undefined.
  x.resize(6 * 6 * 6);
  a.resize(x.size());
  CHECK(std::isnan(fit(x, a).dimension));
}

TEST_CASE("periodic boxes: clusters unwrap across the boundary; a cluster around the box is spanning") {
  const Vec3 L(20.0, 20.0, 20.0);
  for (double strain : {0.0, 0.3}) {
    const Domain d = Domain::periodic_box(L, strain);
    std::vector<Vec3> x;
    std::vector<double> a;
    add_chain(x, a, Vec3(16.0, 5.0, 5.0), Vec3(1, 0, 0), 6, 1.0, 2.02);  // crosses x = 20
    for (Vec3& p : x) d.wrap(p);
    const Clusters c = trees::find_clusters(x, a, d, 0.05);
    REQUIRE(c.members.size() == 1);
    const ClusterShape sh = trees::cluster_shapes(c, x, a, d).at(0);
    CHECK_FALSE(sh.spanning);
    CHECK(sh.radius_of_gyration == doctest::Approx(std::sqrt(2.02 * 2.02 * 35.0 / 12.0 + 0.6)));
    CHECK(sh.feret == doctest::Approx(5 * 2.02 + 2.0));
    Vec3 expect(16.0 + 2.5 * 2.02, 5.0, 5.0);
    d.wrap(expect);
    CHECK((sh.centre - expect).norm() == doctest::Approx(0.0).epsilon(1e-9));
    // Ten spheres at spacing 2 around x: bonded to their own image.
    std::vector<Vec3> ring;
    std::vector<double> ra;
    add_chain(ring, ra, Vec3(0.5, 3.0, 3.0), Vec3(1, 0, 0), 10, 1.0, 2.0);
    const Clusters cr = trees::find_clusters(ring, ra, Domain::periodic_box(L), 0.01);
    REQUIRE(cr.members.size() == 1);
    const ClusterShape sr = trees::cluster_shapes(cr, ring, ra, Domain::periodic_box(L)).at(0);
    CHECK(sr.spanning);
    CHECK(std::isnan(sr.radius_of_gyration));
    CHECK(sr.mass == doctest::Approx(10.0));
  }
}
