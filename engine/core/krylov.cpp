#include "engine/core/krylov.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace stokesian {

std::string describe(const KrylovResult& r) {
  std::ostringstream o;
  switch (r.status) {
    case KrylovStatus::converged: o << "converged"; break;
    case KrylovStatus::max_iterations: o << "reached the iteration cap"; break;
    case KrylovStatus::stagnated:
      o << "stagnated (the smallest residual did not halve in " << kStagnationWindow << " iterations)";
      break;
    case KrylovStatus::round_off:
      o << "stagnated at round-off (the true residual b - Ax stays above the tolerance: below what double "
           "precision reaches here)";
      break;
    case KrylovStatus::indefinite:
      o << "found the operator not positive definite (curvature " << r.curvature << ")";
      break;
    case KrylovStatus::non_finite: o << "met a non-finite value (NaN or infinity in the operator or right-hand side)"; break;
  }
  return o.str();
}

KrylovResult conjugate_gradient(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter) {
  KrylovResult res;
  const double bnorm = b.norm();
  if (x.size() != b.size()) x.setZero(b.size());
  if (!std::isfinite(bnorm)) {
    res.relative_residual = bnorm;
    res.status = KrylovStatus::non_finite;
    return res;
  }
  if (bnorm == 0.0) {
    x.setZero();
    res.converged = true;
    res.status = KrylovStatus::converged;
    return res;
  }
  VecX Ax;
  A(x, Ax);
  VecX r = b - Ax, p = r, Ap;
  double rr = r.squaredNorm();
  // Stagnation watch: `mark` is the smallest residual when it last halved, at iteration mark_it.
  double best = std::sqrt(rr), mark = best;
  int it = 0, mark_it = 0;
  auto stop = [&](KrylovStatus s) {
    res.status = s;
    res.iterations = it;
    res.relative_residual = std::sqrt(rr) / bnorm;
    res.converged = s == KrylovStatus::converged;
    return res;
  };
  if (!std::isfinite(rr)) return stop(KrylovStatus::non_finite);
  double last_true = -1.0;  // true residual norm at the last restart
  for (;; ++it) {
    if (std::sqrt(rr) <= tol * bnorm) {
      // The recursive residual keeps falling below round-off while the true one b - A x stops at
      // ~eps |A| |x|: accept only a true residual within tolerance. Otherwise restart from the true
      // residual, once per halving of it; a restart that did not halve it is stagnation.
      A(x, Ax);
      r = b - Ax;
      const double true_rr = r.squaredNorm(), true_norm = std::sqrt(true_rr);
      const bool repeat = last_true >= 0.0 && true_norm > 0.5 * last_true;
      rr = true_rr;
      if (!std::isfinite(rr)) return stop(KrylovStatus::non_finite);
      if (true_norm <= tol * bnorm) return stop(KrylovStatus::converged);
      if (repeat) return stop(KrylovStatus::round_off);
      last_true = true_norm;
      p = r;
      best = mark = true_norm;
      mark_it = it;
    }
    if (it >= max_iter) return stop(KrylovStatus::max_iterations);
    A(p, Ap);
    const double pAp = p.dot(Ap);
    if (!std::isfinite(pAp)) return stop(KrylovStatus::non_finite);
    if (pAp <= 0.0) {
      res.curvature = pAp / p.squaredNorm();
      return stop(KrylovStatus::indefinite);
    }
    const double alpha = rr / pAp;
    x += alpha * p;
    r -= alpha * Ap;
    const double rr_new = r.squaredNorm();
    if (!std::isfinite(rr_new)) {
      ++it;
      rr = rr_new;
      return stop(KrylovStatus::non_finite);
    }
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    best = std::min(best, std::sqrt(rr));
    if (best <= 0.5 * mark) {
      mark = best;
      mark_it = it + 1;
    } else if (it + 1 - mark_it >= kStagnationWindow && std::sqrt(rr) > tol * bnorm) {
      ++it;
      return stop(KrylovStatus::stagnated);
    }
  }
}

KrylovResult lanczos_sqrt(const LinearOperator& A, const VecX& z, VecX& y, double tol, int max_iter) {
  KrylovResult res;
  const double znorm = z.norm();
  y.setZero(z.size());
  if (!std::isfinite(znorm)) {
    res.status = KrylovStatus::non_finite;
    return res;
  }
  if (znorm == 0.0) {
    res.converged = true;
    res.status = KrylovStatus::converged;
    return res;
  }
  // Ritz values below -sqrt(eps) times the largest |Ritz value| prove an indefinite operator.
  const double negative = std::sqrt(std::numeric_limits<double>::epsilon());
  std::vector<VecX> V{z / znorm};
  std::vector<double> alpha, beta;
  VecX w, y_prev = VecX::Zero(z.size());
  for (int k = 0; k < max_iter; ++k) {
    A(V[k], w);
    if (k > 0) w -= beta[k - 1] * V[k - 1];
    alpha.push_back(V[k].dot(w));
    res.iterations = k + 1;
    if (!std::isfinite(alpha[k])) {
      res.status = KrylovStatus::non_finite;
      return res;
    }
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
    const double lmin = eig.eigenvalues()(0), lmax = eig.eigenvalues().cwiseAbs().maxCoeff();
    if (lmin < -negative * lmax) {
      res.curvature = lmin;
      res.status = KrylovStatus::indefinite;
      return res;
    }
    const VecX sq = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    const VecX c = znorm * eig.eigenvectors() * sq.asDiagonal() * eig.eigenvectors().row(0).transpose();
    y.setZero();
    for (int i = 0; i < m; ++i) y += c[i] * V[i];
    res.relative_residual = (y - y_prev).norm() / y.norm();
    const double b = w.norm();
    if (!std::isfinite(b)) {
      res.status = KrylovStatus::non_finite;
      return res;
    }
    // Converged, or a happy breakdown (beta = 0: the Krylov space is invariant, y is exact).
    if ((k > 0 && res.relative_residual <= tol) || b <= 1e-14 * std::abs(alpha[0]) || m == z.size()) {
      res.converged = true;
      res.status = KrylovStatus::converged;
      return res;
    }
    y_prev = y;
    beta.push_back(b);
    V.push_back(w / b);
  }
  res.status = KrylovStatus::max_iterations;
  return res;
}

}  // namespace stokesian
