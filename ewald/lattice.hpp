#pragma once
// Periodic (optionally Lees-Edwards sheared) lattice of a Domain and its reciprocal lattice.
//
// Real lattice: a1 = (Lx, 0, 0), a2 = (gamma Ly, Ly, 0), a3 = (0, 0, Lz), gamma the Lees-Edwards
// strain (Domain::shear_strain). Since a2 + n a1 spans the same lattice, gamma is reduced to
// gamma' = gamma - round(gamma Ly / Lx) Lx / Ly (|gamma' Ly| <= Lx / 2): the lattice, hence every
// lattice sum, is exactly periodic in gamma with period Lx / Ly.
// Reciprocal lattice: B = 2 pi A^{-T} (columns b_j, a_i . b_j = 2 pi d_ij), wave vectors k = B n.
// Fractional coordinates s = A^{-1} x are periodic on the unit cube and k . x = 2 pi n . s.
#include "engine/state.hpp"
#include "engine/types.hpp"

namespace stokesian::ewald {

struct Lattice {
  Mat3 A = Mat3::Identity();   // columns a1, a2, a3
  Mat3 Ainv = Mat3::Identity();
  Mat3 B = Mat3::Identity();   // columns b1, b2, b3 = 2 pi A^{-T}
  double volume = 1.0;         // det A = Lx Ly Lz
  double strain = 0.0;         // reduced strain gamma'

  // Throws std::invalid_argument for an open domain or a non-positive box.
  static Lattice from_domain(const Domain& d);
  // The point of the lattice image of r closest to the origin (exact for any strain).
  Vec3 nearest_image(const Vec3& r) const;
  // Smallest |A n|, n != 0 (shortest lattice vector).
  double shortest_vector() const;
};

}  // namespace stokesian::ewald
