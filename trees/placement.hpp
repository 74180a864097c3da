#pragma once
// Initial configurations generated from a target volume fraction (docs/configurations.md).
//
// Radii (drawn first, stream (placement, 0)):
//   monodisperse  a_i = radius
//   bidisperse    a_i = radius (small species) or radius_ratio * radius (large species); exactly
//                 round(large_fraction * count) large ones, at random indices
//   lognormal     a_i = exp(ln(radius) + sigma * z_i), z_i standard normal: radius is the median
//   bimodal       the two species of bidisperse, each spread lognormally about its median:
//                 a_i = m_i exp(sigma * z_i), m_i = radius or radius_ratio * radius
//
// Segregation (open sphere region, two species): the large species is confined to the half z >= 0
// of the sphere (large_up) or z <= 0 (large_down), the small one to the other half.
//
// Hard core: two particles may not come closer than a_i + a_j + min_gap (surface gap >= min_gap);
// in an open domain a particle stays inside the region (|x_i| <= R - a_i for the sphere of radius
// R, x_i within a_i of no face for the cube). The region's volume is sum (4/3) pi a_i^3 / phi.
//
// random:  (1) random sequential addition (RSA): particles in decreasing size, each at uniform
//              random trial positions until it overlaps nobody. With equilibration_sweeps = 0 this
//              is the result (RSA of spheres jams at phi = 0.384 [C88]; refused above 0.35, where
//              the last particles already need millions of attempts each).
//          (2) otherwise RSA is run at reduced size: s_i = lambda0 = (0.25/phi)^(1/3) (if < 1),
//              except the largest particles, which start at full size while the RSA volume
//              fraction stays <= 0.30. Then hard-sphere Metropolis Monte Carlo [M53] sweeps
//              (each particle in turn tries a displacement uniform in a cube, rejected on overlap;
//              the cube's edge adapts towards acceptance 0.4) alternate with growth passes in
//              which each particle grows its scale s_i towards 1 by at most 0.01 and by at most
//              2% x max(1, a_i / median a) (at most 10%) of the room its neighbours and the
//              walls leave: a Monte Carlo form of Lubachevsky–Stillinger compression [LS90],
//              slow enough that the fluid stays near equilibrium. Once every s_i = 1,
//              equilibration_sweeps sweeps at full size equilibrate the hard-sphere fluid.
//              Sweep k uses the counter-based stream (equilibration, k); RSA uses (placement, 1).
// lattice: simple cubic lattice (periodic box or open cube: ceil(count^(1/3)) sites per edge;
//          open sphere: the count sites of spacing (V_region / count)^(1/3) nearest the centre);
//          a site whose particle would overlap is an error.
//
// Every step is O(N) per sweep: a uniform cell grid in which each particle is registered in every
// cell its bounding cube touches (exact for any size ratio; work ~ N + V / h^3).
//
// [C88] Cooper, Phys. Rev. A 38, 522 (1988) — RSA of spheres, jamming at phi = 0.384.
// [M53] Metropolis, Rosenbluth, Rosenbluth, Teller & Teller, J. Chem. Phys. 21, 1087 (1953).
// [LS90] Lubachevsky & Stillinger, J. Stat. Phys. 60, 561 (1990).
#include "engine/core/types.hpp"

#include "engine/core/scene.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace stokesian {

struct PlacementParams {
  enum class Pattern { random, lattice } pattern = Pattern::random;
  enum class Sizes { monodisperse, bidisperse, lognormal, bimodal } sizes = Sizes::monodisperse;
  enum class Segregation { none, large_up, large_down } segregation = Segregation::none;
  enum class Region { sphere, cube } region = Region::sphere;  // open domains only
  long count = 0;               // number of particles
  double volume_fraction = 0.1; // open domains: phi = sum (4/3) pi a^3 / V_region (periodic: unused)
  double radius = 1.0;          // monodisperse: a; bidisperse: small radius; lognormal: median; bimodal: small median [a]
  double radius_ratio = 2.0;    // bidisperse, bimodal: large / small radius (median)
  double large_fraction = 0.5;  // bidisperse, bimodal: number fraction of large particles
  double sigma = 0.2;           // lognormal, bimodal: standard deviation of ln a (of each mode)
  double min_gap = 1e-3;        // hard-core margin: surface gaps >= min_gap [a]
  long equilibration_sweeps = 100;  // random: Monte Carlo sweeps at the target size (0 = plain RSA)
  // Periodic boxes only: confine the particles to the fluid region of these walls (every particle
  // wholly inside it: centre at least a_i from the boundary; engine/core/channel.hpp). The volume
  // fraction is then relative to the fluid volume.
  ChannelParams channel;
  std::uint64_t seed = 1;
};

// Plain RSA is refused above this volume fraction: it jams at ~0.38 [C88], and beyond ~0.35 the
// last particles need millions of attempts each.
inline constexpr double kRsaMaxVolumeFraction = 0.35;

struct Placement {
  std::vector<Vec3> position;
  std::vector<double> radius;
  Vec3 box;                    // the periodic box, or the bounding cube of the open region
  double sphere_radius = 0.0;  // open sphere region: its radius R (centre at the origin); else 0
  long growth_sweeps = 0;      // random: Monte Carlo sweeps spent growing the particles to full size
};

// Rough wall time of place_particles on one core, for the notice before a long placement: lattice
// about 4 us per particle; random about (2 + 0.21 sweeps) us per particle, sweeps = equilibration
// (+ growth, which is of the same order). Measured on the 2-core development machine (2026-11):
// lattice 1e5 -> 0.4 s, 3e5 -> 1.2 s; random (100 sweeps) 1e5 -> 2.3 s, 3e5 -> 8.4 s.
inline double placement_seconds_estimate(const PlacementParams& p) {
  const double n = double(p.count);
  if (p.pattern == PlacementParams::Pattern::lattice) return 4e-6 * n;
  return n * (2e-6 + 0.21e-6 * double(p.equilibration_sweeps));
}

// Volume of the fluid region of `c` (slit or duct, or none: the whole box) in the periodic box [a^3].
double fluid_volume(const ChannelParams& c, const Vec3& box);

// box: the periodic box, or a zero vector for open domains (region centred at the origin).
// Throws std::invalid_argument with a message on impossible requests.
Placement place_particles(const PlacementParams& p, const Vec3& box);

}  // namespace stokesian
