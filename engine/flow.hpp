#pragma once
// Ambient (imposed) linear flows u_inf(x) = Omega_inf x x + E_inf x.
//   simple shear, rate g:   u = (g y, 0, 0): E = g/2 (xy + yx), Omega = (0, 0, -g/2)
//   planar extension, rate g: u = (g x, -g y, 0): E = diag(g, -g, 0), Omega = 0
#include "engine/scene.hpp"
#include "engine/sym_traceless.hpp"

namespace stokesian {

struct AmbientFlow {
  Mat3 E = Mat3::Zero();      // rate of strain
  Vec3 Omega = Vec3::Zero();  // angular velocity of the fluid (half the vorticity)
  Vec3 velocity(const Vec3& x) const { return Omega.cross(x) + E * x; }
  bool has_strain() const { return E.norm() > 0.0; }
  bool any() const { return has_strain() || Omega.norm() > 0.0; }
};

inline AmbientFlow ambient_flow(const FlowParams& p) {
  AmbientFlow f;
  if (p.kind == FlowParams::Kind::simple_shear) {
    f.E(0, 1) = f.E(1, 0) = 0.5 * p.rate;
    f.Omega = Vec3(0, 0, -0.5 * p.rate);
  } else if (p.kind == FlowParams::Kind::planar_extension) {
    f.E(0, 0) = p.rate;
    f.E(1, 1) = -p.rate;
  }
  return f;
}

}  // namespace stokesian
