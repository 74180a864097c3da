// Lattice of a periodic domain; geometry stated in lattice.hpp.
#include "ewald/lattice.hpp"

#include <cmath>
#include <stdexcept>

namespace stokesian::ewald {

Lattice Lattice::from_domain(const Domain& d) {
  if (!d.periodic()) throw std::invalid_argument("ewald: the domain is not periodic");
  if (!(d.box.minCoeff() > 0.0)) throw std::invalid_argument("ewald: periodic box with non-positive edge");
  Lattice l;
  l.strain = d.reduced_strain();
  l.A = d.lattice();
  l.Ainv = l.A.inverse();
  l.B = 2.0 * kPi * l.Ainv.transpose();
  l.volume = d.box.x() * d.box.y() * d.box.z();
  return l;
}

Vec3 Lattice::nearest_image(const Vec3& r) const {
  // Round the fractional coordinates, then search the 27 neighbouring images (the reduced basis
  // is nearly orthogonal, |gamma'| <= Lx / (2 Ly), so the nearest image is among them).
  Vec3 s = Ainv * r;
  for (int i = 0; i < 3; ++i) s[i] -= std::round(s[i]);
  const Vec3 base = A * s;
  Vec3 best = base;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k) {
        const Vec3 c = base + A * Vec3(i, j, k);
        if (c.squaredNorm() < best.squaredNorm()) best = c;
      }
  return best;
}

double Lattice::shortest_vector() const {
  double best = 1e300;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k)
        if (i || j || k) best = std::min(best, (A * Vec3(i, j, k)).norm());
  return best;
}

}  // namespace stokesian::ewald
