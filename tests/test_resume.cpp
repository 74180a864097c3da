// Kill-and-resume equivalence through the command line: a run killed with SIGKILL at random
// moments (seeded) and continued with --resume until it completes must write exactly the
// trajectory of an uninterrupted run (bitwise), and the trajectory must be readable after every
// kill. A --resume before the first checkpoint starts afresh (and says so), but never replaces the
// trajectory of another run.
#include <doctest/doctest.h>

#include "io/h5md.hpp"

#include <hdf5.h>

#include "support/child_process.hpp"
#include "support/hdf5_read.hpp"
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

using stokesian::test::read_doubles;

namespace {

// Exit status of `stokesian run scene --out out [--resume]`, killed after `kill_ms` (< 0: never),
// or as soon as the file `kill_when` exists (when not empty). Returns -1 when killed. With
// `err` set, the child's stderr goes to that file; `command` replaces "run" (e.g. "solve").
int run_cli(const std::string& scene, const std::string& out, bool resume, int kill_ms, const std::string& err = "",
            const std::string& kill_when = "", const std::string& command = "run") {
  std::vector<std::string> args{STOKESIAN_BINARY, command, scene, "--out", out, "--quiet", "--threads", "1"};
  if (resume) args.push_back("--resume");
  const stokesian::test::ChildOutcome c = stokesian::test::run_child(args, kill_ms, kill_when, err, -1, false);
  return c.killed ? -1 : c.status;
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
    // Bitwise (NaN marks the empty slots of open channels, and NaN != NaN).
    const std::vector<double> a = read_doubles(cut, d), b = read_doubles(ref, d);
    CHECK(a.size() == b.size());
    CHECK((a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0));
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

TEST_CASE("SIGKILL at random moments, then --resume: identical open-channel run (inflow, removal, Brownian SD)") {
  // Brownian constrained SD in a straight outline channel fed through its inlet (engine/inflow.hpp):
  // the inserted particles, their places and ids, the removals and the inflow's credit continue
  // exactly across restarts.
  const std::string scene = R"(
[fluid]
kT = 1.0
[walls]
kind = "outline"
outline = [[0, 0], [24, 0], [24, 8], [0, 8]]
openings = [1, 3]
inlet = 3
[particles]
generate = "random"
count = 6
seed = 3
[inflow]
areal_fraction = 0.25
[[forces.pair]]
kind = "hertz"
[flow]
kind = "poiseuille"
mean_velocity = 4.0
[hydrodynamics]
model = "stokesian"
tolerance = 1e-3
lubrication_min_gap = 1e-2   # as the fouling configs: lets the contact force hold a sphere at a wall
[brownian]
seed = 5
[time]
dt = 0.005
steps = 800
[output]
every = 10
checkpoint_every = 40
xyz = true
)";
  check_kill_resume(scene, {"particles/all/position/value", "particles/all/id/value", "particles/all/velocity/value",
                            "observables/inflow_inserted/value", "observables/inflow_removed/value",
                            "observables/particles_present/value"},
                    23);
}

TEST_CASE("SIGKILL at random moments, then --resume: identical Brownian SD trajectory (sheared, accelerated, FTS)") {
  // Brownian Stokesian dynamics (fixman: near-field and Lanczos far-field Brownian forces, drift),
  // bidisperse spheres in a sheared periodic box with PME; the noise streams continue exactly.
  const std::string scene = R"(
[fluid]
kT = 1.0
[domain]
kind = "periodic"
box = [12, 12, 12]
[particles]
generate = "random"
volume_fraction = 0.2
size_distribution = "bidisperse"
radius_ratio = 1.4
large_fraction = 0.3
seed = 4
[[forces.pair]]
kind = "hertz"
[flow]
kind = "simple_shear"
rate = 0.5
[hydrodynamics]
model = "stokesian"
solver = "accelerated"
tolerance = 1e-3
[brownian]
seed = 99
[time]
dt = 0.002
steps = 60
[output]
every = 5
checkpoint_every = 10
)";
  // The Brownian stress averages over the steps between frames (engine/stress.hpp).
  check_kill_resume(scene, {"particles/all/position/value", "particles/all/velocity/value",
                            "particles/all/stresslet/value", "observables/min_gap/value",
                            "observables/stress_brownian/value", "observables/brownian_samples/value",
                            "observables/relative_viscosity/value"},
                    13);
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

namespace {

std::string text_of(const std::string& path) {
  std::ifstream is(path);
  std::ostringstream ss;
  ss << is.rdbuf();
  return ss.str();
}

std::vector<char> bytes_of(const std::string& path) {
  std::ifstream is(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>()};
}

const char* const kAfresh = "nothing to resume, starting afresh";

}  // namespace

TEST_CASE("--resume with nothing to resume from: killed before, during and after the first checkpoint") {
  // Runs that are always continued with --resume, also the very first one. Before the first
  // checkpoint there is nothing to resume: the run must start afresh and say so; after it, it
  // must continue. The result must equal an uninterrupted run bitwise. A trajectory of another
  // run (finished, checkpoint removed; a solve result) must never be replaced by --resume.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const std::string scene_text = R"(
[fluid]
kT = 1.0
[particles]
positions = [[-1.5,-1.5,-1.5],[1.5,-1.5,-1.5],[-1.5,1.5,-1.5],[1.5,1.5,-1.5],[-1.5,-1.5,1.5],[1.5,-1.5,1.5],[-1.5,1.5,1.5],[1.5,1.5,1.5]]
[forces]
external_force = [0.0, 0.0, -1.0]
[hydrodynamics]
model = "far_field"
tolerance = 1e-10
[brownian]
seed = 5
[time]
dt = 0.0005
steps = 4800
[output]
every = 80
checkpoint_every = 2400
)";
  const fs::path dir = fs::temp_directory_path() / ("stokesian_afresh_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = (dir / "scene.toml").string(), err = (dir / "err.txt").string();
  std::ofstream(scene) << scene_text;
  const std::string ref = (dir / "ref.h5").string(), cut = (dir / "cut.h5").string();
  const std::vector<std::string> datasets{"particles/all/position/value", "particles/all/position/time",
                                          "particles/all/velocity/value"};

  const auto t0 = std::chrono::steady_clock::now();
  REQUIRE(run_cli(scene, ref, false, -1) == 0);
  const int full_ms = int(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());

  // One --resume of `cut`: checks the notice against the files present before it.
  int kills = 0, resumed = 0;
  auto resume_once = [&](int kill_ms, const std::string& kill_when = "") {
    const bool had_checkpoint = fs::exists(cut + ".ckpt");
    resumed += had_checkpoint;
    const int status = run_cli(scene, cut, true, kill_ms, err, kill_when);
    const std::string said = text_of(err);
    CAPTURE(said);
    CAPTURE(had_checkpoint);
    if (had_checkpoint) CHECK(said.find(kAfresh) == std::string::npos);
    if (!had_checkpoint && status == 0) CHECK(said.find(kAfresh) != std::string::npos);
    if (status == -1) ++kills;
    if (status == -1 && fs::exists(cut)) CHECK_NOTHROW(stokesian::io::inspect_trajectory(cut));
    if (status != -1) CHECK(status == 0);
    return said;
  };

  // 1. Nothing there yet; killed as soon as the trajectory's working copy exists, i.e. after the
  //    start created cut.h5 (0 frames) and long before the first checkpoint (half-way).
  CHECK(resume_once(-1, cut + ".shadow").find("does not exist yet") != std::string::npos);
  REQUIRE(fs::exists(cut));
  REQUIRE(!fs::exists(cut + ".ckpt"));
  // 2. The leftover of that interrupted start is replaced (killed again just after starting).
  fs::remove(cut + ".shadow");
  CHECK(resume_once(-1, cut + ".shadow").find("interrupted start is replaced") != std::string::npos);
  // 3. Killed at seeded moments around the first checkpoint (half-way): until one exists, every
  //    run starts afresh; a kill during the first commit/checkpoint must not confuse the next one.
  std::mt19937_64 rng(21);
  std::uniform_int_distribution<int> around(int(0.35 * full_ms), int(0.75 * full_ms));
  for (int ms : {0, around(rng), around(rng), around(rng), around(rng)}) resume_once(ms);
  // 4. If no checkpoint exists yet: killed as soon as the first one exists. Then killed after it.
  if (!fs::exists(cut + ".ckpt")) resume_once(-1, cut + ".ckpt");
  REQUIRE(fs::exists(cut + ".ckpt"));
  CHECK(resume_once(int(0.2 * full_ms)).find(kAfresh) == std::string::npos);
  resume_once(-1);  // to the end
  CHECK(fs::exists(cut + ".ckpt"));
  CHECK(!fs::exists(cut + ".starting"));
  CHECK(resumed >= 2);  // the runs of step 4 and the last one
  for (const std::string& d : datasets) {
    CAPTURE(d);
    CHECK(stokesian::test::read_doubles(cut, d) == read_doubles(ref, d));
  }

  // 5. A 0-frame trajectory without the start marker (e.g. left by an older version) is replaced.
  const std::string zero = (dir / "zero.h5").string();
  REQUIRE(run_cli(scene, zero, false, -1, err, zero + ".shadow") == -1);
  fs::remove(zero + ".starting");
  REQUIRE(stokesian::io::inspect_trajectory(zero).frames == 0);
  CHECK(run_cli(scene, zero, true, -1, err) == 0);
  CHECK(text_of(err).find("holds no frames and is replaced") != std::string::npos);
  CHECK(read_doubles(zero, datasets[0]) == read_doubles(ref, datasets[0]));

  // 6. Never replaced: a finished run whose checkpoint was removed, and a solve result.
  fs::remove(ref + ".ckpt");
  const std::vector<char> before = bytes_of(ref);
  CHECK(run_cli(scene, ref, true, -1, err) == 4);
  CHECK(text_of(err).find("refusing to replace it") != std::string::npos);
  CHECK(bytes_of(ref) == before);
  const std::string solved = (dir / "solved.h5").string();
  REQUIRE(run_cli(scene, solved, false, -1, err, "", "solve") == 0);
  const std::vector<char> solved_bytes = bytes_of(solved);
  CHECK(run_cli(scene, solved, true, -1, err) == 4);
  CHECK(bytes_of(solved) == solved_bytes);
  MESSAGE("uninterrupted run " << full_ms << " ms; " << kills << " kills, " << resumed << " runs resumed from a checkpoint");
  fs::remove_all(dir);
}
