#pragma once
// The lubrication cutoff of Stokesian dynamics as an accuracy knob (docs/lubrication.md, section 7).
//
// Near-field correction with a switch (lubrication/near_field.hpp):
//
//     R_nf = sum over pairs of  w(s) [ R2B_exact(pair) - R2B_inf(pair) ],   s = 2 r / (a_i + a_j),
//
//     w(s) = 1                                   for s <= s_in,
//          = 1 - t^3 (10 - 15 t + 6 t^2),        t = (s - s_in) / (s_cut - s_in), s_in < s < s_cut,
//          = 0                                   for s >= s_cut
//
// (the quintic "smoothstep": w, w' and w'' are continuous, so R and its first two derivatives in the
// positions are continuous).  s_in = s_cut is the hard step of published SD (Durlofsky, Brady & Bossis
// 1987; s_cut = 4): w = 1 below s_cut and 0 from s_cut on.
//
// Two-sphere error.  For an isolated pair, SD gives R = R2B_inf + w (R2B_exact - R2B_inf): exact for
// s <= s_in, the engine's two-body far field alone for s >= s_cut, in between a blend.  Error norm
// (what a user sees: every velocity, angular velocity and stresslet response of the pair, in units
// of an isolated sphere's):
//
//     e(s) = || D^{1/2} (M_SD - M_exact) D^{1/2} ||_2,   M = R^{-1} (2d x 2d, the solve's moment level),
//
// D = diag of the isolated-sphere resistances (6 pi mu a, 8 pi mu a^3, (20/3) pi mu a^3 per particle).
// Measured for the far field alone (w = 0) against the exact two-sphere solution
// (lubrication/resistance_functions.hpp), worst over size ratios lambda in [1/16, 16] (49 ratios;
// coarser to 100; the worst lambda is 3-5) and pair orientation-independent, s in [4, 60]:
//
//     F, FT :  e(s) <= 6.8 s^-4    (max of e s^4: 6.68 at s = 4, lambda = 3.4; 6.33 as s -> infinity)
//     FTS   :  e(s) <= 32  s^-6    (max of e s^6: 31.3 at s = 4, lambda = 4.5; 27.9 as s -> infinity)
//
// (F and FT give the same e: the worst response is translational.)  e decreases monotonically in s,
// and in the band the error is (1 - w) times the far-field error to first order, so a band with
// e(s_in) <= tol keeps the two-sphere error <= tol at every separation (tested on a fine grid,
// tests/test_lubrication_cutoff.cpp).
#include "engine/core/types.hpp"

namespace stokesian::lubrication {

/// The switch band [s_in, s_cut] in symmetric separations s = 2 r / (a_i + a_j) [1].
struct CutoffBand {
  double s_in = 4.0;   // full correction for s <= s_in
  double s_cut = 4.0;  // no correction for s >= s_cut (the pair search radius)
};

/// The standard cutoff of published SD, and the smallest s_in an automatic band uses: the automatic
/// near field always holds at least the full correction of published SD.
inline constexpr double kStandardCutoff = 4.0;
/// Width s_cut - s_in of an automatic band [1].
inline constexpr double kAutoTaper = 0.5;
/// Default cap of an automatic band's s_cut (so s_in <= 5.5).  Near-field neighbours per particle
/// grow as s_cut^3 (phi (s_cut^3 - 8) at volume fraction phi; at phi = 0.4: 22 at s_cut = 4, 83 at 6,
/// 202 at 8), and with them the memory and the factorisation fill of the sparse near field.  Below
/// tolerance_floor(m) (7.4e-3 for F and FT, 1.2e-3 for FTS with this cap) the two-sphere error is
/// bounded by the cap's error instead of the tolerance.
inline constexpr double kDefaultMaxAutoCutoff = 6.0;

/// Measured bound of the two-sphere error of the far field alone at separation s >= 4 (the fit
/// above; e(s) for w = 0).
double far_field_pair_error(double s, Moments m);

/// The band for which the two-sphere error is <= tol at every separation:
///   s_in = max(4, (A_m / tol)^(1/p_m)), s_cut = s_in + kAutoTaper, with s_cut capped at max_cutoff
/// (>= 4 + kAutoTaper).  Never below the standard 4.  When the cap binds (tol < tolerance_floor),
/// the two-sphere error is bounded by far_field_pair_error(max_cutoff - kAutoTaper, m) instead.
CutoffBand cutoff_for_tolerance(double tol, Moments m, double max_cutoff = kDefaultMaxAutoCutoff);

/// The smallest tolerance cutoff_for_tolerance meets with this cap: far_field_pair_error(s_in max).
double tolerance_floor(Moments m, double max_cutoff = kDefaultMaxAutoCutoff);

/// The switch w(s) of the band (formula above); a band with s_in >= s_cut is the hard step.
double cutoff_weight(double s, const CutoffBand& band);

}  // namespace stokesian::lubrication
