#pragma once
// Two-sphere resistance functions for unequal rigid spheres in Stokes flow.
//
// Mathematics (see docs/lubrication.md for the full statement and accuracy table):
//  * Jeffrey & Onishi 1984, J. Fluid Mech. 139, 261 (JO84): X^A, Y^A, Y^B, X^C, Y^C.
//  * Jeffrey 1992, Phys. Fluids A 4, 16 (J92): X^G, Y^G, Y^H, X^M, Y^M, Z^M.
//  * Corrections of Townsend, arXiv:1802.08226 (v4, 2023) to the recurrences and the
//    near-contact coefficients of JO84/J92.
//
// Geometry: sphere 1 (radius a1) at x1, sphere 2 (radius a2) at x2, r = |x2 - x1|,
// d = (x2 - x1)/r (unit vector FROM sphere 1 TO sphere 2), lambda = a2/a1,
// s = 2r/(a1 + a2) (> 2), gap xi = s - 2.
//
// Convention (JO84 section 1, J92 section II): particles exert (F, T, S) on the fluid and
//   (F_a, T_a, S_a) = sum_b [ A_ab  Bt_ab  Gt_ab ] (U_b - U_inf(x_b), Omega_b - Omega_inf, -E_inf)
//                           [ B_ab  C_ab   Ht_ab ]
//                           [ G_ab  H_ab   M_ab  ]
// with, for each ordered pair (a, b) in {1,2}^2,
//   A_ij   = X^A (d_i d_j) + Y^A (delta_ij - d_i d_j)
//   B_ij   = Y^B eps_ijk d_k
//   C_ij   = X^C (d_i d_j) + Y^C (delta_ij - d_i d_j)
//   G_ijk  = X^G (d_i d_j - delta_ij/3) d_k + Y^G (d_i delta_jk + d_j delta_ik - 2 d_i d_j d_k)
//   H_ijk  = Y^H (eps_ikl d_l d_j + eps_jkl d_l d_i)
//   M_ijkl = X^M d0_ijkl + Y^M d1_ijkl + Z^M d2_ijkl   (J92), with
//     d0 = 3/2 (d_i d_j - delta_ij/3)(d_k d_l - delta_kl/3)
//     d1 = 1/2 (d_i delta_jl d_k + d_j delta_il d_k + d_i delta_jk d_l + d_j delta_ik d_l
//               - 4 d_i d_j d_k d_l)
//     d2 = 1/2 (delta_ik delta_jl + delta_jk delta_il - delta_ij delta_kl + d_i d_j delta_kl
//               + delta_ij d_k d_l - d_i delta_jl d_k - d_j delta_il d_k - d_i delta_jk d_l
//               - d_j delta_ik d_l + d_i d_j d_k d_l)
// and Bt_ab = B_ba^T, Gt_ab = G_ba^T, Ht_ab = H_ba^T (reciprocal theorem).
//
// Normalisation (JO84, J92; verified by the far-field tests): the dimensional function is the
// dimensionless one returned here times
//   X^A, Y^A            : 3 pi mu (a_a + a_b)
//   Y^B                 : pi mu (a_a + a_b)^2
//   X^C, Y^C            : pi mu (a_a + a_b)^3
//   X^G, Y^G            : pi mu (a_a + a_b)^2
//   Y^H                 : pi mu (a_a + a_b)^3
//   X^M, Y^M, Z^M       : (5/6) pi mu (a_a + a_b)^3
// e.g. F_1 = 3 pi mu (a1+a2) [X^A_12 d d + Y^A_12 (I - d d)] . U_2 for sphere 2 moving alone,
// and F_1 = 6 pi mu a1 [X^A_11 dd + Y^A_11 (I - dd)] . U_1 for sphere 1 moving alone.
// Isolated spheres: X^A_11 = Y^A_11 = X^C_11 = Y^C_11 = X^M_11 = Y^M_11 = Z^M_11 = 1, others 0.
//
// Sphere relabelling (1 <-> 2 is lambda -> 1/lambda and d -> -d):
//   F_22(s, lambda) =  F_11(s, 1/lambda),  F_21(s, lambda) =  F_12(s, 1/lambda)
// for F in {X^A, Y^A, X^C, Y^C, Y^H, X^M, Y^M, Z^M} (tensor forms even in d), and with a minus
// sign for F in {Y^B, X^G, Y^G} (tensor forms odd in d).  relabel_spheres() applies this.
// (Y^H has d twice, hence no sign change; the pair-matrix tests fail if one is added.)

#include <Eigen/Dense>

#include <array>
#include <vector>

namespace stokesian::lubrication {

/// The 22 dimensionless scalars of the ordered pair (1,2): "11" = self term of sphere 1,
/// "12" = effect on sphere 1 of the motion of sphere 2 (JO84/J92 normalisation, see above).
struct ResistanceScalars {
  double XA11, XA12, YA11, YA12, YB11, YB12, XC11, XC12, YC11, YC12, XG11, XG12, YG11, YG12,
      YH11, YH12, XM11, XM12, YM11, YM12, ZM11, ZM12;
};

/// Number of scalars in ResistanceScalars and access by index (order of the members above).
inline constexpr int kNumScalars = 22;
double& scalar_at(ResistanceScalars& r, int i);
double scalar_at(const ResistanceScalars& r, int i);
/// Name of scalar i, e.g. "XA11".
const char* scalar_name(int i);

/// Relabel the spheres: given the scalars evaluated at (s, 1/lambda), return the scalars with
/// indices 22 (stored in the "11" members) and 21 (stored in the "12" members) at (s, lambda).
ResistanceScalars relabel_spheres(const ResistanceScalars& at_inverse_lambda);

/// Near-contact form F ~ g1/xi + g2 ln(1/xi) + constant + g3 xi ln(1/xi) of one function
/// (JO84 eq. 3.17 etc.), in the same normalisation as ResistanceScalars.
struct NearContactForm {
  double g1 = 0, g2 = 0, g3 = 0, constant = 0;
  double operator()(double xi) const;
};

/// All resistance functions for one size ratio lambda = a2/a1 (0 < lambda; tested for
/// 0.01 <= lambda <= 100).  The series order K (highest power of 1/s) defaults to
/// default_order(lambda): 200 for max(lambda, 1/lambda) <= 4, 400 up to 16, 800 beyond
/// (construction ~0.1 s, 0.5 s, 1-3 s: lambda-weighted recurrences, at most O(K^3) time and
/// O(K^2) memory, much less for very unequal spheres; K is limited to [20, 1200]).  The
/// recurrence sums are cached per (lambda, K) in the process.
class ResistanceSeries {
 public:
  explicit ResistanceSeries(double lambda, int order = 0);
  static int default_order(double lambda);

  double lambda() const { return lambda_; }
  int order() const { return order_; }

  /// All 22 scalars at gap xi = s - 2 > 0 (use this form near contact to avoid losing digits
  /// of xi in s).
  ResistanceScalars at_gap(double xi) const;
  /// All 22 scalars at s = 2r/(a1+a2) > 2.
  ResistanceScalars at_s(double s) const { return at_gap(s - 2.0); }

  /// Pure near-contact forms (asymptotic, JO84/J92), constants computed from our series.
  const std::array<NearContactForm, kNumScalars>& near_contact() const { return near_; }
  ResistanceScalars near_contact_at_gap(double xi) const;

  /// Plain truncated far-field power series in 1/s (no near-contact resummation); valid and
  /// converged for s >= about 2.5.  X^C uses the exact bispherical sum in both paths.
  ResistanceScalars far_field_series(double s) const;

  /// Separation s above which at_gap() uses the plain series (the two agree to <= 5e-13 there).
  static constexpr double kSwitchS = 3.0;

  /// Series coefficient c_k (natural normalisation, see docs) of function i (0..21).
  double coefficient(int i, int k) const { return fn_[i].c.empty() ? 0.0 : fn_[i].c[k]; }
  /// Remainder c_k - a_k after subtracting the near-contact asymptotic part.
  double remainder(int i, int k) const { return fn_[i].r.empty() ? 0.0 : fn_[i].r[k]; }

 private:
  struct Function {
    std::vector<double> c;  // c_k, k = 0..order (zero for the wrong parity)
    std::vector<double> r;  // c_k - asymptotic part a_k
    int parity = 0;         // 0: even powers, 1: odd powers
    double g1 = 0, g2 = 0, g3 = 0;  // asymptotic a_k = g1 + 2 g2/k - 4 g3/(k(k+2))
    double factor = 1;      // sign and normalisation (2/(1+lambda))^m
  };
  double series_value(const Function& f, double xi, bool resum) const;
  void xc_values(double xi, double& xc11, double& xc12) const;

  double lambda_;
  int order_;
  std::array<Function, kNumScalars> fn_{};  // XC entries unused
  std::array<NearContactForm, kNumScalars> near_{};
};

/// Convenience: scalars of the ordered pair (1,2) at (s, lambda).  Rebuilds a
/// ResistanceSeries unless lambda equals the previous call's (per thread); for many pairs use
/// ResistanceSeries or ResistanceTable directly.
ResistanceScalars resistance_scalars(double s, double lambda);
/// Scalars 22 (in the "11" members) and 21 (in the "12" members) at (s, lambda).
ResistanceScalars resistance_scalars_22_21(double s, double lambda);

/// Dense FTS resistance matrix of an isolated pair, 22 x 22, in the engine's interleaved layout
/// [F1(3) T1(3) S1(5) F2(3) T2(3) S2(5)] = R [U1 Om1 e1 U2 Om2 e2], where U_a, Om_a are the
/// particle velocities relative to the ambient flow at the particle and e_a are the 5
/// coordinates of -E_inf in the orthonormal basis of engine/core/sym_traceless.hpp (so for a
/// uniform ambient strain both e columns carry the same -E_inf).  F, T, S are exerted by the
/// particles on the fluid.  Blocks: A, Bt, Gt / B, C, Ht / G, H, M of JO84/J92 with the
/// normalisations above; R is symmetric and positive definite.
/// r_vec = x2 - x1 (|r_vec| > a1 + a2), radii a1, a2, viscosity mu.
using PairMatrix = Eigen::Matrix<double, 22, 22>;
PairMatrix two_sphere_resistance(const Eigen::Vector3d& r_vec, double a1, double a2, double mu);
/// Same, from precomputed scalars (e.g. from ResistanceTableCache::pair_scalars):
/// s11_12 at (s, a2/a1) and s22_21 = relabel_spheres(scalars at (s, a1/a2)).
PairMatrix two_sphere_resistance(const Eigen::Vector3d& r_vec, double a1, double a2, double mu,
                                 const ResistanceScalars& s11_12,
                                 const ResistanceScalars& s22_21);
/// The same assembled term by term from the tensors G_ijk, H_ijk, M_ijkl of JO84/J92 contracted
/// with the basis: the plain reference twin of the closed-form contraction above (tests).
PairMatrix two_sphere_resistance_reference(const Eigen::Vector3d& r_vec, double a1, double a2, double mu,
                                           const ResistanceScalars& s11_12, const ResistanceScalars& s22_21);

namespace detail {
/// Sums sum_q T_{n,k-q,q} lambda^q/(1+lambda)^k, k = 0..order, of coefficient array id
/// (0..9: XA P1, YA P1, YA Q1, YC Q1, XA P2, YA P2, YC P2, XM P2, YM P2, ZM P2), from the
/// lambda-weighted recurrences (reference = false, used by ResistanceSeries) or from the
/// lambda-independent O(K^4) recurrences (reference = true; for tests only).
std::vector<double> series_sums(double lambda, int order, int id, bool reference);
}  // namespace detail

/// Hurwitz zeta(3, a) for a > 0 (used for the X^C contact values).
double hurwitz_zeta3(double a);

}  // namespace stokesian::lubrication
