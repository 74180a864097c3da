#pragma once
// What an integrator sees of the physics: velocities at any positions and time within a step,
// and Brownian displacements. The Simulation implements it (forces -> hydrodynamic solve).
#include "engine/core/layout.hpp"
#include "engine/core/state.hpp"
#include "engine/pair_forces.hpp"

#include <optional>
#include <vector>

namespace stokesian {

// Surface-gap statistics of a configuration (overlap diagnostics).
struct GapStats {
  double min_gap = 0.0;      // smallest surface gap among the pairs searched [a]; +inf when none
  long overlaps = 0;         // pairs with a negative gap
};

// Everything computed at one configuration.
struct Evaluation {
  std::vector<Vec3> force, torque;  // non-hydrodynamic force and torque on each particle
  HydroResult hydro;                // velocities etc. (deterministic part)
  forces::PairForceTotals pair;     // pair energy and virial
  std::optional<GapStats> gaps;     // computed in the step's task graph at output steps
};

class Dynamics {
 public:
  virtual ~Dynamics() = default;
  // Evaluation at positions x and time t after the start of the step of s (t enters through the
  // Lees-Edwards strain of sheared boxes).
  virtual Evaluation evaluate(const State& s, const std::vector<Vec3>& x, double t) = 0;
  // sqrt(2 kT dt) B W at the positions of s (zero for fixed particles); empty when athermal.
  virtual std::vector<Vec3> brownian_displacement(const State& s, double dt, Rng& rng) = 0;
};

}  // namespace stokesian
