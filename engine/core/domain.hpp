#pragma once
// The simulation box and its geometry: the only place that knows periodic images and the
// Lees-Edwards lattice (Lees & Edwards 1972).
//
// Open: no box, free space. Periodic: box [Lx, Ly, Lz] (units of a) whose lattice is spanned by
//   a1 = (Lx, 0, 0),  a2 = (gamma Ly, Ly, 0),  a3 = (0, 0, Lz),
// gamma = shear_strain (x displacement of the image at +Ly, in units of Ly). Since a2 + k a1
// spans the same lattice, gamma is equivalent to the reduced strain
//   gamma' = gamma - p round(gamma / p),  p = Lx / Ly,  |gamma'| <= p / 2,
// and every lattice sum is exactly periodic in gamma with period p. Fractional coordinates
// s = A^{-1} x (A = [a1 a2 a3] with gamma') are periodic on the unit cube:
//   s = ((x - gamma' y) / Lx, y / Ly, z / Lz).
#include "engine/core/names.hpp"
#include "engine/core/types.hpp"

namespace stokesian {

struct Domain {
  enum class Kind { open, periodic } kind = Kind::open;
  Vec3 box = Vec3::Zero();
  double shear_strain = 0.0;
  bool periodic() const { return kind == Kind::periodic; }
  // A periodic box of edges `box` [a] at Lees-Edwards strain `shear_strain`.
  static Domain periodic_box(const Vec3& box, double shear_strain = 0.0) {
    Domain d;
    d.kind = Kind::periodic;
    d.box = box;
    d.shear_strain = shear_strain;
    return d;
  }

  // Minimum-image separation x_i - x_j (identity for open domains): rounds the y image first
  // (shifting x by gamma Ly), then x and z. Exact for |x_i - x_j| < min(Lx, Ly, Lz) / 2.
  Vec3 minimum_image(const Vec3& d) const;
  // Maps a position into the primary box [0, L)^3; leaving through a y face shifts x by gamma Ly.
  void wrap(Vec3& x) const;
  // gamma' of the header formula (the strain itself for open domains).
  double reduced_strain() const { return periodic() ? reduce_strain(shear_strain, box) : shear_strain; }
  static double reduce_strain(double strain, const Vec3& box);
  // The same box after a further strain increment, strain reduced (Lees-Edwards remap).
  Domain strained_by(double increment) const;
  // Lattice matrix A = [a1 a2 a3] at the reduced strain.
  Mat3 lattice() const;
  // Fractional coordinates s (not wrapped) of the header formula, at the reduced strain.
  Vec3 fractional(const Vec3& x) const;
  // Same kind, box and strain (the strain as stored, not reduced).
  bool operator==(const Domain& o) const { return kind == o.kind && box == o.box && shear_strain == o.shear_strain; }
  bool operator!=(const Domain& o) const { return !(*this == o); }
};

template <>
struct Names<Domain::Kind> {
  static constexpr NameTable<Domain::Kind, 2> table{{{Domain::Kind::open, "open"}, {Domain::Kind::periodic, "periodic"}}};
};

}  // namespace stokesian
