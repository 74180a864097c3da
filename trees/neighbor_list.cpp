// Cell-list neighbour search; the geometry and the contract are stated in neighbor_list.hpp.
#include "trees/neighbor_list.hpp"

#include "engine/core/parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace stokesian::trees {
namespace {

void check_inputs(const std::vector<Vec3>& x, const std::vector<double>& radius) {
  if (x.size() != radius.size())
    throw std::invalid_argument("neighbor_pairs: " + std::to_string(x.size()) + " positions but " +
                                std::to_string(radius.size()) + " radii");
}

double max_radius(const std::vector<double>& radius) {
  double a = 0.0;
  for (double r : radius) a = std::max(a, r);
  return a;
}

// Rejects periodic boxes in which one pair could have two images within range (header contract).
void check_periodic_range(const Domain& domain, double range) {
  if (!domain.periodic()) return;
  const double lmin = domain.box.minCoeff();
  if (!(lmin > 0.0)) throw std::invalid_argument("neighbor_pairs: periodic box with non-positive edge");
  if (range > 0.5 * lmin)
    throw std::invalid_argument("neighbor_pairs: interaction range " + std::to_string(range) +
                                " exceeds half the smallest box edge " + std::to_string(0.5 * lmin) +
                                "; the minimum-image pair list cannot represent this box");
}

bool pair_in_range(const std::vector<Vec3>& x, const std::vector<double>& radius, const Domain& domain,
                   double cutoff_gap, int i, int j, NeighborPair& out) {
  const Vec3 r = domain.minimum_image(x[i] - x[j]);
  const double d = r.norm();
  if (!(d < cutoff_gap + radius[i] + radius[j])) return false;
  out = NeighborPair{i, j, r, d};
  return true;
}

void sort_pairs(std::vector<NeighborPair>& pairs) {
  std::sort(pairs.begin(), pairs.end(), [](const NeighborPair& p, const NeighborPair& q) {
    return p.i != q.i ? p.i < q.i : p.j < q.j;
  });
}

// Cell grid over fractional coordinates: periodic (wrapping) or open (clipped bounding box).
struct CellGrid {
  std::array<int, 3> n{1, 1, 1};
  bool wrap = false;
  std::vector<std::array<int, 3>> cell_of;  // per particle
  std::vector<int> start, members;          // CSR: members[start[c] .. start[c+1]) in index order
  // Per member (CSR order): the wrapped position A s (periodic; x in open space) and the index.
  // A stencil cell's image of member j is w_j + A shift, so |w_i - w_j - A shift| is the distance
  // of that image: a cheap pre-test before the exact minimum image.
  std::vector<double> wx, wy, wz;
  Mat3 lattice = Mat3::Identity();

  int id(int cx, int cy, int cz) const { return (cz * n[1] + cy) * n[0] + cx; }
};

// Bounds the cell count to about 8 per particle (at least 27) so dilute systems do not allocate huge
// empty grids; larger cells stay correct. Halves the largest direction, never below `floor_n`.
void cap_cells(std::array<int, 3>& n, std::size_t particles, int floor_n) {
  const double cap = std::max<double>(27.0, 8.0 * static_cast<double>(particles));
  while (double(n[0]) * n[1] * n[2] > cap) {
    int k = 0;
    for (int d = 1; d < 3; ++d)
      if (n[d] > n[k]) k = d;
    if (n[k] <= floor_n) break;
    n[k] = std::max(floor_n, n[k] / 2);
  }
}

// Returns false when a periodic direction has fewer than 3 cells (caller uses the O(N^2) loop).
bool build_grid(const std::vector<Vec3>& x, const Domain& domain, double range, CellGrid& g) {
  const std::size_t N = x.size();
  std::vector<Vec3> s(N);  // cell coordinate in units of the whole grid, in [0, 1)
  if (domain.periodic()) {
    const Vec3& L = domain.box;
    const double gamma = domain.reduced_strain();  // same lattice, smallest tilt
    const std::array<double, 3> width{L.x() / std::sqrt(1.0 + gamma * gamma), L.y(), L.z()};
    for (int k = 0; k < 3; ++k) g.n[k] = static_cast<int>(std::floor(width[k] / range));
    if (g.n[0] < 3 || g.n[1] < 3 || g.n[2] < 3) return false;
    cap_cells(g.n, N, 3);
    for (std::size_t i = 0; i < N; ++i) {
      Vec3 f = domain.fractional(x[i]);
      for (int k = 0; k < 3; ++k) f[k] -= std::floor(f[k]);
      s[i] = f;
    }
    g.wrap = true;
  } else {
    Vec3 lo = x[0], hi = x[0];
    for (const Vec3& p : x) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Vec3 extent = hi - lo;
    for (int k = 0; k < 3; ++k) g.n[k] = std::max(1, static_cast<int>(std::floor(extent[k] / range)));
    cap_cells(g.n, N, 1);
    for (std::size_t i = 0; i < N; ++i)
      for (int k = 0; k < 3; ++k) s[i][k] = extent[k] > 0.0 ? (x[i][k] - lo[k]) / extent[k] : 0.0;
    g.wrap = false;
  }
  const int ncell = g.n[0] * g.n[1] * g.n[2];
  g.cell_of.resize(N);
  std::vector<int> count(ncell + 1, 0);
  for (std::size_t i = 0; i < N; ++i) {
    for (int k = 0; k < 3; ++k)  // clamp: s = 1 - tiny can round up to n
      g.cell_of[i][k] = std::min(g.n[k] - 1, std::max(0, static_cast<int>(s[i][k] * g.n[k])));
    ++count[g.id(g.cell_of[i][0], g.cell_of[i][1], g.cell_of[i][2]) + 1];
  }
  for (int c = 0; c < ncell; ++c) count[c + 1] += count[c];
  g.start = count;
  g.members.resize(N);
  std::vector<int> fill(count.begin(), count.end() - 1);
  for (std::size_t i = 0; i < N; ++i)
    g.members[fill[g.id(g.cell_of[i][0], g.cell_of[i][1], g.cell_of[i][2])]++] = static_cast<int>(i);
  g.wx.resize(N);
  g.wy.resize(N);
  g.wz.resize(N);
  if (g.wrap) g.lattice = domain.lattice();
  for (std::size_t m = 0; m < N; ++m) {
    const int i = g.members[m];
    const Vec3 w = g.wrap ? Vec3(g.lattice * s[i]) : x[i];
    g.wx[m] = w.x();
    g.wy[m] = w.y();
    g.wz[m] = w.z();
  }
  return true;
}

}  // namespace

std::vector<NeighborPair> neighbor_pairs_bruteforce(const std::vector<Vec3>& x,
                                                    const std::vector<double>& radius,
                                                    const Domain& domain, double cutoff_gap) {
  check_inputs(x, radius);
  const double range = cutoff_gap + 2.0 * max_radius(radius);
  std::vector<NeighborPair> pairs;
  if (x.size() < 2 || !(range > 0.0)) return pairs;
  check_periodic_range(domain, range);
  const int N = static_cast<int>(x.size());
  NeighborPair p;
  for (int i = 0; i < N; ++i)
    for (int j = i + 1; j < N; ++j)
      if (pair_in_range(x, radius, domain, cutoff_gap, i, j, p)) pairs.push_back(p);
  return pairs;
}

std::vector<NeighborPair> nearest_image_pairs(const std::vector<Vec3>& x, const std::vector<double>& radius,
                                              const Domain& domain, double cutoff_gap) {
  check_inputs(x, radius);
  const double range = cutoff_gap + 2.0 * max_radius(radius);
  if (!domain.periodic() || range <= 0.5 * domain.box.minCoeff()) return neighbor_pairs(x, radius, domain, cutoff_gap);
  std::vector<NeighborPair> pairs;
  NeighborPair p;
  for (int i = 0; i < int(x.size()); ++i)
    for (int j = i + 1; j < int(x.size()); ++j)
      if (pair_in_range(x, radius, domain, cutoff_gap, i, j, p)) pairs.push_back(p);
  return pairs;
}

std::vector<NeighborPair> neighbor_pairs(const std::vector<Vec3>& x, const std::vector<double>& radius,
                                         const Domain& domain, double cutoff_gap) {
  check_inputs(x, radius);
  const double range = cutoff_gap + 2.0 * max_radius(radius);
  std::vector<NeighborPair> pairs;
  if (x.size() < 2 || !(range > 0.0)) return pairs;
  check_periodic_range(domain, range);

  CellGrid g;
  if (!build_grid(x, domain, range, g)) return neighbor_pairs_bruteforce(x, radius, domain, cutoff_gap);

  const int N = static_cast<int>(x.size());
  // Position of each particle in the CSR order (its w).
  std::vector<int> slot(N);
  for (int m = 0; m < N; ++m) slot[g.members[m]] = m;
  const double amax = max_radius(radius);
  // The pre-test keeps a superset of the pairs: its bound exceeds every pair's range by a slack
  // far above the rounding of the two ways of forming the separation.
  const double slack = 1e-9 * (g.wrap ? domain.box.maxCoeff() + range : range + 1.0);
  // Each thread collects into its own vector; the final sort makes the order thread-independent
  // (every pair's r is computed by the same expression whichever thread finds it).
#pragma omp parallel if (N >= parallel::kNeighborParticles)
  {
    std::vector<NeighborPair> local;
#pragma omp for schedule(static) nowait
    for (int i = 0; i < N; ++i) {
      const auto& c = g.cell_of[i];
      const int si = slot[i];
      const double bound = cutoff_gap + radius[i] + amax + slack, bound2 = bound * bound;
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            std::array<int, 3> nb{c[0] + dx, c[1] + dy, c[2] + dz};
            std::array<int, 3> wrapped{0, 0, 0};
            bool inside = true;
            for (int k = 0; k < 3; ++k) {
              if (g.wrap) {
                wrapped[k] = (nb[k] >= g.n[k]) - (nb[k] < 0);
                nb[k] = (nb[k] + g.n[k]) % g.n[k];
              } else if (nb[k] < 0 || nb[k] >= g.n[k]) {
                inside = false;
              }
            }
            if (!inside) continue;
            const int cell = g.id(nb[0], nb[1], nb[2]);
            // The stencil cell's image of w_j is w_j + A wrapped.
            const Vec3 shift = g.wrap ? Vec3(g.lattice * Vec3(wrapped[0], wrapped[1], wrapped[2])) : Vec3::Zero();
            const double px = g.wx[si] - shift.x(), py = g.wy[si] - shift.y(), pz = g.wz[si] - shift.z();
            NeighborPair p;
            for (int m = g.start[cell]; m < g.start[cell + 1]; ++m) {
              const double ex = px - g.wx[m], ey = py - g.wy[m], ez = pz - g.wz[m];
              if (ex * ex + ey * ey + ez * ez > bound2) continue;
              const int j = g.members[m];
              if (j > i && pair_in_range(x, radius, domain, cutoff_gap, i, j, p)) local.push_back(p);
            }
          }
    }
#pragma omp critical(stokesian_neighbor_merge)
    pairs.insert(pairs.end(), local.begin(), local.end());
  }
  sort_pairs(pairs);
  return pairs;
}

}  // namespace stokesian::trees
