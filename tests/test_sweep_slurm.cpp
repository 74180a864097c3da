// `stokesian sweep --slurm` against a real Slurm (issue 14): a one-node cluster from Debian's
// slurm-wlm and munge is started locally (tests/slurm/local_slurm.sh), a 4-run sweep is prepared
// with --slurm, its job array submitted with `sbatch --wait`, and the summary written with
// --summary; every trajectory (byte for byte per dataset) and the summary table (apart from the
// timing columns) must equal the local path's. Where the daemons cannot start (packages missing,
// not root, no network namespace for the ports), the suite exits 77, which CTest reports as
// skipped, after printing why.
#include "support/h5_compare.hpp"
#include "support/sweep_support.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;
using namespace stokesian::test;

namespace {

const char* kBase = R"([fluid]
kT = 1.0
[particles]
generate = "random"
count = 30
volume_fraction = 0.05
seed = 11
[[forces.pair]]
kind = "hertz"
stiffness = 2000.0
[hydrodynamics]
model = "far_field"
[time]
dt = 0.002
steps = 200
integrator = "euler"
[output]
every = 10
)";

const char* kSweep = R"(base = "base.toml"
[[zip]]
keys = ["particles.volume_fraction", "fluid.kT"]
values = [[0.05, 1.0], [0.1, 0.5]]
[replicas]
count = 2
[slurm]
time = "00:10:00"
mem = "500M"
cpus_per_task = 1
)";

struct LocalSlurm {
  fs::path dir;
  bool up = false;
  std::string why;
  explicit LocalSlurm(const fs::path& d) : dir(d) {
    const std::string script = std::string(STOKESIAN_SOURCE_DIR) + "/tests/slurm/local_slurm.sh";
    const fs::path err = dir.string() + ".start.err";
    const ChildOutcome o = run_child({"/bin/bash", script, "start", dir.string()}, -1, "", err.string(), 120000.0);
    up = !o.killed && o.status == 0;
    why = slurp(err);
    if (up) setenv("SLURM_CONF", (dir / "slurm.conf").c_str(), 1);
  }
  ~LocalSlurm() {
    const std::string script = std::string(STOKESIAN_SOURCE_DIR) + "/tests/slurm/local_slurm.sh";
    run_child({"/bin/bash", script, "stop", dir.string()}, -1, "", "", 60000.0);
  }
};

}  // namespace

TEST_CASE("sweep --slurm: a 4-task job array on a local Slurm gives the local path's results") {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  SweepWork w("sweep_slurm", kBase, kSweep);
  LocalSlurm slurm(w.dir / "slurm");
  if (!slurm.up) {
    std::fprintf(stderr, "test_sweep_slurm: SKIPPED: the local Slurm did not start: %s\n", slurm.why.c_str());
    std::fflush(stderr);
    std::_Exit(77);
  }
  const fs::path local = w.dir / "local", cluster = w.dir / "cluster";
  REQUIRE(run_sweep(w.dir / "sweep.toml", local).status == 0);

  const ChildOutcome prep = run_sweep(w.dir / "sweep.toml", cluster, -1, {"--slurm"});
  REQUIRE(prep.status == 0);
  const std::string script = slurp(cluster / "sweep.sbatch");
  CHECK(script.find("#SBATCH --array=0-3%2") != std::string::npos);
  CHECK(script.find("#SBATCH --time=00:10:00") != std::string::npos);
  CHECK(script.find("--run \"$SLURM_ARRAY_TASK_ID\"") != std::string::npos);
  CHECK(!fs::exists(cluster / "run_0000" / "trajectory.h5"));  // --slurm runs nothing itself

  const ChildOutcome sb = run_child({"/usr/bin/sbatch", "--wait", (cluster / "sweep.sbatch").string()}, -1, "",
                                    (w.dir / "sbatch.err").string(), 300000.0);
  INFO(slurp(w.dir / "sbatch.err"));
  REQUIRE(!sb.killed);
  REQUIRE(sb.status == 0);
  REQUIRE(run_sweep(w.dir / "sweep.toml", cluster, -1, {"--summary"}).status == 0);

  for (int i = 0; i < 4; ++i) {
    char name[16];
    std::snprintf(name, sizeof name, "run_%04d", i);
    CAPTURE(name);
    CHECK(slurp(cluster / name / "status").find("status = done") == 0);
    std::map<std::string, Blob> a, b;
    std::string ea, eb;
    REQUIRE(read_file((local / name / "trajectory.h5").string(), a, ea));
    REQUIRE(read_file((cluster / name / "trajectory.h5").string(), b, eb));
    for (const auto& d : compare(b, a, false)) CHECK_MESSAGE(false, d);
  }
  CHECK(summary_without_timing(local / "summary.csv") == summary_without_timing(cluster / "summary.csv"));
  CHECK(summary_without_timing(cluster / "summary.csv").find("pending") == std::string::npos);
}
