#pragma once
// Error types. ConfigError: bad scene input (names file, line, key, value, allowed range).
// PhysicsError: a bad physical state during a run (overlap, non-convergence, NaN), naming the
// particle and step where known. IoError: a file that cannot be read or written, naming the file
// and the problem. All are reported by the CLI with distinct non-zero exit statuses.
#include <stdexcept>
#include <string>

namespace stokesian {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct PhysicsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A matrix that should be symmetric positive definite is not; `column` is the failing column of
// the factorisation (callers translate it into a particle and pair).
struct NotPositiveDefinite : PhysicsError {
  NotPositiveDefinite(const std::string& what, long col) : PhysicsError(what), column(col) {}
  long column;
};

}  // namespace stokesian
