#pragma once
// The dynamic state of a simulation: everything a checkpoint must hold to continue a run exactly.
//
// Image counts. In a periodic box a position is kept in the primary cell; `image` counts the
// lattice vectors removed so far, so that the unwrapped position is
//   u = x + n_x a1 + n_y a2 + n_z a3,   a1 = (Lx,0,0), a2 = (gamma Ly, Ly, 0), a3 = (0,0,Lz),
// with the box's current strain gamma (Domain). Under Lees-Edwards shear a2 moves with the flow,
// so u is the position of the particle's image in the n_y-th layer, which the flow carries along:
// u is continuous in time and its velocity is the particle's velocity in the unbounded sheared
// suspension (the wrapped velocity plus n_y Ly d(gamma)/dt in x). When the stored strain is
// reduced by k periods (gamma -> gamma - k Lx/Ly, Domain::strained_by) a2 changes by -k a1, and
// n_x gains k n_y so that u does not jump.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace stokesian {

struct State {
  std::vector<Vec3> position;  // centres, units of a (wrapped into the box when periodic)
  std::vector<double> radius;  // units of a
  std::vector<char> fixed;     // 1 = immobile (wall) particle
  // Periodic boxes: lattice vectors removed by wrapping (header); empty for open domains or
  // before the first wrap (then all zero).
  std::vector<std::array<std::int32_t, 3>> image;
  double time = 0.0;           // units of the scene's time unit (docs/units.md)
  std::int64_t step = 0;
  double dt = 0.0;             // current step (adaptive integrators change it)
  Domain domain;
  // Random-number generator state (Rng serialised as text) for exact restarts.
  std::string rng_state;
  // Sums over the steps taken since the last frame, for observables that average over those steps
  // (engine/stress.hpp: the Brownian stresslet samples); cleared after each frame, kept by checkpoints.
  std::int64_t brownian_samples = 0;
  Mat3 brownian_stresslet_sum = Mat3::Zero();  // sum over samples of sum_i (A(x') - A(x0)) xi [kT]
  // Open channels ([inflow], engine/inflow.hpp): id[i] is the serial number of the particle in slot
  // i, -1 for an empty slot (whose position is NaN); empty when the scene has no inflow.
  std::vector<std::int64_t> id;
  struct InflowTally {
    double credit = 0.0;         // particles due at the inlet and not yet placed
    double pending = -1.0;       // place along the inlet (s in [0, 1]) of the next one; -1: not drawn
    double waited = 0.0;         // time the next one has waited at `pending`
    std::int64_t next_id = 0;    // serial number of the next particle
    std::int64_t inserted = 0, removed = 0;
    std::int64_t deferred = 0;   // steps whose due particles could not all be placed
    std::int64_t redrawn = 0;    // due particles whose blocked place was given up for a new one
  } inflow;
  std::size_t size() const { return position.size(); }
};

// Wrap every position into the box (Domain::wrap) and add the removed lattice vectors to
// s.image. `unreduced_strain` is the strain of the box before Lees-Edwards reduction (equal to
// s.domain.shear_strain when the box is not sheared); the difference is a whole number of
// periods Lx/Ly, which is moved into the x counts (header).
inline void wrap_positions(State& s, double unreduced_strain) {
  if (!s.domain.periodic()) return;
  s.image.resize(s.size(), {0, 0, 0});
  const Vec3& L = s.domain.box;
  const double g = s.domain.shear_strain;
  const auto k = static_cast<std::int32_t>(std::lround((unreduced_strain - g) * L.y() / L.x()));
  for (std::size_t i = 0; i < s.size(); ++i) {
    Vec3& x = s.position[i];
    const Vec3 before = x;
    s.domain.wrap(x);
    const Vec3 d = before - x;  // = n_x a1 + n_y a2 + n_z a3
    const auto ny = static_cast<std::int32_t>(std::lround(d.y() / L.y()));
    const auto nz = static_cast<std::int32_t>(std::lround(d.z() / L.z()));
    const auto nx = static_cast<std::int32_t>(std::lround((d.x() - ny * g * L.y()) / L.x()));
    auto& n = s.image[i];
    n[0] += k * n[1] + nx;
    n[1] += ny;
    n[2] += nz;
  }
}

// Unwrapped position of particle i (header); x itself for open domains.
inline Vec3 unwrapped(const State& s, std::size_t i) {
  if (!s.domain.periodic() || s.image.empty()) return s.position[i];
  const Vec3& L = s.domain.box;
  const auto& n = s.image[i];
  return s.position[i] + Vec3(n[0] * L.x() + n[1] * s.domain.shear_strain * L.y(), n[1] * L.y(), n[2] * L.z());
}

}  // namespace stokesian
