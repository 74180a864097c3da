#pragma once
// The bulk stress of a suspension in a periodic box, by contribution (docs/rheology.md).
//
// Batchelor (1970) and, for Stokesian dynamics, Brady, Phillips, Lester & Bossis (1988) eq. 2.4
// and Banchio & Brady (2003) eqs. 2.16-2.18: with V the box volume and n = N_mobile / V,
//   Sigma = -p_f I + 2 mu E_inf                                   fluid
//         + (1/V) sum_{mobile i} S^H_i                            hydrodynamic
//         - (1/V) sum_{pairs} r_ij F_ij^T                         interparticle
//         - n kT I + (1/V) sum_{mobile i} <S^B_i>                 Brownian
//         + (1/V) sum_{fixed i} S^H_i                             fixed particles
// S^H_i is the stresslet of the traction the fluid exerts on particle i (Batchelor 1970; +20/3 pi
// mu a^3 E_inf for an isolated sphere in a straining flow). The FTS solve returns the stresslet the
// particle exerts on the fluid (HydroResult::S, like its forces): S_i = -S^H_i, so every particle
// term enters with -1/V times the solve's stresslets. S^H holds both the ambient-flow part
// (R_SE - R_SU R_FU^{-1} R_FE) : E_inf and the hydrodynamic coupling of the interparticle forces,
// -R_SU R_FU^{-1} F^P, so that "hydrodynamic" is everything the solve returns; r_ij = x_i - x_j (nearest image) and F_ij the pair force on i (PairForceTotals::virial,
// every pair law, contact forces included). External forces (gravity) enter no stress: their
// moment -x F depends on the origin in a periodic box. The fluid pressure p_f is not computed.
//
// Brownian stresslet: S^B = -kT div(R_SU R_FU^{-1}) (Banchio & Brady 2003 eq. 2.17, the
// divergence over the particle positions), i.e. kT div(dS^H/dF^P) since S^H = -R_SU R_FU^{-1} F^P
// + ...: the average of S^H under the Brownian force -kT grad ln P, integrated by parts. With
// A = dS/dF = R_SU R_FU^{-1} the response of the solve's stresslets to the given forces, the
// Fixman step (engine/integrators.hpp) gives it without extra solves: both stages are driven by
// the same Brownian force xi of covariance (2 kT/dt) R, and the midpoint x' = x0 + (dt/2) R^{-1} xi
// + O(dt), so
//   E[(A(x') - A(x0)) xi] = (dt/2) d_l A_{.k} (R^{-1})_{lm} E[xi_m xi_k] + O(dt)
//     = kT d_l A_{.l} = -S^B + O(dt)
// (summed over particles). Only the responses to xi enter the sample (two solves with xi alone):
// the stages' full stresslets also carry A F^P + B E_inf, whose change over a step is not small on
// average when F^P is a stiff contact force. The sample is O(1) in dt; it is taken every
// [brownian] stress_every steps, the samples since a frame are averaged in the next frame
// (State::brownian_stresslet_sum), and it enters the stress with -1/V like the solve's stresslets.
// tests/test_stress.cpp checks it against -kT div(R_SU R_FU^{-1}) from finite differences of the
// dense Stokesian-dynamics solver.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

#include <string>
#include <vector>

namespace stokesian {

// One contribution to the bulk stress [kT/a^3].
struct StressPart {
  std::string name;  // "fluid", "hydrodynamic", "interparticle", "brownian", "fixed"
  Mat3 sigma = Mat3::Zero();
};

struct StressInput {
  double volume = 0.0;        // V [a^3]
  double viscosity = 1.0;     // mu
  Mat3 E = Mat3::Zero();      // ambient rate of strain
  long mobile = 0;            // mobile particles (n = mobile / V)
  // Each contribution is reported when its flag is set.
  bool hydrodynamic = false;  // FTS: stresslet sums below
  // sum_i S_i of the solve's stresslets (exerted on the fluid, = -S^H) [kT]
  Mat3 stresslet_mobile = Mat3::Zero(), stresslet_fixed = Mat3::Zero();
  bool fixed = false;         // fixed particles present (with FTS)
  bool interparticle = false; // pair forces present
  Mat3 virial = Mat3::Zero(); // sum over pairs of r_ij F_ij^T [kT]
  bool brownian = false;      // kT > 0
  double kT = 0.0;
  // mean of the Fixman samples sum_i [(A(x') - A(x0)) xi]_i, estimating -sum_i S^B_i [kT] (0 when none)
  Mat3 brownian_stresslet = Mat3::Zero();
};

// The contributions in the order of the header, then "total" (their sum).
std::vector<StressPart> bulk_stress(const StressInput& in);

// Relative viscosity sigma_xy / (mu rate) and the normal-stress differences N1 = sigma_xx -
// sigma_yy, N2 = sigma_yy - sigma_zz of one contribution in simple shear u = (rate y, 0, 0).
inline double shear_viscosity(const Mat3& sigma, double mu, double rate) { return sigma(0, 1) / (mu * rate); }
inline double normal_difference_1(const Mat3& sigma) { return sigma(0, 0) - sigma(1, 1); }
inline double normal_difference_2(const Mat3& sigma) { return sigma(1, 1) - sigma(2, 2); }

}  // namespace stokesian
