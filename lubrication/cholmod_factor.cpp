#include "lubrication/cholmod_factor.hpp"

#include "engine/core/errors.hpp"

#include <cholmod.h>

#include <sstream>
#include <vector>

namespace stokesian::lubrication {

struct CholmodFactor::Impl {
  cholmod_common common;
  cholmod_factor* L = nullptr;
  cholmod_sparse* Ls = nullptr;  // simplicial copy of L for products (built lazily)
  std::vector<int> pattern_p, pattern_i;
  Impl() {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.final_ll = 1;  // keep L L^T (not L D L^T), needed for the Brownian product
    common.print = 0;
  }
  ~Impl() {
    if (Ls) cholmod_free_sparse(&Ls, &common);
    if (L) cholmod_free_factor(&L, &common);
    cholmod_finish(&common);
  }
};

namespace {
// A non-owning cholmod_sparse view of an Eigen compressed column matrix (upper triangle used).
cholmod_sparse view(const SparseMatrix& R) {
  cholmod_sparse A{};
  A.nrow = std::size_t(R.rows());
  A.ncol = std::size_t(R.cols());
  A.nzmax = std::size_t(R.nonZeros());
  A.p = const_cast<int*>(R.outerIndexPtr());
  A.i = const_cast<int*>(R.innerIndexPtr());
  A.x = const_cast<double*>(R.valuePtr());
  A.stype = 1;
  A.itype = CHOLMOD_INT;
  A.xtype = CHOLMOD_REAL;
  A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1;
  A.packed = 1;
  return A;
}
}  // namespace

CholmodFactor::CholmodFactor() : impl_(std::make_unique<Impl>()) {}
CholmodFactor::~CholmodFactor() = default;

bool CholmodFactor::factorize(const SparseMatrix& R_in) {
  SparseMatrix R = R_in;
  R.makeCompressed();
  cholmod_sparse A = view(R);
  Impl& m = *impl_;
  const bool same = m.L && std::equal(R.outerIndexPtr(), R.outerIndexPtr() + R.cols() + 1, m.pattern_p.begin(),
                                      m.pattern_p.end()) &&
                    std::equal(R.innerIndexPtr(), R.innerIndexPtr() + R.nonZeros(), m.pattern_i.begin(), m.pattern_i.end());
  if (m.Ls) cholmod_free_sparse(&m.Ls, &m.common);
  if (!same) {
    if (m.L) cholmod_free_factor(&m.L, &m.common);
    m.L = cholmod_analyze(&A, &m.common);
    if (!m.L) throw PhysicsError("CHOLMOD analysis failed (status " + std::to_string(m.common.status) + ")");
    m.pattern_p.assign(R.outerIndexPtr(), R.outerIndexPtr() + R.cols() + 1);
    m.pattern_i.assign(R.innerIndexPtr(), R.innerIndexPtr() + R.nonZeros());
    ++analyses_;
  }
  cholmod_factorize(&A, m.L, &m.common);
  if (m.common.status == CHOLMOD_NOT_POSDEF || m.L->minor < m.L->n) {
    const long col = long(static_cast<int*>(m.L->Perm)[m.L->minor]);
    std::ostringstream o;
    o << "near-field resistance is not positive definite: factorisation failed at matrix column " << col;
    // Force a fresh analysis next time: the factor is unusable.
    cholmod_free_factor(&m.L, &m.common);
    m.pattern_p.clear();
    throw NotPositiveDefinite(o.str(), col);
  }
  if (m.common.status < CHOLMOD_OK) throw PhysicsError("CHOLMOD factorisation failed (status " + std::to_string(m.common.status) + ")");
  return same;
}

VecX CholmodFactor::solve(const VecX& b) const {
  Impl& m = *impl_;
  cholmod_dense B{};
  B.nrow = std::size_t(b.size());
  B.ncol = 1;
  B.nzmax = std::size_t(b.size());
  B.d = std::size_t(b.size());
  B.x = const_cast<double*>(b.data());
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* X = cholmod_solve(CHOLMOD_A, m.L, &B, &m.common);
  VecX x = Eigen::Map<VecX>(static_cast<double*>(X->x), b.size());
  cholmod_free_dense(&X, &m.common);
  return x;
}

VecX CholmodFactor::multiply_L(const VecX& w) const {
  Impl& m = *impl_;
  if (!m.Ls) {
    cholmod_factor* copy = cholmod_copy_factor(m.L, &m.common);
    m.Ls = cholmod_factor_to_sparse(copy, &m.common);  // lower triangular L, column major
    cholmod_free_factor(&copy, &m.common);
  }
  const int* p = static_cast<const int*>(m.Ls->p);
  const int* i = static_cast<const int*>(m.Ls->i);
  const double* x = static_cast<const double*>(m.Ls->x);
  const int* perm = static_cast<const int*>(m.L->Perm);
  const long n = long(m.Ls->ncol);
  VecX Lw = VecX::Zero(n);
  for (long c = 0; c < n; ++c)
    for (int k = p[c]; k < p[c + 1]; ++k) Lw[i[k]] += x[k] * w[c];
  VecX psi(n);
  for (long k = 0; k < n; ++k) psi[perm[k]] = Lw[k];
  return psi;
}

long CholmodFactor::factor_nonzeros() const {
  Impl& m = *impl_;
  if (!m.L) return 0;
  if (m.L->is_super) {
    // Supernodal: count from the column counts of the symbolic analysis.
    long nz = 0;
    const int* cc = static_cast<const int*>(m.L->ColCount);
    for (std::size_t c = 0; c < m.L->n; ++c) nz += cc[c];
    return nz;
  }
  return long(static_cast<const int*>(m.L->p)[m.L->n]);
}

}  // namespace stokesian::lubrication
