#pragma once
// Error types. ConfigError: bad scene input (names file, line, key, value, allowed range).
// PhysicsError: a bad physical state during a run (overlap, non-convergence, NaN), naming the
// particle and step where known. Both are reported by the CLI with a non-zero exit status.
#include <stdexcept>
#include <string>

namespace stokesian {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct PhysicsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace stokesian
