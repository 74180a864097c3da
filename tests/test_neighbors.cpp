// Cell-list neighbour search against the O(N^2) reference: same pairs, same minimum-image vectors,
// each pair once, in open, periodic and Lees-Edwards boxes, polydisperse radii, several cut-offs.
#include "trees/neighbor_list.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>

using namespace stokesian;
using trees::NeighborPair;

namespace {

struct Config {
  std::vector<Vec3> x;
  std::vector<double> a;
};

// N centres uniform in [lo, lo + L) (positions deliberately not wrapped into the box, some outside),
// radii log-uniform in [a_min, a_max].
Config random_config(int N, const Vec3& L, double a_min, double a_max, std::uint64_t seed, double spill = 0.3) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Config c;
  for (int i = 0; i < N; ++i) {
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = (u(rng) * (1.0 + 2.0 * spill) - spill) * L[k];
    c.x.push_back(p);
    c.a.push_back(a_min * std::pow(a_max / a_min, u(rng)));
  }
  return c;
}

// Same (i, j) sequence and bit-identical r; every pair once with i < j; each listed pair really
// within range and every unlisted pair out of range (the brute force checks the latter).
void require_same(const std::vector<NeighborPair>& cell, const std::vector<NeighborPair>& ref) {
  REQUIRE(cell.size() == ref.size());
  std::set<std::pair<int, int>> seen;
  for (std::size_t k = 0; k < cell.size(); ++k) {
    CHECK(cell[k].i < cell[k].j);
    CHECK(cell[k].i == ref[k].i);
    CHECK(cell[k].j == ref[k].j);
    CHECK((cell[k].r - ref[k].r).norm() == 0.0);  // same expression on the same inputs
    CHECK(cell[k].dist == ref[k].dist);
    CHECK(seen.insert({cell[k].i, cell[k].j}).second);
  }
}

}  // namespace

TEST_CASE("brute force reference: pair set equals the definition") {
  // Independent check of the oracle itself: exhaustive scan over 27 images for a small box where the
  // minimum image is unique (range <= L/2).
  const Vec3 L(9.0, 10.0, 11.0);
  const Config c = random_config(60, L, 0.5, 1.5, 7, 0.0);
  for (double strain : {0.0, 0.37, -1.3}) {
    const Domain d = Domain::periodic_box(L, strain);
    const double gap = 0.8;
    const auto ref = trees::neighbor_pairs_bruteforce(c.x, c.a, d, gap);
    std::set<std::pair<int, int>> expected;
    for (int i = 0; i < 60; ++i)
      for (int j = i + 1; j < 60; ++j) {
        double best = 1e300;
        for (int ny = -2; ny <= 2; ++ny)
          for (int nx = -4; nx <= 4; ++nx)
            for (int nz = -1; nz <= 1; ++nz) {
              Vec3 s(nx * L.x() + ny * strain * L.y(), ny * L.y(), nz * L.z());
              best = std::min(best, (c.x[i] - c.x[j] + s).norm());
            }
        if (best < gap + c.a[i] + c.a[j]) expected.insert({i, j});
      }
    std::set<std::pair<int, int>> got;
    for (const auto& p : ref) {
      got.insert({p.i, p.j});
      CHECK(p.dist == doctest::Approx(p.r.norm()).epsilon(1e-15));
    }
    CHECK(got == expected);
  }
}

TEST_CASE("cell list equals brute force: open domain") {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Config c = random_config(400, Vec3(20, 15, 10), 0.1, 2.0, seed);
    Domain open;
    for (double gap : {0.0, 0.1, 1.0, 4.0}) {
      CAPTURE(seed);
      CAPTURE(gap);
      require_same(trees::neighbor_pairs(c.x, c.a, open, gap), trees::neighbor_pairs_bruteforce(c.x, c.a, open, gap));
    }
  }
}

TEST_CASE("cell list equals brute force: periodic and Lees-Edwards boxes") {
  const Vec3 L(24.0, 20.0, 18.0);
  for (double strain : {0.0, 0.25, -0.5, 0.8, 3.7}) {
    const Config c = random_config(500, L, 0.2, 2.0, 11, 0.5);
    const Domain d = Domain::periodic_box(L, strain);
    for (double gap : {0.0, 0.05, 1.0, 3.0}) {
      CAPTURE(strain);
      CAPTURE(gap);
      const auto cell = trees::neighbor_pairs(c.x, c.a, d, gap);
      CHECK(!cell.empty());
      require_same(cell, trees::neighbor_pairs_bruteforce(c.x, c.a, d, gap));
    }
  }
}

TEST_CASE("polydisperse radius ratio 10 and dense packing") {
  // Cells are sized by the largest pair; small-small and small-large pairs must still all be found.
  const Vec3 L(30.0, 30.0, 30.0);
  Config c = random_config(800, L, 0.3, 3.0, 5, 0.0);
  const Domain d = Domain::periodic_box(L, 0.1);
  require_same(trees::neighbor_pairs(c.x, c.a, d, 0.5), trees::neighbor_pairs_bruteforce(c.x, c.a, d, 0.5));
}

TEST_CASE("small boxes: fewer than 3 cells fall back correctly, too-small boxes are rejected") {
  // Range R = gap + 2 max a = 0.5 + 2 = 2.5: L = 6 gives 2 cells (fallback), L = 5 is the limit.
  const Config c = random_config(40, Vec3(6, 6, 6), 1.0, 1.0, 3);
  for (double strain : {0.0, 0.4}) {
    const Domain d = Domain::periodic_box(Vec3(6.0, 6.0, 6.0), strain);
    require_same(trees::neighbor_pairs(c.x, c.a, d, 0.5), trees::neighbor_pairs_bruteforce(c.x, c.a, d, 0.5));
  }
  // One long direction with enough cells, two short ones: still brute force, still exact.
  const Config c2 = random_config(60, Vec3(40, 6, 6), 1.0, 1.0, 4);
  const Domain d2 = Domain::periodic_box(Vec3(40.0, 6.0, 6.0), 0.2);
  require_same(trees::neighbor_pairs(c2.x, c2.a, d2, 0.5), trees::neighbor_pairs_bruteforce(c2.x, c2.a, d2, 0.5));
  // Exactly at the limit R = L/2 is accepted; beyond it an image of the same pair could be in range.
  const Domain d3 = Domain::periodic_box(Vec3(5.0, 5.0, 5.0), 0.0);
  CHECK_NOTHROW(trees::neighbor_pairs(c.x, c.a, d3, 0.5));
  CHECK_THROWS_AS(trees::neighbor_pairs(c.x, c.a, d3, 0.6), std::invalid_argument);
  CHECK_THROWS_AS(trees::neighbor_pairs_bruteforce(c.x, c.a, d3, 0.6), std::invalid_argument);
}

TEST_CASE("nearest_image_pairs: the cell list where it applies, every pair's nearest image in any box") {
  const Config c = random_config(40, Vec3(6, 6, 6), 1.0, 1.0, 3);
  const Domain fits = Domain::periodic_box(Vec3(6.0, 6.0, 6.0), 0.3);
  require_same(trees::nearest_image_pairs(c.x, c.a, fits, 0.5), trees::neighbor_pairs(c.x, c.a, fits, 0.5));
  // Range 3.2 > L/2 = 2.5: the pair list proper is refused; here each pair counts once, by the
  // definition (minimum-image distance below gap + a_i + a_j) written out independently.
  const Domain small = Domain::periodic_box(Vec3(5.0, 5.0, 5.0), 0.3);
  const auto got = trees::nearest_image_pairs(c.x, c.a, small, 1.2);
  std::size_t expected = 0;
  for (std::size_t i = 0; i < c.x.size(); ++i)
    for (std::size_t j = i + 1; j < c.x.size(); ++j)
      if (small.minimum_image(c.x[i] - c.x[j]).norm() < 1.2 + c.a[i] + c.a[j]) ++expected;
  CHECK(got.size() == expected);
  for (const auto& p : got) CHECK(p.dist == doctest::Approx(small.minimum_image(c.x[std::size_t(p.i)] - c.x[std::size_t(p.j)]).norm()));
}

TEST_CASE("degenerate inputs") {
  Domain open;
  CHECK(trees::neighbor_pairs({}, {}, open, 1.0).empty());
  CHECK(trees::neighbor_pairs({Vec3::Zero()}, {1.0}, open, 1.0).empty());
  CHECK_THROWS_AS(trees::neighbor_pairs({Vec3::Zero()}, {}, open, 1.0), std::invalid_argument);
  // Coincident and collinear points (zero bounding-box extent in two directions).
  std::vector<Vec3> x{Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(1.5, 0, 0), Vec3(100, 0, 0)};
  std::vector<double> a{1.0, 1.0, 0.5, 1.0};
  const auto p = trees::neighbor_pairs(x, a, open, 0.1);
  require_same(p, trees::neighbor_pairs_bruteforce(x, a, open, 0.1));
  CHECK(p.size() == 3);  // (0,1), (0,2), (1,2)
  // Two far-apart particles: the grid is capped, not 1e12 cells.
  std::vector<Vec3> far{Vec3(0, 0, 0), Vec3(1e6, 1e6, 1e6), Vec3(1e6 + 1, 1e6, 1e6)};
  const auto q = trees::neighbor_pairs(far, {0.5, 0.5, 0.5}, open, 0.5);
  REQUIRE(q.size() == 1);
  CHECK(q[0].i == 1);
  CHECK(q[0].j == 2);
  CHECK(q[0].r.x() == doctest::Approx(-1.0));
}
