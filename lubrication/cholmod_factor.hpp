#pragma once
// Sparse Cholesky factorisation of the near-field resistance with CHOLMOD (Chen, Davis, Hager &
// Rajamanickam 2008): R = P^T L L^T P with a fill-reducing permutation P (AMD/METIS chosen by
// CHOLMOD's analysis) and a supernodal lower-triangular factor L.
//
//   factorize(R)   analyse once (ordering + symbolic factor), reused while the sparsity pattern of
//                  R is unchanged; numeric factorisation every call.
//   solve(b)       x = R^{-1} b.
//   multiply_L(w)  psi = P^T L w, whose covariance for standard normal w is P^T L L^T P = R: the
//                  near-field Brownian force (Banchio & Brady 2003, eq. 2.11; docs/stokesian_dynamics.md).
// A matrix that is not positive definite raises NotPositiveDefinite (engine/core/errors.hpp) with the
// failing column; NearField::factorize translates it into the particle and its closest pair.
#include "engine/core/types.hpp"

#include <Eigen/SparseCore>

#include <memory>

namespace stokesian::lubrication {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

class CholmodFactor {
 public:
  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  // R must be symmetric; only its upper triangle is read. Returns true if the symbolic analysis
  // was reused.
  bool factorize(const SparseMatrix& R);
  VecX solve(const VecX& b) const;
  VecX multiply_L(const VecX& w) const;
  // Number of nonzeros of L (fill), for benchmarks.
  long factor_nonzeros() const;
  long analyses() const { return analyses_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long analyses_ = 0;
};

}  // namespace stokesian::lubrication
