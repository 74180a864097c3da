#pragma once
// The application layer: the only code that joins the engine (simulation) and its writers (io/).
// A run writes its trajectory (H5MD), its checkpoint and optionally an XYZ export through one
// OutputSink; --resume continues from the checkpoint.
#include "engine/simulation.hpp"

#include <string>

namespace stokesian::app {

struct RunOptions {
  std::string out;         // trajectory path
  bool resume = false;
  bool quiet = false;
  long max_steps = -1;     // stop after this many steps of this invocation (tests); -1 = run to the end
};

// Full run with periodic checkpoints; returns the number of steps taken by this call.
long run(Simulation& sim, const RunOptions& opt);
// One solve of the initial configuration written as a single frame.
void solve(Simulation& sim, const std::string& out);

}  // namespace stokesian::app
