#pragma once
// Two spheres meeting in simple shear under the thesis's alumina DLVO forces, integrated to capture
// or escape (bench/validate_capture.cpp, tests/test_capture.cpp; docs/capture.md gives the set-up,
// the criteria and the units: rate = gdot* F0 / (6 pi), F0 the force scale in kT/a1).
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace stokesian::test_support {

inline constexpr double kCaptureGap = 0.1;
inline constexpr double kHoldStrain = 10.0;
inline constexpr double kMaxStrain = 400.0;

enum class Outcome { captured, escaped, undecided };

struct Trajectory {
  Outcome outcome = Outcome::undecided;
  double strain = 0.0;  // shear strain at the decision
  double gap = 0.0;     // surface gap then
  double min_gap = 1e300;  // smallest surface gap on the way
  long steps = 0;
};

// lubrication: the near-field level, "exact" or the thesis's "squeeze" ([hydrodynamics] lubrication).
inline std::string scene_text(double lambda, double rate, double s, double theta, const std::string& lubrication = "exact") {
  const double x0 = lambda == 1.0 ? 3.0 : 6.0;
  const double y = s * std::cos(theta), z = s * std::sin(theta);
  std::ostringstream o;
  o.precision(17);
  o << "[particles]\npositions = [[" << -x0 << ", " << y << ", " << z << "], [" << x0 << ", " << -y << ", " << -z
    << "]]\nradii = [1.0, " << lambda << "]\n"
    << "[flow]\nkind = \"simple_shear\"\nrate = " << rate << "\n"
    << "[[forces.pair]]\nkind = \"dlvo\"\nhamaker = 11.569308609513\ndebye_kappa = 100.0\n"
    << "surface_potential = 553.64872421\nborn_sigma = 1.8957508309584e-3\nmin_gap = 2e-4\n"
    << "[[forces.pair]]\nkind = \"hertz\"\nstiffness = 1e4\n"
    << "[hydrodynamics]\nmodel = \"stokesian\"\nmoments = \"FTS\"\nlubrication = \"" << lubrication << "\"\n"
    << "[time]\ndt = " << 0.01 / rate << "\nsteps = 100000000\nintegrator = \"rkf45\"\nrkf_tolerance = 1e-7\n";
  return o.str();
}

inline Trajectory run_pair(double lambda, double gdot_star, double F0, double s, double theta,
                           const std::string& lubrication = "exact") {
  const double rate = gdot_star * F0 / (6.0 * kPi);
  const double x0 = lambda == 1.0 ? 3.0 : 6.0;
  Simulation sim(io::parse_scene(scene_text(lambda, rate, s, theta, lubrication), "capture.toml"));
  State st = sim.initial_state();
  Trajectory tr;
  double held_since = -1.0;  // strain at which the gap fell below kCaptureGap
  for (;;) {
    const Evaluation ev = sim.evaluate(st, st.position, 0.0);
    sim.advance(st, ev);
    ++tr.steps;
    const Vec3 d = st.position[1] - st.position[0];
    tr.gap = d.norm() - 1.0 - lambda;
    tr.min_gap = std::min(tr.min_gap, tr.gap);
    tr.strain = rate * st.time;
    if (held_since >= 0.0) {
      if (tr.gap > 1.5 * kCaptureGap) {
        held_since = -1.0;
      } else if (tr.strain - held_since >= kHoldStrain) {
        tr.outcome = Outcome::captured;
        return tr;
      }
    } else if (tr.gap < kCaptureGap) {
      held_since = tr.strain;
    }
    if (held_since < 0.0 && d.x() < -4.0 * x0) {
      tr.outcome = Outcome::escaped;
      return tr;
    }
    if (tr.strain > kMaxStrain) return tr;
  }
}

}  // namespace stokesian::test_support
