#include "engine/integrators.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/sym_traceless.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace stokesian {

std::vector<Vec3> axpy(const std::vector<Vec3>& x, double h, const std::vector<Vec3>& u) {
  std::vector<Vec3> y(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) y[i] = x[i] + h * u[i];
  return y;
}

RkfStep rkf45_step(const VelocityField& U, const std::vector<Vec3>& x0, const std::vector<Vec3>& k1, double dt,
                   double tol, double dt_min) {
  // Fehlberg's coefficients (Butcher tableau of RKF45).
  const std::size_t n = x0.size();
  RkfStep out;
  for (;;) {
    // Stage at time c dt with positions x0 + dt sum_j a_j k_j.
    auto stage = [&](double c, std::initializer_list<std::pair<double, const std::vector<Vec3>*>> terms) {
      std::vector<Vec3> y = x0;
      for (const auto& [w, k] : terms)
        for (std::size_t i = 0; i < n; ++i) y[i] += dt * w * (*k)[i];
      return U(y, c * dt);
    };
    const auto k2 = stage(1.0 / 4, {{1.0 / 4, &k1}});
    const auto k3 = stage(3.0 / 8, {{3.0 / 32, &k1}, {9.0 / 32, &k2}});
    const auto k4 = stage(12.0 / 13, {{1932.0 / 2197, &k1}, {-7200.0 / 2197, &k2}, {7296.0 / 2197, &k3}});
    const auto k5 = stage(1.0, {{439.0 / 216, &k1}, {-8.0, &k2}, {3680.0 / 513, &k3}, {-845.0 / 4104, &k4}});
    const auto k6 = stage(0.5, {{-8.0 / 27, &k1}, {2.0, &k2}, {-3544.0 / 2565, &k3}, {1859.0 / 4104, &k4}, {-11.0 / 40, &k5}});
    std::vector<Vec3> x4(n);
    double err = 0;
    std::size_t worst = 0;  // particle with the largest error estimate (named in failures)
    for (std::size_t i = 0; i < n; ++i) {
      x4[i] = x0[i] + dt * (25.0 / 216 * k1[i] + 1408.0 / 2565 * k3[i] + 2197.0 / 4104 * k4[i] - 0.2 * k5[i]);
      const Vec3 x5 = x0[i] + dt * (16.0 / 135 * k1[i] + 6656.0 / 12825 * k3[i] + 28561.0 / 56430 * k4[i] -
                                    9.0 / 50 * k5[i] + 2.0 / 55 * k6[i]);
      const double e = (x5 - x4[i]).norm();
      if (!std::isfinite(e))
        throw PhysicsError("rkf45: non-finite error estimate at particle " + std::to_string(i) +
                           " (non-finite stage positions or velocities)");
      if (e > err) {
        err = e;
        worst = i;
      }
    }
    const double fac = err > 0 ? std::clamp(0.9 * std::pow(tol / err, 0.2), 0.2, 5.0) : 5.0;
    if (err <= tol) {
      out.x = std::move(x4);
      out.dt_used = dt;
      out.dt_next = dt * fac;
      out.error = err;
      return out;
    }
    ++out.rejected;
    dt *= fac;
    if (dt < dt_min) {
      std::ostringstream o;
      o << "rkf45: step size fell below " << dt_min << " (local error " << err << " a at particle " << worst
        << " > tolerance " << tol << ")";
      throw PhysicsError(o.str());
    }
  }
}

namespace {
// Adds the Brownian displacement (if any) drawn at the start of the step.
void add_noise(const State& s, Dynamics& d, double dt, Rng& rng, std::vector<Vec3>& x1) {
  const std::vector<Vec3> dX = d.brownian_displacement(s, dt, rng);
  for (std::size_t i = 0; i < dX.size(); ++i) x1[i] += dX[i];
}
}  // namespace

StepResult EulerIntegrator::step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) {
  StepResult r{axpy(s.position, s.dt, start.hydro.U), s.dt, s.dt, {}};
  add_noise(s, d, s.dt, rng, r.x);
  return r;
}

StepResult MidpointIntegrator::step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) {
  const double dt = s.dt;
  const std::vector<Vec3> xmid = axpy(s.position, 0.5 * dt, start.hydro.U);
  WarmStart warm = start.warm;
  StepResult r{axpy(s.position, dt, d.evaluate(s, xmid, 0.5 * dt, nullptr, &warm).hydro.U), dt, dt, {}};
  add_noise(s, d, dt, rng, r.x);
  return r;
}

StepResult FixmanIntegrator::step(const State& s, const Evaluation& start, Dynamics& d, Rng& rng) {
  const double dt = s.dt;
  const VecX xi = d.brownian_force(s, dt, rng);
  // First stage at x0: the deterministic solve of `start` is reused when athermal.
  if (!xi.size()) {
    const std::vector<Vec3> xmid = axpy(s.position, 0.5 * dt, start.hydro.U);
    WarmStart warm = start.warm;
    return StepResult{axpy(s.position, dt, d.evaluate(s, xmid, 0.5 * dt, nullptr, &warm).hydro.U), dt, dt, {}};
  }
  // Brownian stresslet (engine/stress.hpp): (A(x') - A(x0)) xi, A = dS/dF (S the stresslets exerted
  // on the fluid), whose mean by the expansion above is kT d_k A_{.k} = -S^B. The responses to xi
  // alone are solved for at each stage right after its solve (the set-up is kept): the stages'
  // stresslets also hold A F + B E_inf, whose change over the step is O(dt) on average only while
  // sqrt(kT dt R^{-1}) is small against the scale of F; a stiff contact repulsion (F ~ F0/h) makes
  // that change dominate. Two solves more on the steps that sample.
  // Warm starts (engine/core/layout.hpp, WarmStart): the midpoint solve starts from the iterate of
  // the solve at x0, and the responses to xi alone from that iterate (the full solve is the response
  // to xi plus the deterministic one, so at low Peclet numbers it is most of the answer) and then
  // from each other. The full solves are the same whether or not the step samples, so sampling
  // leaves the trajectory unchanged; iterative solvers start from zero again at the next step.
  const bool sample = start.sample_brownian_stress;  // FTS in periodic boxes only (resolve_model)
  WarmStart full;  // not start.warm: start is solved on frame steps only, and the trajectory must not depend on them
  const HydroResult h0 = d.evaluate(s, s.position, 0.0, &xi, &full).hydro;
  WarmStart noise = full;
  const HydroResult a0 = sample ? d.noise_response(s, s.position, 0.0, xi, &noise) : HydroResult{};
  const std::vector<Vec3> xmid = axpy(s.position, 0.5 * dt, h0.U);
  const HydroResult h1 = d.evaluate(s, xmid, 0.5 * dt, &xi, &full).hydro;
  StepResult r{axpy(s.position, dt, h1.U), dt, dt, {}};
  if (sample) {
    const HydroResult a1 = d.noise_response(s, xmid, 0.5 * dt, xi, &noise);
    Mat3 sum = Mat3::Zero();
    for (std::size_t i = 0; i < a0.S.size(); ++i) sum += from_vec5(a1.S[i]) - from_vec5(a0.S[i]);
    r.brownian_stresslet = sum;
  }
  return r;
}

StepResult Rkf45Integrator::step(const State& s, const Evaluation& start, Dynamics& d, Rng&) {
  const VelocityField U = [&](const std::vector<Vec3>& x, double t) { return d.evaluate(s, x, t).hydro.U; };
  RkfStep k = rkf45_step(U, s.position, start.hydro.U, s.dt, tol_, dt_min_);
  return StepResult{std::move(k.x), k.dt_used, k.dt_next, {}};
}

}  // namespace stokesian
