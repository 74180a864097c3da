#pragma once
// Equilibrium hard-sphere configurations for the validations of short-time transport properties
// (tests/support/self_diffusion.hpp, tests/support/transport.hpp): n spheres of radius 1 in a
// periodic cube of side L from trees/placement.hpp (RSA at reduced size, Monte Carlo growth, 100
// sweeps at full size; surface gaps >= 1e-3 a), seeded.
#include "trees/placement.hpp"

#include <cstdint>

namespace stokesian::test {

inline Placement equilibrium_hard_spheres(long n, double L, std::uint64_t seed) {
  PlacementParams pp;
  pp.count = n;
  pp.seed = seed;
  pp.min_gap = 1e-3;
  pp.equilibration_sweeps = 100;
  return place_particles(pp, Vec3(L, L, L));
}

}  // namespace stokesian::test
