// Continuing a finished run from its trajectory ([particles] file = "run.h5"): the new run starts
// in the old run's box and lattice strain, counts steps and time on from its last frame (so the
// Brownian noise, keyed by step, does not repeat), and the last step of every run is stored even
// when it is not a multiple of [output] every. The reference is the uninterrupted run: continuing
// after k steps must reproduce it exactly (same arithmetic on the same state).
#include <doctest/doctest.h>

#include "engine/app/run.hpp"
#include "engine/core/errors.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"

#include <hdf5.h>

#include "support/hdf5_read.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace stokesian;
using stokesian::test::read_doubles;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("stokesian_continuation_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Runs `text` (scene file written in dir) to `out`.
void run_scene(const fs::path& dir, const std::string& name, const std::string& text, const std::string& out) {
  {
    std::ofstream f(dir / name);
    f << text;
  }
  Simulation sim(io::load_scene((dir / name).string()));
  app::RunOptions o;
  o.out = (dir / out).string();
  o.quiet = true;
  app::run(sim, o);
}


// A sheared, Brownian, periodic suspension of a few spheres: lattice strain, images and noise all
// matter for continuation.
std::string sheared(const std::string& particles, long steps, long every) {
  return "[domain]\nkind = \"periodic\"\nbox = [8.0, 8.0, 8.0]\n[fluid]\nkT = 0.5\n" + particles +
         "[[forces.pair]]\nkind = \"hertz\"\nstiffness = 1000.0\n"
         "[flow]\nkind = \"simple_shear\"\nrate = 0.5\n[hydrodynamics]\nmodel = \"free_draining\"\n"
         "[time]\ndt = 0.05\nsteps = " + std::to_string(steps) + "\n[output]\nevery = " + std::to_string(every) + "\n";
}
const std::string kParticles =
    "[particles]\npositions = [[1.0, 1.0, 1.0], [3.5, 1.2, 1.0], [1.0, 6.9, 4.0], [5.0, 5.0, 5.0], [7.0, 3.0, 6.5]]\n";

}  // namespace

TEST_CASE("the last step is stored even when it is not a multiple of [output] every") {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const fs::path dir = scratch("last");
  run_scene(dir, "a.toml", sheared(kParticles, 13, 5), "a.h5");
  const auto info = io::inspect_trajectory((dir / "a.h5").string());
  CHECK(info.frames == 4);  // steps 0, 5, 10, 13 (earlier versions: 0, 5, 10)
  CHECK(info.last_step == 13);
  fs::remove_all(dir);
}

TEST_CASE("continuing a finished sheared Brownian run from its file reproduces the uninterrupted run") {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const fs::path dir = scratch("continue");
  run_scene(dir, "whole.toml", sheared(kParticles, 30, 5), "whole.h5");
  run_scene(dir, "first.toml", sheared(kParticles, 17, 5), "first.h5");
  run_scene(dir, "second.toml", sheared("[particles]\nfile = \"first.h5\"\n", 13, 5), "second.h5");

  const Scene second = io::load_scene((dir / "second.toml").string());
  CHECK(second.time.start_step == 17);
  CHECK(second.time.start_time == doctest::Approx(17 * 0.05).epsilon(1e-14));
  CHECK(second.domain.shear_strain != 0.0);  // carried over (earlier versions restarted at strain 0)

  const auto info = io::inspect_trajectory((dir / "second.h5").string());
  CHECK(info.first_step == 17);
  CHECK(info.last_step == 30);
  // Final frame equals the uninterrupted run's: same box strain, same noise for steps 17..29. The
  // strain is read back from the stored box edges (strain * Ly / Ly), which may round by one ulp,
  // hence 1e-12 rather than bitwise.
  const auto a = read_doubles((dir / "whole.h5").string(), "/particles/all/position/value");
  const auto b = read_doubles((dir / "second.h5").string(), "/particles/all/position/value");
  const std::size_t n3 = 5 * 3;
  REQUIRE(a.size() >= n3);
  REQUIRE(b.size() >= n3);
  for (std::size_t k = 0; k < n3; ++k) CHECK(b[b.size() - n3 + k] == doctest::Approx(a[a.size() - n3 + k]).epsilon(1e-12));
  // Continuing from step 0 instead (what earlier versions did) replays the first run's noise and
  // strain and ends elsewhere.
  std::string replay = sheared("[particles]\nfile = \"first.h5\"\n", 13, 5);
  replay.replace(replay.find("[time]\n"), 7, "[time]\nstart_step = 0\nstart_time = 0.0\n");
  replay.replace(replay.find("box = [8.0, 8.0, 8.0]\n"), 22, "box = [8.0, 8.0, 8.0]\nshear_strain = 0.0\n");
  run_scene(dir, "replay.toml", replay, "replay.h5");
  const auto r = read_doubles((dir / "replay.h5").string(), "/particles/all/position/value");
  double diff = 0;
  for (std::size_t k = 0; k < n3; ++k) diff = std::max(diff, std::abs(r[r.size() - n3 + k] - a[a.size() - n3 + k]));
  CHECK(diff > 1e-3);
  const auto ta = read_doubles((dir / "whole.h5").string(), "/particles/all/position/time");
  const auto tb = read_doubles((dir / "second.h5").string(), "/particles/all/position/time");
  CHECK(tb.back() == doctest::Approx(ta.back()).epsilon(1e-14));
  fs::remove_all(dir);
}

TEST_CASE("a periodic run cannot be continued in an open domain or another box") {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const fs::path dir = scratch("refuse");
  run_scene(dir, "first.toml", sheared(kParticles, 4, 2), "first.h5");
  auto error_of = [&](const std::string& text) -> std::string {
    std::ofstream(dir / "c.toml") << text;
    try {
      io::load_scene((dir / "c.toml").string());
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  const std::string open = error_of("[particles]\nfile = \"first.h5\"\n[time]\ndt = 0.1\nsteps = 2\n");
  CHECK(open.find("[particles] file") != std::string::npos);
  CHECK(open.find("periodic box [8, 8, 8]") != std::string::npos);
  const std::string other = error_of("[domain]\nkind = \"periodic\"\nbox = [9.0, 8.0, 8.0]\n"
                                     "[particles]\nfile = \"first.h5\"\n[time]\ndt = 0.1\nsteps = 2\n");
  CHECK(other.find("but [domain] box is [9, 8, 8]") != std::string::npos);
  // The same box continues; an explicit shear_strain or start_step overrides the file's.
  CHECK(error_of("[domain]\nkind = \"periodic\"\nbox = [8.0, 8.0, 8.0]\nshear_strain = 0.0\n"
                 "[particles]\nfile = \"first.h5\"\n[time]\ndt = 0.1\nsteps = 2\nstart_step = 0\n").empty());
  fs::remove_all(dir);
}
