// Long-run memory: resident set size (RSS) of a small Brownian run over 10^5 steps (--quick: 10^4),
// sampled every 1000 steps at each checkpoint. The run goes through the real run loop
// (Simulation::run) and the real output sink (io::RunOutput: H5MD trajectory, a frame every 100
// steps, and a checkpoint every 1000 steps) into a temporary file. A leak of a few bytes per step
// or per frame shows as a slope; the result records every sample, the first and last RSS and the
// least-squares slope over the second half (after the allocator and HDF5 caches have settled).
// Usage: bench_memory [--quick] [--out DIR] [--steps N] [--no-output] [--hdf5-gc].
//
// Scene: 27 Brownian spheres (kT = 1) on a 3 x 3 x 3 lattice in a periodic box of edge 9 a, free
// draining (the cheapest level that still runs the whole loop), Morse attraction and Hertz contact
// (the pair-force neighbour list is rebuilt every step), Euler-Maruyama, dt = 1e-4.
#include "bench/harness.hpp"
#include "engine/app/run.hpp"
#include "engine/simulation.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_toml.hpp"

#include <hdf5.h>
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

using namespace stokesian;
namespace fs = std::filesystem;

namespace {

// Resident set size [bytes]: the second field of /proc/self/statm, in pages.
double rss_bytes() {
  std::ifstream in("/proc/self/statm");
  long size = 0, resident = 0;
  in >> size >> resident;
  return double(resident) * double(::sysconf(_SC_PAGESIZE));
}

// Bytes the C heap has handed out and not taken back (glibc mallinfo2: uordblks + hblkhd). Flat
// while RSS grows means the allocator's arena grows (fragmentation), not a leak.
double heap_in_use() {
  const struct mallinfo2 m = mallinfo2();
  return double(m.uordblks) + double(m.hblkhd);
}

std::string scene_text(long steps) {
  std::ostringstream t;
  t << "[domain]\nkind = \"periodic\"\nbox = [9.0, 9.0, 9.0]\n"
       "[fluid]\nkT = 1.0\n"
       "[particles]\ngenerate = \"lattice\"\ncount = 27\n"
       "[[forces.pair]]\nkind = \"morse\"\ndepth = 2.0\nkappa = 5.0\n"
       "[[forces.pair]]\nkind = \"hertz\"\nstiffness = 2000.0\n"
       "[hydrodynamics]\nmodel = \"free_draining\"\n"
       "[brownian]\nseed = 11\n"
       "[time]\ndt = 1e-4\nsteps = "
    << steps << "\nintegrator = \"euler\"\n"
    << "[output]\nevery = 100\ncheckpoint_every = 1000\n";
  return t.str();
}

// Forwards to the run's files and samples the RSS after every checkpoint. The samples go into
// vectors reserved up front (the result rows are made after the run), so that the measurement
// itself allocates nothing while the run goes on.
class SamplingSink final : public OutputSink {
 public:
  SamplingSink(std::optional<io::RunOutput> out, std::size_t samples, std::chrono::steady_clock::time_point t0)
      : out_(std::move(out)), t0_(t0) {
    steps.reserve(samples);
    rss_samples.reserve(samples);
    heap_samples.reserve(samples);
    elapsed.reserve(samples);
  }
  void record(const Frame& f) override {
    if (out_) out_->record(f);
  }
  void checkpoint(const State& s) override {
    if (out_) out_->checkpoint(s);
    else if (s.step % 1000 != 0) return;
    if (gc) H5garbage_collect();
    const double rss = rss_bytes();
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    heap_samples.push_back(heap_in_use());
    elapsed.push_back(t);
    steps.push_back(double(s.step));
    rss_samples.push_back(rss);
  }
  void finish() {
    if (out_) out_->trajectory().finish();
  }
  std::vector<double> steps, rss_samples, heap_samples, elapsed;
  bool gc = false;

 private:
  std::optional<io::RunOutput> out_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace

int main(int argc, char** argv) {
  // --steps N (this driver only): another run length, e.g. 10^6 to see whether a slope saturates.
  // --no-output (this driver only): frames and checkpoints discarded, RSS still sampled every 1000
  // steps: the engine alone, to tell its memory from the output's. --hdf5-gc: empty the HDF5
  // library's free lists (H5garbage_collect) after every checkpoint, to tell them from a leak.
  long steps_opt = 0;
  bool no_output = false;
  bool hdf5_gc = false;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::string(argv[i]) == "--steps" && i + 1 < argc) steps_opt = std::atol(argv[++i]);
    else if (std::string(argv[i]) == "--no-output") no_output = true;
    else if (std::string(argv[i]) == "--hdf5-gc") hdf5_gc = true;
    else args.push_back(argv[i]);
  }
  const bench::Options opt = bench::parse_options(int(args.size()), args.data());
  const long steps = steps_opt > 0 ? steps_opt : opt.quick ? 10000 : 100000;
  bench::Results res(std::string(no_output ? "memory_no_output" : hdf5_gc ? "memory_hdf5_gc" : "memory") +
                     (steps_opt > 0 ? "_" + std::to_string(steps) : opt.quick ? "_quick" : ""));
  const fs::path dir = fs::temp_directory_path() / ("stokesian_bench_memory_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "run.h5").string();

  const double rss_before = rss_bytes();
  Simulation sim(io::parse_scene(scene_text(steps), "bench_memory.toml"));
  State s = sim.initial_state();
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<io::RunOutput> out;
  if (!no_output) out.emplace(io::RunOutput::start(path, app::run_header(sim)));
  SamplingSink sink(std::move(out), std::size_t(steps / 1000 + 2), t0);
  sink.gc = hdf5_gc;
  // Before the simulation is built.
  res.add({{"step", -1.0}}, {{"rss_bytes", rss_before}, {"heap_in_use_bytes", heap_in_use()}, {"elapsed", 0.0}});
  RunControl control;
  control.quiet = true;
  sim.run(s, sink, control);
  sink.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (std::size_t k = 0; k < sink.steps.size(); ++k)
    res.add({{"step", sink.steps[k]}},
            {{"rss_bytes", sink.rss_samples[k]}, {"heap_in_use_bytes", sink.heap_samples[k]}, {"elapsed", sink.elapsed[k]}});

  // Least-squares slope of RSS over the second half of the samples [bytes per step].
  const std::size_t m = sink.steps.size(), h = m / 2;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = h; k < m; ++k) {
    sx += sink.steps[k];
    sy += sink.rss_samples[k];
    sxx += sink.steps[k] * sink.steps[k];
    sxy += sink.steps[k] * sink.rss_samples[k];
  }
  const double q = double(m - h);
  const double slope = q > 1 ? (q * sxy - sx * sy) / (q * sxx - sx * sx) : 0.0;
  const double file_bytes = no_output ? 0.0 : double(fs::file_size(path));
  res.add({{"summary", 1.0}, {"steps", double(steps)}},
          {{"rss_first", sink.rss_samples.front()}, {"rss_last", sink.rss_samples.back()},
           {"rss_max", *std::max_element(sink.rss_samples.begin(), sink.rss_samples.end())},
           {"slope_bytes_per_step_second_half", slope}, {"heap_in_use_first", sink.heap_samples.front()},
           {"heap_in_use_last", sink.heap_samples.back()}, {"trajectory_bytes", file_bytes}, {"seconds", seconds}});
  std::printf("%ld steps in %.1f s; RSS before the simulation %.2f MB, at the first checkpoint (step %.0f) %.2f MB, "
              "at the last (step %.0f) %.2f MB, max %.2f MB; slope over the second half %.3g bytes/step "
              "(%.3g MB per 10^5 steps); heap in use %.3f MB -> %.3f MB; trajectory %.2f MB\n",
              steps, seconds, rss_before / 1048576, sink.steps.front(), sink.rss_samples.front() / 1048576,
              sink.steps.back(), sink.rss_samples.back() / 1048576,
              *std::max_element(sink.rss_samples.begin(), sink.rss_samples.end()) / 1048576, slope,
              slope * 1e5 / 1048576, sink.heap_samples.front() / 1048576, sink.heap_samples.back() / 1048576,
              file_bytes / 1048576);
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  fs::remove_all(dir);
  return 0;
}
