#pragma once
// Matrix-free Krylov methods used by the hydrodynamic solvers.
//
// conjugate_gradient: solves A x = b for symmetric positive definite A given as a product
//   (Hestenes & Stiefel 1952), stopping when |r| <= tol |b|.
// lanczos_sqrt: y = A^{1/2} z by the Lanczos approximation of Chow & Saad (2014, SIAM J. Sci.
//   Comput. 36, A1092, alg. 2.1): y_k = |z| V_k T_k^{1/2} e_1, stopped when successive iterates
//   differ by less than tol relative.
#include "engine/core/types.hpp"

#include <functional>

namespace stokesian {

using LinearOperator = std::function<void(const VecX& in, VecX& out)>;

struct KrylovResult {
  int iterations = 0;
  double relative_residual = 0.0;  // CG: |b - A x|/|b|; Lanczos: last relative change
  bool converged = false;
};

KrylovResult conjugate_gradient(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter);

KrylovResult lanczos_sqrt(const LinearOperator& A, const VecX& z, VecX& y, double tol, int max_iter);

}  // namespace stokesian
