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

// A run stopped by a physics failure during a step (docs/reliability.md, "Failure policies during a
// run"). what() names the failed step, the failure and the particles. checkpoint_step is the step of
// the last good state, written as the checkpoint (the state before the failed step); -1 when no
// checkpoint was written because the failure is at the first evaluation of this run (the initial
// or resumed state itself fails).
struct RunStopped : PhysicsError {
  RunStopped(const std::string& what, long long failed, long long checkpoint)
      : PhysicsError(what), failed_step(failed), checkpoint_step(checkpoint) {}
  long long failed_step;
  long long checkpoint_step;
};

// A matrix that should be symmetric positive definite is not; `column` is the failing column of
// the factorisation (callers translate it into a particle and pair).
struct NotPositiveDefinite : PhysicsError {
  NotPositiveDefinite(const std::string& what, long col) : PhysicsError(what), column(col) {}
  long column;
};

}  // namespace stokesian
