#pragma once
// `stokesian average`: time averages of a trajectory's observables over a window, with standard
// errors from block averaging (engine/core/statistics.hpp; the same estimator as the sweep
// summary, docs/sweeps.md). The window is given in accumulated shear strain (simple shear:
// strain = rate * time, the scene's rate), in time, or as fractions of the recorded time span
// (default [0.5, 1]). Output: one line per observable component (docs/cli.md).
#include <cstdio>
#include <string>
#include <vector>

namespace stokesian::app {

struct AverageOptions {
  enum class Axis { fraction, time, strain } axis = Axis::fraction;
  double from = 0.5, to = 1.0;           // window on that axis (inclusive)
  std::vector<std::string> observables;  // empty: all
};

// Parses "A:B" (two numbers, A < B) for --strain/--time/--window; throws std::invalid_argument
// with a message naming the option and the allowed form.
void parse_window(const std::string& option, const std::string& text, AverageOptions& opt);

// Prints the table to `out`; IoError for an unreadable file, ConfigError for a strain window on a
// trajectory without simple shear, or an observable the file does not hold.
int average(const std::string& trajectory, const AverageOptions& opt, std::FILE* out);

}  // namespace stokesian::app
