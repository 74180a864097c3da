#pragma once
// Matrix-free Krylov methods used by the hydrodynamic solvers.
//
// conjugate_gradient: solves A x = b for symmetric positive definite A given as a product
//   (Hestenes & Stiefel 1952), stopping when |r| <= tol |b|.
// lanczos_power: y = A^p z (p = 1/2: lanczos_sqrt; p = -1/2: the Brownian force M^{-1/2} z) by
//   the Lanczos approximation of Chow & Saad (2014, SIAM J. Sci. Comput. 36, A588):
//   y_k = |z| V_k T_k^p e_1, stopped when successive iterates differ by less than tol relative.
//   For p < 0 the iteration converges like CG on A (error ~ ((sqrt(k)-1)/(sqrt(k)+1))^m, k the
//   condition number); a Ritz value <= 0 is reported as indefinite.
//
// gmres: restarted GMRES(m) for a general (nonsymmetric) A (Saad & Schultz 1986): the iterate of
//   least residual norm over the Krylov space, Arnoldi with modified Gram-Schmidt and one
//   reorthogonalisation pass, Givens rotations for the small least-squares problem; restarted
//   every `restart` iterations from the true residual. Stops when |b - A x| <= tol |b|; can keep
//   the iterate where the residual first reaches a looser tolerance (GmresSnapshot). Starts from
//   the x it is given (one product for its residual; zero instead when that residual exceeds |b|).
// bicgstab: van der Vorst's (1992) BiCGStab, two products per iteration and short recurrences;
//   kept as the alternative the accelerated SD solver was measured against (bench_asd).
//
// Failure detection (docs/reliability.md, "Failure policies during a run"). Both methods stop
// early, instead of running to max_iter, and say why (KrylovResult::status):
//   non_finite  a residual, step length or Lanczos coefficient is NaN or infinite (a non-finite
//               operator or right-hand side);
//   indefinite  CG: a search direction with p.Ap <= 0; Lanczos: an eigenvalue of the tridiagonal
//               T_k below -sqrt(eps) |T_k| (the Ritz values of T_k lie in the spectrum's hull, so
//               a clearly negative one proves A is not positive definite);
//   stagnated   CG only: (a) the smallest residual so far has not halved in kStagnationWindow
//               iterations. For SPD A, CG reduces the error by (sqrt(k)-1)/(sqrt(k)+1) per
//               iteration (k the condition number), halving it in ~0.35 sqrt(k) iterations, so a
//               window of 200 is met by any system with k below ~3e5; an operator that is not
//               symmetric stagnates. (b) The recursively updated residual keeps falling below
//               round-off while the true residual b - A x stops near eps |A| |x|, so convergence
//               is accepted only after checking the true residual (one extra product); when it is
//               above the tolerance CG restarts from it;
//   round_off   CG only: such a restart did not halve the true residual: the tolerance is below
//               what double precision reaches for this system;
//   stagnated   GMRES: a whole restart cycle did not reduce the residual by 1 %; BiCGStab: a
//               breakdown (rho or omega = 0);
//   max_iterations  the cap was reached while still progressing.
// A Lanczos "happy breakdown" (beta_k = 0: the Krylov space is invariant) is exact convergence.
#include "engine/core/types.hpp"

#include <functional>
#include <string>

namespace stokesian {

using LinearOperator = std::function<void(const VecX& in, VecX& out)>;

enum class KrylovStatus { converged, max_iterations, stagnated, round_off, indefinite, non_finite };

struct KrylovResult {
  int iterations = 0;
  int products = 0;  // operator applications (gmres, bicgstab)
  double relative_residual = 0.0;  // CG: |b - A x|/|b|; Lanczos: last relative change
  bool converged = false;
  KrylovStatus status = KrylovStatus::max_iterations;
  double curvature = 0.0;  // indefinite: CG's p.Ap/|p|^2, or Lanczos' most negative Ritz value
};

// One phrase for messages: "converged", "stagnated (...)", ...
std::string describe(const KrylovResult& r);

// CG iterations without halving the smallest residual after which CG is declared stagnated.
constexpr int kStagnationWindow = 200;

KrylovResult conjugate_gradient(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter);

// The iterate at an intermediate tolerance of the same GMRES run: taken the first time the
// residual is at or below tol |b| (x, its relative residual and the iterations so far).
struct GmresSnapshot {
  double tol = 0.0;
  bool taken = false;
  VecX x;
  double relative_residual = 0.0;
  int iterations = 0;
};

KrylovResult gmres(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter, int restart = 40,
                   GmresSnapshot* snapshot = nullptr);

KrylovResult bicgstab(const LinearOperator& A, const VecX& b, VecX& x, double tol, int max_iter);

// Products with A made by a Krylov call: GMRES one per iteration plus one per restart (the true
// residual), BiCGStab two per iteration.

KrylovResult lanczos_power(const LinearOperator& A, const VecX& z, VecX& y, double power, double tol, int max_iter);
inline KrylovResult lanczos_sqrt(const LinearOperator& A, const VecX& z, VecX& y, double tol, int max_iter) {
  return lanczos_power(A, z, y, 0.5, tol, max_iter);
}

}  // namespace stokesian
