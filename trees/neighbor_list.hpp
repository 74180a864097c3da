#pragma once
// Neighbour search: every pair of spheres whose surface gap h = |r_ij| - a_i - a_j is below a
// cut-off gap, in open space or in a periodic (optionally Lees-Edwards sheared) box.
//
// Geometry. A periodic box is the sheared lattice of engine/core/domain.hpp. The cell list bins
// the fractional coordinates s = Domain::fractional(x) (periodic on the unit cube) into n_k cells
// along each lattice direction with n_k = floor(w_k / R), where R = cutoff_gap + 2 max(a) is the largest interaction range and w_k the distance between
// lattice planes (w_x = Lx / sqrt(1 + gamma'^2) with gamma' the strain reduced to
// |gamma' Ly| <= Lx/2, w_y = Ly, w_z = Lz). Two centres closer than R then differ by at most one
// cell index in each direction, so the 27-cell stencil finds every pair. Each candidate is first
// tested on its stencil cell's image (wrapped positions A s, shifted by the lattice vector of the
// wrap) against cutoff_gap + a_i + max(a) plus a slack of 1e-9 of the box; only those within it
// take the exact minimum-image test, so the pair set and every r are those of the plain search.
//
// Contract (periodic): each unordered pair appears at most once, with r the minimum image. That
// representation is exact only if no pair has two images in range, which holds when
// R <= min(Lx, Ly, Lz) / 2 (the shortest lattice vector is at least min(Lx, Ly, Lz), and then
// Domain::minimum_image returns the nearest image for any separation below min(L)/2). Smaller
// boxes are rejected with std::invalid_argument. When a direction has fewer than 3 cells the
// stencil would visit a cell twice; the search then falls back to the O(N^2) loop, which is exact
// under the same contract.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian::trees {

struct NeighborPair {
  int i, j;     // particle indices, i < j
  Vec3 r;       // x_i - x_j, minimum image in periodic boxes [a]
  double dist;  // |r| [a]
};

// All pairs with |r_ij| < cutoff_gap + a_i + a_j, sorted by (i, j). Cell list, O(N) for bounded
// density; OpenMP over particles, output independent of the thread count.
// x, radius: N entries each (units of a). Throws std::invalid_argument on size mismatch or a
// periodic box smaller than twice the interaction range (see contract above).
std::vector<NeighborPair> neighbor_pairs(const std::vector<Vec3>& x, const std::vector<double>& radius,
                                         const Domain& domain, double cutoff_gap);

// Pairs within cutoff_gap counting only each pair's nearest image, in any box: the cell list, or in
// a periodic box too small for it (range above half an edge, so few particles) the plain loop over
// minimum images. For diagnostics and input checks; force and hydrodynamic kernels use
// neighbor_pairs, which refuses such boxes.
std::vector<NeighborPair> nearest_image_pairs(const std::vector<Vec3>& x, const std::vector<double>& radius,
                                              const Domain& domain, double cutoff_gap);

// Same result by the plain O(N^2) double loop: the reference the cell list is tested against.
std::vector<NeighborPair> neighbor_pairs_bruteforce(const std::vector<Vec3>& x,
                                                    const std::vector<double>& radius,
                                                    const Domain& domain, double cutoff_gap);

}  // namespace stokesian::trees
