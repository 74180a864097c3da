#pragma once
// The hydrodynamic stage of a step: the resolved model's solver (engine/methods.hpp) and the
// ambient flow sampled at the particles. The Simulation prepares it in the step's task graph and
// then solves; the conveniences below do both at once (tests, one-off solves).
#include "engine/core/flow.hpp"
#include "engine/hydro_solver.hpp"
#include "engine/model.hpp"
#include "lubrication/near_field.hpp"

#include <memory>
#include <vector>

namespace stokesian {

class Hydrodynamics {
 public:
  // radius_ratio: a_max / a_min of the particles (accuracy knobs, engine/accuracy.hpp).
  Hydrodynamics(const ResolvedModel& model, double viscosity, std::shared_ptr<const AmbientField> flow,
                double tolerance, lubrication::NearFieldParams near_field = {}, double radius_ratio = 1.0);
  // A linear ambient flow (tests, one-off solves).
  Hydrodynamics(const ResolvedModel& model, double viscosity, const AmbientFlow& flow, double tolerance,
                lubrication::NearFieldParams near_field = {}, double radius_ratio = 1.0)
      : Hydrodynamics(model, viscosity, std::make_shared<AmbientFlow>(flow), tolerance, near_field, radius_ratio) {}

  // Set-up at a configuration; skipped when it equals the last prepared one.
  void prepare(const Configuration& c);
  // The same as phases for the step's task graph (none when c is the prepared configuration); the
  // last phase marks c prepared.
  std::vector<PreparePhase> prepare_phases(const Configuration& c);
  // At the prepared configuration; noise: a Brownian force added to the given loads (or nullptr);
  // warm: an iterative solver's warm start (engine/hydro_solver.hpp), or nullptr.
  HydroResult solve(const Configuration& c, const std::vector<char>& fixed, const std::vector<Vec3>& F,
                    const std::vector<Vec3>& T, const VecX* noise = nullptr, WarmStart* warm = nullptr);
  // prepare + the solver's Brownian force, covariance (2 kT / dt) R (engine/brownian.hpp).
  VecX brownian_force(const Configuration& c, const std::vector<char>& fixed, double kT, double dt, Rng& rng);
  // At the prepared configuration: the velocities that the force xi alone gives (no loads, no
  // ambient flow).
  HydroResult noise_velocity(const Configuration& c, const std::vector<char>& fixed, const VecX& xi,
                             WarmStart* warm = nullptr);

  // prepare + solve. F, T: non-hydrodynamic force and torque on each particle (T ignored at F level).
  HydroResult solve(const std::vector<Vec3>& x, const std::vector<double>& a, const std::vector<char>& fixed,
                    const std::vector<Vec3>& F, const std::vector<Vec3>& T, const Domain& domain = Domain{});
  // prepare + sqrt(2 kT dt) M^{1/2} W for the positions (rotations are not tracked).
  std::vector<Vec3> brownian_displacement(const std::vector<Vec3>& x, const std::vector<double>& a, double kT,
                                          double dt, Rng& rng, const Domain& domain = Domain{});

  HydroSolver& solver() { return *solver_; }
  const ResolvedModel& model() const { return model_; }
  const AmbientField& flow() const { return *flow_; }

 private:
  ResolvedModel model_;
  std::shared_ptr<const AmbientField> flow_;
  std::unique_ptr<HydroSolver> solver_;
  StoredConfiguration prepared_;  // the last prepared configuration
};

}  // namespace stokesian
