#pragma once
// The dynamic state of a simulation: everything a checkpoint must hold to continue a run exactly.
#include "engine/types.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace stokesian {

// Simulation box. Open: no box, free space. Periodic: box [Lx, Ly, Lz] (units of a), with the
// Lees-Edwards strain of the lattice (x displacement of the image at +Ly, in units of Ly).
struct Domain {
  enum class Kind { open, periodic } kind = Kind::open;
  Vec3 box = Vec3::Zero();
  double shear_strain = 0.0;
  bool periodic() const { return kind == Kind::periodic; }
  // Minimum-image separation x_i - x_j (identity for open domains).
  Vec3 minimum_image(const Vec3& d) const;
};

struct State {
  std::vector<Vec3> position;  // centres, units of a
  std::vector<double> radius;  // units of a
  std::vector<char> fixed;     // 1 = immobile (wall) particle
  double time = 0.0;           // units of the scene's time unit (docs/units.md)
  std::int64_t step = 0;
  double dt = 0.0;             // current step (adaptive integrators change it)
  Domain domain;
  // Random-number generator state (std::mt19937_64 serialised as text) for exact restarts.
  std::string rng_state;
  std::size_t size() const { return position.size(); }
};

}  // namespace stokesian
