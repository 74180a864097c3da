#include "engine/core/domain.hpp"

#include <cmath>

namespace stokesian {

Vec3 Domain::minimum_image(const Vec3& d) const {
  if (kind == Kind::open) return d;
  Vec3 r = d;
  const double ny = std::round(r.y() / box.y());
  r.x() -= ny * shear_strain * box.y();
  r.y() -= ny * box.y();
  r.x() -= std::round(r.x() / box.x()) * box.x();
  r.z() -= std::round(r.z() / box.z()) * box.z();
  return r;
}

void Domain::wrap(Vec3& x) const {
  if (kind == Kind::open) return;
  const double ny = std::floor(x.y() / box.y());
  x.x() -= ny * shear_strain * box.y();
  x.y() -= ny * box.y();
  x.x() -= std::floor(x.x() / box.x()) * box.x();
  x.z() -= std::floor(x.z() / box.z()) * box.z();
}

double Domain::reduce_strain(double strain, const Vec3& box) {
  const double period = box.x() / box.y();
  return strain - period * std::round(strain / period);
}

Domain Domain::strained_by(double increment) const {
  Domain d = *this;
  d.shear_strain = reduce_strain(shear_strain + increment, box);
  return d;
}

Mat3 Domain::lattice() const {
  const double g = reduced_strain();
  Mat3 A;
  A << box.x(), g * box.y(), 0.0, 0.0, box.y(), 0.0, 0.0, 0.0, box.z();
  return A;
}

Vec3 Domain::fractional(const Vec3& x) const {
  const double g = reduced_strain();
  return Vec3((x.x() - g * x.y()) / box.x(), x.y() / box.y(), x.z() / box.z());
}

}  // namespace stokesian
