#pragma once
// The hydrodynamic solver interface: from loads and the ambient flow to particle motion at one
// configuration. Every solver (free draining, far field, dense Stokesian dynamics, and next the
// accelerated solver) implements it and passes the solver conformance test
// (tests/test_conformance.cpp).
//
// Problem (generalised layout and rigid-body constraints of engine/core/layout.hpp): with R the
// solver's resistance (M_inf^{-1} for the far field, M_inf^{-1} + R_nf for Stokesian dynamics,
// Durlofsky, Brady & Bossis 1987, eq. 2.17), the relative motion V = [U - u_inf, Omega -
// Omega_inf, -E_inf] solves
//     R V = f + f_B + M_inf^{-1} u_s,
// f the given forces/torques (and the unknown stresslets / holding forces at the entries whose
// motion is given), f_B an optional Brownian force (near-field noise, added to the given forces)
// and u_s an optional slip velocity (far-field noise or a random-finite-difference probe) that a
// far-field-only solver adds to the velocities: U = M_inf (f + f_B) + u_s. The reported moments
// are f + f_B: the given loads plus the noise force at given entries, the solved stresslets and
// holding forces elsewhere.
//
// Life cycle per configuration: prepare (far-field operator set-up, near-field assembly and
// factorisation; the step's task graph runs it beside the pair forces), then any number of solves
// and Brownian draws at that configuration.
#include "engine/core/flow.hpp"
#include "engine/core/layout.hpp"
#include "engine/core/operators.hpp"

#include <functional>
#include <string>
#include <vector>

namespace stokesian {

// One phase of a solver's set-up, for the step's task graph (engine/core/task_graph.hpp): `after`
// lists earlier phases of the same set-up (indices into the list) it depends on.
struct PreparePhase {
  std::string name;
  bool uses_threads = false;  // OpenMP loops over every thread inside (a team node)
  std::function<void()> body;
  std::vector<int> after;
};

struct HydroProblem {
  const Configuration& config;      // the prepared configuration
  const std::vector<char>& fixed;   // empty or one flag per particle
  const FlowSample& flow;           // ambient flow at the centres
  const std::vector<Vec3>& force;   // non-hydrodynamic force on each particle
  const std::vector<Vec3>& torque;  // idem torque (ignored at F level; may be empty)
  const VecX* force_noise = nullptr;  // f_B, generalised layout (nullptr: none)
  const VecX* slip = nullptr;         // u_s, generalised layout (nullptr: none)
  WarmStart* warm = nullptr;          // initial iterate in, final iterate out (nullptr: start from zero)
};

class HydroSolver {
 public:
  virtual ~HydroSolver() = default;
  virtual const char* name() const = 0;
  virtual Moments moments() const = 0;
  virtual void prepare(const Configuration& c) = 0;
  virtual HydroResult solve(const HydroProblem& p) = 0;
  // Brownian displacements sqrt(2 kT dt) B W, B B^T the translational mobility the solver
  // samples at the prepared configuration (W standard normal, drawn from rng).
  virtual std::vector<Vec3> brownian_displacement(double kT, double dt, Rng& rng) = 0;
  // Brownian force xi at the prepared configuration (engine/brownian.hpp): covariance
  // (2 kT / dt) R restricted to the entries whose force is given (the mobile particles' F, T), zero
  // elsewhere; solved for as force_noise it gives velocities of covariance (2 kT / dt) R_vv^{-1}.
  // fixed: empty or one flag per particle. Draws from rng and a fork of it (RandomStream::fork).
  virtual VecX brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) = 0;
  // True when kT div(mobility) does not vanish (any near-field resistance): such a solver needs
  // a drift term from the integrator to sample the right equilibrium.
  virtual bool needs_drift() const = 0;
  // Whether prepare() for n particles runs OpenMP loops over every thread (see TaskGraph::Kind).
  virtual bool prepare_uses_threads(long n) const = 0;
  // prepare(c) as phases that the step's task graph may overlap with other work (c must outlive
  // them); running every phase in an order that respects `after` equals prepare(c). Default: one.
  virtual std::vector<PreparePhase> prepare_phases(const Configuration& c) {
    return {{"hydro_setup", prepare_uses_threads(long(c.x.size())), [this, &c] { prepare(c); }, {}}};
  }
  // The far-field operator the solver uses (nullptr for none).
  virtual const MobilityOperator* far_field() const = 0;
};

}  // namespace stokesian
