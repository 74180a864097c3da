// Time integrators against an analytic trajectory: a force-free sphere advected by planar
// extension, x(t) = x0 e^{g t}, y(t) = y0 e^{-g t}; convergence orders and the RKF45 error control.
#include <doctest/doctest.h>

#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <cmath>
#include <sstream>

using namespace stokesian;

namespace {
double final_error_single(const std::string& integrator, double dt, double t_end, double rkf_tol = 1e-6) {
  std::ostringstream t;
  t << "[particles]\npositions = [[1.0, 2.0, 0.5]]\n[flow]\nkind = \"planar_extension\"\nrate = 0.5\n"
    << "[time]\ndt = " << dt << "\nintegrator = \"" << integrator << "\"\nrkf_tolerance = " << rkf_tol << "\n";
  Simulation sim(io::parse_scene(t.str(), "ext.toml"));
  State s = sim.initial_state();
  while (s.time < t_end - 1e-12) {
    s.dt = std::min(s.dt, t_end - s.time);
    sim.advance(s, sim.evaluate(s, s.position));
  }
  const Vec3 exact(1.0 * std::exp(0.5 * s.time), 2.0 * std::exp(-0.5 * s.time), 0.5);
  return (s.position[0] - exact).norm();
}
}  // namespace

TEST_CASE("Euler is first order and midpoint second order") {
  // Halving dt must divide the error by ~2 (Euler) and ~4 (midpoint); the asymptotic ratios are
  // reached to within 15 % at these step sizes.
  const double e1 = final_error_single("euler", 0.02, 2.0), e2 = final_error_single("euler", 0.01, 2.0);
  CHECK(e1 / e2 == doctest::Approx(2.0).epsilon(0.15));
  const double m1 = final_error_single("midpoint", 0.02, 2.0), m2 = final_error_single("midpoint", 0.01, 2.0);
  CHECK(m1 / m2 == doctest::Approx(4.0).epsilon(0.15));
  CHECK(m2 < e2);
}

TEST_CASE("RKF45 keeps the global error near the requested local tolerance") {
  for (double tol : {1e-4, 1e-7, 1e-10}) {
    const double e = final_error_single("rkf45", 0.5, 2.0, tol);
    CAPTURE(tol);
    // Global error accumulates over the ~10-100 accepted steps: allow 100 tol.
    CHECK(e < 100 * tol);
  }
}

TEST_CASE("fixman: athermal it is the explicit midpoint; Brownian SD steps repeat exactly for a seed") {
  const std::string base = R"([particles]
positions = [[0,0,0],[2.2,0.3,0],[0.5,2.3,0.4]]
radii = [1.0, 1.2, 0.8]
[forces]
external_force = [0.0, 0.0, -1.0]
[[forces.pair]]
kind = "hertz"
[hydrodynamics]
model = "stokesian"
tolerance = 1e-8
[time]
dt = 0.01
steps = 3
)";
  // Athermal: the same positions as the midpoint rule.
  Simulation f(io::parse_scene(base + "integrator = \"fixman\"\n", "f.toml"));
  Simulation m(io::parse_scene(base + "integrator = \"midpoint\"\n", "m.toml"));
  State sf = f.initial_state(), sm = m.initial_state();
  for (int k = 0; k < 3; ++k) {
    f.advance(sf, f.evaluate(sf, sf.position));
    m.advance(sm, m.evaluate(sm, sm.position));
  }
  for (std::size_t i = 0; i < sf.position.size(); ++i) CHECK((sf.position[i] - sm.position[i]).norm() < 1e-12);
  // Brownian: fixman is chosen, the noise moves the particles, and a second run repeats the first.
  const std::string hot = base + "[fluid]\nkT = 1.0\n[brownian]\nseed = 7\n";
  Simulation a(io::parse_scene(hot, "a.toml")), b(io::parse_scene(hot, "b.toml"));
  CHECK(a.model().integrator == "fixman");
  State sa = a.initial_state(), sb = b.initial_state();
  for (int k = 0; k < 3; ++k) {
    a.advance(sa, a.evaluate(sa, sa.position));
    b.advance(sb, b.evaluate(sb, sb.position));
  }
  CHECK(sa.position == sb.position);
  double moved = 0;
  for (std::size_t i = 0; i < sa.position.size(); ++i) moved += (sa.position[i] - sf.position[i]).norm();
  CHECK(moved > 1e-3);  // thermal displacements ~ sqrt(2 D dt) ~ 0.03 a per step
}
