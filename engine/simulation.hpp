#pragma once
// The run driver: scene -> state -> forces -> hydrodynamic solve -> integrator -> outputs.
#include "engine/hydrodynamics.hpp"
#include "engine/model.hpp"
#include "engine/pair_forces.hpp"
#include "engine/scene.hpp"
#include "engine/state.hpp"
#include "io/h5md.hpp"

#include <random>
#include <string>

namespace stokesian {

// Everything computed at one configuration.
struct Evaluation {
  std::vector<Vec3> force, torque;  // non-hydrodynamic force and torque on each particle
  HydroResult hydro;                // velocities etc. (deterministic part)
  forces::PairForceTotals pair;     // pair energy and virial
};

struct RunOptions {
  std::string out;         // trajectory path
  bool resume = false;
  bool quiet = false;
  long max_steps = -1;     // stop after this many steps of this invocation (tests); -1 = run to the end
};

class Simulation {
 public:
  explicit Simulation(Scene scene);  // resolves the model; ConfigError if it is not available

  const Scene& scene() const { return scene_; }
  const ResolvedModel& model() const { return model_; }

  State initial_state() const;
  Evaluation evaluate(const State& s, const std::vector<Vec3>& x) const;
  io::Frame frame(const State& s, const Evaluation& ev) const;
  io::TrajectoryHeader header() const;

  // Advance s by one (accepted) step; ev is the evaluation at s.position.
  void advance(State& s, const Evaluation& ev, std::mt19937_64& rng) const;

  // Full run with periodic checkpoints; returns the number of steps taken by this call.
  long run(const RunOptions& opt) const;
  // One solve of the initial configuration written as a single frame.
  void solve(const std::string& out) const;

 private:
  void wrap(State& s) const;
  void check_finite(const State& s) const;
  Scene scene_;
  ResolvedModel model_;
  AmbientFlow flow_;
  Hydrodynamics hydro_;
};

}  // namespace stokesian
