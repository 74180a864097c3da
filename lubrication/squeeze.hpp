#pragma once
// The thesis's pairwise squeeze lubrication [T] (Buelow, s.5.2.2, eqs. 5.5-5.9; docs/lubrication.md
// section 8): a cheaper near-field level than exact two-sphere lubrication. A pair (i, j) at surface
// gap h = r - a_i - a_j with unit vector n = (x_j - x_i)/r exchanges only a normal force,
//
//     F_i = c(h) ((U_j - U_i) . n) n,    F_j = -F_i,
//
// no torque and no tangential force. U are the particles' own velocities, not relative to the
// ambient flow. In resistance form this is the rank-one block c(h) g g^T, g.v = n.(U_j - U_i) in the
// solvers' generalised velocities v (at FTS the strain columns carry the ambient part r n.E_inf.n
// and the stresslet rows the pair's force dipole; F and FT have no strain columns, so there, as for
// exact lubrication, the ambient strain does not enter; lubrication/near_field.cpp). It is added to
// M_inf^{-1} as it stands: the thesis neither subtracts the far field's own two-body part nor states
// an outer cutoff (ours is the near field's, [hydrodynamics] lubrication_cutoff). With the reduced
// radius a_r = a_i a_j/(a_i + a_j) (5.6), slip gap d_s and transition gap d_t:
//
//   no slip (5.5), h >= d_t:
//     c_ns = k1 6 pi mu a_r^2 (1/h - 1/(h + 2 a_r)),  k1 = 1.041 - 0.281 L - 0.0351 L^2,
//   slip (5.7), h < d_s:
//     c_sl = k2 pi mu a_r^2 / (3 d_s^2) [ (h + 6 d_s) ln((h + 6 d_s)/h)
//                                       - (h + 2 a_r + 6 d_s) ln((h + 2 a_r + 6 d_s)/(h + 2 a_r)) ],
//     k2 = 1.309 - 0.082 L - 0.009 L^2,
//   transition (5.8, 5.9), d_s <= h < d_t:
//     c = l c_ns + (1 - l) c_sl,  l = [erf(12 (h - d_s)/(d_t - d_s) - 6) + 1]/2,
//
// L = ln(h / (2 a_r)). Gaps below the contact gap d_c are evaluated at d_c (regime iv belongs to the
// contact forces). Two choices where the printed formulas are ambiguous (method notes, thesis 2.3):
//  - the slip prefactor is pi mu/(3 d_s^2), not the printed pi mu/(3 d_s), which is not a force per
//    velocity; with d_s^2, c_sl/k2 -> c_ns/k1 for h >> d_s (Hocking's slip correction);
//  - "log" in k1, k2 is the natural logarithm (5.7 writes ln; with it the model is closer to the exact
//    two-sphere squeeze resistance than with log10: +31 % against +57 % at h = 1e-3, lambda = 1).
// k1 and k2 are clamped at 0: the fits turn negative far outside their range (k1 at h/(2 a_r) > 17,
// reachable only for size ratios below 0.03 inside the default cutoff).
// Without k1 the no-slip form is the leading term of the exact squeeze resistance (Jeffrey & Onishi
// 1984): -n.(R_exact)_ij.n = 6 pi mu a_r^2/h (1 + O(h ln h)) (tests/test_squeeze.cpp).
#include "engine/core/scene.hpp"
#include "engine/core/types.hpp"

namespace stokesian::lubrication {

/// c(h) of the no-slip form (5.5), the slip form (5.7) with slip gap d, and the blended model.
double squeeze_no_slip(double h, double a_red, double mu);
double squeeze_slip(double h, double a_red, double mu, double d);
double squeeze_coefficient(double h, double ai, double aj, double mu, const SqueezeParams& p);

}  // namespace stokesian::lubrication
