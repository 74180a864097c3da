#pragma once
// Channels: the fluid region bounded by walls of immobile "wall particles" (constrained SD, Lee et
// al. 2024 [L24] §2.1.3, excluded-volume placement of its fig. 2a), and the pressure-driven flows
// through them used as ambient flows.
//
// Geometry (the scene's [walls] table; docs/channels.md). The flow runs along x. With centre c
// (the box centre in a periodic domain, the origin in an open one) and eta = y - c_y, zeta = z - c_z:
//   plane: fluid y > c_y (one wall below; no height)
//   slit:  fluid |eta| < H/2 (walls normal to y)
//   duct:  fluid |eta| < H/2 and |zeta| < W/2 (walls normal to y and to z)
// Wall particles of radius r_w lie wholly outside the fluid and touch its boundary (centres at
// distance r_w outside it); trees/walls.hpp places them.
//
// Pressure-driven flows, u = (u(eta, zeta), 0, 0), zero outside the fluid (so excluded-volume wall
// particles, whose centres lie outside, see no ambient flow: [L24] needs U, Omega, E = 0 there):
//   plane Poiseuille (slit): u = (3/2) U (1 - (2 eta / H)^2), U the mean velocity.
//   rectangular duct, a = H/2, b = W/2, G/mu = -(dp/dx)/mu (White, Viscous Fluid Flow, 3rd ed.
//   2006, the rectangular duct; Shah & London 1978 for the check values in tests/test_channel.cpp):
//     u = (G/2mu)(a^2 - eta^2) - (16 a^2 G / (mu pi^3)) sum_{n odd} (-1)^((n-1)/2) n^-3
//           cosh(n pi zeta / 2a) / cosh(n pi b / 2a) cos(n pi eta / 2a)
//     U = (G a^2 / 3mu) [1 - (192 a / (pi^5 b)) sum_{n odd} n^-5 tanh(n pi b / 2a)]
//   The correction series converges like exp(-n pi (b - |zeta|) / 2a); it is summed until its terms
//   fall below 1e-16 of the leading one (at most kDuctTerms terms).
// The particles see u, Omega = (1/2) curl u = (0, u_z / 2, -u_y / 2) and E = sym grad u at their
// centres (Faxen's laws without the (a^2/6) lap u term: [L24] eq. 2.12, method note P22; for plane
// Poiseuille that term is -(4/3)(a/H)^2 u_c everywhere, u_c the centreline speed).
#include "engine/core/flow.hpp"

#include <memory>
#include <vector>

namespace stokesian {

// The channel's centre: box centre (periodic) or origin (open).
inline Vec3 channel_centre(const Domain& d) { return d.periodic() ? Vec3(0.5 * d.box) : Vec3::Zero(); }

// Whether the point x lies in the fluid region (strictly inside the walls' boundary).
bool in_channel(const ChannelParams& c, const Domain& d, const Vec3& x);
// The first of the points outside the fluid region, or -1 when all are inside (the geometry built
// once for all of them).
long first_outside_channel(const ChannelParams& c, const Domain& d, const std::vector<Vec3>& x);

// Cross-section normal to the flow [a^2]: H x (box z edge, or `depth` in open domains) for a slit,
// H W for a duct; 0 for a plane wall (no cross-section).
double cross_section_area(const ChannelParams& c, const Domain& d);

constexpr int kDuctTerms = 20000;

// Pressure-driven flow of mean velocity U through a slit or duct (header formulas).
class ChannelFlow final : public AmbientField {
 public:
  ChannelFlow(const ChannelParams& c, const Domain& d, double mean_velocity);
  void sample(const std::vector<Vec3>& x, FlowSample& out) const override;
  bool has_strain() const override { return mean_ != 0.0; }
  bool any() const override { return mean_ != 0.0; }
  // u_x at x and its gradient (du/deta, du/dzeta); zero outside the fluid.
  double velocity(const Vec3& x, double* du_dy = nullptr, double* du_dz = nullptr) const;
  double max_velocity() const { return velocity(centre_); }
  // G / mu = -(dp/dx) / mu of the particle-free flow [1/(a time)].
  double pressure_gradient_over_viscosity() const { return g_mu_; }

 private:
  ChannelParams c_;
  Domain d_;
  Vec3 centre_;
  double mean_ = 0.0;
  double g_mu_ = 0.0;
};

// A velocity field tabulated on a rectilinear grid by a fluid solver ([flow] kind = "tabulated";
// io/flow_table.hpp reads it). Interpolation: u by trilinear interpolation of the nodal velocities;
// grad u by trilinear interpolation of nodal gradients (central differences inside, one-sided at
// the grid's faces). Both are second-order accurate in the spacing h for smooth fields;
// tests/test_channel.cpp measures the error on a sampled duct flow. A grid with a single plane
// along an axis is uniform along it (2D exports). Outside the grid the flow is zero; a node without
// data (NaN, e.g. inside a solid) counts as zero velocity, the no-slip value.
// Omega = (1/2) curl u, E = sym grad u minus its trace / 3 (the solver's residual divergence).
class TabulatedFlow final : public AmbientField {
 public:
  explicit TabulatedFlow(std::shared_ptr<const FlowGrid> g);
  void sample(const std::vector<Vec3>& x, FlowSample& out) const override;
  bool has_strain() const override { return strain_; }
  bool any() const override { return moving_; }
  // u at x and its gradient G_ij = du_i/dx_j.
  Vec3 velocity(const Vec3& x, Mat3* grad = nullptr) const;

 private:
  std::shared_ptr<const FlowGrid> g_;
  std::vector<Vec3> u_;   // nodal velocities (NaN replaced by 0)
  std::vector<Mat3> du_;  // nodal gradients
  bool strain_ = false, moving_ = false;
};

// The ambient field of a scene's [flow] with its [walls]: the linear flows of flow.hpp, a
// ChannelFlow for kind = "poiseuille", a TabulatedFlow for kind = "tabulated".
std::shared_ptr<const AmbientField> make_ambient_field(const FlowParams& f, const ChannelParams& c, const Domain& d);

}  // namespace stokesian
