#pragma once
// Symmetric traceless 3x3 tensors (stresslets S, strain rates E) as 5-vectors.
//
// Orthonormal basis under the Frobenius product A:B = A_ij B_ij:
//   B1 = (xx - yy)/sqrt2, B2 = (2zz - xx - yy)/sqrt6, B3 = (xy + yx)/sqrt2,
//   B4 = (xz + zx)/sqrt2, B5 = (yz + zy)/sqrt2.
// With s_m = S:B_m and e_m = E:B_m, the pairing E:S equals e.s, so the grand mobility written in
// these coordinates is a symmetric matrix.
#include "engine/core/types.hpp"

#include <array>
#include <cmath>

namespace stokesian {

using Vec5 = Eigen::Matrix<double, 5, 1>;

inline Vec5 to_vec5(const Mat3& A) {
  const double r2 = std::sqrt(0.5), r6 = 1.0 / std::sqrt(6.0);
  Vec5 v;
  v << r2 * (A(0, 0) - A(1, 1)), r6 * (2.0 * A(2, 2) - A(0, 0) - A(1, 1)), r2 * (A(0, 1) + A(1, 0)),
      r2 * (A(0, 2) + A(2, 0)), r2 * (A(1, 2) + A(2, 1));
  return v;
}

inline Mat3 from_vec5(const Vec5& v) {
  const double r2 = std::sqrt(0.5), r6 = 1.0 / std::sqrt(6.0);
  Mat3 A;
  A(0, 0) = r2 * v[0] - r6 * v[1];
  A(1, 1) = -r2 * v[0] - r6 * v[1];
  A(2, 2) = 2.0 * r6 * v[1];
  A(0, 1) = A(1, 0) = r2 * v[2];
  A(0, 2) = A(2, 0) = r2 * v[3];
  A(1, 2) = A(2, 1) = r2 * v[4];
  return A;
}

// The basis tensors B_1 ... B_5 themselves (B_m = from_vec5(unit vector m)).
inline const std::array<Mat3, 5>& sym_traceless_basis() {
  static const std::array<Mat3, 5> basis = [] {
    std::array<Mat3, 5> b;
    for (int m = 0; m < 5; ++m) b[std::size_t(m)] = from_vec5(Vec5::Unit(m));
    return b;
  }();
  return basis;
}

// A symmetric 3x3 tensor as its 6 independent Cartesian components xx, xy, xz, yy, yz, zz (the
// storage of stresslets and stress tensors in output files).
using Vec6 = Eigen::Matrix<double, 6, 1>;
inline Vec6 six_components(const Mat3& A) {
  Vec6 v;
  v << A(0, 0), 0.5 * (A(0, 1) + A(1, 0)), 0.5 * (A(0, 2) + A(2, 0)), A(1, 1), 0.5 * (A(1, 2) + A(2, 1)), A(2, 2);
  return v;
}
inline Vec6 six_components(const Vec5& s) { return six_components(from_vec5(s)); }

}  // namespace stokesian
