#pragma once
// The run driver: scene -> state -> forces -> hydrodynamic solve -> integrator -> observers ->
// outputs. One step's phases form a task graph (engine/core/task_graph.hpp): pair forces, the
// hydrodynamic set-up (far-field operator, near-field assembly) and the output diagnostics are
// independent and run concurrently; the solve follows them.
#include "engine/core/output.hpp"
#include "engine/core/scene.hpp"
#include "engine/core/state.hpp"
#include "engine/core/task_graph.hpp"
#include "engine/dynamics.hpp"
#include "engine/hydrodynamics.hpp"
#include "engine/inflow.hpp"
#include "engine/integrators.hpp"
#include "engine/model.hpp"
#include "engine/observers.hpp"

#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace stokesian {

struct RunControl {
  bool quiet = false;
  long max_steps = -1;      // stop after this many steps of this call (tests); -1 = run to the end
  bool frame_done = false;  // the frame of the state's step is already recorded (resumed runs)
};

// Wall time of the phases of the last evaluation (benchmarks).
struct PhaseTimes {
  std::vector<std::string> names;
  std::vector<double> seconds;
};

class Simulation final : public Dynamics {
 public:
  explicit Simulation(Scene scene);  // resolves the model; ConfigError if it is not available

  const Scene& scene() const { return scene_; }
  const ResolvedModel& model() const { return model_; }

  State initial_state() const;
  // Evaluation at positions x, time t into the step of s; with `diagnostics`, also the gap
  // statistics (computed beside the forces and the solve).
  Evaluation evaluate(const State& s, const std::vector<Vec3>& x, double t = 0.0) override {
    return evaluate(s, x, t, false);
  }
  Evaluation evaluate(const State& s, const std::vector<Vec3>& x, double t, bool diagnostics);
  // The evaluation run() makes at the start of every step: the deterministic solve only on frame
  // steps (output_step, with the gap diagnostics) or where the integrator reads it (the Fixman step
  // with noise solves with F + xi itself), and the overlaps for the overlap policy (into overlaps if
  // given). Benchmarks time a step as this (output_step false) plus advance().
  Evaluation evaluate_step_start(const State& s, bool output_step = false, GapSurvey* overlaps = nullptr);
  // The hydrodynamic solver (benchmarks read its statistics).
  HydroSolver& hydro_solver() { return hydro_.solver(); }
  Evaluation evaluate(const State& s, const std::vector<Vec3>& x, double t, const VecX* noise,
                      WarmStart* warm = nullptr) override;
  std::vector<Vec3> brownian_displacement(const State& s, double dt, Rng& rng) override;
  VecX brownian_force(const State& s, double dt, Rng& rng) override;
  HydroResult noise_response(const State& s, const std::vector<Vec3>& x, double t, const VecX& xi,
                             WarmStart* warm = nullptr) override;

  Frame frame(const State& s, const Evaluation& ev) const;
  const Inflow* inflow() const { return inflow_ ? &*inflow_ : nullptr; }
  // The particles the solvers see: s itself, or in an open channel its present particles
  // (Inflow::compact); frame_of_present writes a frame of them back into the slots of s.
  State present(const State& s) const { return inflow_ ? Inflow::compact(s, inflow_->present(s)) : s; }
  Frame frame_of_present(const State& s, const Evaluation& ev) const;
  RunHeader header() const;

  // Advance s by one (accepted) step; ev is the evaluation at s.position.
  void advance(State& s, const Evaluation& ev);
  // Steps that write a frame: every [output] every steps from the start, and the last step.
  bool frame_step(std::int64_t step) const;
  // The step from `step` samples the Brownian stresslet ([brownian] stress_every).
  bool samples_brownian_stress(std::int64_t step) const;

  // Steps s to the scene's last step, recording every output step and checkpointing; returns the
  // number of steps taken by this call.
  // Failure policy (docs/reliability.md): a PhysicsError while taking a step (the evaluation of the
  // state it reaches included: non-finite positions, forces or velocities, a pair overlapping beyond
  // [run] max_overlap, a failed factorisation or Krylov solve) stops the run with RunStopped after
  // checkpointing the state before that step (s is left at it). At the first evaluation of a call
  // there is no earlier state: RunStopped with checkpoint_step = -1 and nothing written.
  long run(State& s, OutputSink& out, const RunControl& control);

  // Phase graph mode (serial: the same phases one after another, for comparisons).
  void set_task_mode(TaskGraph::Mode mode) { task_mode_ = mode; }
  const PhaseTimes& phase_times() const { return phases_; }

 private:
  void check_finite(const State& s) const;
  // [run] max_overlap applies when something in the model keeps surfaces apart: a pair force, or
  // lubrication (Stokesian dynamics). Free-draining or far-field spheres without pair forces are
  // penetrable in the model: their overlaps are counted and reported, never a failure.
  bool overlap_policy_applies() const {
    return !scene_.forces.pair.empty() || model_.level == HydroModel::stokesian;
  }
  // evaluate(), plus (overlaps != nullptr) the overlapping pairs of x, checked against
  // [run] max_overlap before the solve; every failure is a PhysicsError naming step and particles.
  Evaluation evaluate_checked(const State& s, const std::vector<Vec3>& x, double t, bool diagnostics,
                              GapSurvey* overlaps, const VecX* noise = nullptr, bool solve = true,
                              WarmStart* warm = nullptr);
  Scene scene_;
  ResolvedModel model_;
  double strain_rate_;  // d(Lees-Edwards strain)/dt of the box
  Hydrodynamics hydro_;
  std::unique_ptr<Integrator> integrator_;
  std::vector<std::unique_ptr<Observer>> observers_;
  TaskGraph::Mode task_mode_ = TaskGraph::Mode::automatic;
  PhaseTimes phases_;
  std::optional<std::mt19937_64> legacy_noise_;  // set while continuing a run of 0.1.0 (see run())
  // Outline channels: a monolayer at z = 0. The motion out of the plane (U_z, Omega_x, Omega_y) is
  // removed from every solve and Brownian displacement. For coplanar spheres the mirror symmetry
  // z -> -z decouples the in-plane motions (U_x, U_y, Omega_z) from the out-of-plane ones in the
  // mobility, resistance and near field alike, so the in-plane block is the constrained system's
  // mobility itself: deterministic velocities are unchanged (their out-of-plane part is zero), the
  // Brownian displacement keeps the covariance 2 kT M_inplane dt, and the midpoint stages stay in
  // the plane, so Fixman's drift is that of the in-plane dynamics (docs/channels.md, "Outlines").
  bool monolayer_ = false;
  void keep_in_plane(HydroResult& r) const;
  // Open channels ([inflow]): run() steps the present particles (engine/inflow.hpp).
  std::optional<Inflow> inflow_;
};

}  // namespace stokesian
