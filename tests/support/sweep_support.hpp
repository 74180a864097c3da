#pragma once
// Helpers of the sweep tests (tests/test_sweep_kill.cpp, tests/test_sweep_slurm.cpp): a scratch
// folder with a base scene and a sweep file, reading files, the summary table without the
// columns that time the runs, and running `stokesian sweep` as a child process.
#include "child_process.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace stokesian::test {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The CSV without the wall_seconds and attempts columns (they measure interruptions and machines).
inline std::string summary_without_timing(const std::filesystem::path& csv) {
  std::istringstream in(slurp(csv));
  std::string line, out;
  std::vector<bool> keep;
  bool header = true;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) f.push_back(cell);
    if (header) {
      for (const auto& c : f) keep.push_back(c != "wall_seconds" && c != "attempts");
      header = false;
    }
    for (std::size_t k = 0; k < f.size(); ++k)
      if (k < keep.size() && keep[k]) out += f[k] + ",";
    out += "\n";
  }
  return out;
}

// A scratch folder (removed at the end) holding base.toml and sweep.toml.
struct SweepWork {
  std::filesystem::path dir;
  SweepWork(const std::string& tag, const std::string& base, const std::string& sweep) {
    dir = std::filesystem::temp_directory_path() / ("stokesian_" + tag + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "base.toml") << base;
    std::ofstream(dir / "sweep.toml") << sweep;
  }
  ~SweepWork() { std::filesystem::remove_all(dir); }
};

// `stokesian sweep SWEEP --out OUT --jobs J --quiet [extra...]`, stderr to OUT.stderr.
inline ChildOutcome run_sweep(const std::filesystem::path& sweep_file, const std::filesystem::path& out, double kill_ms = -1,
                              const std::vector<std::string>& extra = {}, int jobs = 2) {
  std::vector<std::string> args{STOKESIAN_BINARY, "sweep", sweep_file.string(), "--out", out.string(), "--jobs",
                                std::to_string(jobs), "--quiet"};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_child(args, kill_ms, "", out.string() + ".stderr", 600000.0);
}

}  // namespace stokesian::test
