// Regression: eight spheres at the corners of a cube settling under equal forces perform the
// periodic motion of Durlofsky, Brady & Bossis (1987, s.4): the thesis [T] (README.md; table 2.1)
// reports the period t_per in units of a/U0, U0 = F/(6 pi mu a), for the far-field FT mobility
// problem (St = 0): FT 31.9 (edge 3), 61.9 (edge 4) with one process and 32.7, 59.7 with eight;
// FTS (rigid-particle stresslets) 39.9 (edge 3, one process), 39.0 (eight). One period
// spans two planar configurations (all eight centres at one height). With zero torques the F and
// FT velocities coincide; the FTS period differs by 25 % at edge 3, so the FTS case tests the
// stresslet couplings and the constrained CG solve.
#include <doctest/doctest.h>

#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <cmath>
#include <sstream>

using namespace stokesian;

namespace {

double measured_period(double edge, const char* moments, double t_end) {
  const double h = 0.5 * edge;
  std::ostringstream toml;
  toml << "[particles]\npositions = [";
  for (int k = 0; k < 8; ++k)
    toml << (k ? "," : "") << "[" << (k & 1 ? h : -h) << "," << (k & 2 ? h : -h) << "," << (k & 4 ? h : -h) << "]";
  toml << "]\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n[[forces.pair]]\nkind = \"hertz\"\n"
       << "[hydrodynamics]\nmodel = \"far_field\"\nmoments = \"" << moments << "\"\ntolerance = 1e-10\n"
       << "[time]\ndt = 1.0\nsteps = 100000\nintegrator = \"rkf45\"\nrkf_tolerance = 1e-8\n";
  Simulation sim(io::parse_scene(toml.str(), "cube.toml"));
  State s = sim.initial_state();
  const double U0 = 1.0 / (6.0 * M_PI);
  std::vector<double> spread, time;
  while (s.time * U0 < t_end) {
    double zmin = INFINITY, zmax = -INFINITY;
    for (const Vec3& x : s.position) {
      zmin = std::min(zmin, x.z());
      zmax = std::max(zmax, x.z());
    }
    spread.push_back(zmax - zmin);
    time.push_back(s.time * U0);
    sim.advance(s, sim.evaluate(s, s.position));
    s.dt = std::min(s.dt, 5.0);  // resolve the planar events to 0.3 a/U0
  }
  std::vector<double> events;
  for (std::size_t i = 1; i + 1 < spread.size(); ++i)
    if (spread[i] < spread[i - 1] && spread[i] <= spread[i + 1] && spread[i] < 0.5) events.push_back(time[i]);
  REQUIRE(events.size() >= 3);
  return 2.0 * (events.back() - events.front()) / double(events.size() - 1);
}

}  // namespace

TEST_CASE("settling cube of eight spheres: far-field periods match thesis table 2.1 (FT and FTS)") {
  // The thesis' own runs of one model differ by up to 3.6 % (P = 1 vs P = 8); we allow 5 %.
  struct Case {
    double edge;
    const char* moments;
    double t_per, t_end;
  };
  for (const Case c : {Case{3, "FT", 31.9, 140}, Case{4, "FT", 61.9, 260}, Case{3, "FTS", 39.9, 170}}) {
    const double T = measured_period(c.edge, c.moments, c.t_end);
    const std::string level = c.moments;
    CAPTURE(level);
    CAPTURE(c.edge);
    CAPTURE(T);
    CHECK(std::abs(T / c.t_per - 1.0) < 0.05);
  }
}
