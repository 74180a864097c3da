#include "trees/octree.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

namespace stokesian::trees {

namespace {

struct Cube {
  Vec3 mid;
  double half;
};

void finish_node(OctreeNode& node, const std::vector<int>& order, const std::vector<Vec3>& x,
                 const std::vector<double>& a) {
  Vec3 lo = x[std::size_t(order[std::size_t(node.begin)])], hi = lo;
  node.a_max = 0;
  for (int k = node.begin; k < node.end; ++k) {
    const std::size_t i = std::size_t(order[std::size_t(k)]);
    lo = lo.cwiseMin(x[i]);
    hi = hi.cwiseMax(x[i]);
    node.a_max = std::max(node.a_max, a[i]);
  }
  node.centre = 0.5 * (lo + hi);
  double r2 = 0;
  for (int k = node.begin; k < node.end; ++k)
    r2 = std::max(r2, (x[std::size_t(order[std::size_t(k)])] - node.centre).squaredNorm());
  node.radius = std::sqrt(r2);
}

}  // namespace

Octree build_octree(const std::vector<Vec3>& x, const std::vector<double>& a, int leaf_size) {
  if (x.size() != a.size())
    throw std::invalid_argument("octree: " + std::to_string(x.size()) + " positions but " + std::to_string(a.size()) +
                                " radii");
  if (leaf_size < 1) throw std::invalid_argument("octree: leaf size " + std::to_string(leaf_size) + " < 1");
  Octree t;
  t.leaf_size = leaf_size;
  const int n = int(x.size());
  t.order.resize(std::size_t(n));
  for (int i = 0; i < n; ++i) t.order[std::size_t(i)] = i;
  if (n == 0) return t;

  Vec3 lo = x[0], hi = x[0];
  for (const Vec3& p : x) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double root_half = std::max(0.5 * (hi - lo).maxCoeff(), 1e-300);
  const double min_half = 1e-9 * root_half;
  std::vector<Cube> cubes{{0.5 * (lo + hi), root_half}};
  t.nodes.push_back(OctreeNode{});
  t.nodes[0].begin = 0;
  t.nodes[0].end = n;
  // Level by level (breadth first): the nodes of one level are finished and partitioned in parallel
  // (each owns its range of `order`), then their children are appended in node order, so the tree
  // is the same for any thread count.
  std::size_t level_begin = 0;
  while (level_begin < t.nodes.size()) {
    const std::size_t level_end = t.nodes.size();
    const long count_nodes = long(level_end - level_begin);
    std::vector<std::array<int, 9>> counts(static_cast<std::size_t>(count_nodes));
    std::vector<char> split(static_cast<std::size_t>(count_nodes), 0);
#pragma omp parallel if (count_nodes > 1 && n > 4096)
    {
      std::vector<int> scratch;
#pragma omp for schedule(dynamic, 1)
      for (long j = 0; j < count_nodes; ++j) {
        const std::size_t k = level_begin + std::size_t(j);
        OctreeNode& node = t.nodes[k];
        finish_node(node, t.order, x, a);
        const Cube cube = cubes[k];
        if (node.size() <= leaf_size || cube.half < min_half) continue;
        split[std::size_t(j)] = 1;
        const int begin = node.begin, end = node.end;
        std::array<int, 9>& count = counts[std::size_t(j)];
        count.fill(0);
        auto octant = [&](int i) {
          const Vec3& p = x[std::size_t(i)];
          return (p.x() >= cube.mid.x() ? 1 : 0) | (p.y() >= cube.mid.y() ? 2 : 0) | (p.z() >= cube.mid.z() ? 4 : 0);
        };
        for (int q = begin; q < end; ++q) ++count[std::size_t(octant(t.order[std::size_t(q)]) + 1)];
        for (int o = 0; o < 8; ++o) count[std::size_t(o + 1)] += count[std::size_t(o)];
        scratch.assign(std::size_t(end - begin), 0);
        std::array<int, 9> fill = count;
        for (int q = begin; q < end; ++q) {
          const int i = t.order[std::size_t(q)];
          scratch[std::size_t(fill[std::size_t(octant(i))]++)] = i;
        }
        std::copy(scratch.begin(), scratch.end(), t.order.begin() + begin);
      }
    }
    for (long j = 0; j < count_nodes; ++j) {
      const std::size_t k = level_begin + std::size_t(j);
      t.depth = std::max(t.depth, t.nodes[k].level);
      if (!split[std::size_t(j)]) continue;
      const std::array<int, 9>& count = counts[std::size_t(j)];
      const Cube cube = cubes[k];
      const int first = int(t.nodes.size());
      int children = 0;
      for (int o = 0; o < 8; ++o) {
        if (count[std::size_t(o + 1)] == count[std::size_t(o)]) continue;
        OctreeNode child;
        child.begin = t.nodes[k].begin + count[std::size_t(o)];
        child.end = t.nodes[k].begin + count[std::size_t(o + 1)];
        child.level = t.nodes[k].level + 1;
        const double h = 0.5 * cube.half;
        const Vec3 mid = cube.mid + Vec3((o & 1) ? h : -h, (o & 2) ? h : -h, (o & 4) ? h : -h);
        t.nodes.push_back(child);
        cubes.push_back({mid, h});
        ++children;
      }
      t.nodes[k].first_child = first;
      t.nodes[k].child_count = children;
    }
    level_begin = level_end;
  }
  return t;
}

}  // namespace stokesian::trees
