#pragma once
// Sweep files (TOML): a base scene and the keys to vary, expanded into one scene per run.
// Every key, its type, unit and default is documented in docs/sweeps.md.
//
//   base = "scene.toml"                     # relative to the sweep file
//   [set]      "time.steps" = 1000          # keys set alike in every run
//   [[grid]]   key = "fluid.kT"   values = [0.5, 1.0]            # cartesian product of the grids
//   [[zip]]    keys = ["time.dt", "time.steps"]                   # one factor: lists taken together
//              values = [[0.01, 100], [0.02, 50]]
//   [replicas] count = 3                    # innermost factor; the scene's seeds are derived
//   [summary]  observables = [...]  window = [0.5, 1.0]
//   [slurm]    partition, time, cpus_per_task, mem, account, extra
//
// Runs are numbered in expansion order: the factors in file order (grids, then zips, then
// replicas), the last factor varying fastest. Every expanded scene is validated by the scene
// parser before anything runs; an error names the file and line of the offending value (the
// sweep file for swept values, the base scene for its own keys) and the run.
#include <cstdint>
#include <string>
#include <vector>

namespace stokesian::io {

struct SweepRun {
  std::size_t index = 0;
  std::string name;                 // "run_0007": the run's folder
  std::vector<std::string> values;  // one per Sweep::columns entry, as TOML text (strings quoted)
  int replica = 0;
  std::string scene;                // resolved scene TOML (io::resolved_toml)
};

struct SummarySpec {
  std::vector<std::string> observables;  // scalar observables to average; empty: every one a run writes
  double window_begin = 0.5, window_end = 1.0;  // fraction of each run's recorded time span
};

struct SlurmSpec {
  std::string partition, time = "01:00:00", mem = "2G", account;
  int cpus_per_task = 1;
  std::vector<std::string> extra;  // further "#SBATCH" lines, verbatim
};

struct Sweep {
  std::string path;                  // the sweep file
  std::string base;                  // the base scene's path (resolved against the sweep file)
  std::vector<std::string> columns;  // swept keys in factor order, then "replica" if any
  std::vector<SweepRun> runs;
  int replicas = 1;
  SummarySpec summary;
  SlurmSpec slurm;
};

// Throws ConfigError naming file, line and key; nothing is run or written.
Sweep load_sweep(const std::string& path);
Sweep parse_sweep(const std::string& text, const std::string& path);

// Seed of replica r derived from a scene seed (replica 0 keeps the scene's seed): a SplitMix64
// hash of (seed, r), reduced to [0, 2^31).
std::int64_t replica_seed(std::int64_t seed, int replica);

}  // namespace stokesian::io
