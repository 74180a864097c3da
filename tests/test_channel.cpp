// Channels (issue 17; engine/core/channel.hpp, trees/walls.hpp, docs/channels.md).
//
// References, each independent of the code under test:
//   - plane Poiseuille: u = (3/2) U (1 - (2 eta/H)^2) in closed form;
//   - rectangular duct: the Poisson problem lap u = -G/mu with u = 0 on the walls (checked by finite
//     differences of the series), and Shah & London's (1978) square-duct values
//     u_max / U = 2.0962 and Fanning f Re = 14.227, i.e. G s^2 / (mu U) = 2 f Re = 28.454;
//   - a sphere near a wall of wall particles: Faxen's parallel series and the leading terms of
//     Brenner's perpendicular series (method note, validation item 7), xi = a / z, z the centre's
//     distance from the wall's boundary plane:
//       mu_par / mu_0  = 1 - (9/16) xi + (1/8) xi^3 - (45/256) xi^4 - (1/16) xi^5
//       mu_perp / mu_0 = 1 - (9/8) xi + (1/2) xi^3;
//     between two walls the point-force reflection of two no-slip planes (Liron & Mochon 1976),
//     checked against one wall's exact -9/16 xi, -9/8 xi and Faxen's midplane coefficient 1.004;
//   - the momentum balance of a held obstacle (the particle pressure drop, Lee et al. 2024 §3.2);
//   - tabulated flows: the duct's closed form sampled on grids of two spacings (the interpolation
//     error and its second-order decrease).
#include <doctest/doctest.h>

#include "engine/core/channel.hpp"
#include "engine/hydrodynamics.hpp"
#include "io/flow_table.hpp"
#include "io/scene_toml.hpp"
#include "tests/support/wall_mobility.hpp"
#include "trees/walls.hpp"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

using namespace stokesian;
using stokesian::io::parse_scene;
using stokesian::test_support::brenner_perpendicular;
using stokesian::test_support::faxen_parallel;

namespace {
// Scratch files of this suite, in the system's temporary folder.
std::string scratch(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("stokesian_test_channel_" + name)).string();
}
}  // namespace

namespace {

ChannelParams slit(double H, double L = 0.0) {
  ChannelParams c;
  c.kind = ChannelParams::Kind::slit;
  c.height = H;
  c.length = c.depth = L;
  return c;
}

Domain periodic_box(const Vec3& box) {
  Domain d;
  d.kind = Domain::Kind::periodic;
  d.box = box;
  return d;
}

ResolvedModel far_field_model(Moments m) {
  ResolvedModel r;
  r.level = HydroModel::far_field;
  r.moments = m;
  r.far_field = "tree";
  return r;
}

// Mobility of one sphere among the held wall particles (tests/support/wall_mobility.hpp).
double sphere_mobility(Hydrodynamics& h, const std::vector<Vec3>& walls, const Vec3& x, int d) {
  const HydroResult r = test_support::sphere_among_walls(h, walls, x, d);
  for (std::size_t i = 0; i + 1 < r.U.size(); ++i) REQUIRE(r.U[i].norm() == 0.0);  // walls held
  return r.U.back()[d];
}

}  // namespace

TEST_CASE("plane Poiseuille flow of a slit: closed form, zero outside, Faxen data") {
  const Domain d = periodic_box(Vec3(10, 14, 8));
  const ChannelParams c = slit(10.0);
  const ChannelFlow f(c, d, 0.8);
  CHECK(f.max_velocity() == doctest::Approx(1.2).epsilon(1e-14));
  CHECK(f.pressure_gradient_over_viscosity() == doctest::Approx(12 * 0.8 / 100).epsilon(1e-14));
  std::vector<Vec3> x{Vec3(1, 7, 2), Vec3(3, 10.5, 4), Vec3(0, 2.5, 0), Vec3(0, 1.9, 0), Vec3(5, 12.1, 1)};
  FlowSample s;
  f.sample(x, s);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double eta = x[i].y() - 7.0;
    const bool inside = std::abs(eta) < 5.0;
    const double u = inside ? 1.2 * (1 - std::pow(2 * eta / 10, 2)) : 0.0;
    const double uy = inside ? -1.2 * 8 * eta / 100 : 0.0;
    CHECK(s.u[i].x() == doctest::Approx(u).epsilon(1e-13).scale(1));
    CHECK(s.omega[i].z() == doctest::Approx(-0.5 * uy).scale(1));
    const Mat3 E = from_vec5(s.E[i]);
    CHECK(E(0, 1) == doctest::Approx(0.5 * uy).scale(1));
    CHECK(std::abs(E.trace()) < 1e-15);
  }
}

TEST_CASE("rectangular duct flow: Poisson equation, no slip, Shah & London's square-duct values") {
  const Domain open;
  ChannelParams c;
  c.kind = ChannelParams::Kind::duct;
  c.height = 6.0;
  c.width = 6.0;
  const ChannelFlow sq(c, open, 1.0);
  CHECK(sq.max_velocity() == doctest::Approx(2.0962).epsilon(1e-4));
  CHECK(sq.pressure_gradient_over_viscosity() * 36.0 == doctest::Approx(28.454).epsilon(1e-4));
  // Aspect ratio 1:3 (height 4, width 12): lap u = -G/mu inside, u = 0 on the walls.
  c.height = 4.0;
  c.width = 12.0;
  const ChannelFlow f(c, open, 0.7);
  const double G = f.pressure_gradient_over_viscosity(), h = 1e-3;
  for (const Vec3& p : {Vec3(0, 0.3, -4.1), Vec3(0, -1.5, 5.0), Vec3(0, 1.0, 0.5), Vec3(0, -0.2, -5.7)}) {
    double lap = 0;
    for (int ax : {1, 2}) {
      Vec3 e = Vec3::Zero();
      e[ax] = h;
      lap += (f.velocity(p + e) - 2 * f.velocity(p) + f.velocity(p - e)) / (h * h);
    }
    CHECK(lap == doctest::Approx(-G).epsilon(2e-5));
    double uy = 0, uz = 0;
    f.velocity(p, &uy, &uz);
    CHECK(uy == doctest::Approx((f.velocity(p + Vec3(0, h, 0)) - f.velocity(p - Vec3(0, h, 0))) / (2 * h)).epsilon(1e-5));
    CHECK(uz == doctest::Approx((f.velocity(p + Vec3(0, 0, h)) - f.velocity(p - Vec3(0, 0, h))) / (2 * h)).epsilon(1e-5));
  }
  for (const Vec3& p : {Vec3(0, 2.0 - 1e-9, 1.0), Vec3(0, 0.5, 6.0 - 1e-9), Vec3(0, -2.0 + 1e-9, -3.0)})
    CHECK(std::abs(f.velocity(p)) < 1e-7);
  // The mean over the cross-section is the requested U (midpoint rule on a fine grid).
  double sum = 0;
  const int n = 200;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) sum += f.velocity(Vec3(0, -2.0 + 4.0 * (i + 0.5) / n, -6.0 + 12.0 * (k + 0.5) / n));
  CHECK(sum / (n * n) == doctest::Approx(0.7).epsilon(2e-4));
}

TEST_CASE("wall particles: excluded-volume placement, seamless periodic walls, layers close the pores") {
  const Domain d = periodic_box(Vec3(16.4, 20, 12.3));
  for (long layers : {1L, 2L, 3L}) {
    ChannelParams c = slit(8.0);
    c.layers = layers;
    c.gap = 0.05;
    const std::vector<Vec3> w = wall_particles(c, d);
    // floor(16.4 / 2.05) = 8 and floor(12.3 / 2.05) = 6 sites per layer and wall.
    CHECK(w.size() == std::size_t(2 * layers * 8 * 6));
    double closest_boundary = 1e300, closest_pair = 1e300;
    for (std::size_t i = 0; i < w.size(); ++i) {
      const double out = std::abs(w[i].y() - 10.0) - 4.0;  // centre's distance outside the fluid
      CHECK(out >= 1.0 - 1e-12);                           // wholly outside the fluid
      closest_boundary = std::min(closest_boundary, out);
      for (std::size_t j = i + 1; j < w.size(); ++j)
        closest_pair = std::min(closest_pair, d.minimum_image(w[i] - w[j]).norm());
    }
    CHECK(closest_boundary == doctest::Approx(1.0));  // the first layer touches the boundary
    CHECK(closest_pair == doctest::Approx(2.05));      // across the periodic seam too
    CHECK(wall_thickness(c) == doctest::Approx(2.0 + double(layers - 1) * 2.05 / std::sqrt(2.0)));
  }
  ChannelParams too_tall = slit(17.0);
  CHECK_THROWS_WITH_AS(wall_particles(too_tall, d), doctest::Contains("Ly = 20"), std::invalid_argument);
}

TEST_CASE("duct walls: no overlaps, closed corners") {
  // Every point of the duct's boundary lies within sqrt(2 (s'/2)^2 + r^2) of a wall-particle centre,
  // the farthest a point of a plane touching a square lattice of spacing s' can be (above a cell's
  // middle), s' the spacing stretched by at most 10 % here; a hole at a corner would leave boundary
  // points farther away.
  Domain d;
  d.kind = Domain::Kind::periodic;
  d.box = Vec3(8.2, 14.0, 14.0);
  for (long layers : {1L, 2L}) {
    ChannelParams c;
    c.kind = ChannelParams::Kind::duct;
    c.height = 6.2;
    c.width = 6.2;
    c.layers = layers;
    const std::vector<Vec3> w = wall_particles(c, d);
    const double s = 1.1 * c.spacing(), bound = std::sqrt(0.5 * s * s + 1.0) + 1e-9;
    double closest = 1e300, worst = 0;
    for (std::size_t i = 0; i < w.size(); ++i) {
      CHECK_FALSE(in_channel(c, d, w[i]));
      for (std::size_t j = i + 1; j < w.size(); ++j) closest = std::min(closest, d.minimum_image(w[i] - w[j]).norm());
    }
    for (int k = 0; k <= 400; ++k) {
      const double t = k / 400.0;
      for (const Vec3& p : {Vec3(0, -3.1 + 6.2 * t, 3.1), Vec3(0, -3.1 + 6.2 * t, -3.1), Vec3(0, 3.1, -3.1 + 6.2 * t),
                            Vec3(0, -3.1, -3.1 + 6.2 * t)})
        for (double x : {0.0, 0.5 * c.spacing(), 1.0}) {
          double best = 1e300;
          for (const Vec3& q : w) best = std::min(best, d.minimum_image(p + Vec3(x + 4.1, 7.0, 7.0) - q).norm());
          worst = std::max(worst, best);
        }
    }
    MESSAGE("duct, " << layers << " layer(s): " << w.size() << " wall particles, closest pair " << closest
                     << ", farthest boundary point from a centre " << worst << " (bound " << bound << ")");
    CHECK(closest >= 2.0 + 0.5 * c.gap - 1e-9);
    CHECK(worst <= bound);
  }
}

TEST_CASE("channel scenes: walls appended and listed by [walls], interior checked, errors name the key") {
  const std::string base = R"(
[domain]
kind = "periodic"
box = [12.3, 14.05, 12.3]
[walls]
kind = "slit"
height = 10.0
[flow]
kind = "poiseuille"
mean_velocity = 2.0
)";
  const Scene s = parse_scene(base + "[particles]\npositions = [[1.0, 7.0, 1.0], [5.0, 3.0, 5.0]]\n", "ch.toml");
  CHECK(s.interior_count() == 2);
  CHECK(s.wall_count == 2 * 6 * 6);
  CHECK(s.fixed.back() == 1);
  CHECK(s.fixed[0] == 0);
  // The resolved scene lists the interior particles and [walls]; read back, it is the same scene.
  const Scene again = parse_scene(s.toml, "again.toml");
  CHECK(again.positions.size() == s.positions.size());
  CHECK(again.toml == s.toml);
  CHECK_THROWS_WITH(parse_scene(base + "[particles]\npositions = [[1.0, 12.5, 1.0]]\n", "ch.toml"),
                    doctest::Contains("[particles] positions: particle 0 at [1, 12.5, 1] lies outside the fluid region"));
  CHECK_THROWS_WITH(parse_scene(R"(
[walls]
kind = "slit"
height = 10.0
length = 20.0
[particles]
positions = [[0.0, 0.0, 0.0]]
)", "open.toml"),
                    doctest::Contains("open.toml:2: [walls] depth: required in an open domain"));
  CHECK_THROWS_WITH(parse_scene(R"(
[particles]
positions = [[0.0, 0.0, 0.0]]
[flow]
kind = "poiseuille"
mean_velocity = 1.0
)", "nowall.toml"),
                    doctest::Contains("[flow] kind: \"poiseuille\" flows through a channel"));
  // Generated particles fill the fluid region at the requested fraction of its volume.
  const Scene g = parse_scene(base + "[particles]\ngenerate = \"random\"\nvolume_fraction = 0.2\nseed = 3\n", "g.toml");
  double v = 0;
  for (std::size_t i = 0; i < g.interior_count(); ++i) {
    CHECK(std::abs(g.positions[i].y() - 7.025) <= 4.0 + 1e-12);  // centre >= a from the boundary
    v += 4.0 / 3.0 * kPi;
  }
  CHECK(v / (12.3 * 10.0 * 12.3) == doctest::Approx(0.2).epsilon(0.01));
}

TEST_CASE("constrained solve in a channel: an empty channel holds no force, an obstacle raises the pressure drop") {
  // Periodic slit, walls see no ambient flow (their centres lie outside the fluid): with no
  // interior particle every wall force vanishes exactly. One held obstacle on the centreline takes
  // the drag of the flow; the solids together take dP A = -sum F_x (holding forces) > 0. (For a
  // sealed channel at fixed flux the reciprocal theorem gives dP A = drag u(x_p) / U = 1.5 drag here
  // (Happel & Brenner 1965); the wall-particle slit measures about 1.93: its walls are porous and the
  // periodic box couples it to its images through them. docs/channels.md.)
  const Domain d = periodic_box(Vec3(16.4, 14.05, 16.4));
  const ChannelParams c = slit(10.0);
  const std::vector<Vec3> w = wall_particles(c, d);
  FlowParams fp;
  fp.kind = FlowParams::Kind::poiseuille;
  fp.mean_velocity = 1.0;
  const auto field = make_ambient_field(fp, c, d);
  for (Moments m : {Moments::FT, Moments::FTS}) {
    ResolvedModel rm;
    rm.level = HydroModel::far_field;
    rm.moments = m;
    rm.far_field = "pme";
    Hydrodynamics h(rm, 1.0, field, 1e-6);
    std::vector<double> a(w.size(), 1.0);
    std::vector<char> fixed(w.size(), 1);
    std::vector<Vec3> zero(w.size(), Vec3::Zero());
    const HydroResult empty = h.solve(w, a, fixed, zero, zero, d);
    double fmax = 0;
    for (const Vec3& f : empty.F) fmax = std::max(fmax, f.norm());
    CHECK(fmax == 0.0);

    std::vector<Vec3> x = w;
    x.push_back(Vec3(8.2, 7.025, 8.2));
    a.push_back(1.0);
    fixed.push_back(1);
    zero.push_back(Vec3::Zero());
    const HydroResult r = h.solve(x, a, fixed, zero, zero, d);
    double held_x = 0;
    for (const Vec3& f : r.F) held_x += f.x();
    const double dP = -held_x / cross_section_area(c, d);
    const double stokes = 6 * kPi * 1.5;  // 6 pi mu a u_c, u_c = 1.5 U
    const double drag = -r.F.back().x();  // the fluid's force on the obstacle
    MESSAGE("moments " << std::string(to_string(m)) << ": obstacle drag / (6 pi mu a u_c) = " << drag / stokes
                       << ", dP A / obstacle drag = " << dP * cross_section_area(c, d) / drag);
    CHECK(dP > 0.0);
    // The obstacle's drag: Stokes' raised by the walls (Faxen's two-wall factor 1/(1 - 1.004 a/l +
    // ...) = 1.25 at a/l = 0.2 for a translating sphere) and by its periodic images.
    CHECK(drag / stokes > 1.0);
    CHECK(drag / stokes < 1.6);
    // The walls take more than the obstacle's drag: the flow around it shears them harder.
    CHECK(dP * cross_section_area(c, d) > drag);
  }
}

TEST_CASE("two-plane point-force reflection: one-wall limit and Faxen's midplane coefficient") {
  // Far from the second plane the reflection is one wall's, -9/16 xi and -9/8 xi exactly; midway
  // between two planes 2l apart Faxen's parallel coefficient is 1.004 a/l (Happel & Brenner 1965) (the series
  // 1 - 1.004 xi + 0.418 xi^3 + 0.21 xi^4 - 0.169 xi^5 gives 0.9374 at l = 16).
  for (double z : {2.0, 4.0, 9.0}) {
    CHECK(test_support::two_plane_reflection(z, 1e4, 0) == doctest::Approx(-9.0 / 16 / z).epsilon(1e-6));
    CHECK(test_support::two_plane_reflection(z, 1e4, 1) == doctest::Approx(-9.0 / 8 / z).epsilon(1e-6));
  }
  CHECK(-16 * test_support::two_plane_reflection(16, 32, 0) == doctest::Approx(1.004).epsilon(5e-4));
  const double xi = 1.0 / 16;
  const double faxen_mid = 1 - 1.004 * xi + 0.418 * std::pow(xi, 3) + 0.21 * std::pow(xi, 4) - 0.169 * std::pow(xi, 5);
  CHECK(test_support::slit_parallel(16, 32) == doctest::Approx(faxen_mid).epsilon(2e-4));
  // The superposed walls overstate the perpendicular reflection: midway 2 x 9/8 against 1.4516.
  CHECK(-16 * test_support::two_plane_reflection(16, 32, 1) == doctest::Approx(1.4516).epsilon(1e-4));
}

TEST_CASE("sphere beside walls of wall particles: mobility against the flat-wall results") {
  // Open domain, square patches of side 64 a of touching-plus-0.05 spheres of radius 1 (1 layer).
  // One plane wall: both directions within 5 % of Faxen / Brenner from 3 a off the boundary.
  // Slit of height 32 (Lee et al. 2024 fig. 4a): both directions within 5 % of two flat planes
  // (their point-force reflection plus each wall's finite-size terms, tests/support/wall_mobility.hpp).
  Hydrodynamics h(far_field_model(Moments::FT), 1.0, AmbientFlow{}, 1e-5);
  ChannelParams plane;
  plane.kind = ChannelParams::Kind::plane;
  plane.length = plane.depth = 64.0;
  const std::vector<Vec3> pw = wall_particles(plane, Domain{});
  for (double gap : {3.0, 8.0}) {
    const double z = 1.0 + gap, xi = 1.0 / z;
    const double par = sphere_mobility(h, pw, Vec3(0, z, 0), 0), perp = sphere_mobility(h, pw, Vec3(0, z, 0), 1);
    MESSAGE("plane, gap " << gap << ": parallel " << par << " (series " << faxen_parallel(xi) << "), perpendicular "
                          << perp << " (series " << brenner_perpendicular(xi) << ")");
    CHECK(std::abs(par / faxen_parallel(xi) - 1) < 0.05);
    CHECK(std::abs(perp / brenner_perpendicular(xi) - 1) < 0.05);
  }
  const double H = 32.0;
  const std::vector<Vec3> sw = wall_particles(slit(H, 64.0), Domain{});
  for (double gap : {3.0, 8.0, 15.0}) {
    const double z1 = 1.0 + gap;
    const Vec3 x(0, -0.5 * H + z1, 0);
    const double par = sphere_mobility(h, sw, x, 0), perp = sphere_mobility(h, sw, x, 1);
    const double par_ref = test_support::slit_parallel(z1, H), perp_ref = test_support::slit_perpendicular(z1, H);
    MESSAGE("slit, gap " << gap << ": parallel " << par << " (two planes " << par_ref << "), perpendicular " << perp
                         << " (two planes " << perp_ref << ")");
    CHECK(std::abs(par / par_ref - 1) < 0.05);
    CHECK(std::abs(perp / perp_ref - 1) < 0.05);
  }
}

namespace {

// The 4 x 6 rectangular duct of the tabulated-flow tests.
ChannelParams duct_4x6() {
  ChannelParams c;
  c.kind = ChannelParams::Kind::duct;
  c.height = 4.0;
  c.width = 6.0;
  return c;
}

// Writes the duct flow f sampled on a grid of spacing h over [-1, 1] x [-H/2, H/2] x [-W/2, W/2]
// (x, y, z, u, v, w per line, a header line of names, comma separated), nodes in a shuffled order.

std::string write_duct_table(const ChannelFlow& f, double H, double W, double h, const std::string& name) {
  const std::string path = scratch(name);
  std::ofstream o(path);
  o.precision(17);
  o << "% exported by a fluid solver\nx,y,z,u,v,w\n";
  const long nx = 3, ny = std::lround(H / h) + 1, nz = std::lround(W / h) + 1;
  for (long k = nz - 1; k >= 0; --k)
    for (long i = 0; i < nx; ++i)
      for (long j = 0; j < ny; ++j) {
        const Vec3 p(-1.0 + double(i), -0.5 * H + double(j) * H / double(ny - 1), -0.5 * W + double(k) * W / double(nz - 1));
        o << p.x() << "," << p.y() << "," << p.z() << "," << f.velocity(p) << ",0,0\n";
      }
  return path;
}

}  // namespace

TEST_CASE("tabulated flow from a fluid solver's grid: second-order interpolation of u and grad u") {
  const ChannelFlow exact(duct_4x6(), Domain{}, 1.0);
  double err_u[2] = {0, 0}, err_g[2] = {0, 0};
  const double spacing[2] = {0.25, 0.125};
  for (int r = 0; r < 2; ++r) {
    const FlowGrid g = io::read_flow_table(write_duct_table(exact, 4.0, 6.0, spacing[r], "duct_table.csv"));
    CHECK(g.axis[0].size() == 3);
    const TabulatedFlow tab(std::make_shared<FlowGrid>(g));
    // Points at least one spacing of the coarse grid inside the walls (the nodal gradients are
    // one-sided on the faces).
    std::uint64_t state = 12345;
    auto uni = [&] {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return double(state >> 11) / 9007199254740992.0;
    };
    for (int k = 0; k < 400; ++k) {
      const Vec3 p(-0.5 + uni(), -1.75 + 3.5 * uni(), -2.75 + 5.5 * uni());
      double uy, uz;
      const double u = exact.velocity(p, &uy, &uz);
      Mat3 G;
      const Vec3 v = tab.velocity(p, &G);
      err_u[r] = std::max(err_u[r], (v - Vec3(u, 0, 0)).norm() / exact.max_velocity());
      Mat3 Ge = Mat3::Zero();
      Ge(0, 1) = uy;
      Ge(0, 2) = uz;
      err_g[r] = std::max(err_g[r], (G - Ge).norm() / exact.pressure_gradient_over_viscosity());
    }
  }
  MESSAGE("spacing 0.25 -> 0.125: max |u error| / u_max " << err_u[0] << " -> " << err_u[1] << ", max |grad u error| / (G/mu) "
                                                           << err_g[0] << " -> " << err_g[1]);
  // Trilinear interpolation errs by at most (h^2/8)(|u_yy| + |u_zz|) <= (h^2/8) 2 G/mu here.
  CHECK(err_u[0] * exact.max_velocity() < 0.25 * 0.25 / 8 * 2 * exact.pressure_gradient_over_viscosity());
  CHECK(err_g[0] < 2e-2);
  CHECK(err_u[0] / err_u[1] > 3.5);  // second order: 4 when the spacing halves
  CHECK(err_g[0] / err_g[1] > 3.0);
  CHECK(err_g[1] < 1e-2);
  // Outside the grid: no flow; a 2D export (x y u v) is uniform along z.
  const std::string p2 = scratch("table2d.txt");
  {
    std::ofstream o(p2);
    o << "# x y u v\n0 0 0 0\n1 0 1 0\n0 1 0 2\n1 1 nan nan\n";
  }
  const TabulatedFlow t2(std::make_shared<FlowGrid>(io::read_flow_table(p2)));
  CHECK((t2.velocity(Vec3(0.5, 0.5, 37.0)) - Vec3(0.25, 0.5, 0.0)).norm() < 1e-15);  // NaN node = 0
  CHECK(t2.velocity(Vec3(1.5, 0.5, 0.0)).norm() == 0.0);
  // Incomplete grids and ragged rows are refused with the file and line.
  {
    std::ofstream o(p2);
    o << "0 0 0 1 0 0\n1 0 0 1 0 0\n0 1 0 1 0 0\n";
  }
  CHECK_THROWS_WITH(io::read_flow_table(p2), doctest::Contains("3 nodes do not form a complete rectilinear grid (2 x 2 x 1"));
  {
    std::ofstream o(p2);
    o << "0 0 0 1 0 0\n1 0 0 1 0\n";
  }
  CHECK_THROWS_WITH(io::read_flow_table(p2), doctest::Contains("table2d.txt:2: 5 columns"));
}

TEST_CASE("tabulated flow from a legacy VTK file: the same grid as the plain table, ASCII and binary") {
  // Reference: the duct's closed form written as the plain table (read above) and as VTK files of
  // the same nodes, written here byte by byte from the VTK format's definition (big-endian binary).
  const ChannelFlow exact(duct_4x6(), Domain{}, 1.0);
  const FlowGrid ref = io::read_flow_table(write_duct_table(exact, 4.0, 6.0, 0.25, "duct_vtk.csv"));
  const std::size_t n = ref.u.size();
  auto big_endian = [](std::ofstream& o, const void* p, std::size_t size) {
    const unsigned char* b = static_cast<const unsigned char*>(p);
    for (std::size_t k = 0; k < size; ++k) o.put(char(b[size - 1 - k]));  // this machine is little-endian
  };
  auto write = [&](const std::string& name, bool binary, bool rectilinear, const std::string& type, bool extra) {
    const std::string path = scratch(name);
    std::ofstream o(path, std::ios::binary);
    o.precision(17);
    o << "# vtk DataFile Version 3.0\nduct flow\n" << (binary ? "BINARY" : "ASCII") << "\n";
    auto put = [&](double v) {
      if (!binary) {
        o << v << " ";
      } else if (type == "float") {
        const float f = float(v);
        big_endian(o, &f, 4);
      } else {
        big_endian(o, &v, 8);
      }
    };
    const char* dims = "xyz";
    if (rectilinear) {
      o << "DATASET RECTILINEAR_GRID\nDIMENSIONS " << ref.axis[0].size() << " " << ref.axis[1].size() << " " << ref.axis[2].size() << "\n";
      for (int a = 0; a < 3; ++a) {
        o << char(std::toupper(dims[a])) << "_COORDINATES " << ref.axis[std::size_t(a)].size() << " " << type << "\n";
        for (double x : ref.axis[std::size_t(a)]) put(x);
        o << "\n";
      }
    } else {
      o << "DATASET STRUCTURED_POINTS\nDIMENSIONS " << ref.axis[0].size() << " " << ref.axis[1].size() << " " << ref.axis[2].size()
        << "\nORIGIN " << ref.axis[0][0] << " " << ref.axis[1][0] << " " << ref.axis[2][0] << "\nSPACING "
        << ref.axis[0][1] - ref.axis[0][0] << " " << ref.axis[1][1] - ref.axis[1][0] << " " << ref.axis[2][1] - ref.axis[2][0] << "\n";
    }
    o << "POINT_DATA " << n << "\n";
    if (extra) {  // ParaView's mask (one point outside the mesh) and a second vector array
      o << "SCALARS vtkValidPointMask char 1\nLOOKUP_TABLE default\n";
      for (std::size_t k = 0; k < n; ++k) {
        if (binary) o.put(char(k == 5 ? 0 : 1));
        else o << (k == 5 ? 0 : 1) << " ";
      }
      o << "\nVECTORS vorticity " << type << "\n";
      for (std::size_t k = 0; k < 3 * n; ++k) put(1.0);
      o << "\n";
    }
    if (extra) o << "METADATA\nINFORMATION 1\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0 1\n\n";  // as ParaView writes
    o << "VECTORS U " << type << "\n";
    for (const Vec3& u : ref.u)
      for (int d = 0; d < 3; ++d) put(u[d]);
    o << "\n";
    return path;
  };
  struct Case {
    const char* name;
    bool binary, rectilinear;
    const char* type;
    bool extra;
    double tol;
  };
  for (const Case& k : {Case{"a.vtk", false, false, "double", false, 1e-15}, Case{"b.vtk", true, true, "double", true, 0.0},
                        Case{"c.vtk", true, false, "float", false, 1e-7}, Case{"d.vtk", false, true, "float", true, 1e-15}}) {
    CAPTURE(k.name);
    const FlowGrid g = io::read_flow_table(write(k.name, k.binary, k.rectilinear, k.type, k.extra));
    for (int a = 0; a < 3; ++a) {
      REQUIRE(g.axis[std::size_t(a)].size() == ref.axis[std::size_t(a)].size());
      for (std::size_t i = 0; i < ref.axis[std::size_t(a)].size(); ++i)
        CHECK(std::abs(g.axis[std::size_t(a)][i] - ref.axis[std::size_t(a)][i]) <= 1e-12);
    }
    REQUIRE(g.u.size() == n);
    double err = 0;
    for (std::size_t j = 0; j < n; ++j) {
      if (k.extra && j == 5) {
        CHECK(std::isnan(g.u[j].x()));  // masked point: no data
        continue;
      }
      err = std::max(err, (g.u[j] - ref.u[j]).norm() / exact.max_velocity());
    }
    CHECK(err <= k.tol);
  }
  // Errors name the file and, where it helps, the line.
  const std::string bad = scratch("bad.vtk");
  {
    std::ofstream o(bad);
    o << "# vtk DataFile Version 3.0\nmesh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 float\n";
  }
  CHECK_THROWS_WITH(io::read_flow_table(bad), doctest::Contains("bad.vtk:4: DATASET UNSTRUCTURED_GRID is not read"));
  {
    std::ofstream o(bad);
    o << "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 1\nORIGIN 0 0 0\nSPACING 1 1 1\n"
      << "POINT_DATA 4\nVECTORS a float\n0 0 0 1 0 0 0 1 0 1 1 0\nVECTORS b float\n0 0 0 0 0 0 0 0 0 0 0 0\n";
  }
  CHECK_THROWS_WITH(io::read_flow_table(bad), doctest::Contains("which 3-component point array is the velocity? (a, b"));
  {
    std::ofstream o(bad);
    o << "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 1\nORIGIN 0 0 0\nSPACING 1 1 1\n"
      << "POINT_DATA 4\nVECTORS U float\n0 0 0 1 0 0\n";
  }
  CHECK_THROWS_WITH(io::read_flow_table(bad), doctest::Contains("the file ends early"));
  {
    std::ofstream o(bad);
    o << "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 1\nORIGIN 0 0 0\nSPACING 1 1 1\n"
      << "POINT_DATA 4\nVECTORS U double\n\x01\x02";
  }
  CHECK_THROWS_WITH(io::read_flow_table(bad), doctest::Contains("ends inside its binary data"));
}

TEST_CASE("tabulated flow in a scene: resolved with the file's path and hash; a changed file is refused") {
  const std::string path = scratch("scene_flow.csv");
  {
    std::ofstream o(path);
    o << "x,y,z,u,v,w\n";
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 2; ++i) o << 20 * i << "," << -5 + 5 * j << "," << 20 * k << "," << 0.1 * j << ",0,0\n";
  }
  const std::string scene = "[particles]\npositions = [[1.0, 1.0, 1.0], [4.0, 1.0, 1.0]]\n[flow]\nkind = \"tabulated\"\nfile = \"" + path + "\"\n";
  const Scene s = io::parse_scene(scene, "tab.toml");
  CHECK(s.toml.find("file_hash") != std::string::npos);
  const Scene again = io::parse_scene(s.toml, "again.toml");
  CHECK(again.toml == s.toml);
  {
    std::ofstream o(path, std::ios::app);
    o << "# edited\n";
  }
  CHECK_THROWS_WITH(io::parse_scene(s.toml, "again.toml"), doctest::Contains("[flow] file_hash: the flow table"));
  CHECK_THROWS_WITH(io::parse_scene("[particles]\npositions = [[0.0, 0.0, 0.0]]\n[flow]\nkind = \"tabulated\"\nfile = \"nope.csv\"\n", "t.toml"),
                    doctest::Contains("t.toml:5: [flow] file: "));
}
