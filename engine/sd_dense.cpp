#include "engine/sd_dense.hpp"

#include "engine/core/errors.hpp"
#include "engine/kernels/far_field.hpp"
#include "ewald/ewald_reference.hpp"

#include <sstream>

namespace stokesian {

namespace {

// First generalised entry m at which the Cholesky factorisation of the symmetric matrix A breaks
// down: the smallest m whose leading (m+1) x (m+1) block is not positive definite (every leading
// block of a positive definite matrix is positive definite, so bisection over the block size finds
// it with O(log n) factorisations; called only after a failure). -1 when A is positive definite.
long first_failing_entry(const MatX& A) {
  long lo = 0, hi = A.rows();  // the leading lo x lo block is PD; the hi x hi block is not
  if (Eigen::LLT<MatX>(A).info() == Eigen::Success) return -1;
  while (hi - lo > 1) {
    const long mid = (lo + hi) / 2;
    if (Eigen::LLT<MatX>(A.topLeftCorner(mid, mid)).info() == Eigen::Success) lo = mid;
    else hi = mid;
  }
  return hi - 1;
}

// "particle p (closest earlier particle q at surface gap h a, symmetric gap xi)": the failing entry's
// particle p and, among the particles of the leading block that was still positive definite, the
// one closest to it (the pair whose coupling broke the factorisation).
std::string failing_particles(long p, const Configuration& c) {
  std::ostringstream o;
  o << "particle " << p;
  long q = -1;
  double best = 0.0, gap = 0.0;
  for (long j = 0; j < p; ++j) {
    const double r = c.domain.minimum_image(c.x[std::size_t(p)] - c.x[std::size_t(j)]).norm();
    const double ai = c.a[std::size_t(p)], aj = c.a[std::size_t(j)];
    const double xi = 2.0 * r / (ai + aj) - 2.0;
    if (q < 0 || xi < best) {
      best = xi;
      gap = r - ai - aj;
      q = j;
    }
  }
  if (q >= 0) o << " (closest earlier particle " << q << ": pair (" << q << ", " << p << ") at surface gap " << gap
                << " a, symmetric gap " << best << ")";
  else o << " (its own block)";
  return o.str();
}

}  // namespace

DenseStokesianDynamics::DenseStokesianDynamics(std::unique_ptr<MobilityOperator> far_field, double mu,
                                               lubrication::NearFieldParams p)
    : m_(far_field->moments()), mu_(mu), op_(std::move(far_field)), near_(m_, mu, p) {}

DenseStokesianDynamics::DenseStokesianDynamics(Moments m, double mu, const AmbientFlow& flow,
                                               lubrication::NearFieldParams p)
    : m_(m), mu_(mu), flow_(flow), reference_(true), near_(m, mu, p) {}

void DenseStokesianDynamics::select_reference_operator(const Domain& domain) {
  if (op_ && op_periodic_ == domain.periodic()) return;
  const MobilitySpec spec{m_, mu_, 0.0};
  if (domain.periodic()) op_ = std::make_unique<ewald::EwaldFarField>(spec);
  else op_ = std::make_unique<DirectFarField>(spec);
  op_periodic_ = domain.periodic();
}

void DenseStokesianDynamics::prepare(const Configuration& c) {
  if (reference_) select_reference_operator(c.domain);
  op_->set_configuration(c);
  const MatX* M = op_->dense();
  if (!M) throw std::logic_error(std::string("dense Stokesian dynamics needs a dense far field, not \"") + op_->name() + "\"");
  Eigen::LLT<MatX> llt(*M);
  if (llt.info() != Eigen::Success) {
    const long e = first_failing_entry(*M);
    throw PhysicsError("far-field mobility is not positive definite: its Cholesky factorisation fails at " +
                       (e >= 0 ? failing_particles(e / dof_per_particle(m_), c) : std::string("an unknown entry")));
  }
  R_ = llt.solve(MatX::Identity(M->rows(), M->cols()));
  stats_ = {};
  R_ += MatX(near_.assemble(c.x, c.a, c.domain, &stats_));
  R_ = (0.5 * (R_ + R_.transpose())).eval();
}

HydroResult DenseStokesianDynamics::solve(const HydroProblem& p) {
  const RigidConstraints c = RigidConstraints::of(m_, p.fixed, p.force, p.torque, p.flow);
  const std::vector<long>& v = c.force_given;   // unknown motion
  const std::vector<long>& k = c.motion_given;  // known motion
  // Right-hand side f + f_B + M_inf^{-1} u_s (engine/hydro_solver.hpp).
  VecX noise = VecX::Zero(c.force.size()), slip_force;
  if (p.force_noise)
    for (long q : v) noise[q] += (*p.force_noise)[q];
  if (p.slip) {
    slip_force = op_->dense()->llt().solve(*p.slip);
    noise += slip_force;
  }
  MatX Rvv(v.size(), v.size());
  VecX rhs(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    double s = c.force[v[i]] + noise[v[i]];
    for (long q : k) s -= R_(v[i], q) * c.motion[q];
    rhs[long(i)] = s;
    for (std::size_t j = 0; j < v.size(); ++j) Rvv(long(i), long(j)) = R_(v[i], v[j]);
  }
  Eigen::LLT<MatX> llt(Rvv);
  if (llt.info() != Eigen::Success) {
    const long e = first_failing_entry(Rvv);
    throw PhysicsError("SD resistance matrix (far field + near field) is not positive definite: its Cholesky "
                       "factorisation fails at " +
                       (e >= 0 ? failing_particles(v[std::size_t(e)] / dof_per_particle(m_), p.config)
                               : std::string("an unknown entry")));
  }
  const VecX V = llt.solve(rhs);
  VecX gen = c.motion;  // full generalised motion [U - u_inf, Omega - Omega_inf, -E_inf]
  for (std::size_t i = 0; i < v.size(); ++i) gen[v[i]] = V[long(i)];
  VecX moments = R_ * gen;  // f + f_B + M^{-1} u_s at given entries
  if (p.slip) moments -= slip_force;
  return unpack_solution(m_, p.flow, gen, moments, p.fixed);
}

std::vector<Vec3> DenseStokesianDynamics::brownian_displacement(double, double, Rng&) {
  throw PhysicsError("dense Stokesian dynamics does not sample Brownian motion (it needs near-field noise and drift)");
}

MatX DenseStokesianDynamics::resistance(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                                        lubrication::NearFieldStats* stats) {
  prepare({x, a, domain});
  if (stats) *stats = stats_;
  return R_;
}

HydroResult DenseStokesianDynamics::mobility_problem(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                     const std::vector<char>& fixed, const std::vector<Vec3>& F,
                                                     const std::vector<Vec3>& T, const Domain& domain,
                                                     lubrication::NearFieldStats* stats) {
  const Configuration c{x, a, domain};
  prepare(c);
  if (stats) *stats = stats_;
  FlowSample flow;
  flow_.sample(x, flow);
  return solve(HydroProblem{c, fixed, flow, F, T});
}

HydroResult DenseStokesianDynamics::resistance_problem(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                       const std::vector<Vec3>& U, const std::vector<Vec3>& Omega,
                                                       const Domain& domain) {
  const int d = dof_per_particle(m_);
  const long n = long(x.size());
  FlowSample flow;
  flow_.sample(x, flow);
  VecX gen = VecX::Zero(n * d);
  for (long i = 0; i < n; ++i) {
    const std::size_t s = std::size_t(i);
    gen.segment<3>(i * d) = U[s] - flow.u[s];
    if (d > 3) gen.segment<3>(i * d + 3) = (Omega.empty() ? Vec3::Zero() : Omega[s]) - flow.omega[s];
    if (d > 6) gen.segment<5>(i * d + 6) = -flow.E[s];
  }
  const VecX FTS = resistance(x, a, domain) * gen;
  HydroResult res;
  res.U = U;
  res.Omega = Omega;
  for (long i = 0; i < n; ++i) {
    res.F.push_back(FTS.segment<3>(i * d));
    if (d > 3) res.T.push_back(FTS.segment<3>(i * d + 3));
    if (d > 6) res.S.push_back(FTS.segment<5>(i * d + 6));
  }
  return res;
}

}  // namespace stokesian
