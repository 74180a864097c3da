// Kill-and-resume equivalence through the command line: a run killed with SIGKILL at random
// moments (seeded) and continued with --resume until it completes must write exactly the
// trajectory of an uninterrupted run (bitwise), and the trajectory must be readable after every
// kill.
#include <doctest/doctest.h>

#include "io/h5md.hpp"

#include <hdf5.h>

#include "support/hdf5_read.hpp"
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

using stokesian::test::read_doubles;

namespace {

// Exit status of `stokesian run scene --out out [--resume]`, killed after `kill_ms` (< 0: never).
// Returns -1 when killed.
int run_cli(const std::string& scene, const std::string& out, bool resume, int kill_ms) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<std::string> args{STOKESIAN_BINARY, "run", scene, "--out", out, "--quiet", "--threads", "1"};
    if (resume) args.push_back("--resume");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  if (kill_ms >= 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(kill_ms));
    kill(pid, SIGKILL);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFSIGNALED(status)) return -1;
  return WEXITSTATUS(status);
}


void check_kill_resume(const std::string& scene_text, const std::vector<std::string>& datasets, std::uint64_t seed) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const fs::path dir = fs::temp_directory_path() / ("stokesian_resume_" + std::to_string(getpid()) + "_" + std::to_string(seed));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = (dir / "scene.toml").string();
  std::ofstream(scene) << scene_text;
  const std::string ref = (dir / "ref.h5").string(), cut = (dir / "cut.h5").string();

  const auto t0 = std::chrono::steady_clock::now();
  REQUIRE(run_cli(scene, ref, false, -1) == 0);
  const int full_ms = int(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());

  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> when(0, std::max(1, full_ms / 3));
  int kills = 0, status = -1;
  for (int attempt = 0; attempt < 40 && status != 0; ++attempt) {
    const bool resume = fs::exists(cut + ".ckpt");
    status = run_cli(scene, cut, resume, attempt < 8 ? when(rng) : -1);
    if (status == -1) {
      ++kills;
      // After any kill the visible trajectory, if it exists, is a complete and consistent file.
      if (fs::exists(cut)) CHECK_NOTHROW(stokesian::io::inspect_trajectory(cut));
    }
  }
  CHECK(status == 0);
  CHECK(kills >= 1);
  MESSAGE("uninterrupted run " << full_ms << " ms, " << kills << " kills before completion");
  for (const std::string& d : datasets) {
    CAPTURE(d);
    CHECK(read_doubles(cut, d) == read_doubles(ref, d));
  }
  fs::remove_all(dir);
}

}  // namespace

TEST_CASE("SIGKILL at random moments, then --resume: identical Brownian far-field trajectory") {
  // 27 interacting spheres, FT far field with Brownian motion (Lanczos noise), Morse attraction and
  // Hertz contact; the random stream must continue exactly across restarts.
  const std::string scene = R"(
[fluid]
kT = 1.0
[particles]
generate = "lattice"
count = 27
volume_fraction = 0.15
size_distribution = "lognormal"
sigma = 0.2
seed = 4
[forces]
external_torque = [0.0, 0.0, 0.5]
[[forces.pair]]
kind = "morse"
depth = 2.0
[[forces.pair]]
kind = "hertz"
[hydrodynamics]
model = "far_field"
tolerance = 1e-8
[brownian]
seed = 99
[time]
dt = 0.01
steps = 600
[output]
every = 5
checkpoint_every = 20
)";
  check_kill_resume(scene, {"particles/all/position/value", "particles/all/position/time", "particles/all/velocity/value",
                            "particles/all/angular_velocity/value", "observables/pair_energy/value"},
                    11);
}

TEST_CASE("SIGKILL at random moments, then --resume: identical adaptive RKF45 trajectory") {
  const std::string scene = R"(
[particles]
positions = [[-1.5,-1.5,-1.5],[1.5,-1.5,-1.5],[-1.5,1.5,-1.5],[1.5,1.5,-1.5],[-1.5,-1.5,1.5],[1.5,-1.5,1.5],[-1.5,1.5,1.5],[1.5,1.5,1.5]]
[forces]
external_force = [0.0, 0.0, -1.0]
[flow]
kind = "planar_extension"
rate = 0.001
[hydrodynamics]
model = "far_field"
tolerance = 1e-10
[time]
dt = 1.0
steps = 1500
integrator = "rkf45"
rkf_tolerance = 1e-9
[output]
every = 10
checkpoint_every = 50
)";
  check_kill_resume(scene, {"particles/all/position/value", "particles/all/position/time", "particles/all/stresslet/value",
                            "observables/dt/value"},
                    12);
}
