#pragma once
// Benchmark harness: named phase timers, machine metadata, and a JSON results file that the plot
// scripts in bench/ read. Timings are wall-clock medians over repeats; report ratios (method vs
// direct, 2 threads vs 1) because shared machines are noisy.
#include <algorithm>
#include <chrono>
#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

namespace stokesian::bench {

// Command line shared by every driver: bench_<name> [--quick] [--out DIR]. --quick is the short
// form CI runs; results go to DIR (default bench/results).
struct Options {
  bool quick = false;
  std::string out = "bench/results";
};
Options parse_options(int argc, char** argv);

// A numeric knob from the environment: `fallback` when `name` is unset; a value that is not a whole
// number (or, with `integer`, not an integer) or lies outside [lo, hi] stops the driver with a
// message naming the variable, its value and the range (exit 2).
double env_number(const char* name, double fallback, double lo, double hi, bool integer = false);

// Random cloud shared by the far-field drivers: n centres uniform in the cube [0, L)^3 (overlaps
// allowed) and radii uniform in [0.5, 1.5] (<a^3> = 1.25), drawn from std::mt19937_64(seed).
struct Cloud {
  std::vector<Eigen::Vector3d> x;
  std::vector<double> a;
};
Cloud random_cloud(long n, double L, unsigned long seed);

// Machine and build metadata: host, CPU model, logical cores, OpenMP max threads, compiler,
// build type, git revision, UTC date.
std::map<std::string, std::string> machine_metadata();

class Results {
 public:
  explicit Results(std::string name) : name_(std::move(name)) {}
  // One measurement row: named parameters (N, threads, ...) and named phase times in seconds.
  void add(const std::map<std::string, double>& params, const std::map<std::string, double>& phases);
  // Writes bench/results/<name>.json (or `path`): {"benchmark", "machine", "rows": [...]}.
  std::string write(const std::string& dir) const;

 private:
  std::string name_;
  std::vector<std::pair<std::map<std::string, double>, std::map<std::string, double>>> rows_;
};

// Wall time of one call of f (seconds), no warm-up: for one-off phases (set-up, first factorisation).
template <class F>
double time_once(F&& f) {
  const auto a = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

// Median wall time of `repeats` (>= 1) calls of f (seconds); one untimed warm-up call first.
template <class F>
double median_time(F&& f, int repeats) {
  f();
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto a = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

}  // namespace stokesian::bench
