#pragma once
// The inverse of the engine's two-body far-field mobility, R2B_inf = (M2B_inf)^{-1}, as the scalars of
// the two-sphere form (lubrication/resistance_functions.hpp), so that the near-field pair block
//     R2B_exact - R2B_inf = two_sphere_resistance(r, a1, a2, mu, s_exact - s_inf)
// needs one tensor assembly per pair and no 22 x 22 inversion (near_field.hpp).
//
// Why the scalar form holds. M2B_inf of two spheres (engine/kernels/mobility_pair.hpp) is symmetric
// and invariant under rotations about the line of centres and reflections through planes containing
// it, and so is its inverse. The two-sphere form of Jeffrey & Onishi (1984, J. Fluid Mech. 139, 261)
// and Jeffrey (1992, Phys. Fluids A 4, 16), blocks A, B, C, G, H, M with the scalars XA, YA, YB, XC,
// YC, XG, YG, YH, XM, YM, ZM per ordered pair of spheres, is the general symmetric matrix with those
// symmetries; the scalars are read off in the pair frame (line of centres = e_z).
//
// Inversion in the pair frame. With d = e_z the generalised coordinates fall into groups that the
// symmetries do not mix (per sphere; m the azimuthal order, +/- the parity under y -> -y):
//     {F_z, S_zz} (m = 0, +),  {T_z} (m = 0, -),  {F_x, T_y, S_xz} (m = 1, +),  {F_y, T_x, S_yz} (m = 1, -),
//     {S_xx - S_yy} (m = 2, +),  {S_xy} (m = 2, -)
// (for the engine's basis of engine/core/sym_traceless.hpp the groups are found from the pattern of
// M2B_inf at one generic pair when this class is built). M2B_inf is block diagonal over the groups of
// both spheres, so its inverse is the inverse of blocks of at most 6 x 6 (FTS), 4 x 4 (FT) or 2 x 2 (F).
//
// Reading the scalars. Block (a, b) of the pair matrix (rows F_a, T_a, S_a; columns U_b, Omega_b,
// e_b) holds A_ab, B_ab, C_ab, G_ab, H_ab, M_ab, each linear in its own scalars with factors
// 3 pi mu L, pi mu L^2, pi mu L^3, pi mu L^2, pi mu L^3, (5/6) pi mu L^3 (L = a_a + a_b). The
// unit-scalar patterns of those entries at L = 1 come from two_sphere_resistance itself, and the
// scalars are their least-squares fit (exact up to rounding; tests/test_lubrication.cpp holds the
// resulting pair block to the direct 22 x 22 inversion).
#include "engine/core/types.hpp"
#include "lubrication/resistance_functions.hpp"

#include <vector>

namespace stokesian::lubrication {

class FarPairInverse {
 public:
  explicit FarPairInverse(Moments m);
  // Scalars of R2B_inf at the solve's moment level for sphere 1 (radius a1) at the origin and
  // sphere 2 (radius a2) at distance r: s11_12 (blocks 11 and 12) and s22_21 (blocks 22 and 21,
  // stored in the "11" and "12" members), the layout of two_sphere_resistance. Scalars that the
  // level does not hold are zero.
  void scalars(double r, double a1, double a2, double mu, ResistanceScalars& s11_12, ResistanceScalars& s22_21) const;

 private:
  Moments m_;
  int d_;
  std::vector<std::vector<int>> groups_;  // pair-frame coordinates (0 .. 2d-1) of each group
  // The least-squares fit (far_pair_inverse.cpp) as its non-zero terms: scalar type (0..10: XA YA YB
  // XC YC XG YG YH XM YM ZM), entry (row, column) inside a d x d block, power of L, weight.
  struct Term {
    int type, row, col, power;
    double weight;
  };
  std::vector<Term> terms_;
};

}  // namespace stokesian::lubrication
