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
  // The step from this state samples the Brownian stresslet (engine/stress.hpp; every
  // [brownian] stress_every steps where the stress is recorded: Simulation::samples_brownian_stress).
  bool sample_brownian_stress = false;
  // The iterative solver's last iterate of this evaluation's solve (engine/core/layout.hpp): the
  // integrator's stages of the same step start from it.
  WarmStart warm;
};

class Dynamics {
 public:
  virtual ~Dynamics() = default;
  // Evaluation at positions x and time t after the start of the step of s (t enters through the
  // Lees-Edwards strain of sheared boxes).
  virtual Evaluation evaluate(const State& s, const std::vector<Vec3>& x, double t) = 0;
  // The same with the Brownian force xi (from brownian_force) added to the given loads: the
  // solve is R V = f + xi (engine/hydro_solver.hpp); noise == nullptr or empty: none. warm: the
  // iterative solver's warm start (engine/hydro_solver.hpp), shared by the stages of one step.
  virtual Evaluation evaluate(const State& s, const std::vector<Vec3>& x, double t, const VecX* noise,
                              WarmStart* warm = nullptr) = 0;
  // Displacement of Brownian motion without drift at the positions of s: sqrt(2 kT dt) M^{1/2} W
  // for the far field, dt R^{-1} xi for solvers with a resistance (zero for fixed particles);
  // empty when athermal.
  virtual std::vector<Vec3> brownian_displacement(const State& s, double dt, Rng& rng) = 0;
  // Brownian force xi of covariance (2 kT / dt) R at the positions of s (engine/brownian.hpp,
  // generalised layout of the model's moments); empty when athermal.
  virtual VecX brownian_force(const State& s, double dt, Rng& rng) = 0;
  // The response to the force xi alone (no other loads, no ambient flow) at positions x and time t
  // into the step of s: U = R^{-1} xi and the stresslets A xi, A = dS/dF (engine/stress.hpp).
  virtual HydroResult noise_response(const State& s, const std::vector<Vec3>& x, double t, const VecX& xi,
                                     WarmStart* warm = nullptr) = 0;
};

}  // namespace stokesian
