// `stokesian sweep` survives SIGKILL (issue 14): a 12-run sweep with --jobs 2 is killed at seeded
// random moments several times and resumed with the same command until it finishes; then every
// run's trajectory (every dataset and attribute, byte for byte), its resolved scene and status,
// and the summary table (apart from the wall-time and attempt columns, which measure the
// interruptions) equal an uninterrupted sweep's. Also: a failing run is recorded and the others
// finish; exit status 6.
#include "support/h5_compare.hpp"
#include "support/sweep_support.hpp"

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace stokesian::test;

namespace {

const char* kBase = R"([fluid]
kT = 1.0
[particles]
generate = "random"
count = 40
volume_fraction = 0.05
seed = 3
[[forces.pair]]
kind = "hertz"
stiffness = 2000.0
[forces]
gravity = [0, 0, -0.5]
[hydrodynamics]
model = "far_field"
[time]
dt = 0.002
steps = 600
integrator = "euler"
[output]
every = 20
checkpoint_every = 60
)";

const char* kSweep = R"(base = "base.toml"
[[grid]]
key = "particles.volume_fraction"
values = [0.05, 0.1]
[[grid]]
key = "fluid.kT"
values = [0.5, 1.0]
[replicas]
count = 3
[summary]
window = [0.25, 1.0]
)";

}  // namespace

TEST_CASE("sweep: killed at seeded moments and resumed, identical to an uninterrupted sweep") {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  SweepWork w("sweep_kill", kBase, kSweep);
  const fs::path ref = w.dir / "ref", got = w.dir / "killed";
  const ChildOutcome r = run_sweep(w.dir / "sweep.toml", ref);
  INFO(slurp(ref.string() + ".stderr"));
  REQUIRE(!r.killed);
  REQUIRE(r.status == 0);
  const double T = r.ms;
  MESSAGE("uninterrupted sweep: " << T << " ms");

  std::mt19937_64 rng(20261124);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int kills = 0, invocations = 0;
  for (; invocations < 40; ++invocations) {
    // Five kills at uniform moments within the remaining work, then let it finish.
    const double at = kills < 5 ? (u(rng) < 0.25 ? 300.0 * u(rng) : 0.5 * T * u(rng)) : -1.0;
    const ChildOutcome o = run_sweep(w.dir / "sweep.toml", got, at);
    if (o.killed) {
      ++kills;
      continue;
    }
    if (o.status == 0) break;
    // 6: a run was still locked by a child of a killed sweep that had not died yet; go on.
    INFO(slurp(got.string() + ".stderr"));
    REQUIRE(o.status == 6);
  }
  MESSAGE(kills << " kills, " << invocations + 1 << " invocations");
  CHECK(kills >= 3);

  for (int i = 0; i < 12; ++i) {
    char name[16];
    std::snprintf(name, sizeof name, "run_%04d", i);
    CAPTURE(name);
    std::map<std::string, Blob> a, b;
    std::string ea, eb;
    REQUIRE(read_file((ref / name / "trajectory.h5").string(), a, ea));
    REQUIRE(read_file((got / name / "trajectory.h5").string(), b, eb));
    const auto diffs = compare(b, a, false);
    for (const auto& d : diffs) CHECK_MESSAGE(false, d);
    CHECK(slurp(ref / name / "scene.toml") == slurp(got / name / "scene.toml"));
    CHECK(slurp(got / name / "status").find("status = done") == 0);
  }
  CHECK(summary_without_timing(ref / "summary.csv") == summary_without_timing(got / "summary.csv"));
  // The replicas differ (derived seeds) and the grid values reached the scenes.
  CHECK(slurp(ref / "run_0000" / "trajectory.h5") != slurp(ref / "run_0001" / "trajectory.h5"));
  CHECK(slurp(ref / "run_0011" / "scene.toml").find("kT = 1") != std::string::npos);

  // The chart of the table (tools/stokesian_sweep_plot.py through `stokesian plot`).
  const ChildOutcome png = run_child({STOKESIAN_BINARY, "plot", ref.string(), "--y", "pair_energy", "--series", "fluid.kT"},
                                     -1, "", (w.dir / "plot.err").string(), 120000.0);
  INFO(slurp(w.dir / "plot.err"));
  CHECK(png.status == 0);
  CHECK(fs::file_size(ref / "pair_energy.png") > 10000);
  CHECK(run_child({STOKESIAN_BINARY, "plot", ref.string(), "--y", "no_such_observable"}, -1, "", (w.dir / "plot.err").string(),
                  120000.0).status == 1);
  CHECK(slurp(w.dir / "plot.err").find("no_such_observable") != std::string::npos);

  // A second call on a finished sweep runs nothing and rewrites the same summary.
  const std::string before = summary_without_timing(got / "summary.csv");
  const ChildOutcome again = run_sweep(w.dir / "sweep.toml", got);
  CHECK(again.status == 0);
  CHECK(summary_without_timing(got / "summary.csv") == before);
}

TEST_CASE("sweep: a malformed sweep is refused with exit status 2 before anything is written") {
  SweepWork w("sweep_bad", kBase, "base = \"base.toml\"\n[[grid]]\nkey = \"time.steps\"\nvalues = [10, -1]\n");
  const fs::path out = w.dir / "out";
  const ChildOutcome o = run_sweep(w.dir / "sweep.toml", out);
  CHECK(o.status == 2);
  CHECK(!fs::exists(out));
  const std::string err = slurp(out.string() + ".stderr");
  CHECK(err.find((w.dir / "sweep.toml").string() + ":4: [time] steps") != std::string::npos);
  CHECK(err.find("run_0001") != std::string::npos);
}

TEST_CASE("sweep: a failing run is recorded, the others finish, exit status 6") {
  SweepWork w("sweep_fail", kBase, kSweep);
  // dt so large that the contact force blows the dense replica up: overlap beyond max_overlap.
  std::ofstream(w.dir / "fail.toml") << "base = \"base.toml\"\n[[grid]]\nkey = \"time.dt\"\nvalues = [0.002, 5.0]\n"
                                     << "[[grid]]\nkey = \"particles.volume_fraction\"\nvalues = [0.3]\n";
  const fs::path out = w.dir / "fail";
  const ChildOutcome o = run_sweep(w.dir / "fail.toml", out);
  INFO(slurp(out.string() + ".stderr"));
  CHECK(o.status == 6);
  CHECK(slurp(out / "run_0000" / "status").find("status = done") == 0);
  const std::string st = slurp(out / "run_0001" / "status");
  CHECK(st.find("status = failed") == 0);
  CHECK(st.find("exit_code = 3") != std::string::npos);
  CHECK(st.find("message = stokesian:") != std::string::npos);
  const std::string csv = slurp(out / "summary.csv");
  CHECK(csv.find("run_0001") != std::string::npos);
  CHECK(csv.find(",failed,3,") != std::string::npos);
  // Without --retry-failed a second call does not run it again; with it, it does (and fails again).
  const std::string attempts = slurp(out / "run_0001" / "attempts");
  CHECK(run_sweep(w.dir / "fail.toml", out).status == 6);
  CHECK(slurp(out / "run_0001" / "attempts") == attempts);
  CHECK(run_sweep(w.dir / "fail.toml", out, -1, {"--retry-failed"}).status == 6);
  CHECK(slurp(out / "run_0001" / "status").find("attempts = 2") != std::string::npos);
}
