#pragma once
// Initial configurations generated from a target volume fraction.
//   random:  uniform random centres, then overlaps removed by sweeps of pairwise separation along
//            the lines of centres (cell-list neighbour search, O(N) per sweep); reaches phi ~ 0.6.
//   lattice: simple cubic lattice of spacing (4 pi a_mean^3 / (3 phi))^(1/3) (radii may still
//            differ; overlapping draws are rejected).
// Radii: monodisperse a; bidisperse a and ratio*a with number fraction f of the large ones;
// lognormal with median a and log standard deviation sigma.
#include "engine/core/types.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace stokesian {

struct PlacementParams {
  enum class Pattern { random, lattice } pattern = Pattern::random;
  enum class Sizes { monodisperse, bidisperse, lognormal } sizes = Sizes::monodisperse;
  long count = 0;               // number of particles
  double volume_fraction = 0.1; // phi = sum (4/3) pi a^3 / V
  double radius = 1.0;          // a (median for lognormal) [a]
  double radius_ratio = 2.0;    // bidisperse: large / small radius
  double large_fraction = 0.5;  // bidisperse: number fraction of large particles
  double sigma = 0.2;           // lognormal: standard deviation of ln a
  std::uint64_t seed = 1;
};

struct Placement {
  std::vector<Vec3> position;
  std::vector<double> radius;
  Vec3 box;  // the region filled: the periodic box, or the cube used for open domains
};

// box: the periodic box, or a zero vector for open domains (a cube of the right volume centred at
// the origin is used). Throws std::invalid_argument with a message on impossible requests.
Placement place_particles(const PlacementParams& p, const Vec3& box);

}  // namespace stokesian
