// Resource estimates (engine/resources.hpp): component sizes against hand-computed figures and the
// operators' own parameters, and the CLI refusing scenes the memory cannot hold (exit 2, nothing
// written), before any particle is generated when the count alone is too large.
#include "engine/core/memory.hpp"
#include "engine/model.hpp"
#include "engine/resources.hpp"
#include "ewald/pme.hpp"
#include "io/scene_toml.hpp"
#include "support/cli.hpp"

#include <doctest/doctest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace stokesian;

namespace {

using Cli = test::CliResult;
using test::contains;

// A fresh folder `name` inside this process's scratch folder (removed at exit).
fs::path scratch(const std::string& name) {
  static const test::ScratchDir root("stokesian_test_resources_");
  const fs::path d = root.path / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Runs the CLI binary in `dir` with the scene text written to dir/scene.toml and `env` prepended;
// its stdout and stderr go to files in the parent folder, so `dir` holds only what the run wrote.
Cli cli(const fs::path& dir, const std::string& scene, const std::string& args, const std::string& env = "") {
  std::ofstream(dir / "scene.toml") << scene;
  return test::run_stokesian(args, dir.parent_path(), env, dir);
}

bool has(const std::string& s, const std::string& what) { return contains(s, what); }

// 64 spheres on a 4 x 4 x 4 lattice of spacing 3 a, open domain.
std::string lattice64(const std::string& extra) {
  std::ostringstream o;
  o << "[particles]\npositions = [";
  for (int i = 0; i < 64; ++i) o << (i ? ", " : "") << "[" << 3 * (i % 4) << ", " << 3 * (i / 4 % 4) << ", " << 3 * (i / 16) << "]";
  o << "]\n" << extra;
  return o.str();
}

}  // namespace

TEST_CASE("dense SD at N = 64: the matrices are (d N)^2 doubles") {
  for (const auto& [moments, d] : {std::pair{"F", 3}, std::pair{"FT", 6}}) {
    const Scene s = io::parse_scene(lattice64(std::string("[hydrodynamics]\nmodel = \"stokesian\"\nsolver = \"dense\"\nmoments = \"") +
                                              moments + "\"\n[time]\ndt = 0.01\nsteps = 1\n"),
                                    "sd64.toml");
    const ResolvedModel m = resolve_model(s);
    REQUIRE(solver_of(m) == "dense_sd");
    const ResourceEstimate e = estimate_resources(s, m);
    const ResourceComponent* far = e.find("far-field matrix");
    const ResourceComponent* sd = e.find("SD resistance");
    REQUIRE(far);
    REQUIRE(sd);
    const double n = 64.0 * d;  // F: 192 x 192, FT: 384 x 384
    CHECK(far->bytes == n * n * 8);
    CHECK(sd->bytes == 3 * n * n * 8);
    CHECK(e.find("scene and particle arrays")->bytes == 64 * kBytesPerParticle);
    // FT: 384^2 doubles = 1 179 648 bytes.
    if (d == 6) CHECK(far->bytes == 1179648.0);
    double sum = 0;
    for (const auto& c : e.components) sum += c.bytes;
    CHECK(e.peak_bytes == sum);
    CHECK(e.seconds_per_step > 0);
  }
}

TEST_CASE("PME grid of a given box: the operator's own grid, 3 padded fields, their spectra and the kernel") {
  const std::string text = lattice64(
      "[domain]\nkind = \"periodic\"\nbox = [12.0, 12.0, 24.0]\n[hydrodynamics]\nmodel = \"far_field\"\n"
      "far_field = \"pme\"\ntolerance = 1e-4\n[time]\ndt = 0.01\nsteps = 1\n");
  const Scene s = io::parse_scene(text, "pme.toml");
  const ResolvedModel m = resolve_model(s);
  REQUIRE(m.far_field == "pme");
  REQUIRE(m.moments == Moments::F);
  const ResourceEstimate e = estimate_resources(s, m);
  const ResourceComponent* grid = e.find("PME grid");
  REQUIRE(grid);
  // The grid the operator itself builds for this configuration, with the cost hint the engine
  // passes (engine/hydrodynamics.cpp): one product per configuration for forces given at F.
  CHECK(far_field_products_per_configuration(m) == 1.0);
  ewald::PmeFarField op(MobilitySpec{Moments::F, 1.0, 1e-4, far_field_products_per_configuration(m)});
  op.set_configuration(Configuration{s.positions, s.radii, s.domain});
  const auto M = op.parameters().grid;
  const int P = op.parameters().support;
  // ewald/pme.cpp: 3 fields of M0 M1 rows of (M2 + P) rounded up to a multiple of 4 doubles, 3 half
  // spectra and the kernel's two factors per spectral point.
  const double G = double(M[0]) * M[1] * ((M[2] + P + 3) / 4 * 4), spectral = double(M[0]) * M[1] * (M[2] / 2 + 1);
  CHECK(grid->bytes == 8.0 * 3 * G + 16.0 * 3 * spectral + 16.0 * spectral);
  CHECK(has(grid->formula, std::to_string(M[0]) + " x " + std::to_string(M[1]) + " x " + std::to_string(M[2])));
}

TEST_CASE("memory sizes and STOKESIAN_MEMORY_LIMIT") {
  CHECK(format_bytes(512) == "512 B");
  CHECK(format_bytes(1179648) == "1.12 MB");
  CHECK(format_bytes(3.0 * 1024 * 1024 * 1024) == "3 GB");
  CHECK(parse_memory_limit("8G") == 8.0 * 1024 * 1024 * 1024);
  CHECK(parse_memory_limit("512M") == 512.0 * 1024 * 1024);
  CHECK(parse_memory_limit("1000") == 1000.0);
  for (const char* bad : {"", "x", "8Q", "-1G", "0", "nan", "1e999", "8GB"}) CHECK_THROWS_AS(parse_memory_limit(bad), ConfigError);
}

TEST_CASE("CLI: a PME box the machine cannot hold is refused up front (exit 2, the figure, nothing written)") {
  // Two particles in a 1.5e4 x 1.5e4 x 8 slab: the short edge bounds the real-space cut-off, so the
  // grid must resolve wave numbers ~ 4 / a along both long edges (~2 10^4 points each): hundreds of GB. (A
  // 1e6 x 8 x 8 tube no longer serves: there the long-wave flow of the periodic tube dominates |M x|,
  // and the tolerance, relative to |M x|, is met on a coarse grid; docs/ewald.md s.4.)
  const std::string scene =
      "[domain]\nkind = \"periodic\"\nbox = [1.5e4, 1.5e4, 8]\n[particles]\npositions = [[1, 4, 4], [5, 4, 4]]\n"
      "[hydrodynamics]\nmodel = \"far_field\"\n[time]\ndt = 0.01\nsteps = 10\n";
  for (const char* cmd : {"solve scene.toml --out o.h5", "run scene.toml --out o.h5", "check scene.toml --out o.h5"}) {
    CAPTURE(cmd);
    const fs::path dir = scratch("pme_box");
    const Cli c = cli(dir, scene, cmd);
    CAPTURE(c.err);
    CHECK(c.status == 2);
    CHECK(has(c.err, "scene.toml: this scene needs about "));
    CHECK(has(c.err, "GB of memory (largest part: PME grid"));
    CHECK(has(c.err, "is available (MemAvailable"));
    CHECK(has(c.err, "[domain] box"));
    CHECK(!has(c.err, "bad_alloc"));
    for (const char* f : {"o.h5", "o.h5.ckpt", "o.h5.starting", "o.h5.shadow"}) CHECK(!fs::exists(dir / f));
  }
}

TEST_CASE("CLI: dense SD over STOKESIAN_MEMORY_LIMIT is refused naming the largest part; above half warns") {
  const std::string scene =
      lattice64("[hydrodynamics]\nmodel = \"stokesian\"\nsolver = \"dense\"\nmoments = \"FT\"\n[time]\ndt = 0.01\nsteps = 1\n");
  // Peak: 4 x 1.12 MB (matrices) + 64 KB (particles) + the near field: about 4.9 MB.
  const fs::path dir = scratch("sd_limit");
  Cli c = cli(dir, scene, "run scene.toml --out o.h5", "STOKESIAN_MEMORY_LIMIT=2M");
  CAPTURE(c.err);
  CHECK(c.status == 2);
  CHECK(has(c.err, "largest part: SD resistance and factors, 3.38 MB"));
  CHECK(has(c.err, "but only 2 MB is available (STOKESIAN_MEMORY_LIMIT)"));
  CHECK(has(c.err, "[hydrodynamics] model (line"));
  CHECK(!fs::exists(dir / "o.h5"));

  c = cli(dir, scene, "check scene.toml --no-estimate", "STOKESIAN_MEMORY_LIMIT=8M");
  CAPTURE(c.err);
  CHECK(c.status == 0);
  CHECK(has(c.err, "warning: scene.toml: the run will need about"));
  CHECK(has(c.out, "resources (estimate; docs/reliability.md):"));
  CHECK(has(c.out, "far-field matrix (direct, dense): 1.12 MB"));
  CHECK(has(c.out, "available memory: 8 MB (STOKESIAN_MEMORY_LIMIT)"));

  c = cli(dir, scene, "check scene.toml --no-estimate", "STOKESIAN_MEMORY_LIMIT=lots");
  CHECK(c.status == 2);
  CHECK(has(c.err, "STOKESIAN_MEMORY_LIMIT = \"lots\": not a memory size"));
}

TEST_CASE("CLI: a generated count too large for the memory is refused before placement") {
  // 10^6 particles: refused with a 100 MB limit before any is placed.
  const std::string scene =
      "[domain]\nkind = \"periodic\"\nbox = [400, 400, 400]\n[particles]\ngenerate = \"random\"\ncount = 1000000\n"
      "[time]\ndt = 0.01\nsteps = 1\n";
  const fs::path dir = scratch("count");
  const Cli c = cli(dir, scene, "check scene.toml --no-estimate", "STOKESIAN_MEMORY_LIMIT=100M");
  CAPTURE(c.err);
  CHECK(c.status == 2);
  CHECK(has(c.err, "scene.toml:6: [particles] count: 1000000 particles need about 977 MB of memory"));
  CHECK(has(c.err, "allowed: at most 102400 particles here"));
}
