#pragma once
// The application layer: the only code that joins the engine (simulation) and its writers (io/).
// A run writes its trajectory (H5MD), its checkpoint and optionally an XYZ export through one
// OutputSink; --resume continues from the checkpoint, or starts afresh when there is nothing to
// resume (no checkpoint, and no frames another run could lose). A run that reaches its last step removes
// the trajectory's working copy (.shadow) and keeps the checkpoint (docs/output.md).
#include "engine/simulation.hpp"

#include <cstdio>
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
// One solve of the initial configuration written as a single frame (no working copy, no
// checkpoint).
void solve(Simulation& sim, const std::string& out);
// Warns on `to` about the pairs of the scene's initial configuration that overlap or, with a near
// field, are closer than [hydrodynamics] lubrication_min_gap (their lubrication is regularised:
// evaluated at that gap), naming them; returns their number. `solve` calls it before solving.
std::size_t report_close_pairs(const Scene& scene, const ResolvedModel& model, std::FILE* to);

// The run's header with /h5md/author: [output] author, else default_author().
RunHeader run_header(const Simulation& sim);
// Login name of the user running the program (passwd entry, else $USER, $LOGNAME), else "unknown".
std::string default_author();
// Path of the XYZ export of a run writing trajectory `out` ("" when [output] xyz is off):
// <out stem>.xyz beside `out`, or [output] xyz resolved against the folder of `out`.
std::string xyz_path(const Scene& scene, const std::string& out);

}  // namespace stokesian::app
