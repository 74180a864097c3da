#include "engine/state.hpp"

#include <cmath>

namespace stokesian {

Vec3 Domain::minimum_image(const Vec3& d) const {
  if (kind == Kind::open) return d;
  Vec3 r = d;
  // Lees-Edwards: crossing the y boundary shifts x by the lattice strain times Ly.
  const double ny = std::round(r.y() / box.y());
  r.x() -= ny * shear_strain * box.y();
  r.y() -= ny * box.y();
  r.x() -= std::round(r.x() / box.x()) * box.x();
  r.z() -= std::round(r.z() / box.z()) * box.z();
  return r;
}

}  // namespace stokesian
