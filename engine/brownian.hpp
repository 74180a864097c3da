#pragma once
// Brownian forces of the hydrodynamic solvers (docs/brownian.md).
//
// With R the solver's resistance in the generalised layout (engine/core/layout.hpp) and v the
// entries whose force is given (the mobile particles' F and T; stresslets and fixed particles'
// entries have their motion given), the Brownian velocity V_v must have covariance
// (2 kT / dt) (R_vv)^{-1} (fluctuation-dissipation; for fixed particles and rigid stresslets the
// mobility of the mobile block, seed 1 s. 2.1.3). A force xi with covariance (2 kT / dt) R_vv,
// solved for like any given force, R_vv V_v = xi_v, gives exactly that. With R = M_inf^{-1} + R_nf
// (Stokesian dynamics, Durlofsky, Brady & Bossis 1987) xi is the sum of two independent parts
// (method notes s. 5; seed 1 eqs. 2.50-2.51):
//   near field  xi_nf = sum over pairs of L_p w_p, L_p L_p^T the pair's lubrication block on the
//               v entries (NearField::brownian_force): covariance R_nf,vv exactly, O(pairs);
//   far field   xi_ff = (M_inf^{-1/2} psi)_v, psi standard normal on all entries, by the Lanczos
//               approximation of f(M) = M^{-1/2} (Chow & Saad 2014) with far-field products
//               only: covariance (M_inf^{-1})_vv.
// Both are scaled by sqrt(2 kT / dt). The same xi is reused by both stages of the Fixman midpoint
// step (engine/integrators.hpp), which then produces the drift kT div(R_vv^{-1}).
//
// Why these samplers (measured, bench/bench_brownian.cpp and docs/brownian.md):
//  - near field, pairwise rather than P^T L w with L the CHOLMOD factor of R_nf: the accelerated
//    solver factorises only the strong pairs plus a shift (engine/sd_accelerated.hpp) because the
//    factor of the whole R_nf fills like N^1.5 at phi >= 0.3 (bench_asd "fill": 2.3e6 against
//    5.1e4 nonzeros at N = 500, phi = 0.45); a factor of R_nf itself would be a second, much larger
//    factorisation per step, and R_nf is singular for particles with no pair. The pairwise sum is
//    exact, linear in the pairs, and parallel.
//  - far field, Lanczos rather than a positively split Ewald sampler (Fiore et al. 2017): it works
//    with every far-field method (direct, Ewald, PME, sheared) through the operator alone.
//    Measured (bench_brownian, phi = 0.4, sheared, FTS, tolerance 1e-3): 26 / 44 / 65 Lanczos
//    iterations at N = 1e3 / 1e4 / 1e5 against 22 / 23 / 30 GMRES products per solve: the largest
//    single part of a step at N >= 1e4; a preconditioned or split-Ewald sampler is the next step.
// Streams: psi from the caller's stream, then the pair vectors from a fork of it (RandomStream::fork).
#include "engine/core/layout.hpp"
#include "engine/core/operators.hpp"

#include <vector>

namespace stokesian {

// One flag per generalised entry (length n d): 1 where the force is given (mobile particles' F, T).
std::vector<char> force_given_flags(Moments m, long n, const std::vector<char>& fixed);

// Self resistance per generalised entry: 6 pi mu a (F), 8 pi mu a^3 (T), 20/3 pi mu a^3 (S, in the
// orthonormal symmetric-traceless coordinates of engine/core/sym_traceless.hpp).
VecX self_resistance(const std::vector<double>& a, double mu, Moments m);

struct LanczosReport {
  int iterations = 0;
};

// scale * (M^{-1/2} psi) with psi standard normal from rng (M.size() draws),
// zero outside the flagged entries. Lanczos to relative change `tol`; PhysicsError when it fails.
VecX far_field_brownian_force(const MobilityOperator& M, const std::vector<char>& given, double scale,
                              double tol, Rng& rng, LanczosReport* report = nullptr);

}  // namespace stokesian
