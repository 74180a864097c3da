#pragma once
// `stokesian sweep`: a sweep file (io/sweep.hpp) expanded into one folder per run under --out,
// run J at a time as child processes of `stokesian run --resume` (so every run keeps the run's
// own checkpoint guarantee), finished runs skipped, failures recorded, and a summary table of the
// runs' observables written at the end (docs/sweeps.md).
//
// Folder layout (DIR = --out):
//   DIR/sweep.toml            copy of the sweep file as expanded (a later call must expand alike)
//   DIR/run_XXXX/scene.toml   the run's resolved scene
//   DIR/run_XXXX/trajectory.h5 (+ .ckpt)   the run's outputs
//   DIR/run_XXXX/log.txt      stdout and stderr of every attempt, appended
//   DIR/run_XXXX/status       "done" or "failed" with exit code, message and wall time (written
//                             atomically when an attempt ends; absent while a run is unfinished)
//   DIR/summary.csv, summary.h5   one row per run
//   DIR/sweep.sbatch          with --slurm: a Slurm job array, one task per run
#include <string>

namespace stokesian::app {

struct SweepOptions {
  std::string out;       // the sweep's folder
  int jobs = 1;          // runs at a time
  int threads = 1;       // OpenMP threads per run
  long only_run = -1;    // run only this run (index), no summary (Slurm array tasks)
  bool slurm = false;    // write DIR/sweep.sbatch instead of running
  bool summary_only = false;
  bool retry_failed = false;
  bool quiet = false;
};

// Exit status as the CLI's (docs/cli.md); 6 when the sweep ended with failed runs.
int sweep(const std::string& sweep_file, const SweepOptions& opt);

}  // namespace stokesian::app
