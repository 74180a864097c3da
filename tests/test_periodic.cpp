// Periodic and Lees-Edwards boxes through the solver and the run driver: a sphere in a cubic box
// against Hasimoto (1959) for PME, Ewald and dense Stokesian dynamics; a particle crossing the
// sheared boundary follows the unwrapped open-domain trajectory.
#include <doctest/doctest.h>

#include "engine/hydrodynamics.hpp"
#include "engine/sd_dense.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <cmath>
#include <sstream>

using namespace stokesian;

namespace {
// Hasimoto (1959) for the RPY sphere in a simple cubic lattice of side L (docs/ewald.md).
double hasimoto(double a, double L, double mu) {
  return (1.0 - 2.837297 * a / L + 4.0 * M_PI / 3.0 * std::pow(a / L, 3)) / (6.0 * M_PI * mu * a);
}
Domain cube(double L, double strain = 0.0) {
  Domain d;
  d.kind = Domain::Kind::periodic;
  d.box = Vec3::Constant(L);
  d.shear_strain = strain;
  return d;
}
}  // namespace

TEST_CASE("one sphere in a cubic box: PME, Ewald and dense SD give Hasimoto's mobility") {
  // The expansion is exact to O((a/L)^6) for the RPY sphere: at L = 10 a the neglected terms are
  // ~1e-6, so compare to 1e-5 relative.
  const double a = 1.0, L = 10.0, mu = 1.3;
  const Vec3 F(0.3, -1.0, 0.5);
  for (const char* method : {"pme", "ewald"}) {
    ResolvedModel m;
    m.level = HydroModel::far_field;
    m.moments = Moments::FTS;
    m.far_field = method;
    Hydrodynamics h(m, mu, AmbientFlow{}, 1e-9);
    const HydroResult r = h.solve({Vec3(3, 4, 5)}, {a}, {}, {F}, {Vec3::Zero()}, cube(L));
    CAPTURE(method);
    CHECK((r.U[0] - hasimoto(a, L, mu) * F).norm() < 1e-5 * hasimoto(a, L, mu) * F.norm());
  }
  DenseStokesianDynamics sd(Moments::FT, mu, AmbientFlow{});
  const HydroResult r = sd.mobility_problem({Vec3(3, 4, 5)}, {a}, {}, {F}, {Vec3::Zero()}, cube(L));
  CHECK((r.U[0] - hasimoto(a, L, mu) * F).norm() < 1e-5 * hasimoto(a, L, mu) * F.norm());
}

TEST_CASE("periodic Stokesian dynamics: a close pair in a large box approaches the open-domain result") {
  // The periodic images change the pair's velocity by O(a/L); at L = 60 a the leading Hasimoto
  // correction is 2.84/60 = 4.7 % of the single-sphere mobility, applied to both spheres alike,
  // so the relative velocity of the pair (driven by opposite forces) differs from the open
  // domain by less than 1 %.
  const std::vector<Vec3> x{Vec3(10, 10, 10), Vec3(12.1, 10.2, 10)};
  const std::vector<double> a{1.0, 0.8};
  const std::vector<Vec3> F{Vec3(1, 0, 0), Vec3(-1, 0, 0)};
  DenseStokesianDynamics sd(Moments::FT, 1.0, AmbientFlow{});
  const HydroResult open = sd.mobility_problem(x, a, {}, F, {Vec3::Zero(), Vec3::Zero()});
  const HydroResult per = sd.mobility_problem(x, a, {}, F, {Vec3::Zero(), Vec3::Zero()}, cube(60.0));
  const Vec3 rel_open = open.U[0] - open.U[1], rel_per = per.U[0] - per.U[1];
  CHECK((rel_per - rel_open).norm() < 1e-2 * rel_open.norm());
}

TEST_CASE("Lees-Edwards: a particle crossing the sheared boundary follows the unwrapped trajectory") {
  // Free draining, simple shear rate g, constant force along y: in the unbounded shear flow
  // y(t) = y0 + v t, x(t) = x0 + g (y0 t + v t^2 / 2). In the box the particle re-enters at
  // y - Ly with x shifted by -(strain Ly), strain = g t; positions agree modulo Lx.
  const double g = 0.2, L = 10.0, Fy = 6 * M_PI * 0.5;  // v = Fy / (6 pi mu a) = 0.5
  std::ostringstream t;
  t.precision(17);
  t << "[domain]\nkind = \"periodic\"\nbox = [" << L << ", " << L << ", " << L << "]\n"
    << "[particles]\npositions = [[2.0, 8.0, 5.0]]\n[forces]\nexternal_force = [0.0, " << Fy << ", 0.0]\n"
    << "[flow]\nkind = \"simple_shear\"\nrate = " << g << "\n[hydrodynamics]\nmodel = \"free_draining\"\n"
    << "[time]\ndt = 0.01\nintegrator = \"midpoint\"\n";
  Simulation sim(io::parse_scene(t.str(), "le.toml"));
  State s = sim.initial_state();
  const double T = 12.0;  // v T = 6: crosses y = L once, at t = 4
  while (s.time < T - 1e-9) sim.advance(s, sim.evaluate(s, s.position));
  const double v = 0.5, y_open = 8.0 + v * s.time, x_open = 2.0 + g * (8.0 * s.time + 0.5 * v * s.time * s.time);
  const double crossings = std::floor(y_open / L);
  double dx = (x_open - crossings * g * s.time * L) - s.position[0].x();
  dx -= L * std::round(dx / L);
  CHECK(std::abs(s.position[0].y() - (y_open - crossings * L)) < 1e-9);
  // The midpoint rule integrates the quadratic x(t) exactly; the strain is reduced modulo 1.
  CHECK(std::abs(dx) < 1e-8);
  CHECK(crossings == 1.0);
}
