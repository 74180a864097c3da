#include "engine/hydrodynamics.hpp"

#include "engine/errors.hpp"
#include "engine/far_field.hpp"
#include "engine/krylov.hpp"
#include "engine/mobility_pair.hpp"
#include "engine/sd_dense.hpp"
#include "ewald/ewald_reference.hpp"
#include "ewald/pme.hpp"

#include <cmath>
#include <sstream>

namespace stokesian {

Hydrodynamics::Hydrodynamics(const ResolvedModel& model, double viscosity, const AmbientFlow& flow, double tolerance,
                             double lubrication_cutoff, double lubrication_min_gap)
    : model_(model), mu_(viscosity), flow_(flow), tol_(tolerance) {
  if (model_.level == HydroModel::stokesian)
    sd_ = std::make_unique<DenseStokesianDynamics>(model_.moments, mu_, flow_,
                                                   lubrication::NearFieldParams{lubrication_cutoff, lubrication_min_gap});
}
Hydrodynamics::~Hydrodynamics() = default;
Hydrodynamics::Hydrodynamics(Hydrodynamics&&) noexcept = default;

const FarFieldOperator& Hydrodynamics::far_field(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                 const Domain& domain) const {
  if (model_.far_field == FarFieldMethod::pme) {
    auto* pme = dynamic_cast<ewald::PmeFarField*>(op_.get());
    if (pme && op_radii_ == a && op_domain_.box == domain.box && op_domain_.shear_strain == domain.shear_strain) {
      pme->update_positions(x);
      return *op_;
    }
    op_ = std::make_unique<ewald::PmeFarField>(x, a, mu_, model_.moments, domain, tol_);
    op_radii_ = a;
    op_domain_ = domain;
  } else if (model_.far_field == FarFieldMethod::ewald) {
    // The dense Ewald matrix is kept while the configuration is identical (e.g. repeated draws).
    if (dynamic_cast<ewald::EwaldFarField*>(op_.get()) && op_positions_ == x && op_radii_ == a &&
        op_domain_.box == domain.box && op_domain_.shear_strain == domain.shear_strain)
      return *op_;
    op_ = std::make_unique<ewald::EwaldFarField>(x, a, mu_, model_.moments, domain);
    op_positions_ = x;
    op_radii_ = a;
    op_domain_ = domain;
  } else {
    op_ = std::make_unique<DirectFarField>(x, a, mu_, model_.moments);
  }
  return *op_;
}

HydroResult Hydrodynamics::solve(const std::vector<Vec3>& x, const std::vector<double>& a,
                                 const std::vector<char>& fixed, const std::vector<Vec3>& F,
                                 const std::vector<Vec3>& T, const Domain& domain) const {
  if (sd_) return sd_->mobility_problem(x, a, fixed, F, T, domain);
  const Moments m = model_.moments;
  const int d = dof_per_particle(m);
  const long n = long(x.size());
  const long N = n * d;
  // Known generalised forces and the mask of unknowns.
  VecX known = VecX::Zero(N), target = VecX::Zero(N);
  std::vector<char> unknown(std::size_t(N), 0);
  const Vec5 Einf = to_vec5(flow_.E);
  for (long i = 0; i < n; ++i) {
    const bool fx = !fixed.empty() && fixed[std::size_t(i)];
    for (int k = 0; k < 3; ++k) {
      if (fx) {
        unknown[std::size_t(i * d + k)] = 1;
        target[i * d + k] = -flow_.velocity(x[std::size_t(i)])[k];
      } else {
        known[i * d + k] = F[std::size_t(i)][k];
      }
      if (d > 3) {
        if (fx) {
          unknown[std::size_t(i * d + 3 + k)] = 1;
          target[i * d + 3 + k] = -flow_.Omega[k];
        } else {
          known[i * d + 3 + k] = T.empty() ? 0.0 : T[std::size_t(i)][k];
        }
      }
    }
    if (d > 6)
      for (int k = 0; k < 5; ++k) {
        unknown[std::size_t(i * d + 6 + k)] = 1;
        target[i * d + 6 + k] = -Einf[k];
      }
  }

  // The operator y = M x at the resolved level.
  LinearOperator M;
  const FarFieldOperator* op = nullptr;
  if (model_.level == HydroModel::free_draining) {
    M = [&](const VecX& in, VecX& out) {
      out.setZero(in.size());
      for (long i = 0; i < n; ++i) mobility::apply_self(a[std::size_t(i)], mu_, m, in.data() + i * d, out.data() + i * d);
    };
  } else {
    op = &far_field(x, a, domain);
    M = [op](const VecX& in, VecX& out) { op->apply(in, out); };
  }

  int iterations = 0;
  VecX gen = known;
  std::vector<long> idx;
  for (long k = 0; k < N; ++k)
    if (unknown[std::size_t(k)]) idx.push_back(k);
  if (!idx.empty()) {
    VecX y;
    M(known, y);
    VecX b(long(idx.size()));
    for (std::size_t q = 0; q < idx.size(); ++q) b[long(q)] = target[idx[q]] - y[idx[q]];
    VecX full(N), fy;
    LinearOperator Mzz = [&](const VecX& z, VecX& out) {
      full.setZero();
      for (std::size_t q = 0; q < idx.size(); ++q) full[idx[q]] = z[long(q)];
      M(full, fy);
      out.resize(z.size());
      for (std::size_t q = 0; q < idx.size(); ++q) out[long(q)] = fy[idx[q]];
    };
    VecX z = VecX::Zero(b.size());
    const KrylovResult kr = conjugate_gradient(Mzz, b, z, tol_, 10 * int(b.size()) + 100);
    if (!kr.converged) {
      std::ostringstream o;
      o << "constrained mobility solve (stresslets/fixed particles) did not converge: relative residual "
        << kr.relative_residual << " after " << kr.iterations << " CG iterations (tolerance " << tol_ << ")";
      throw PhysicsError(o.str());
    }
    iterations = kr.iterations;
    for (std::size_t q = 0; q < idx.size(); ++q) gen[idx[q]] = z[long(q)];
  }
  VecX vel;
  M(gen, vel);
  HydroResult out = unpack_solution(m, x, flow_, vel, gen, fixed);
  out.iterations = iterations;
  return out;
}

HydroResult unpack_solution(Moments m, const std::vector<Vec3>& x, const AmbientFlow& flow, const VecX& relative,
                            const VecX& moments, const std::vector<char>& fixed) {
  const int d = dof_per_particle(m);
  const std::size_t n = x.size();
  HydroResult res;
  res.U.resize(n);
  res.F.resize(n);
  if (d > 3) {
    res.Omega.resize(n);
    res.T.resize(n);
  }
  if (d > 6) res.S.resize(n);
  for (std::size_t s = 0; s < n; ++s) {
    const long i = long(s);
    const bool fx = !fixed.empty() && fixed[s];
    res.F[s] = moments.segment<3>(i * d);
    res.U[s] = fx ? Vec3::Zero() : Vec3(relative.segment<3>(i * d) + flow.velocity(x[s]));
    if (d > 3) {
      res.T[s] = moments.segment<3>(i * d + 3);
      res.Omega[s] = fx ? Vec3::Zero() : Vec3(relative.segment<3>(i * d + 3) + flow.Omega);
    }
    if (d > 6) res.S[s] = moments.segment<5>(i * d + 6);
  }
  return res;
}

std::vector<Vec3> Hydrodynamics::brownian_displacement(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                       double kT, double dt, std::mt19937_64& rng,
                                                       const Domain& domain) const {
  const long n = long(x.size());
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vec3> dx(static_cast<std::size_t>(n));
  const double pref = std::sqrt(2.0 * kT * dt);
  if (model_.level == HydroModel::free_draining) {
    for (long i = 0; i < n; ++i) {
      const double D = 1.0 / (6.0 * M_PI * mu_ * a[std::size_t(i)]);
      for (int k = 0; k < 3; ++k) dx[std::size_t(i)][k] = pref * std::sqrt(D) * gauss(rng);
    }
    return dx;
  }
  const Moments m = model_.moments;
  const int d = dof_per_particle(m);
  VecX w(n * d), y;
  for (auto& v : w) v = gauss(rng);
  const FarFieldOperator& op = far_field(x, a, domain);
  LinearOperator M = [&op](const VecX& in, VecX& out) { op.apply(in, out); };
  const KrylovResult kr = lanczos_sqrt(M, w, y, tol_, 200);
  if (!kr.converged) {
    std::ostringstream o;
    o << "Lanczos square root of the far-field mobility did not converge (relative change "
      << kr.relative_residual << " after " << kr.iterations << " iterations)";
    throw PhysicsError(o.str());
  }
  for (long i = 0; i < n; ++i) dx[std::size_t(i)] = pref * y.segment<3>(i * d);
  return dx;
}

}  // namespace stokesian
