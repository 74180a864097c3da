// Stability where methods fail: near contact, dense packing, large steps. Runs must stay finite,
// count and report overlaps, and keep their invariants (no NaN, regularised gaps).
#include <doctest/doctest.h>

#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <cmath>

using namespace stokesian;

namespace {
struct Outcome {
  double min_gap = INFINITY;
  long max_overlaps = 0;
};
Outcome run_steps(const std::string& toml, int steps) {
  Simulation sim(io::parse_scene(toml, "stability.toml"));
  State s = sim.initial_state();
  Outcome o;
  for (int k = 0; k < steps; ++k) {
    const Evaluation ev = sim.evaluate(s, s.position);
    for (const Vec3& u : ev.hydro.U) REQUIRE(u.allFinite());
    const Frame f = sim.frame(s, ev);
    o.min_gap = std::min(o.min_gap, f.scalar("min_gap"));
    o.max_overlaps = std::max(o.max_overlaps, long(f.scalar("overlaps")));
    sim.advance(s, ev);
  }
  return o;
}
}  // namespace

TEST_CASE("dense attractive packing with large steps: Stokesian dynamics stays finite, lubrication keeps gaps open") {
  // phi = 0.4 cluster pulled together by a Morse well with steps of 0.05 time units: lubrication
  // (1/xi resistance) slows approach so no pair should overlap by more than the regularised gap.
  const std::string toml = R"(
[particles]
generate = "random"
count = 40
volume_fraction = 0.4
size_distribution = "bidisperse"
radius_ratio = 1.5
seed = 2
[[forces.pair]]
kind = "morse"
depth = 10.0
[[forces.pair]]
kind = "hertz"
[hydrodynamics]
model = "stokesian"
[time]
dt = 0.05
integrator = "euler"
)";
  const Outcome o = run_steps(toml, 15);
  MESSAGE("SD dense attractive packing: smallest gap " << o.min_gap << ", most overlaps " << o.max_overlaps);
  CHECK(std::isfinite(o.min_gap));
  // Measured: smallest gap 8e-11 a, no overlap. Explicit Euler may overshoot into contact; a deep
  // overlap (beyond 1e-2 a) would mean the lubrication resistance is not acting.
  CHECK(o.min_gap > -1e-2);
}

TEST_CASE("far-field Brownian run through heavy overlaps stays finite and counts them") {
  // Strong Morse attraction without lubrication pulls spheres into overlap; the overlap-regularised
  // mobility must stay positive definite (Lanczos converges) and the run finite.
  const std::string toml = R"(
[fluid]
kT = 1.0
[particles]
generate = "lattice"
count = 27
volume_fraction = 0.3
seed = 3
[[forces.pair]]
kind = "morse"
depth = 50.0
kappa = 3.0
[hydrodynamics]
model = "far_field"
moments = "FT"
[time]
dt = 0.2
)";
  const Outcome o = run_steps(toml, 30);
  MESSAGE("far-field Brownian: smallest gap " << o.min_gap << ", most overlaps " << o.max_overlaps);
  CHECK(o.max_overlaps > 0);
  CHECK(std::isfinite(o.min_gap));
}
