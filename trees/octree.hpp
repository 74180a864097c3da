#pragma once
// Adaptive octree over sphere centres, the spatial index of the Barnes-Hut far field
// (trees/tree_mobility.hpp).
//
// The root is the bounding cube of the centres. A node holding more than `leaf_size` particles is
// split at its cube's midpoint into up to eight children (empty octants are dropped); splitting
// stops at leaf_size particles or when the cube edge falls below 1e-9 of the root's (coincident
// centres). Particles are permuted (`order`) so that every node owns one contiguous range, and the
// children of a node are stored contiguously. Each node records its expansion centre c (the
// midpoint of its particles' bounding box), the radius rho = max |x_i - c| over its particles and
// the largest sphere radius in it, the quantities of the multipole acceptance test. Built level by
// level, the nodes of a level in parallel (OpenMP); the result does not depend on the thread count.
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian::trees {

struct OctreeNode {
  Vec3 centre = Vec3::Zero();  // expansion centre [a]
  double radius = 0;           // max |x_i - centre| over the node's particles [a]
  double a_max = 0;            // largest sphere radius among them [a]
  int begin = 0, end = 0;      // particles order[begin..end)
  int first_child = -1;        // children nodes[first_child .. first_child + child_count)
  int child_count = 0;
  int level = 0;               // root 0
  bool leaf() const { return child_count == 0; }
  int size() const { return end - begin; }
};

struct Octree {
  std::vector<int> order;        // particle indices, each node's range contiguous
  std::vector<OctreeNode> nodes; // nodes[0] is the root (absent for zero particles)
  int leaf_size = 0;
  int depth = 0;                 // largest node level
};

// Builds the tree. leaf_size >= 1; x and a have equal sizes (std::invalid_argument otherwise).
Octree build_octree(const std::vector<Vec3>& x, const std::vector<double>& a, int leaf_size);

}  // namespace stokesian::trees
