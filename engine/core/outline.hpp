#pragma once
// Channels drawn as a 2D outline ([walls] kind = "outline"; docs/channels.md): a closed polygon in
// the x-y plane bounding the fluid, whose edges are walls or openings (one inlet, one or more
// outlets), as the T-junction and the 4:1 contraction of Lee et al. 2024 [L24] §3.3, figs. 7-12.
// The particles form a monolayer at z = 0 ([L24]: all particles in one plane).
//
// The pressure-driven flow through the outline ([flow] kind = "poiseuille") is the particle-free
// 2D Stokes flow, solved once before the run ([L24] §2.2 solves it with COMSOL). Stream function
// psi, u = d psi/dy, v = -d psi/dx, so that mu lap^2 psi = 0 in the fluid (Stokes with the pressure
// eliminated), with:
//   walls:    psi constant (no flux through them) and d psi/dn = 0 (no slip);
//   openings: the fully developed (parabolic) normal velocity of the opening's flux q, i.e.
//             psi = psi_0 + o q (3 s^2 - 2 s^3) along it (s in [0, 1] along the edge, o = +1 for a
//             counter-clockwise outline) and d psi/dn = 0 (no tangential velocity).
// Walking the outline, psi changes only across openings, by each one's outward flux; the fluxes
// sum to zero. The inlet carries -Q = -U w_in (U the mean inlet velocity, per unit depth); the
// outlets' shares alpha_m (sum 1) are set by equal (zero) pressure at every outlet, as with
// [L24]'s zero-pressure outlets: one solve per outlet carrying all of Q gives the outlet pressures
// P_jm (pressure at outlet m when only outlet j is open); the combination sum_j alpha_j P_jm is
// equal at all outlets. The solution is that combination's solve.
//
// Discretisation: a uniform grid of spacing h on which every vertex lies; openings parallel to the
// axes, walls parallel or oblique. Fluid nodes carry psi; the 13-point stencil of lap^2 (O(h^2))
// reaches at most two nodes out. A stencil node beyond the boundary is a ghost: along the ray from
// the centre node through it, the boundary is crossed at distance d (in the ray's grid steps), where
// psi = psi_b and, psi being constant along a wall with d psi/dn = 0, the whole gradient vanishes;
// the ghost value is the cubic psi_b + a2 x^2 + a3 x^3 (x = s - d along the ray) through the two
// nodes s1 < d - kSnap and s1 - 1 behind that point, evaluated at the ghost's s (exact for a fully
// developed flow, cubic in the distance from the wall, at any inclination). A boundary on a grid
// line (d = 1 from a node beside it) gives psi_g = 3 psi_1 - psi_2 / 2 - 3 psi_b / 2. At an acute
// corner with no second node behind, the quadratic with zero slope. Fluid nodes closer than
// kSnap h = h/4 to an oblique wall take psi_b (their error (kSnap h)^2 |psi''| / 2, of the scheme's
// order; nearer nodes would make the extrapolation ill-conditioned). The system is solved by sparse
// LU. A particle sampling the grid within one cell of an oblique wall sees the interpolation toward
// the zero velocity of the nodes beyond it.
// Nodal velocities are central differences of psi (O(h^2)); on walls u = 0, on openings the
// parabolic profile. The pressure follows from grad p = mu lap u: dp/dx = mu d(lap psi)/dy,
// dp/dy = -mu d(lap psi)/dx, integrated (trapezoid) along grid paths through nodes whose eight
// neighbours are fluid, from the inlet to each outlet, and carried from the node nearest an
// opening's centre to the opening by the fully developed gradient dp/dn = -12 mu q / w^3.
// The grid flow is then a TabulatedFlow (trilinear u and grad u, engine/core/channel.hpp).
#include "engine/core/scene.hpp"

#include <Eigen/Dense>
#include <vector>

namespace stokesian {

using Vec2 = Eigen::Vector2d;

// The outline's polygon with the scene's edge roles.
struct Outline {
  std::vector<Vec2> v;    // vertices; edge k runs from v[k] to v[(k + 1) % n]
  std::vector<char> open; // edge k is an opening
  long inlet = -1;        // edge index of the inlet
  double orientation = 1; // +1 counter-clockwise, -1 clockwise
  double area = 0;        // enclosed area [a^2]

  std::size_t edges() const { return v.size(); }
  Vec2 a(std::size_t k) const { return v[k]; }
  Vec2 b(std::size_t k) const { return v[(k + 1) % v.size()]; }
  double length(std::size_t k) const { return (b(k) - a(k)).norm(); }
  Vec2 outward_normal(std::size_t k) const;  // unit normal pointing out of the fluid
  // Strictly inside the polygon (points on an edge count as outside).
  bool contains(const Vec2& p) const;
  // Distance from p to the nearest edge (all edges, or walls only).
  double distance(const Vec2& p, bool walls_only = false) const;
  // The wall edge nearest to p.
  std::size_t nearest_wall(const Vec2& p) const;
  // Area of the fluid between the lines x = x0 and x = x1 (polygon clipped to the strip).
  double area_between(double x0, double x1) const;
};

// Branches: the straight channels an outline's openings feed ([L24] §3.3 reports the T-junction's
// pressure drop and areal fraction per channel, "main" and "side"). Each opening has a flow
// direction d (inlet: its inward normal; outlets: their outward normals) and a span [lo, hi] of the
// coordinate s = p . (-d_y, d_x) across it. Openings with the same direction (d . d' > 1 - 1e-9)
// and overlapping spans form one branch (the main channel's inlet and outlet), whose strip is the
// union of their spans. Branch 0 holds the inlet, the others follow in the order of their lowest
// opening edge. A point p belongs to the first branch whose strip holds p and from which p reaches
// one of the branch's openings along d without entering another branch's strip (strips that hold p
// themselves do not count). So the crossing of a T belongs to the branch listed first, and the two
// arms of a bar fed from a stem between them are two branches. A wall particle belongs to the branch
// of its foot point on its nearest wall edge (strip edges widened by 1e-9 of the outline's size).
// A branch's cross-section width is that of its defining opening (the inlet for branch 0).
struct OutlineBranch {
  Vec2 direction = Vec2(1.0, 0.0);   // unit flow direction
  double lo = 0, hi = 0;             // strip: lo <= p . (-d_y, d_x) <= hi
  double width = 0;                  // cross-section width [a]
  double area = 0;                   // fluid area of the points it owns [a^2]
  std::vector<std::size_t> openings; // its opening edges, the defining one first
  std::vector<double> at;            // d . (the opening's midpoint), per opening
  double across(const Vec2& p) const { return -direction.y() * p.x() + direction.x() * p.y(); }
  bool holds(const Vec2& p, double eps = 0.0) const { return across(p) >= lo - eps && across(p) <= hi + eps; }
};
struct OutlineBranches {
  std::vector<OutlineBranch> branch;
  double eps = 0;  // strip widening for points on a wall
  // The branch owning point p (-1: none); `on_wall` widens the strips by eps.
  long of_point(const Vec2& p, bool on_wall = false) const;
  // The branch of a wall particle at p: its foot on wall edge k of o (its nearest, o.nearest_wall(p)).
  long of_wall_particle(const Outline& o, const Vec2& p, std::size_t k) const;
  long of_wall_particle(const Outline& o, const Vec2& p) const { return of_wall_particle(o, p, o.nearest_wall(p)); }
};
// Groups the openings into branches and measures the area each owns (cell-centre sampling on a grid
// of spacing h = (narrowest opening) / 200 anchored at the lowest vertex: exact when the vertices
// lie on that grid and the edges follow its lines, otherwise within O(h / width) relative).
OutlineBranches outline_branches(const Outline& o);

// Builds and checks the outline of a kind = "outline" channel; throws std::invalid_argument naming
// the problem (fewer than 3 vertices, zero-length or crossing edges, opening indices).
Outline make_outline(const ChannelParams& c);

// The pressure-driven flow through an outline (header formulas).
struct OutlineFlow {
  FlowGrid grid;                     // nodal velocities on the grid (a single z plane at 0)
  double h = 0;                      // grid spacing [a]
  std::vector<double> flux;          // per edge: outward flux per unit depth [a^2/time] (0 on walls)
  double pressure_drop_over_mu = 0;  // (p_inlet - p_outlets) / mu [1/time]
  std::size_t fluid_nodes = 0;
};

// Solves for mean inlet velocity U [a/time] on a grid of spacing h [a] (h = 0: the inlet width /
// 40, refined until every vertex lies on the grid). Throws std::invalid_argument when the outline
// has an oblique opening, a vertex off the grid, or a passage too narrow for the stencil.
OutlineFlow solve_outline_flow(const Outline& o, double mean_velocity, double h);

// The grid spacing solve_outline_flow uses for a requested h (0 = automatic).
double outline_grid_spacing(const Outline& o, double h);

}  // namespace stokesian
