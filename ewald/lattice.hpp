#pragma once
// Periodic (optionally Lees-Edwards sheared) lattice of a Domain and its reciprocal lattice.
//
// Real lattice: the columns of Domain::lattice() (engine/core/domain.hpp), at the reduced strain
// gamma', so that every lattice sum is exactly periodic in the strain with period Lx / Ly.
// Reciprocal lattice: B = 2 pi A^{-T} (columns b_j, a_i . b_j = 2 pi d_ij), wave vectors k = B n.
// Fractional coordinates s = A^{-1} x are periodic on the unit cube and k . x = 2 pi n . s.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

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
