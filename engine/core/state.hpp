#pragma once
// The dynamic state of a simulation: everything a checkpoint must hold to continue a run exactly.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace stokesian {

struct State {
  std::vector<Vec3> position;  // centres, units of a
  std::vector<double> radius;  // units of a
  std::vector<char> fixed;     // 1 = immobile (wall) particle
  double time = 0.0;           // units of the scene's time unit (docs/units.md)
  std::int64_t step = 0;
  double dt = 0.0;             // current step (adaptive integrators change it)
  Domain domain;
  // Random-number generator state (Rng serialised as text) for exact restarts.
  std::string rng_state;
  std::size_t size() const { return position.size(); }
};

}  // namespace stokesian
