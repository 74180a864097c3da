#include "engine/sd_dense.hpp"

#include "engine/brownian.hpp"

#include "engine/core/errors.hpp"
#include "engine/kernels/far_field.hpp"
#include "ewald/ewald_reference.hpp"

#include <cstddef>
#include <limits>
#include <sstream>
#include <stdexcept>

// LAPACK (Fortran interface; the trailing arguments are the lengths of the character arguments).
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t);
void dpotri_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t);
void dpotrs_(const char* uplo, const int* n, const int* nrhs, const double* a, const int* lda, double* b,
             const int* ldb, int* info, std::size_t);
// BLAS.
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n,
            const double* alpha, const double* a, const int* lda, double* b, const int* ldb, std::size_t, std::size_t,
            std::size_t, std::size_t);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha, const double* a,
            const int* lda, const double* beta, double* c, const int* ldc, std::size_t, std::size_t);
}

namespace stokesian {

namespace {

using SparseMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

namespace lapack {
int dim(long n) {
  if (n > long(std::numeric_limits<int>::max())) throw std::length_error("dense SD: matrix too large for LAPACK");
  return int(n);
}
// Cholesky A = L L^T in the lower triangle (the strict upper triangle is left alone); 0 on success.
int potrf(MatX& A) {
  const int n = dim(A.rows());
  int info = 0;
  if (n > 0) dpotrf_("L", &n, A.data(), &n, &info, 1);
  return info;
}
// From the factor L (lower triangle): (L L^T)^{-1} in the lower triangle.
int potri(MatX& A) {
  const int n = dim(A.rows());
  int info = 0;
  if (n > 0) dpotri_("L", &n, A.data(), &n, &info, 1);
  return info;
}
// W <- L^{-1} W (L lower triangular, W with L.rows() rows).
void trsm_lower(const MatX& L, MatX& W) {
  const int m = dim(W.rows()), k = dim(W.cols());
  const double one = 1.0;
  if (m > 0 && k > 0) dtrsm_("L", "L", "N", "N", &m, &k, &one, L.data(), &m, W.data(), &m, 1, 1, 1, 1);
}
// Lower triangle of C <- C - W^T W.
void syrk_minus(const MatX& W, MatX& C) {
  const int n = dim(C.rows()), k = dim(W.rows());
  const double minus = -1.0, one = 1.0;
  if (n > 0 && k > 0) dsyrk_("L", "T", &n, &k, &minus, W.data(), &k, &one, C.data(), &n, 1, 1);
}
// x <- (L L^T)^{-1} x.
void potrs(const MatX& L, VecX& x) {
  const int n = dim(L.rows()), one = 1;
  int info = 0;
  if (n > 0) dpotrs_("L", &n, &one, L.data(), &n, x.data(), &n, &info, 1);
  if (info != 0) throw std::logic_error("dense SD: dpotrs failed");
}
}  // namespace lapack

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
  config_.store(c);
  M_ = nullptr;  // formed when the factorisation needs it (full_mobility), or only its mobile rows
  have_Rvv_ = have_R_ = false;
  factor_ = Factor::none;
  // Near field, symmetrised (added to the force/torque block when the far field is factored).
  stats_ = {};
  const auto N = near_.assemble(c.x, c.a, c.domain, &stats_);
  Rnf_ = 0.5 * (N + SparseMat(N.transpose()));
}

const MatX& DenseStokesianDynamics::full_mobility() const {
  if (!M_) M_ = op_->dense();
  if (!M_) throw std::logic_error(std::string("dense Stokesian dynamics needs a dense far field, not \"") + op_->name() + "\"");
  return *M_;
}

void DenseStokesianDynamics::far_field_not_positive_definite() const {
  const long e = first_failing_entry(full_mobility());
  throw PhysicsError("far-field mobility is not positive definite: its Cholesky factorisation fails at " +
                     (e >= 0 ? failing_particles(e / dof_per_particle(m_), Configuration{config_.x, config_.a, config_.domain}) : std::string("an unknown entry")));
}

void DenseStokesianDynamics::factor(const std::vector<char>& fixed) {
  const std::size_t np = config_.x.size();
  std::vector<char> held(np, 0);
  bool any = false;
  if (held_blocks_ && !fixed.empty())
    for (std::size_t i = 0; i < np; ++i)
      if (fixed[i]) held[i] = 1, any = true;
  if (factor_ != Factor::none && held == factor_held_) return;
  have_Rvv_ = have_R_ = false;
  reused_held_ = false;
  if (any) factor_blocks(held);
  else factor_full();
  factor_held_ = std::move(held);
}

void DenseStokesianDynamics::add_near_field_tt() {
  const long nt = Rtt_.rows();
#pragma omp parallel for schedule(static)
  for (long col = 0; col < nt; ++col)  // mirror the lower triangle dpotri wrote
    for (long r = 0; r < col; ++r) Rtt_(r, col) = Rtt_(col, r);
  for (int k = 0; k < Rnf_.outerSize(); ++k)
    for (SparseMat::InnerIterator it(Rnf_, k); it; ++it) {
      const long pr = pos_[std::size_t(it.row())], pq = pos_[std::size_t(it.col())];
      if (pr < n0_ || pq < n0_) continue;  // outside the order, or a stresslet row
      Rtt_(pr - n0_, pq - n0_) += it.value();
    }
}

void DenseStokesianDynamics::order_entries(const std::vector<char>& held) {
  const int d = dof_per_particle(m_);
  const long np = long(config_.x.size());
  // The entries of the particles not held: their stresslets first, then their forces/torques.
  perm_.clear();
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) n0_ = long(perm_.size());
    const int k0 = pass == 0 ? 6 : 0, k1 = pass == 0 ? d : std::min(d, 6);
    for (long i = 0; i < np; ++i)
      if (!held[std::size_t(i)])
        for (int k = k0; k < k1; ++k) perm_.push_back(i * d + k);
  }
  pos_.assign(std::size_t(np * d), -1);
  for (long r = 0; r < long(perm_.size()); ++r) pos_[std::size_t(perm_[std::size_t(r)])] = r;
}

void DenseStokesianDynamics::factor_full() {
  const MatX& M = full_mobility();
  const long n = long(M.rows());
  order_entries(std::vector<char>(config_.x.size(), 0));
  L_.resize(n, n);
#pragma omp parallel for schedule(static)
  for (long col = 0; col < n; ++col) {
    const double* src = M.data() + perm_[std::size_t(col)] * n;
    double* dst = L_.data() + col * n;
    for (long r = col; r < n; ++r) dst[r] = src[perm_[std::size_t(r)]];
  }
  if (lapack::potrf(L_) != 0) far_field_not_positive_definite();
  const long nt = n - n0_;
  Rtt_ = L_.bottomRightCorner(nt, nt);
  if (lapack::potri(Rtt_) != 0) throw std::logic_error("dense SD: dpotri failed on a factored far-field block");
  add_near_field_tt();
  factor_ = Factor::full;
}

void DenseStokesianDynamics::factor_blocks(const std::vector<char>& held) {
  const int d = dof_per_particle(m_);
  const long np = long(config_.x.size()), n = np * d;
  order_entries(held);  // the mobile entries; the held ones by particle:
  std::vector<long> hs;
  for (long i = 0; i < np; ++i)
    if (held[std::size_t(i)])
      for (int k = 0; k < d; ++k) hs.push_back(i * d + k);
  const long ni = long(perm_.size()), nh = long(hs.size());

  // The held block is kept while the held particles, their radii and the domain are those it was
  // factored for (the far field's entries are functions of these alone). Then only the mobile
  // particles' rows of M_inf are formed, when the operator can (dense_rows); otherwise all of it.
  std::vector<long> mobile, held_ids;
  for (long i = 0; i < np; ++i) (held[std::size_t(i)] ? held_ids : mobile).push_back(i);
  std::vector<Vec3> hx;
  std::vector<double> ha;
  for (long i : held_ids) hx.push_back(config_.x[std::size_t(i)]), ha.push_back(config_.a[std::size_t(i)]);
  reused_held_ = held_L_.size() != 0 && held_entries_ == hs && held_x_ == hx && held_a_ == ha &&
                 held_domain_ == config_.domain;
  // Entries of M_inf by block rows (dense_rows) when the operator forms them, so that a
  // configuration's arithmetic does not depend on whether the held factor was kept (a resumed run
  // repeats the uninterrupted one); otherwise from the whole matrix.
  MatX mobile_rows;  // (d N_I) x n, row d k + c: entry c of mobile[k]
  const bool by_rows = op_->dense_rows(mobile, mobile_rows);
  std::vector<long> mobile_row(std::size_t(n), -1);
  for (std::size_t k = 0; k < mobile.size(); ++k)
    for (int c = 0; c < d; ++c) mobile_row[std::size_t(mobile[k] * d + c)] = long(k) * d + c;
  const MatX* M = by_rows ? nullptr : &full_mobility();
  const auto entry = [&](long q, long col) {
    return by_rows ? mobile_rows(mobile_row[std::size_t(q)], col) : (*M)(q, col);
  };
  if (!reused_held_) {
    MatX held_rows;  // (d N_H) x n, in the order of hs
    if (by_rows) op_->dense_rows(held_ids, held_rows);
    held_L_.resize(nh, nh);
#pragma omp parallel for schedule(static)
    for (long col = 0; col < nh; ++col)
      for (long r = 0; r < nh; ++r)
        held_L_(r, col) = by_rows ? held_rows(r, hs[std::size_t(col)]) : (*M)(hs[std::size_t(r)], hs[std::size_t(col)]);
    held_entries_.clear();
    if (lapack::potrf(held_L_) != 0) far_field_not_positive_definite();
    held_entries_ = hs;
    held_x_ = hx;
    held_a_ = ha;
    held_domain_ = config_.domain;
  }
  // W = L_H^{-1} B^T (n_H x n_I, B = A_IH in the mobile order), S = A_II - W^T W.
  W_.resize(nh, ni);
#pragma omp parallel for schedule(static)
  for (long col = 0; col < ni; ++col)
    for (long r = 0; r < nh; ++r) W_(r, col) = entry(perm_[std::size_t(col)], hs[std::size_t(r)]);
  lapack::trsm_lower(held_L_, W_);
  L_.resize(ni, ni);
#pragma omp parallel for schedule(static)
  for (long col = 0; col < ni; ++col)
    for (long r = col; r < ni; ++r) L_(r, col) = entry(perm_[std::size_t(r)], perm_[std::size_t(col)]);
  lapack::syrk_minus(W_, L_);
  if (lapack::potrf(L_) != 0) far_field_not_positive_definite();
  const long nt = ni - n0_;
  Rtt_ = L_.bottomRightCorner(nt, nt);
  if (lapack::potri(Rtt_) != 0) throw std::logic_error("dense SD: dpotri failed on a factored far-field block");
  add_near_field_tt();
  factor_ = Factor::blocks;
}

VecX DenseStokesianDynamics::apply_inverse_mobility(const VecX& x) const {
  if (factor_ == Factor::full) {
    const long n = long(perm_.size());
    VecX y(n);
    for (long r = 0; r < n; ++r) y[r] = x[perm_[std::size_t(r)]];
    lapack::potrs(L_, y);
    VecX out(n);
    for (long r = 0; r < n; ++r) out[perm_[std::size_t(r)]] = y[r];
    return out;
  }
  if (factor_ != Factor::blocks) throw std::logic_error("dense SD: the far field is not factored");
  // a = L_H^{-1} x_H;  y_I = S^{-1} (x_I - W^T a);  y_H = L_H^{-T} (a - W y_I).
  const long ni = long(perm_.size()), nh = long(held_entries_.size());
  VecX a(nh), yi(ni);
  for (long r = 0; r < nh; ++r) a[r] = x[held_entries_[std::size_t(r)]];
  held_L_.triangularView<Eigen::Lower>().solveInPlace(a);
  for (long r = 0; r < ni; ++r) yi[r] = x[perm_[std::size_t(r)]];
  if (ni) {
    yi.noalias() -= W_.transpose() * a;
    lapack::potrs(L_, yi);
    a.noalias() -= W_ * yi;
  }
  held_L_.triangularView<Eigen::Lower>().transpose().solveInPlace(a);
  VecX out(x.size());
  for (long r = 0; r < ni; ++r) out[perm_[std::size_t(r)]] = yi[r];
  for (long r = 0; r < nh; ++r) out[held_entries_[std::size_t(r)]] = a[r];
  return out;
}

const MatX& DenseStokesianDynamics::resistance() const {
  if (have_R_) return R_;
  if (!config_.valid) throw std::logic_error("dense SD: resistance() before prepare()");
  if (factor_ == Factor::full) {  // from the full factor in its order
    const long n = long(perm_.size());
    MatX X = L_;
    if (lapack::potri(X) != 0) throw std::logic_error("dense SD: dpotri failed on the factored far field");
    R_.resize(n, n);
#pragma omp parallel for schedule(static)
    for (long col = 0; col < n; ++col)
      for (long r = col; r < n; ++r)
        R_(perm_[std::size_t(r)], perm_[std::size_t(col)]) = R_(perm_[std::size_t(col)], perm_[std::size_t(r)]) = X(r, col);
  } else {  // not factored, or by blocks: the whole far field factored here in the natural order
    MatX X = full_mobility();
    if (lapack::potrf(X) != 0) far_field_not_positive_definite();
    if (lapack::potri(X) != 0) throw std::logic_error("dense SD: dpotri failed on the factored far field");
    R_ = X.selfadjointView<Eigen::Lower>();
  }
  R_ += MatX(Rnf_);
  have_R_ = true;
  return R_;
}

HydroResult DenseStokesianDynamics::solve(const HydroProblem& p) {
  factor(p.fixed);
  const RigidConstraints c = RigidConstraints::of(m_, p.fixed, p.force, p.torque, p.flow);
  const std::vector<long>& v = c.force_given;   // unknown motion
  // Right-hand side f + f_B + M_inf^{-1} u_s (engine/hydro_solver.hpp).
  VecX noise = VecX::Zero(c.force.size()), slip_force;
  if (p.force_noise)
    for (long q : v) noise[q] += (*p.force_noise)[q];
  if (p.slip) {
    slip_force = apply_inverse_mobility(*p.slip);
    noise += slip_force;
  }
  const long nv = long(v.size());
  if (!have_Rvv_ || v != v_) {
    std::vector<long> rows(std::size_t(nv), 0);  // row of each v entry in R_tt
    bool whole = nv == Rtt_.rows();
    for (long i = 0; i < nv; ++i) {
      rows[std::size_t(i)] = pos_[std::size_t(v[std::size_t(i)])] - n0_;
      if (rows[std::size_t(i)] < 0) throw std::logic_error("dense SD: an entry with given force outside the force/torque block");
      whole = whole && rows[std::size_t(i)] == i;
    }
    if (whole) {
      Rvv_ = Rtt_;  // no fixed particles: v is the whole force/torque block, in order
    } else {
      Rvv_.resize(nv, nv);
#pragma omp parallel for schedule(static)
      for (long j = 0; j < nv; ++j)
        for (long i = 0; i < nv; ++i) Rvv_(i, j) = Rtt_(rows[std::size_t(i)], rows[std::size_t(j)]);
    }
    const VecX diagonal = Rvv_.diagonal();
    have_Rvv_ = false;
    if (lapack::potrf(Rvv_) != 0) {
      // dpotrf overwrote the lower triangle: rebuild R_vv from the upper one and the diagonal.
      MatX A = Rvv_.triangularView<Eigen::StrictlyUpper>();
      A += MatX(A.transpose());
      A.diagonal() = diagonal;
      const long e = first_failing_entry(A);
      throw PhysicsError("SD resistance matrix (far field + near field) is not positive definite: its Cholesky "
                         "factorisation fails at " +
                         (e >= 0 ? failing_particles(v[std::size_t(e)] / dof_per_particle(m_), p.config)
                                 : std::string("an unknown entry")));
    }
    v_ = v;
    have_Rvv_ = true;
  }
  // R_vk V_k: the given motion (zero at v) through M_inf^{-1} and the near field (nothing to do
  // when every given motion is zero: no ambient flow).
  VecX V(nv);
  for (long i = 0; i < nv; ++i) V[i] = c.force[v[std::size_t(i)]] + noise[v[std::size_t(i)]];
  if (!c.motion.isZero(0.0)) {
    const VecX given = apply_inverse_mobility(c.motion) + Rnf_ * c.motion;
    for (long i = 0; i < nv; ++i) V[i] -= given[v[std::size_t(i)]];
  }
  lapack::potrs(Rvv_, V);
  VecX gen = c.motion;  // full generalised motion [U - u_inf, Omega - Omega_inf, -E_inf]
  for (long i = 0; i < nv; ++i) gen[v[std::size_t(i)]] = V[i];
  VecX moments = apply_inverse_mobility(gen) + Rnf_ * gen;  // f + f_B + M^{-1} u_s at given entries
  if (p.slip) moments -= slip_force;
  HydroResult res = unpack_solution(m_, p.flow, gen, moments, p.fixed);
  res.regularised_pairs = stats_.regularised;
  return res;
}

std::vector<Vec3> DenseStokesianDynamics::brownian_displacement(double, double, Rng&) {
  throw PhysicsError("dense Stokesian dynamics samples Brownian motion through brownian_force and a drift-corrected "
                     "integrator (fixman), not by displacements");
}

VecX DenseStokesianDynamics::brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) {
  factor(fixed);
  const int d = dof_per_particle(m_);
  const long n = long(config_.x.size()) * d, nr = L_.rows();  // nr = n (full) or the mobile entries (held blocks)
  const std::vector<char> given = force_given_flags(m_, n / d, fixed);
  // n normals either way (the stream advances alike); the held path uses those of the mobile rows.
  VecX psi(n);
  for (auto& v : psi) v = rng.normal();
  // L^{-T} psi over the factored order: covariance (M_inf^{-1}) there (full), S^{-1} = (M_inf^{-1})_II (blocks).
  const VecX z = L_.triangularView<Eigen::Lower>().transpose().solve(psi.head(nr));
  VecX xi = near_.brownian_force(config_.x, config_.a, config_.domain, given, rng.fork());
  const double pref = std::sqrt(2.0 * kT / dt);
  if (factor_ == Factor::blocks)
    for (long q : held_entries_) xi[q] = 0.0;
  for (long r = 0; r < nr; ++r) {
    const long q = perm_[std::size_t(r)];
    xi[q] = given[std::size_t(q)] ? pref * (xi[q] + z[r]) : 0.0;
  }
  return xi;
}

MatX DenseStokesianDynamics::resistance(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                                        lubrication::NearFieldStats* stats) {
  prepare({x, a, domain});
  if (stats) *stats = stats_;
  return resistance();
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
