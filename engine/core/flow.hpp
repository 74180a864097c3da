#pragma once
// Ambient (imposed) flows, sampled per particle.
//
// Solvers see the ambient flow only through a FlowSample: u_inf(x_i), Omega_inf(x_i) and
// E_inf(x_i) at each centre (the Faxen data of a rigid sphere in a locally linear flow). A flow
// that is not linear (e.g. a channel flow tabulated by a fluid solver) is one more AmbientField.
//
// Linear flows u_inf(x) = Omega_inf x x + E_inf x:
//   simple shear, rate g:     u = (g y, 0, 0): E = g/2 (xy + yx), Omega = (0, 0, -g/2)
//   planar extension, rate g: u = (g x, -g y, 0): E = diag(g, -g, 0), Omega = 0
#include "engine/core/scene.hpp"
#include "engine/core/sym_traceless.hpp"

#include <vector>

namespace stokesian {

struct FlowSample {
  std::vector<Vec3> u;      // u_inf at each centre
  std::vector<Vec3> omega;  // Omega_inf (half the vorticity)
  std::vector<Vec5> E;      // rate of strain, symmetric-traceless coordinates
};

class AmbientField {
 public:
  virtual ~AmbientField() = default;
  virtual void sample(const std::vector<Vec3>& x, FlowSample& out) const = 0;
  virtual bool has_strain() const = 0;  // E_inf != 0 somewhere
  virtual bool any() const = 0;         // any ambient motion
};

// A linear flow (constant E and Omega), including no flow at all.
struct AmbientFlow final : AmbientField {
  Mat3 E = Mat3::Zero();      // rate of strain
  Vec3 Omega = Vec3::Zero();  // angular velocity of the fluid (half the vorticity)
  Vec3 velocity(const Vec3& x) const { return Omega.cross(x) + E * x; }
  bool has_strain() const override { return E.norm() > 0.0; }
  bool any() const override { return has_strain() || Omega.norm() > 0.0; }
  void sample(const std::vector<Vec3>& x, FlowSample& out) const override {
    const std::size_t n = x.size();
    out.u.resize(n);
    out.omega.assign(n, Omega);
    out.E.assign(n, to_vec5(E));
    for (std::size_t i = 0; i < n; ++i) out.u[i] = velocity(x[i]);
  }
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

// Rate at which the Lees-Edwards strain of a periodic box advances (d gamma / dt): the shear
// rate of a simple shear, 0 otherwise. The box deforms with the flow; open domains have no box.
inline double lattice_strain_rate(const FlowParams& p, const Domain& d) {
  return d.periodic() && p.kind == FlowParams::Kind::simple_shear ? p.rate : 0.0;
}

}  // namespace stokesian
