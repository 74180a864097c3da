#pragma once
// Mobility-form solvers: free draining and far field.
//
// Mobility problem [Durlofsky, Brady & Bossis 1987, eq. 2.13]:
//     [U - u_inf; Omega - Omega_inf; -E_inf] = M [F; T; S] (+ u_s),
// M the self blocks (free draining) or M_inf (far field, any MobilityOperator). Unknown are the
// entries whose motion is given (stresslets at FTS, forces and torques of fixed particles;
// constrained mobility problem, Lee et al. 2024, s. 2.1.2); they solve the principal sub-system
//     M_zz z = target_z - u_s,z - M_zk x_k,
// which is symmetric positive definite because M is (engine/kernels/mobility_pair.hpp), by
// conjugate gradients to the tolerance.
//
// Brownian displacements (F and FT): dX_B = sqrt(2 kT dt) M^{1/2} W. Free draining: M^{1/2} is
// diagonal, sqrt(D_i) = (6 pi mu a_i)^{-1/2} per translational component. Far field: M^{1/2} W by
// Lanczos (engine/core/krylov.hpp) on the operator at the solve's moments, translational part
// kept. M_inf is divergence free (translational blocks are built from the transverse projector),
// so no thermal drift term is needed. Brownian forces for the Fixman scheme (FTS, fixed particles,
// whose constrained mobilities are not divergence free): engine/brownian.hpp.
#include "engine/hydro_solver.hpp"

#include <memory>

namespace stokesian {

// Far field: M = M_inf of any far-field method.
class MobilitySolver : public HydroSolver {
 public:
  MobilitySolver(std::unique_ptr<MobilityOperator> op, double tolerance);
  const char* name() const override { return "mobility_cg"; }
  Moments moments() const override { return op_->moments(); }
  void prepare(const Configuration& c) override;
  HydroResult solve(const HydroProblem& p) override;
  std::vector<Vec3> brownian_displacement(double kT, double dt, Rng& rng) override;
  // sqrt(2 kT / dt) M^{-1/2} psi on the given entries (Lanczos, engine/brownian.hpp).
  VecX brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) override;
  bool needs_drift() const override { return false; }
  bool prepare_uses_threads(long n) const override { return op_->set_configuration_uses_threads(n); }
  const MobilityOperator* far_field() const override { return op_.get(); }

 protected:
  std::unique_ptr<MobilityOperator> op_;
  double tol_;
  long n_ = 0;  // particles of the prepared configuration
  StoredConfiguration config_;  // the prepared configuration (the Brownian force's deflation)
};

// Free draining: M = the self blocks.
class FreeDrainingSolver final : public MobilitySolver {
 public:
  FreeDrainingSolver(const MobilitySpec& spec);
  const char* name() const override { return "free_draining"; }
  std::vector<Vec3> brownian_displacement(double kT, double dt, Rng& rng) override;
  // sqrt(2 kT / dt) R_self^{1/2} psi: exact (diagonal).
  VecX brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) override;
  const MobilityOperator* far_field() const override { return nullptr; }

 private:
  double mu_;
};

}  // namespace stokesian
