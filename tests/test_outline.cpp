// Outline channels (issue 17; engine/core/outline.hpp, trees/walls.hpp, docs/channels.md).
//
// References, each independent of the code under test:
//   - a straight outline carries plane Poiseuille flow, u = (3/2) U (1 - (2 eta / H)^2), with the
//     pressure drop 12 mu U L / H^2 (closed form);
//   - mass conservation: the flux through every cross-section equals the inlet's;
//   - symmetry: a symmetric T splits the flux evenly; an asymmetric one in the inverse ratio of its
//     outlet arms' lengths (the Poiseuille resistance 12 mu L / w^3 of each arm, to within the
//     junction's local correction, a fraction of a width);
//   - geometry: wall particles outside the fluid, not overlapping, covering every wall edge, none
//     on an opening.
#include <doctest/doctest.h>

#include "engine/core/channel.hpp"
#include "engine/core/outline.hpp"
#include "engine/hydrodynamics.hpp"
#include "engine/model.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"
#include "support/sanitizer.hpp"
#include "trees/walls.hpp"

#include <cmath>
#include <string>

using namespace stokesian;

namespace {

ChannelParams outline(std::vector<std::array<double, 2>> v, std::vector<long> openings, long inlet) {
  ChannelParams c;
  c.kind = ChannelParams::Kind::outline;
  c.outline = std::move(v);
  c.openings = std::move(openings);
  c.inlet = inlet;
  c.depth = 2.0;
  return c;
}

// Straight channel [0, 40] x [-5, 5], inlet at x = 0 (edge 3), outlet at x = 40 (edge 1).
ChannelParams straight() { return outline({{0, -5}, {40, -5}, {40, 5}, {0, 5}}, {1, 3}, 3); }

// T: stem x in [-5, 5], y in [-30, 0] (inlet at its foot, edge 0); bar y in [0, 10] from x = -left
// to x = right (outlets at its ends, edges 3 and 5).
ChannelParams tee(double left, double right) {
  return outline({{-5, -30}, {5, -30}, {5, 0}, {right, 0}, {right, 10}, {-left, 10}, {-left, 0}, {-5, 0}}, {0, 3, 5}, 0);
}

// 4:1 contraction: [0, 60] x [-20, 20] into [60, 120] x [-5, 5]; inlet edge 7, outlet edge 3.
ChannelParams contraction() {
  return outline({{0, -20}, {60, -20}, {60, -5}, {120, -5}, {120, 5}, {60, 5}, {60, 20}, {0, 20}}, {3, 7}, 7);
}

// [L24]'s T-junction as a scene: main channel [0, 100] x [0, 20] (inlet edge 7, outlet 5), side
// branch [50, 70] x [-40, 0] (outlet edge 2), pressure-driven flow.
const std::string kLeeTee = R"(
[walls]
kind = "outline"
outline = [[0, 0], [50, 0], [50, -40], [70, -40], [70, 0], [100, 0], [100, 20], [0, 20]]
openings = [2, 5, 7]
inlet = 7
[flow]
kind = "poiseuille"
mean_velocity = 1.0
)";

Vec3 node_u(const FlowGrid& g, std::size_t i, std::size_t j) { return g.u[g.index(i, j, 0)]; }

// The sanitizer job (tests/support/sanitizer.hpp) skips the cases that take minutes there (a fine flow
// grid, the branches' area sampling, constrained T-junction solves: 116 s, 127 s and more than
// 290 s at -O0, 2026-11-29) and the tapered contraction's two grids (21 s); the release suite runs
// them.
using stokesian::test::kSanitized;

}  // namespace

TEST_CASE("outline flow: a straight outline carries plane Poiseuille flow and its pressure drop") {
  const Outline o = make_outline(straight());
  double prev = 0;
  for (double h : {1.0, 0.5, 0.25}) {
    const OutlineFlow f = solve_outline_flow(o, 1.0, h);
    double err = 0;
    for (std::size_t j = 0; j < f.grid.axis[1].size(); ++j)
      for (std::size_t i = 0; i < f.grid.axis[0].size(); ++i) {
        const double y = f.grid.axis[1][j], exact = std::abs(y) < 5 ? 1.5 * (1 - y * y / 25) : 0.0;
        err = std::max(err, (node_u(f.grid, i, j) - Vec3(exact, 0, 0)).norm());
      }
    MESSAGE("h = " << h << ": max |u - u_Poiseuille| = " << err << ", dp/mu = " << f.pressure_drop_over_mu);
    // Central differences of psi: error (h^2 / 6) |psi'''| = 0.02 h^2 here (psi itself is exact).
    CHECK(err <= 0.02 * h * h * (1 + 1e-6));
    if (prev > 0) CHECK(prev / err == doctest::Approx(4.0).epsilon(0.02));
    prev = err;
    CHECK(f.pressure_drop_over_mu == doctest::Approx(12.0 * 1.0 * 40.0 / 100.0).epsilon(1e-9));
    CHECK(f.flux[3] == doctest::Approx(-10.0));
    CHECK(f.flux[1] == doctest::Approx(10.0));
  }
  // As a field: Faxen data from the grid (trilinear), zero outside and at the walls.
  const TabulatedFlow tf(std::make_shared<FlowGrid>(solve_outline_flow(o, 1.0, 0.25).grid));
  Mat3 G;
  const Vec3 u = tf.velocity(Vec3(20.0, 2.0, 0.0), &G);
  CHECK(u.x() == doctest::Approx(1.5 * (1 - 4.0 / 25)).epsilon(2e-3));
  CHECK(G(0, 1) == doctest::Approx(-1.5 * 2 * 2.0 / 25).epsilon(1e-2));
  CHECK(tf.velocity(Vec3(20.0, 5.0, 0.0)).norm() == 0.0);
  CHECK(tf.velocity(Vec3(20.0, 6.0, 0.0)).norm() == 0.0);
}

TEST_CASE("outline flow: a channel inclined to the grid carries plane Poiseuille flow along its axis") {
  // Walls of slope 1/2 (26.6 degrees to the grid) between vertical openings 10 a high at x = 0 and
  // 60: width w = 10 cos(theta) = 8.94 a normal to the walls, flux Q = 10 a^2/time. Away from the
  // openings (whose imposed profiles are normal to them, not along the axis: their disturbance is
  // 4e-4 u_max at x = 15 and 45 with h = 0.25, 4e-3 at x = 10 and 50) the flow is plane Poiseuille
  // along the axis t: u = (3/2)(Q/w)(1 - (2 n / w)^2) t, n the distance from the axis. Every node
  // with 20 <= x <= 40.
  const Outline o = make_outline(outline({{0, 0}, {60, 30}, {60, 40}, {0, 10}}, {1, 3}, 3));
  const Vec2 t = Vec2(2.0, 1.0).normalized(), nrm(-t.y(), t.x());
  const double w = 10.0 * t.x(), umax = 1.5 * 10.0 / w;
  double prev = 0;
  for (double h : {1.0, 0.5, 0.25}) {
    const OutlineFlow f = solve_outline_flow(o, 1.0, h);
    double err = 0, err_deep = 0;
    for (std::size_t j = 0; j < f.grid.axis[1].size(); ++j)
      for (std::size_t i = 0; i < f.grid.axis[0].size(); ++i) {
        const Vec2 p(f.grid.axis[0][i], f.grid.axis[1][j]);
        if (p.x() < 20 || p.x() > 40 || !o.contains(p)) continue;
        const double n = (p - Vec2(0.0, 5.0)).dot(nrm);  // the axis passes through (0, 5)
        const Vec2 exact = umax * (1 - 4 * n * n / (w * w)) * t;
        const Vec3 u = node_u(f.grid, i, j);
        const double e = (Vec2(u.x(), u.y()) - exact).norm();
        err = std::max(err, e);
        if (o.distance(p) >= 1.0) err_deep = std::max(err_deep, e);
      }
    MESSAGE("inclined channel, h = " << h << ": max |u - u_Poiseuille| / u_max = " << err / umax << " (at >= 1 a from the walls "
                                     << err_deep / umax << "), dp/mu = " << f.pressure_drop_over_mu);
    // psi is a cubic in n, which the ghost closures and the stencil hold exactly; what is left is the
    // central differences' error, (h^2/6) times the third derivative of psi along y and x:
    // (h^2/6)(8 u_max/w^2)(cos^3 + sin^3).
    const double bound = h * h / 6 * 8 * umax / (w * w) * (std::pow(t.x(), 3) + std::pow(t.y(), 3));
    CHECK(err <= 1.02 * bound);
    if (prev > 0) CHECK(prev / err > 3.0);
    prev = err;
  }
}

TEST_CASE("outline flow: a tapered contraction's pressure drop against lubrication theory" * doctest::skip(kSanitized)) {
  // 20 a wide for 0 <= x <= 40, tapering linearly (walls at 7.1 degrees) to 10 a over 40 <= x <= 80,
  // then 10 a wide to x = 120. Lubrication theory: dp/dx = -12 mu Q / w(x)^3, so the drop is
  // 12 Q [40/20^3 + (40/10)(1/10^2 - 1/20^2)/2 + 40/10^3] / mu; its corrections are O(slope^2) in
  // the taper (Jeffery-Hamel) and the local losses at the taper's ends, each under 1 % here.
  const Outline o = make_outline(
      outline({{0, -10}, {40, -10}, {80, -5}, {120, -5}, {120, 5}, {80, 5}, {40, 10}, {0, 10}}, {3, 7}, 7));
  const double Q = 20.0, lubrication = 12 * Q * (40.0 / 8000 + 4.0 * (0.01 - 0.0025) / 2 + 40.0 / 1000);
  for (double h : {0.5, 0.25}) {
    const OutlineFlow f = solve_outline_flow(o, 1.0, h);
    MESSAGE("tapered contraction, h = " << h << ": dp/mu = " << f.pressure_drop_over_mu << ", lubrication " << lubrication);
    CHECK(f.pressure_drop_over_mu == doctest::Approx(lubrication).epsilon(0.01));
  }
}

TEST_CASE("outline flow: equal outlet pressures split a T by its arms' resistance") {
  const OutlineFlow sym = solve_outline_flow(make_outline(tee(40, 40)), 1.0, 0.5);
  CHECK(sym.flux[0] == doctest::Approx(-10.0));
  CHECK(sym.flux[3] == doctest::Approx(5.0).epsilon(1e-6));
  CHECK(sym.flux[5] == doctest::Approx(5.0).epsilon(1e-6));
  // Arms of 80 and 160 a from the stem's axis: resistance ratio 2 (long-arm limit).
  const OutlineFlow asym = solve_outline_flow(make_outline(tee(160, 80)), 1.0, 0.5);
  const double ratio = asym.flux[3] / asym.flux[5];
  MESSAGE("T with arms 80 and 160 a: flux ratio " << ratio << " (resistance network: 2)");
  CHECK(asym.flux[3] + asym.flux[5] == doctest::Approx(10.0));
  CHECK(ratio == doctest::Approx(2.0).epsilon(0.02));
}

TEST_CASE("outline flow: mass is conserved through a 4:1 contraction" * doctest::skip(kSanitized)) {
  // Flux of the nodal velocities (trapezoid) across x = const. Where the flow is fully developed
  // (width w) the central-difference velocities lose (h^2/6)|u''| and the trapezoid (h^2/12)|u'|
  // jump: together 3 (h/w)^2 Q, both second order.
  const Outline o = make_outline(contraction());
  const OutlineFlow f = solve_outline_flow(o, 1.0, 0.5), f2 = solve_outline_flow(o, 1.0, 0.25);  // Q = 40
  auto flux = [](const OutlineFlow& of, double x) {
    const FlowGrid& g = of.grid;
    const std::size_t i = std::size_t(std::lround((x - g.axis[0].front()) / of.h));
    double q = 0;
    for (std::size_t j = 0; j + 1 < g.axis[1].size(); ++j) q += 0.5 * of.h * (node_u(g, i, j).x() + node_u(g, i, j + 1).x());
    return q;
  };
  for (double x : {10.0, 59.0, 61.0, 100.0}) {
    const double e1 = std::abs(flux(f, x) - 40.0), e2 = std::abs(flux(f2, x) - 40.0);
    MESSAGE("x = " << x << ": flux error " << e1 << " (h = 0.5), " << e2 << " (h = 0.25)");
    CHECK(e1 / e2 > 3.5);
    if (x == 10.0) CHECK(e1 <= 3 * std::pow(0.5 / 40.0, 2) * 40.0 * 1.05);
    if (x == 100.0) CHECK(e1 <= 3 * std::pow(0.5 / 10.0, 2) * 40.0 * 1.05);
  }
  // The contraction adds to the two straight channels' Poiseuille drops (entrance losses).
  const double straight_drops = 12.0 * 40.0 * 60.0 / std::pow(40.0, 3) + 12.0 * 40.0 * 60.0 / std::pow(10.0, 3);
  MESSAGE("contraction: dp/mu = " << f.pressure_drop_over_mu << ", straight channels' sum " << straight_drops);
  CHECK(f.pressure_drop_over_mu > straight_drops);
  CHECK(f.pressure_drop_over_mu < 1.1 * straight_drops);
  // Refinement changes the drop little (second order away from the corners' singularities).
  const double fine = f2.pressure_drop_over_mu;
  CHECK(std::abs(fine - f.pressure_drop_over_mu) < 5e-3 * fine);
}

TEST_CASE("outline walls: outside the fluid, no overlaps, every wall edge covered, openings free") {
  for (const ChannelParams& base : {tee(40, 40), contraction()}) {
    for (long layers : {1L, 2L}) {
      ChannelParams c = base;
      c.layers = layers;
      const Outline o = make_outline(c);
      const std::vector<Vec3> w = wall_particles(c, Domain{});
      REQUIRE(!w.empty());
      for (std::size_t i = 0; i < w.size(); ++i) {
        const Vec2 p(w[i].x(), w[i].y());
        CHECK(w[i].z() == 0.0);
        CHECK(!o.contains(p));
        CHECK(o.distance(p) >= c.radius - 1e-9);
        for (std::size_t j = i + 1; j < w.size(); ++j) CHECK((w[i] - w[j]).norm() >= 2 * c.radius + 0.5 * c.gap - 1e-9);
      }
      // Every point of a wall edge has a wall-particle centre within sqrt(r^2 + s^2) (a row of
      // spacing at most 2 s at distance r); no opening has one within r of its interior.
      for (std::size_t k = 0; k < o.edges(); ++k)
        for (int q = 0; q <= 100; ++q) {
          const Vec2 p = o.a(k) + (o.b(k) - o.a(k)) * (q / 100.0);
          double d = 1e300;
          for (const Vec3& x : w) d = std::min(d, (Vec2(x.x(), x.y()) - p).norm());
          if (!o.open[k]) CHECK(d <= std::sqrt(c.radius * c.radius + c.spacing() * c.spacing()));
          else if (q > 0 && q < 100 && std::min(q, 100 - q) * o.length(k) / 100.0 > 2 * c.radius) CHECK(d >= c.radius - 1e-9);
        }
    }
  }
}

TEST_CASE("outline scenes: monolayer fill, resolved round trip, errors name the key") {
  const std::string base = kLeeTee;
  const Scene s = io::parse_scene(base + "[particles]\ngenerate = \"random\"\ncount = 50\nseed = 4\n", "tj.toml");
  REQUIRE(s.interior_count() == 50);
  const Outline o = make_outline(s.walls);
  for (std::size_t i = 0; i < s.interior_count(); ++i) {
    CHECK(s.positions[i].z() == 0.0);
    CHECK(o.contains(Vec2(s.positions[i].x(), s.positions[i].y())));
    CHECK(o.distance(Vec2(s.positions[i].x(), s.positions[i].y())) >= 1.0);
  }
  CHECK(s.wall_count > 100);
  CHECK(s.flow.grid);
  const Scene again = io::parse_scene(s.toml, "again.toml");
  CHECK(again.toml == s.toml);
  CHECK(again.positions.size() == s.positions.size());
  CHECK(cross_section_area(s.walls, s.domain) == doctest::Approx(40.0));  // inlet 20 a x depth 2 a

  CHECK_THROWS_WITH(io::parse_scene(base + "[particles]\npositions = [[60.0, 30.0, 0.0]]\n", "tj.toml"),
                    doctest::Contains("lies outside the fluid region"));
  // An oblique wall is solved (a side branch widening to its outlet); an oblique opening is refused.
  std::string oblique = base;
  oblique.replace(oblique.find("[50, -40]"), 9, "[45, -40]");
  const Scene widening = io::parse_scene(oblique + "[particles]\npositions = [[10.0, 10.0, 0.0]]\n", "tj.toml");
  CHECK(widening.flow.outline);
  CHECK(widening.flow.outline->flux[2] > 0);
  CHECK(widening.flow.outline->flux[5] > 0);
  std::string oblique_opening = base;
  oblique_opening.replace(oblique_opening.find("[70, -40]"), 9, "[70, -35]");
  CHECK_THROWS_WITH(io::parse_scene(oblique_opening + "[particles]\npositions = [[10.0, 10.0, 0.0]]\n", "tj.toml"),
                    doctest::Contains("[flow] kind: the flow through an outline takes openings parallel to x or y (walls may be oblique); opening 2"));
  std::string bad_inlet = base;
  bad_inlet.replace(bad_inlet.find("inlet = 7"), 9, "inlet = 1");
  CHECK_THROWS_WITH(io::parse_scene(bad_inlet + "[particles]\npositions = [[10.0, 10.0, 0.0]]\n", "tj.toml"),
                    doctest::Contains("[walls] outline: the inlet (edge 1) must be one of the openings"));
  CHECK_THROWS_WITH(io::parse_scene(base + "[particles]\ngenerate = \"random\"\ncount = 5000\n", "tj.toml"),
                    doctest::Contains("[particles] count: only"));
  // Above the jamming fraction of random sequential adsorption of discs (0.547, Feder 1980) the fill
  // is refused before any trial, naming the count that fits: 0.547 x 2800 a^2 / pi = 487.
  CHECK_THROWS_WITH(io::parse_scene(base + "[particles]\ngenerate = \"random\"\ncount = 5000\n", "tj.toml"),
                    doctest::Contains("only about 487 of 5000"));
  CHECK_THROWS_WITH(io::parse_scene(base + "[particles]\ngenerate = \"random\"\ncount = 5000\n", "tj.toml"),
                    doctest::Contains("random placement jams at 0.547"));
  CHECK_THROWS_WITH(io::parse_scene("[domain]\nkind = \"periodic\"\nbox = [10, 10, 10]\n" + base +
                                        "[particles]\npositions = [[10.0, 10.0, 0.0]]\n", "tj.toml"),
                    doctest::Contains("\"outline\" is for open domains"));
}

TEST_CASE("outline monolayer: in- and out-of-plane motions decouple; a Brownian run stays in the plane") {
  // The projection of engine/simulation.hpp (monolayer) is exact only if the coplanar system's
  // mobility has no coupling between (U_x, U_y, Omega_z) and (U_z, Omega_x, Omega_y): mirror
  // symmetry z -> -z. Checked on the unprojected solve with wall particles held, lubrication on.
  const std::string scene = R"(
[fluid]
kT = 1.0
[walls]
kind = "outline"
outline = [[0, -6], [24, -6], [24, 6], [0, 6]]
openings = [1, 3]
inlet = 3
[particles]
positions = [[6.0, 0.0, 0.0], [8.3, 0.5, 0.0], [12.0, -3.5, 0.0], [15.0, 3.0, 0.0], [17.2, 2.0, 0.0]]
[hydrodynamics]
model = "stokesian"
moments = "FTS"
tolerance = 1e-6
[time]
dt = 0.001
steps = 10
)";
  const Scene s = io::parse_scene(scene, "mono.toml");
  const ResolvedModel rm = resolve_model(s);
  REQUIRE(rm.level == HydroModel::stokesian);
  Hydrodynamics h(rm, 1.0, make_ambient_field(s.flow, s.walls, s.domain), 1e-8);
  const std::size_t n = s.positions.size(), ni = s.interior_count();
  for (int out_of_plane = 0; out_of_plane < 2; ++out_of_plane) {
    std::vector<Vec3> F(n, Vec3::Zero()), T(n, Vec3::Zero());
    for (std::size_t i = 0; i < ni; ++i) {
      const double a = std::sin(1.0 + double(i)), b = std::cos(2.0 + 3.0 * double(i));
      if (out_of_plane) {
        F[i] = Vec3(0, 0, a);
        T[i] = Vec3(b, a * b, 0);
      } else {
        F[i] = Vec3(a, b, 0);
        T[i] = Vec3(0, 0, a - b);
      }
    }
    const HydroResult r = h.solve(s.positions, s.radii, s.fixed, F, T, s.domain);
    double in = 0, out = 0;
    for (std::size_t i = 0; i < ni; ++i) {
      in = std::max({in, std::abs(r.U[i].x()), std::abs(r.U[i].y()), std::abs(r.Omega[i].z())});
      out = std::max({out, std::abs(r.U[i].z()), std::abs(r.Omega[i].x()), std::abs(r.Omega[i].y())});
    }
    MESSAGE(std::string(out_of_plane ? "out-of-plane" : "in-plane") << " load: in-plane response " << in << ", out-of-plane " << out);
    if (out_of_plane) CHECK(in <= 1e-9 * out);
    else CHECK(out <= 1e-9 * in);
  }
  Simulation sim(s);
  State st = sim.initial_state();
  {
    // min_gap leaves out the wall's own pairs (two fixed particles, 0.025-0.05 a apart here).
    const Evaluation ev = sim.evaluate(st, st.position, 0.0, true);
    double brute = INFINITY;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j)
        if (!(s.fixed[i] && s.fixed[j])) brute = std::min(brute, (s.positions[i] - s.positions[j]).norm() - s.radii[i] - s.radii[j]);
    REQUIRE(ev.gaps);
    CHECK(ev.gaps->min_gap == doctest::Approx(brute).epsilon(1e-12));
    CHECK(brute > 0.3);
  }
  for (int k = 0; k < 10; ++k) sim.advance(st, sim.evaluate(st, st.position, 0.0, true));
  double moved = 0;
  for (std::size_t i = 0; i < ni; ++i) {
    CHECK(st.position[i].z() == 0.0);
    moved = std::max(moved, (st.position[i] - s.positions[i]).norm());
  }
  CHECK(moved > 1e-3);  // the Brownian steps did move the spheres, in the plane
}

TEST_CASE("outline branches: openings grouped into channels, owned areas, wall particles" * doctest::skip(kSanitized)) {
  // [L24]'s T: main channel [0, 100] x [0, 20] (inlet edge 7, outlet edge 5), side branch
  // [50, 70] x [-40, 0] (outlet edge 2). Owned areas by elementary geometry: main 100 x 20 (the
  // crossing included), side 20 x 40.
  const Outline t = make_outline(outline({{0, 0}, {50, 0}, {50, -40}, {70, -40}, {70, 0}, {100, 0}, {100, 20}, {0, 20}}, {2, 5, 7}, 7));
  const OutlineBranches tb = outline_branches(t);
  REQUIRE(tb.branch.size() == 2);
  CHECK(tb.branch[0].openings == std::vector<std::size_t>{7, 5});
  CHECK(tb.branch[1].openings == std::vector<std::size_t>{2});
  CHECK(tb.branch[0].direction.isApprox(Vec2(1, 0)));
  CHECK(tb.branch[1].direction.isApprox(Vec2(0, -1)));
  CHECK(tb.branch[0].width == doctest::Approx(20.0));
  CHECK(tb.branch[1].width == doctest::Approx(20.0));
  CHECK(tb.branch[0].area == doctest::Approx(2000.0).epsilon(1e-9));
  CHECK(tb.branch[1].area == doctest::Approx(800.0).epsilon(1e-9));
  CHECK(tb.of_point(Vec2(30, 10)) == 0);
  CHECK(tb.of_point(Vec2(60, 10)) == 0);  // the crossing
  CHECK(tb.of_point(Vec2(90, 5)) == 0);
  CHECK(tb.of_point(Vec2(60, -20)) == 1);
  // Wall particles (radius 1, centres 1.05 a outside the outline): side walls, the top wall over
  // the crossing, the main channel's floor.
  CHECK(tb.of_wall_particle(t, Vec2(48.95, -20)) == 1);
  CHECK(tb.of_wall_particle(t, Vec2(71.05, -30)) == 1);
  CHECK(tb.of_wall_particle(t, Vec2(60, 21.05)) == 0);
  CHECK(tb.of_wall_particle(t, Vec2(30, -1.05)) == 0);

  // A stem fed from below into a bar with an outlet at each end: three branches, the arms split
  // at the stem (stem 10 x 30 + the 10 x 10 crossing; right arm 20 x 10; left arm 10 x 10).
  const Outline s = make_outline(tee(15, 25));
  const OutlineBranches sb = outline_branches(s);
  REQUIRE(sb.branch.size() == 3);
  CHECK(sb.branch[1].openings == std::vector<std::size_t>{3});
  CHECK(sb.branch[0].area == doctest::Approx(400.0).epsilon(1e-9));
  CHECK(sb.branch[1].area == doctest::Approx(200.0).epsilon(1e-9));
  CHECK(sb.branch[2].area == doctest::Approx(100.0).epsilon(1e-9));
  CHECK(sb.of_point(Vec2(10, 5)) == 1);
  CHECK(sb.of_point(Vec2(-10, 5)) == 2);
  CHECK(sb.of_point(Vec2(0, 5)) == 0);
  CHECK(sb.of_wall_particle(s, Vec2(-10, 11.05)) == 2);  // the bar's top wall over the left arm
  CHECK(sb.of_wall_particle(s, Vec2(0, 11.05)) == 0);    // ... over the stem

  // The contraction: one branch owning all the fluid.
  const Outline c = make_outline(contraction());
  const OutlineBranches cb = outline_branches(c);
  REQUIRE(cb.branch.size() == 1);
  CHECK(cb.branch[0].openings.size() == 2);
  CHECK(cb.branch[0].area == doctest::Approx(c.area).epsilon(1e-9));
  CHECK(cb.branch[0].width == doctest::Approx(40.0));
}

TEST_CASE("outline branch outputs: pressure drop and areal fraction per channel" * doctest::skip(kSanitized)) {
  // Far-field constrained solves of the first frame. References: an empty channel holds no force;
  // with one channel the branch's drop is pressure_drop_particles (the same holding forces along
  // the inlet); an obstacle held in one channel raises that channel's drop far above the other's;
  // areal fractions from the placed spheres and the owned areas (2000 and 800 a^2).
  const std::string tj = kLeeTee + R"([hydrodynamics]
model = "far_field"
moments = "FT"
tolerance = 1e-6
[time]
dt = 0.01
steps = 1
)";
  auto first_frame = [](const Scene& sc) {
    Simulation sim(sc);
    const State st = sim.initial_state();
    return sim.frame(st, sim.evaluate(st, st.position));
  };
  auto values = [](const Frame& f, const std::string& name) { return f.observables.at(name).values; };
  {
    // Three free spheres (two in the main channel, one in the side branch): areal fractions.
    const Scene sc = io::parse_scene(tj + "[particles]\npositions = [[30, 10, 0], [90, 10, 0], [60, -20, 0]]\n", "tj.toml");
    const Frame f = first_frame(sc);
    const auto areal = values(f, "areal_fraction_branches");
    REQUIRE(areal.size() == 2);
    CHECK(areal[0] == doctest::Approx(2.0 * kPi / 2000.0).epsilon(1e-9));
    CHECK(areal[1] == doctest::Approx(kPi / 800.0).epsilon(1e-9));
  }
  for (int where = 0; where < 2; ++where) {
    // One held obstacle, in the main channel upstream of the crossing or deep in the side branch.
    const std::string pos = where == 0 ? "[[25, 10, 0]]" : "[[60, -25, 0]]";
    const Scene sc = io::parse_scene(tj + "[particles]\npositions = " + pos + "\nfixed = [true]\n", "tj.toml");
    const Frame f = first_frame(sc);
    const auto dp = values(f, "pressure_drop_branches");
    REQUIRE(dp.size() == 2);
    MESSAGE("obstacle in the " << (where == 0 ? "main" : "side") << " channel: drops main " << dp[0] << ", side " << dp[1]);
    CHECK(dp[where] > 0.0);
    CHECK(std::abs(dp[1 - where]) < 0.1 * dp[where]);
  }
  {
    const std::string ct = R"(
[walls]
kind = "outline"
outline = [[0, -20], [60, -20], [60, -5], [120, -5], [120, 5], [60, 5], [60, 20], [0, 20]]
openings = [3, 7]
inlet = 7
[flow]
kind = "poiseuille"
mean_velocity = 1.0
[hydrodynamics]
model = "far_field"
moments = "FT"
[time]
dt = 0.01
steps = 1
)";
    const Frame empty = first_frame(io::parse_scene(ct + "[particles]\npositions = [[30, 0, 0]]\n", "ct.toml"));
    // A force- and torque-free sphere at FT sends no disturbance, and the walls see no ambient flow.
    CHECK(values(empty, "pressure_drop_branches")[0] == 0.0);
    const Frame f = first_frame(io::parse_scene(ct + "[particles]\npositions = [[55, 10, 0], [90, 0, 0]]\nfixed = [true, false]\n", "ct.toml"));
    const auto dp = values(f, "pressure_drop_branches");
    REQUIRE(dp.size() == 1);
    CHECK(dp[0] > 0.0);
    CHECK(dp[0] == doctest::Approx(values(f, "pressure_drop_particles")[0]).epsilon(1e-12));
  }
}

TEST_CASE("particle pressure drop: a sphere held by a pair force loads the walls as a held sphere does") {
  // Momentum balance (engine/observers.cpp, ChannelOutputs): the particle pressure drop counts the
  // load on the held particles, the fluid's force and the mobile particles' pair forces. Reference:
  // solve 1 holds a sphere S and an anchor A upstream of it; solve 2 frees S and ties it to A with a
  // spring whose pull equals the force S exerted on the fluid in solve 1. Then S stays at rest, the
  // flow is that of solve 1, and the walls and the anchor carry the same total, so both drops agree;
  // without the pair force on the anchor solve 2 would lose that force over the section (a drop of
  // held - F_S / A < 0). The spring
  // acts on every pair within its cut-off, wall particles too (0.05 a apart): those pulls among held
  // particles are not loads from the suspension.
  const std::string base = R"(
[walls]
kind = "outline"
outline = [[0, -5], [40, -5], [40, 5], [0, 5]]
openings = [1, 3]
inlet = 3
[flow]
kind = "poiseuille"
mean_velocity = 1.0
[hydrodynamics]
model = "far_field"
moments = "F"
tolerance = 1e-9
[time]
dt = 0.01
steps = 1
[particles]
positions = [[20, 0, 0], [17, 0, 0]]
)";
  auto spring = [](double k, double h0) {
    return "[[forces.pair]]\nkind = \"harmonic\"\nstiffness = " + std::to_string(k) + "\nrest_gap = " + std::to_string(h0) +
           "\ncutoff = 1.2\n";
  };
  auto run = [](const Scene& sc, Vec3* F0, Vec3* U0) {
    Simulation sim(sc);
    const State st = sim.initial_state();
    const Evaluation ev = sim.evaluate(st, st.position);
    if (F0) *F0 = ev.hydro.F[0];
    if (U0) *U0 = ev.hydro.U[0];
    const Frame f = sim.frame(st, ev);
    // One branch: its drop takes the pair part by the mobile particle (Q), the total by the held (P).
    const double total = f.observables.at("pressure_drop_particles").values[0];
    CHECK(f.observables.at("pressure_drop_branches").values[0] == doctest::Approx(total).epsilon(1e-12));
    return total;
  };
  Vec3 Fs;
  const double held = run(io::parse_scene(base + "fixed = [true, true]\n" + spring(50.0, 0.5), "held.toml"), &Fs, nullptr);
  // S pushes the fluid upstream (the flow drags it along +x), along the centreline by symmetry.
  REQUIRE(Fs.x() < 0.0);
  CHECK(std::abs(Fs.y()) < 1e-6 * std::abs(Fs.x()));
  // Spring pull on S towards A (along -x): k (h - h0) with h = 1 a; k = 2 |F_S| gives h0 = 0.5 a.
  const double k = 2.0 * std::abs(Fs.x());
  Vec3 Ufree;
  const double tied = run(io::parse_scene(base + "fixed = [false, true]\n" + spring(k, 0.5), "tied.toml"), nullptr, &Ufree);
  MESSAGE("held " << held << ", tied " << tied << " (|U_S| = " << Ufree.norm() << "); F_S / A = " << -Fs.x() / 20.0);
  CHECK(Ufree.norm() < 1e-6);
  CHECK(held > 0.0);
  CHECK(tied == doctest::Approx(held).epsilon(1e-6));  // the pair term alone is F_S / A = 1.8 held
}
