#pragma once
// The hydrodynamic solve: from forces, torques and the ambient flow to velocities, angular
// velocities and stresslets, at the resolved level and moments.
//
// Mobility problem [Durlofsky, Brady & Bossis 1987, eq. 2.13]:
//     [U - U_inf(x); Omega - Omega_inf; -E_inf] = M [F; T; S],
// with F, T, S exerted by the particles on the fluid. Unknown are the stresslets S (FTS: rigid
// particles do not deform with the strain) and the forces/torques of fixed particles (U = Omega
// = 0; constrained mobility problem, seed 1 s.2.1.2). The unknowns z solve the principal
// sub-system M_zz z = target_z - M_zk x_k, which is symmetric positive definite because M is
// (engine/mobility_pair.hpp), by conjugate gradients to the scene's tolerance.
// Free draining keeps only the self blocks (U = F/(6 pi mu a), ...). Stokesian dynamics
// (R = M_inf^{-1} + R_nf) uses the dense reference solver of engine/sd_dense.hpp.
//
// Brownian displacements (kT > 0, F and FT): dX_B = sqrt(2 kT dt) M^{1/2} W with W standard
// normal; M^{1/2} W by Lanczos (engine/krylov.hpp). M_inf is divergence free (translational
// blocks are built from the transverse projector), so no thermal drift term is needed here.
#include "engine/far_field.hpp"
#include "engine/flow.hpp"
#include "engine/model.hpp"
#include "engine/sym_traceless.hpp"

#include <memory>
#include <random>
#include <vector>

namespace stokesian {

struct HydroResult {
  std::vector<Vec3> U, Omega;  // velocities, angular velocities (Omega empty at F level)
  std::vector<Vec5> S;         // stresslets exerted on the fluid (empty below FTS)
  std::vector<Vec3> F, T;      // forces/torques exerted on the fluid (fixed particles: holding force)
  int iterations = 0;          // Krylov iterations of the constrained solve
};

// Per-particle results from generalised vectors in the interleaved layout: `relative` holds
// [U - U_inf, Omega - Omega_inf, ...] and `moments` [F, T, S] (exerted on the fluid). Fixed
// particles get U = Omega = 0.
HydroResult unpack_solution(Moments m, const std::vector<Vec3>& x, const AmbientFlow& flow, const VecX& relative,
                            const VecX& moments, const std::vector<char>& fixed);

class DenseStokesianDynamics;

class Hydrodynamics {
 public:
  Hydrodynamics(const ResolvedModel& model, double viscosity, const AmbientFlow& flow, double tolerance,
                double lubrication_cutoff = 4.0, double lubrication_min_gap = 1e-6);
  ~Hydrodynamics();
  Hydrodynamics(Hydrodynamics&&) noexcept;

  // F, T: non-hydrodynamic force and torque on each particle (T ignored at F level).
  HydroResult solve(const std::vector<Vec3>& x, const std::vector<double>& a, const std::vector<char>& fixed,
                    const std::vector<Vec3>& F, const std::vector<Vec3>& T, const Domain& domain = Domain{}) const;

  // Brownian displacements sqrt(2 kT dt) M^{1/2} W for the positions (rotations are not tracked).
  std::vector<Vec3> brownian_displacement(const std::vector<Vec3>& x, const std::vector<double>& a, double kT,
                                          double dt, std::mt19937_64& rng, const Domain& domain = Domain{}) const;

  // The far-field operator of the resolved method for this configuration (direct, ewald, pme).
  // Valid until the next call. A PME operator is kept between calls and only moved to the new
  // positions (update_positions) while particles, radii, box and strain are unchanged, so its
  // parameters, grid and FFTW plans are made once per run (once per step under shear).
  const FarFieldOperator& far_field(const std::vector<Vec3>& x, const std::vector<double>& a,
                                    const Domain& domain) const;

  const ResolvedModel& model() const { return model_; }

 private:
  ResolvedModel model_;
  double mu_;
  AmbientFlow flow_;
  double tol_;
  std::unique_ptr<DenseStokesianDynamics> sd_;  // model "stokesian" (dense reference solver)
  // Far-field operator of the last call (solves are serial: one evaluation at a time).
  mutable std::unique_ptr<FarFieldOperator> op_;
  mutable std::vector<double> op_radii_;
  mutable std::vector<Vec3> op_positions_;
  mutable Domain op_domain_;
};

}  // namespace stokesian
