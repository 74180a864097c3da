#pragma once
// Time integrators for dx/dt = U(x) (+ Brownian displacement).
//   euler:    x1 = x0 + dt U(x0) + dX_B                       (Euler-Maruyama)
//   midpoint: x1 = x0 + dt U(x0 + dt/2 U(x0), t0 + dt/2) + dX_B (deterministic part 2nd order)
//   rkf45:    Runge-Kutta-Fehlberg 4(5) with step-size control (Fehlberg 1969; thesis s.2.3.3):
//             the 4th-order solution is kept, the embedded 5th-order one estimates the local
//             error e = max_i |x5_i - x4_i|; a step is accepted when e <= tol and the next
//             dt = dt * clamp(0.9 (tol/e)^(1/5), 0.2, 5).
// dX_B = sqrt(2 kT dt) M^{1/2}(x0) W. M_inf is divergence free, so Euler-Maruyama has no
// thermal drift term (shared/notes/method.md s.5 needs one only with the near field).
#include "engine/types.hpp"

#include <functional>
#include <vector>

namespace stokesian {

// Velocities at positions x and time t0 + t (t measured from the start of the step; the time
// enters through the Lees-Edwards strain of sheared boxes).
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
