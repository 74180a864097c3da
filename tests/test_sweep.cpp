// Sweep files (io/sweep.hpp, docs/sweeps.md): expansion order and values, derived replica seeds,
// and rejection of malformed sweeps before anything runs, naming file, line and key.
#include "engine/core/errors.hpp"
#include "io/scene_toml.hpp"
#include "engine/simulation.hpp"
#include "io/sweep.hpp"
#include "support/sanitizer.hpp"

#include <doctest/doctest.h>
#include <toml++/toml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <unistd.h>

using namespace stokesian;
namespace fs = std::filesystem;

namespace {

const char* kBase = R"([fluid]
kT = 1.0
[particles]
generate = "random"
count = 20
volume_fraction = 0.05
seed = 7
[forces]
gravity = [0, 0, -1]
[[forces.pair]]
kind = "hertz"
stiffness = 100.0
[hydrodynamics]
model = "far_field"
[time]
dt = 0.01
steps = 10
)";

struct Dir {
  fs::path p;
  Dir() {
    p = fs::temp_directory_path() / ("stokesian_sweep_" + std::to_string(::getpid()));
    fs::remove_all(p);
    fs::create_directories(p);
    std::ofstream(p / "base.toml") << kBase;
  }
  ~Dir() { fs::remove_all(p); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(p / name) << text;
    return (p / name).string();
  }
};

std::string error_of(const std::string& path) {
  try {
    io::load_sweep(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("sweep: grid x zip x replicas in file order, last factor fastest") {
  Dir d;
  const std::string p = d.write("s.toml", R"(base = "base.toml"
[[grid]]
key = "particles.volume_fraction"
values = [0.05, 0.1]
[[zip]]
keys = ["time.dt", "time.steps"]
values = [[0.01, 10], [0.02, 5], [0.04, 3]]
[replicas]
count = 2
)");
  const io::Sweep sw = io::load_sweep(p);
  REQUIRE(sw.runs.size() == 12);
  CHECK(sw.columns == std::vector<std::string>{"particles.volume_fraction", "time.dt", "time.steps", "replica"});
  CHECK(sw.runs[0].name == "run_0000");
  CHECK(sw.runs[11].name == "run_0011");
  CHECK(sw.runs[0].values == std::vector<std::string>{"0.05", "0.01", "10", "0"});
  CHECK(sw.runs[1].values == std::vector<std::string>{"0.05", "0.01", "10", "1"});
  CHECK(sw.runs[2].values == std::vector<std::string>{"0.05", "0.02", "5", "0"});
  CHECK(sw.runs[6].values == std::vector<std::string>{"0.1", "0.01", "10", "0"});
  CHECK(sw.runs[11].values == std::vector<std::string>{"0.1", "0.04", "3", "1"});
  // The values land in the resolved scenes; replica 0 keeps the seeds, replica 1 derives both.
  const Scene s0 = io::parse_scene(sw.runs[0].scene, "r0"), s1 = io::parse_scene(sw.runs[1].scene, "r1");
  const Scene s11 = io::parse_scene(sw.runs[11].scene, "r11");
  CHECK(s11.time.dt == 0.04);
  CHECK(s11.time.steps == 3);
  CHECK(s0.seed == 1);
  CHECK(s1.seed == std::uint64_t(io::replica_seed(1, 1)));
  // The placement seed too: replicas place differently, equal replicas at equal volume fraction alike.
  const Scene s2 = io::parse_scene(sw.runs[2].scene, "r2");
  CHECK(s0.positions == s2.positions);
  CHECK(s0.positions != s1.positions);
}

TEST_CASE("sweep: replica seeds are distinct, reproducible and in [0, 2^31)") {
  std::set<std::int64_t> seen;
  for (int r = 0; r < 1000; ++r) {
    const std::int64_t s = io::replica_seed(1, r);
    CHECK(s >= 0);
    CHECK(s < (std::int64_t(1) << 31));
    seen.insert(s);
  }
  CHECK(seen.size() == 1000);
  CHECK(io::replica_seed(1, 0) == 1);
  CHECK(io::replica_seed(5, 3) == io::replica_seed(5, 3));
  CHECK(io::replica_seed(5, 3) != io::replica_seed(6, 3));
}

TEST_CASE("sweep: arrays of tables by index; tables the base lacks are created") {
  Dir d;
  const std::string p = d.write("s.toml", R"(base = "base.toml"
[[grid]]
key = "forces.pair[0].stiffness"
values = [50.0, 200.0]
[[grid]]
key = "output.every"
values = [2, 5]
)");
  const io::Sweep sw = io::load_sweep(p);
  REQUIRE(sw.runs.size() == 4);
  CHECK(sw.runs[3].scene.find("stiffness = 200") != std::string::npos);
  CHECK(io::parse_scene(sw.runs[3].scene, "r").output.every == 5);
}

TEST_CASE("sweep: malformed sweeps are rejected with file, line and key") {
  Dir d;
  struct Case {
    const char* what;
    std::string text;
    std::vector<std::string> expect;  // substrings of the message
  };
  const std::string s = (d.p / "s.toml").string();
  const std::vector<Case> cases = {
      {"unknown scene key", "base = \"base.toml\"\n[[grid]]\nkey = \"fluid.kTT\"\nvalues = [1.0, 2.0]\n",
       {s + ":4:", "[fluid] kTT", "unknown key", "run_0000"}},
      {"wrong type", "base = \"base.toml\"\n\n[[grid]]\nkey = \"time.steps\"\nvalues = [10, \"many\"]\n",
       {s + ":5:", "[time] steps", "run_0001", "time.steps = \"many\""}},
      {"invalid expanded scene (out of range)", "base = \"base.toml\"\n[[grid]]\nkey = \"particles.volume_fraction\"\nvalues = [0.1, 0.9]\n",
       {s + ":4:", "volume_fraction", "run_0001"}},
      {"unknown sweep key", "base = \"base.toml\"\nrepeat = 3\n", {s + ":2:", "repeat", "unknown key"}},
      {"zip lengths", "base = \"base.toml\"\n[[zip]]\nkeys = [\"time.dt\", \"time.steps\"]\nvalues = [[0.01, 10], [0.02]]\n",
       {s + ":4:", "[[zip]] values", "2 values"}},
      {"missing base", "base = \"nope.toml\"\n", {s + ":1:", "no such file"}},
      {"swept twice", "base = \"base.toml\"\n[[grid]]\nkey = \"fluid.kT\"\nvalues = [1.0]\n[[grid]]\nkey = \"fluid.kT\"\nvalues = [2.0]\n",
       {s + ":6:", "swept twice"}},
      {"array index out of range", "base = \"base.toml\"\n[[grid]]\nkey = \"forces.pair[3].stiffness\"\nvalues = [1.0]\n",
       {s + ":4:", "no element 3"}},
      {"bad window", "base = \"base.toml\"\n[summary]\nwindow = [0.8, 0.2]\n", {s + ":3:", "[summary] window"}},
      {"TOML syntax", "base = \"base.toml\"\n[[grid]\n", {s + ":2:"}},
  };
  for (const auto& c : cases) {
    CAPTURE(c.what);
    d.write("s.toml", c.text);
    const std::string msg = error_of(s);
    CAPTURE(msg);
    REQUIRE(!msg.empty());
    for (const auto& e : c.expect) CHECK(msg.find(e) != std::string::npos);
  }
}

TEST_CASE("sweep: [set] keys apply to every run and are not columns") {
  Dir d;
  const std::string p = d.write("s.toml", R"(base = "base.toml"
[set]
"time.steps" = 4
"output.every" = 2
[[grid]]
key = "fluid.kT"
values = [0.5, 2.0]
)");
  const io::Sweep sw = io::load_sweep(p);
  REQUIRE(sw.runs.size() == 2);
  CHECK(sw.columns == std::vector<std::string>{"fluid.kT"});
  for (const auto& r : sw.runs) {
    const Scene s = io::parse_scene(r.scene, "r");
    CHECK(s.time.steps == 4);
    CHECK(s.output.every == 2);
  }
  CHECK(io::parse_scene(sw.runs[1].scene, "r").fluid.kT == 2.0);
  d.write("s.toml", "base = \"base.toml\"\n[set]\ntime.steps = 4\n");
  const std::string msg = error_of(p);
  CHECK(msg.find(p + ":3:") != std::string::npos);
  CHECK(msg.find("quoted") != std::string::npos);
  d.write("s.toml", "base = \"base.toml\"\n[set]\n\"time.stepz\" = 4\n");
  CHECK(error_of(p).find(p + ":3: [time] stepz: unknown key") != std::string::npos);
}

TEST_CASE("sweep: one replica is no factor; every run has a value per column") {
  // A "replica" column without values made the summary read past the run's values (a crash when
  // [replicas] count = 1).
  Dir d;
  const std::string p = d.write("s.toml", R"(base = "base.toml"
[[grid]]
key = "fluid.kT"
values = [0.5, 2.0]
[replicas]
count = 1
)");
  const io::Sweep sw = io::load_sweep(p);
  REQUIRE(sw.runs.size() == 2);
  CHECK(sw.columns == std::vector<std::string>{"fluid.kT"});
  for (const auto& r : sw.runs) CHECK(r.values.size() == sw.columns.size());
  CHECK(io::parse_scene(sw.runs[0].scene, "r").seed == 1);  // replica 0 keeps the seeds
  // The example sweeps get the same check in the next case (each is loaded once: loading resolves
  // every run's scene, particles included, which takes minutes in the sanitizer job).
}

// Every example sweep in configs/sweeps/ expands to valid scenes, and the first run of each takes a
// few steps and stays finite.
TEST_CASE("example sweeps in configs/sweeps/ are valid and their runs start") {
  int count = 0;
  for (const auto& e : fs::directory_iterator(std::string(STOKESIAN_SOURCE_DIR) + "/configs/sweeps")) {
    if (e.path().extension() != ".toml") continue;
    CAPTURE(e.path().string());
    // The sanitizer job (tests/support/sanitizer.hpp) skips the example sweeps of more than 200 spheres:
    // expanding one resolves every run's scene, placing its spheres (hard_sphere_peclet: 20
    // placements of 500 spheres at phi = 0.45, 117 s at -O0). The release suite expands and steps them.
    if (stokesian::test::kSanitized) {
      const toml::table t = toml::parse_file(e.path().string());
      const fs::path base = e.path().parent_path() / t["base"].value_or(std::string());
      if (io::load_scene(base.string()).fixed.size() > 200) {
        ++count;
        continue;
      }
    }
    const io::Sweep sw = io::load_sweep(e.path().string());
    CHECK(sw.runs.size() >= 2);
    for (const auto& r : sw.runs) CHECK(r.values.size() == sw.columns.size());
    Simulation sim(io::parse_scene(sw.runs.front().scene, sw.base));
    State s = sim.initial_state();
    // A few steps; one for the large examples (the 500-sphere rheology and destabilisation sweeps).
    const int steps = s.size() > 200 ? 1 : 5;
    for (int k = 0; k < steps; ++k) {
      const Evaluation ev = sim.evaluate(s, s.position);
      sim.advance(s, ev);
    }
    for (const Vec3& x : s.position) CHECK(x.allFinite());
    ++count;
  }
  CHECK(count >= 1);
}
