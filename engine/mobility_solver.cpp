#include "engine/mobility_solver.hpp"

#include "engine/brownian.hpp"
#include "engine/core/errors.hpp"
#include "engine/core/krylov.hpp"
#include "engine/kernels/far_field.hpp"

#include <cmath>
#include <sstream>

namespace stokesian {

namespace {
// CG iteration cap: far above the iterations any SPD system of this size needs in exact
// arithmetic (one per unknown), so that hitting it signals a real failure, not a slow solve.
int cg_iteration_cap(long unknowns) { return 10 * int(unknowns) + 100; }
// Lanczos cap for M^{1/2} W: the square root of the well-conditioned far-field mobility
// converges in tens of iterations.
constexpr int kLanczosCap = 200;
}  // namespace

MobilitySolver::MobilitySolver(std::unique_ptr<MobilityOperator> op, double tolerance)
    : op_(std::move(op)), tol_(tolerance) {}

void MobilitySolver::prepare(const Configuration& c) {
  op_->set_configuration(c);
  n_ = long(c.x.size());
  config_.store(c);
}

HydroResult MobilitySolver::solve(const HydroProblem& p) {
  const Moments m = op_->moments();
  const RigidConstraints c = RigidConstraints::of(m, p.fixed, p.force, p.torque, p.flow);
  const long N = c.n * dof_per_particle(m);
  const MobilityOperator& M = *op_;

  VecX gen = c.force;  // [F T S]: given entries now, unknown ones after the solve
  if (p.force_noise)
    for (long q : c.force_given) gen[q] += (*p.force_noise)[q];
  int iterations = 0;
  const std::vector<long>& idx = c.motion_given;
  if (!idx.empty()) {
    VecX y;
    M.apply(gen, y);
    VecX b(long(idx.size()));
    for (std::size_t q = 0; q < idx.size(); ++q)
      b[long(q)] = c.motion[idx[q]] - (p.slip ? (*p.slip)[idx[q]] : 0.0) - y[idx[q]];
    VecX full(N), fy;
    LinearOperator Mzz = [&](const VecX& z, VecX& out) {
      full.setZero();
      for (std::size_t q = 0; q < idx.size(); ++q) full[idx[q]] = z[long(q)];
      M.apply(full, fy);
      out.resize(z.size());
      for (std::size_t q = 0; q < idx.size(); ++q) out[long(q)] = fy[idx[q]];
    };
    VecX z = VecX::Zero(b.size());
    const KrylovResult kr = conjugate_gradient(Mzz, b, z, tol_, cg_iteration_cap(b.size()));
    if (!kr.converged) {
      std::ostringstream o;
      o << "constrained mobility solve (stresslets/fixed particles) failed: conjugate gradients "
        << describe(kr) << " after " << kr.iterations << " iterations, relative residual " << kr.relative_residual
        << " (tolerance " << tol_ << ", cap " << cg_iteration_cap(b.size()) << ")";
      throw PhysicsError(o.str());
    }
    iterations = kr.iterations;
    for (std::size_t q = 0; q < idx.size(); ++q) gen[idx[q]] = z[long(q)];
  }
  VecX vel;
  M.apply(gen, vel);
  if (p.slip) vel += *p.slip;
  HydroResult out = unpack_solution(m, p.flow, vel, gen, p.fixed);
  out.iterations = iterations;
  return out;
}

std::vector<Vec3> MobilitySolver::brownian_displacement(double kT, double dt, Rng& rng) {
  const int d = dof_per_particle(op_->moments());
  std::vector<Vec3> dx(static_cast<std::size_t>(n_));
  const double pref = std::sqrt(2.0 * kT * dt);
  VecX w(n_ * d), y;
  for (auto& v : w) v = rng.normal();
  const MobilityOperator& op = *op_;
  LinearOperator M = [&op](const VecX& in, VecX& out) { op.apply(in, out); };
  const KrylovResult kr = lanczos_sqrt(M, w, y, tol_, kLanczosCap);
  if (!kr.converged) {
    std::ostringstream o;
    o << "Lanczos square root of the far-field mobility (Brownian displacement) failed: it " << describe(kr)
      << " after " << kr.iterations << " iterations, last relative change " << kr.relative_residual << " (tolerance "
      << tol_ << ", cap " << kLanczosCap << ")";
    throw PhysicsError(o.str());
  }
  for (long i = 0; i < n_; ++i) dx[std::size_t(i)] = pref * y.segment<3>(i * d);
  return dx;
}

VecX MobilitySolver::brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) {
  return far_field_brownian_force(*op_, {config_.x, config_.a, config_.domain}, force_given_flags(op_->moments(), n_, fixed),
                                  std::sqrt(2.0 * kT / dt), tol_, rng);
}

FreeDrainingSolver::FreeDrainingSolver(const MobilitySpec& spec)
    : MobilitySolver(std::make_unique<SelfMobility>(spec), spec.tolerance), mu_(spec.viscosity) {}

std::vector<Vec3> FreeDrainingSolver::brownian_displacement(double kT, double dt, Rng& rng) {
  const auto& a = static_cast<const SelfMobility&>(*op_).radii();
  std::vector<Vec3> dx(a.size());
  const double pref = std::sqrt(2.0 * kT * dt);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double D = 1.0 / (6.0 * kPi * mu_ * a[i]);
    for (int k = 0; k < 3; ++k) dx[i][k] = pref * std::sqrt(D) * rng.normal();
  }
  return dx;
}

VecX FreeDrainingSolver::brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) {
  const auto& a = static_cast<const SelfMobility&>(*op_).radii();
  const Moments m = op_->moments();
  const VecX R = self_resistance(a, mu_, m);
  const std::vector<char> given = force_given_flags(m, long(a.size()), fixed);
  const double pref = std::sqrt(2.0 * kT / dt);
  VecX xi(R.size());
  for (long q = 0; q < R.size(); ++q) {
    const double z = rng.normal();
    xi[q] = given[std::size_t(q)] ? pref * std::sqrt(R[q]) * z : 0.0;
  }
  return xi;
}

}  // namespace stokesian
