#pragma once
// Wall particles of a channel (the scene's [walls]; geometry in engine/core/channel.hpp).
//
// Excluded-volume placement (Lee et al. 2024, fig. 2a): every wall particle lies outside the fluid
// and the first layer touches the fluid's boundary, so its centres sit r_w outside it. In each wall
// the centres form a square lattice of spacing s = 2 r_w + gap; layer k (k = 0, 1, ...) lies
// k s / sqrt(2) further out and is shifted by s/2 along both wall directions, so that neighbouring
// layers touch (at gap = 0) and close each other's pores.
//
// Along a periodic edge of the box the lattice has n = floor(L / s) sites of spacing L / n >= s (a
// seamless periodic wall); along an open extent e it has floor(e / s) + 1 sites of spacing s
// centred on the channel. Duct: the walls normal to y span the duct's width plus the side walls'
// thickness, their end sites in the side walls' planes (closing the corners); the walls normal to z
// span the height between them, their end sites `gap` from the corner sites. Along these open spans
// the end sites sit at the ends: n = ceil(extent/s) + 1 sites when their spacing extent/(n-1) keeps
// a surface gap of at least gap/2, else floor(extent/s) + 1 (spacing between s and 2 s: choose H and
// W so that H - 2 r - 2 gap and W + 2 thickness - 2 r are multiples of s for a uniform wall).
//
// Outline (engine/core/outline.hpp), a monolayer at z = 0: along each wall edge, rows of sites of
// spacing s (end sites at the row's ends, spacing stretched up to 2 s as above, at least
// 2 r_w + gap/2), row k at distance r_w + k s sqrt(3)/2 outside the edge (the touching rows of a
// hexagonal layer at gap = 0) and shifted by s/2. At a corner where the fluid turns by an angle
// phi (positive where the fluid's interior angle is below 180 deg) between two walls, the rows run
// on past the corner by d tan(phi/2) (d the row's distance; negative phi: they stop that much
// before it), so that they meet the next edge's rows; sites are then taken in order, skipping any
// closer than r_w to the fluid or closer than 2 r_w + gap/2 to a site already taken (the overlaps
// of rows at corners). Openings carry no wall.
#include "engine/core/scene.hpp"

#include <cstdint>
#include <vector>

namespace stokesian {

// Centres of the wall particles (radius c.radius each). Throws std::invalid_argument naming the
// problem when the walls cannot be built (e.g. a box too small for the channel and its walls).
std::vector<Vec3> wall_particles(const ChannelParams& c, const Domain& d);

// Interior particles of radius a placed at random (sequential addition, seeded) in an outline's
// fluid at z = 0: each at least a + gap from every wall edge, a from every opening, and
// 2 a + min_gap from every other. Throws std::invalid_argument when `count` do not fit after
// 1000 count trials.
std::vector<Vec3> fill_outline(const ChannelParams& c, long count, double a, double min_gap, std::uint64_t seed);

// Thickness of one wall: from the fluid boundary to the outer surface of its last layer [a].
double wall_thickness(const ChannelParams& c);

}  // namespace stokesian
