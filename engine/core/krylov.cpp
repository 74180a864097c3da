#include "engine/core/krylov.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
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

KrylovResult lanczos_power(const LinearOperator& A, const VecX& z, VecX& y, double power, double tol, int max_iter) {
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
    if (lmin < -negative * lmax || (power < 0 && lmin <= 0.0)) {
      res.curvature = lmin;
      res.status = KrylovStatus::indefinite;
      return res;
    }
    VecX sq = eig.eigenvalues().cwiseMax(0.0);
    for (auto& e : sq) e = power == 0.5 ? std::sqrt(e) : power == -0.5 ? 1.0 / std::sqrt(e) : std::pow(e, power);
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

namespace stokesian {

KrylovResult gmres(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter, int restart,
                   GmresSnapshot* snapshot) {
  KrylovResult res;
  const long n = b.size();
  if (x.size() != n) x.setZero(n);
  const double bnorm = b.norm();
  auto stop = [&](KrylovStatus s, double rel) {
    res.status = s;
    res.relative_residual = rel;
    res.converged = s == KrylovStatus::converged;
    return res;
  };
  if (!std::isfinite(bnorm)) return stop(KrylovStatus::non_finite, bnorm);
  if (bnorm == 0.0) {
    x.setZero();
    return stop(KrylovStatus::converged, 0.0);
  }
  restart = std::max(1, restart);
  std::vector<VecX> V(std::size_t(restart) + 1);
  MatX H = MatX::Zero(restart + 1, restart);
  VecX cs(restart), sn(restart), g(restart + 1), w, Ax;
  // Initial residual: one product unless x starts at zero.
  // A starting iterate worse than zero (|b - A x| > |b|) is dropped for zero.
  VecX r;
  if (x.isZero(0.0)) r = b;
  else {
    A(x, Ax);
    ++res.products;
    r = b - Ax;
    if (!(r.norm() <= bnorm)) {
      x.setZero();
      r = b;
    }
  }
  double rnorm = r.norm();
  double cycle_start = rnorm;
  // x + V_m y with H_m y = g (upper triangular): the iterate of the cycle after m steps.
  auto iterate = [&](int m, VecX& out) {
    VecX y = g.head(m);
    for (int i = m - 1; i >= 0; --i) {
      for (int j = i + 1; j < m; ++j) y[i] -= H(i, j) * y[j];
      y[i] /= H(i, i);
    }
    out = x;
    for (int i = 0; i < m; ++i) out += y[i] * V[std::size_t(i)];
  };
  auto take = [&](const VecX& at, double residual) {
    snapshot->x = at;
    snapshot->relative_residual = residual / bnorm;
    snapshot->iterations = res.iterations;
    snapshot->taken = true;
  };
  for (;;) {
    if (!std::isfinite(rnorm)) return stop(KrylovStatus::non_finite, rnorm);
    if (snapshot && !snapshot->taken && rnorm <= snapshot->tol * bnorm) take(x, rnorm);
    if (rnorm <= tol * bnorm) return stop(KrylovStatus::converged, rnorm / bnorm);
    if (res.iterations >= max_iter) return stop(KrylovStatus::max_iterations, rnorm / bnorm);
    V[0] = r / rnorm;
    g.setZero();
    g[0] = rnorm;
    int m = 0;
    double est = rnorm;  // the least-squares residual, |b - A x_m| in exact arithmetic
    while (m < restart && res.iterations < max_iter) {
      A(V[std::size_t(m)], w);
      ++res.products;
      ++res.iterations;
      // Modified Gram-Schmidt, then a second pass (the basis stays orthonormal to round-off).
      for (int pass = 0; pass < 2; ++pass)
        for (int i = 0; i <= m; ++i) {
          const double h = V[std::size_t(i)].dot(w);
          H(i, m) += h;
          w -= h * V[std::size_t(i)];
        }
      const double hn = w.norm();
      H(m + 1, m) = hn;
      if (!std::isfinite(hn) || !H.col(m).allFinite()) return stop(KrylovStatus::non_finite, hn);
      for (int i = 0; i < m; ++i) {
        const double t = cs[i] * H(i, m) + sn[i] * H(i + 1, m);
        H(i + 1, m) = -sn[i] * H(i, m) + cs[i] * H(i + 1, m);
        H(i, m) = t;
      }
      const double d = std::hypot(H(m, m), H(m + 1, m));
      cs[m] = d > 0 ? H(m, m) / d : 1.0;
      sn[m] = d > 0 ? H(m + 1, m) / d : 0.0;
      H(m, m) = d;
      H(m + 1, m) = 0.0;
      g[m + 1] = -sn[m] * g[m];
      g[m] = cs[m] * g[m];
      est = std::abs(g[m + 1]);
      ++m;
      if (hn > 0.0) V[std::size_t(m)] = w / hn;
      if (snapshot && !snapshot->taken && est <= snapshot->tol * bnorm) {
        VecX at;
        iterate(m, at);
        take(at, est);
      }
      if (est <= tol * bnorm || hn == 0.0) break;  // converged, or an invariant Krylov space (exact)
    }
    {
      VecX next;
      iterate(m, next);
      x = std::move(next);
    }
    H.setZero();
    if (est <= tol * bnorm && res.iterations <= m) {
      // Converged inside the first cycle: the least-squares residual is the residual of x (Arnoldi
      // with reorthogonalisation keeps them equal to round-off; the accelerated-SD tests check the
      // solution against the dense solver).
      rnorm = est;
      continue;
    }
    // Restart (or final check after a later cycle): the true residual.
    A(x, Ax);
    ++res.products;
    r = b - Ax;
    rnorm = r.norm();
    if (rnorm > tol * bnorm && rnorm > 0.99 * cycle_start && res.iterations < max_iter)
      return stop(KrylovStatus::stagnated, rnorm / bnorm);
    cycle_start = rnorm;
  }
}

KrylovResult bicgstab(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter) {
  KrylovResult res;
  const long n = b.size();
  if (x.size() != n) x.setZero(n);
  const double bnorm = b.norm();
  auto stop = [&](KrylovStatus s, double rel) {
    res.status = s;
    res.relative_residual = rel;
    res.converged = s == KrylovStatus::converged;
    return res;
  };
  if (!std::isfinite(bnorm)) return stop(KrylovStatus::non_finite, bnorm);
  if (bnorm == 0.0) {
    x.setZero();
    return stop(KrylovStatus::converged, 0.0);
  }
  VecX Ax;
  VecX r = b;
  if (!x.isZero(0.0)) {
    A(x, Ax);
    ++res.products;
    r = b - Ax;
  }
  const VecX r0 = r;
  double rho = 1.0, alpha = 1.0, omega = 1.0;
  VecX p = VecX::Zero(n), v = VecX::Zero(n), s, t;
  for (;;) {
    const double rn = r.norm();
    if (!std::isfinite(rn)) return stop(KrylovStatus::non_finite, rn);
    if (rn <= tol * bnorm) return stop(KrylovStatus::converged, rn / bnorm);
    if (res.iterations >= max_iter) return stop(KrylovStatus::max_iterations, rn / bnorm);
    const double rho_new = r0.dot(r);
    if (rho_new == 0.0 || omega == 0.0) return stop(KrylovStatus::stagnated, rn / bnorm);
    const double beta = (rho_new / rho) * (alpha / omega);
    rho = rho_new;
    p = r + beta * (p - omega * v);
    A(p, v);
    alpha = rho / r0.dot(v);
    s = r - alpha * v;
    A(s, t);
    res.products += 2;
    ++res.iterations;
    const double tt = t.squaredNorm();
    omega = tt > 0 ? t.dot(s) / tt : 0.0;
    x += alpha * p + omega * s;
    r = s - omega * t;
  }
}

}  // namespace stokesian
