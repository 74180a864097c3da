#include "engine/core/krylov.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

namespace stokesian {

KrylovResult conjugate_gradient(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter) {
  KrylovResult res;
  const double bnorm = b.norm();
  if (x.size() != b.size()) x.setZero(b.size());
  if (bnorm == 0.0) {
    x.setZero();
    res.converged = true;
    return res;
  }
  VecX Ax;
  A(x, Ax);
  VecX r = b - Ax, p = r, Ap;
  double rr = r.squaredNorm();
  for (res.iterations = 0; res.iterations < max_iter; ++res.iterations) {
    if (std::sqrt(rr) <= tol * bnorm) break;
    A(p, Ap);
    const double alpha = rr / p.dot(Ap);
    x += alpha * p;
    r -= alpha * Ap;
    const double rr_new = r.squaredNorm();
    p = r + (rr_new / rr) * p;
    rr = rr_new;
  }
  res.relative_residual = std::sqrt(rr) / bnorm;
  res.converged = res.relative_residual <= tol;
  return res;
}

KrylovResult lanczos_sqrt(const LinearOperator& A, const VecX& z, VecX& y, double tol, int max_iter) {
  KrylovResult res;
  const double znorm = z.norm();
  y.setZero(z.size());
  if (znorm == 0.0) {
    res.converged = true;
    return res;
  }
  std::vector<VecX> V{z / znorm};
  std::vector<double> alpha, beta;
  VecX w, y_prev = VecX::Zero(z.size());
  for (int k = 0; k < max_iter; ++k) {
    A(V[k], w);
    if (k > 0) w -= beta[k - 1] * V[k - 1];
    alpha.push_back(V[k].dot(w));
    w -= alpha[k] * V[k];
    // Full reorthogonalisation keeps the basis orthonormal in floating point.
    for (const VecX& v : V) w -= v.dot(w) * v;
    const int m = k + 1;
    MatX T = MatX::Zero(m, m);
    for (int i = 0; i < m; ++i) {
      T(i, i) = alpha[i];
      if (i + 1 < m) T(i, i + 1) = T(i + 1, i) = beta[i];
    }
    Eigen::SelfAdjointEigenSolver<MatX> eig(T);
    const VecX sq = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    const VecX c = znorm * eig.eigenvectors() * sq.asDiagonal() * eig.eigenvectors().row(0).transpose();
    y.setZero();
    for (int i = 0; i < m; ++i) y += c[i] * V[i];
    res.iterations = m;
    res.relative_residual = (y - y_prev).norm() / y.norm();
    const double b = w.norm();
    if ((k > 0 && res.relative_residual <= tol) || b <= 1e-14 * std::abs(alpha[0]) || m == z.size()) {
      res.converged = true;
      return res;
    }
    y_prev = y;
    beta.push_back(b);
    V.push_back(w / b);
  }
  return res;
}

}  // namespace stokesian
