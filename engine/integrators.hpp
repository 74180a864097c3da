#pragma once
// Time integrators for dx/dt = U(x, t) (+ Brownian displacement), one class per scheme, registered
// by name (engine/methods.cpp). An integrator owns its stages: it asks the Dynamics for velocities
// at stage positions and times, and decides where the Brownian displacement enters.
//   euler:    x1 = x0 + dt U(x0) + dX_B                            (Euler-Maruyama)
//   midpoint: x1 = x0 + dt U(x0 + dt/2 U(x0), t0 + dt/2) + dX_B     (deterministic part 2nd order)
//   rkf45:    Runge-Kutta-Fehlberg 4(5) with step-size control (Fehlberg 1969): the 4th-order
//             solution is kept, the embedded 5th-order one estimates the local error
//             e = max_i |x5_i - x4_i|; a step is accepted when e <= tol and the next
//             dt = dt * clamp(0.9 (tol/e)^(1/5), 0.2, 5). Deterministic only.
//   fixman:   xi = Brownian force at x0, covariance (2 kT / dt) R(x0) (Dynamics::brownian_force);
//             x' = x0 + dt/2 U(x0; F + xi),  x1 = x0 + dt U(x', t0 + dt/2; F(x') + xi)
//             (Fixman 1978; seed 1 eqs. 2.34-2.35 and, in accelerated form, 2.52-2.53).
// dX_B of euler and midpoint = sqrt(2 kT dt) M^{1/2}(x0) W (Dynamics::brownian_displacement). With
// the far field alone at F/FT and no fixed particles M is divergence free and Euler-Maruyama needs
// no drift. Where the mobility varies with the configuration in a way that is not divergence free
// (near-field resistance, rigid stresslets, fixed particles: the model decides, engine/model.cpp)
// the Ito drift kT div(R^{-1}) is required, and fixman provides it: expanding the second stage
// about x0, E[R^{-1}(x') xi] = (dt/2) d_k R^{-1} E[(R^{-1} xi)_k xi] = kT d_k (R^{-1})_{. k}, since
// E[xi xi^T] = (2 kT / dt) R; the covariance of dt R^{-1}(x') xi is 2 kT dt R^{-1} + O(dt^2).
// Rotations are not integrated (spheres: hydrodynamics does not depend on orientation, so the
// rotational part of the divergence vanishes); xi still has torque entries, which couple.
#include "engine/dynamics.hpp"

#include <functional>
#include <optional>
#include <vector>

namespace stokesian {

struct StepResult {
  std::vector<Vec3> x;  // new positions
  double dt_used = 0;   // the step that was taken
  double dt_next = 0;   // proposal for the next step
  // fixman with noise at FTS, on steps that leave a frame: sum_i [(A(x') - A(x0)) xi]_i,
  // A xi the stresslets of the response to xi alone, whose mean is the negative Brownian stresslet
  // sum, kT div(R_SU R_FU^{-1}) + O(dt) (engine/stress.hpp).
  std::optional<Mat3> brownian_stresslet;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual const char* name() const = 0;
  // One step from s (positions, time, dt); `start` is the evaluation at s.position, t = 0.
  virtual StepResult step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) = 0;
  // Whether step() reads start.hydro (the deterministic solve at s.position); when it does not,
  // the run skips that solve on steps that write no frame (the set-up is still done).
  virtual bool reads_start_solve(bool brownian) const {
    (void)brownian;
    return true;
  }
};

class EulerIntegrator final : public Integrator {
 public:
  const char* name() const override { return "euler"; }
  StepResult step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) override;
};

class MidpointIntegrator final : public Integrator {
 public:
  const char* name() const override { return "midpoint"; }
  StepResult step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) override;
};

class FixmanIntegrator final : public Integrator {
 public:
  const char* name() const override { return "fixman"; }
  // With noise the first stage solves with F + xi itself.
  bool reads_start_solve(bool brownian) const override { return !brownian; }
  StepResult step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) override;
};

class Rkf45Integrator final : public Integrator {
 public:
  // tol: local error per step [a]; dt_min: smallest step before giving up.
  Rkf45Integrator(double tol, double dt_min) : tol_(tol), dt_min_(dt_min) {}
  const char* name() const override { return "rkf45"; }
  StepResult step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) override;

 private:
  double tol_, dt_min_;
};

// Velocities at positions x and time t into the step (t measured from the start of the step).
using VelocityField = std::function<std::vector<Vec3>(const std::vector<Vec3>& x, double t)>;

std::vector<Vec3> axpy(const std::vector<Vec3>& x, double h, const std::vector<Vec3>& u);

struct RkfStep {
  std::vector<Vec3> x;  // accepted new positions (4th order)
  double dt_used = 0;   // the step that was accepted
  double dt_next = 0;   // proposal for the next step
  double error = 0;     // estimated local error of the accepted step
  int rejected = 0;     // rejected attempts before acceptance
};

// u0 = U(x0) is passed in (already evaluated by the caller for output).
RkfStep rkf45_step(const VelocityField& U, const std::vector<Vec3>& x0, const std::vector<Vec3>& u0, double dt,
                   double tol, double dt_min);

}  // namespace stokesian
