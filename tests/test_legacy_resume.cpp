// Runs started by stokesian 0.1.0 (tests/data/legacy, written at commit c015545) continue with this
// engine: the trajectory and checkpoint of the old release are accepted (their model is identified
// by the structured lines of its stored description, not by its prose), and the completed run
// ends where the old engine's uninterrupted run ended.
#include <doctest/doctest.h>

#include "engine/core/output.hpp"
#include "io/checkpoint.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"

#include <hdf5.h>

#include "support/hdf5_read.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace stokesian;

using stokesian::test::read_doubles;

namespace {

const fs::path kData = fs::path(STOKESIAN_SOURCE_DIR) / "tests" / "data" / "legacy";


// A scratch copy of one legacy run: scene, trajectory and checkpoint.
fs::path copy_run(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("stokesian_legacy_" + std::to_string(getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const char* ext : {".toml", ".h5", ".h5.ckpt"}) fs::copy_file(kData / (name + ext), dir / (name + ext));
  return dir;
}

int run_cli(const fs::path& dir, const std::string& name, const std::string& scene) {
  const std::string cmd = std::string(STOKESIAN_BINARY) + " run " + (dir / scene).string() + " --out " +
                          (dir / (name + ".h5")).string() + " --resume --quiet --threads 2 2> " +
                          (dir / "err.txt").string();
  return WEXITSTATUS(std::system(cmd.c_str()));
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

TEST_CASE("a 0.1.0 trajectory and checkpoint resume and finish where the old engine finished") {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  for (const std::string name : {"legacy_sd", "legacy_sheared"}) {
    CAPTURE(name);
    const fs::path dir = copy_run(name);
    const auto before = io::inspect_trajectory((dir / (name + ".h5")).string());
    CHECK(before.last_step == 6);
    CHECK(!ModelKey::parse(before.model_key).empty());  // read from the old description

    REQUIRE(run_cli(dir, name, name + ".toml") == 0);
    const std::string traj = (dir / (name + ".h5")).string();
    const auto after = io::inspect_trajectory(traj);
    CHECK(after.frames == 7);
    CHECK(after.last_step == 12);

    // Final frame against the old engine's uninterrupted run (17 significant digits stored). For
    // legacy_sd the arithmetic is the same, so on one machine the results agree to the last bit;
    // across machines libm may round differently, hence the 1e-12 relative bound. legacy_sheared
    // uses the PME far field, rewritten since 0.1.0 (issue 12): its products now differ from the old
    // ones within the scene's tolerance (1e-6), which bounds the difference of the final frame.
    std::istringstream expected(read_text(kData / (name + ".expected.txt")));
    std::string header;
    std::getline(expected, header);
    const auto x = read_doubles(traj, "/particles/all/position/value");
    const auto u = read_doubles(traj, "/particles/all/velocity/value");
    const std::size_t n = after.particles, last = (std::size_t(after.frames) - 1) * n * 3;
    double err = 0.0, scale = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      double ref[6];
      for (double& r : ref) expected >> r;
      for (int c = 0; c < 3; ++c) {
        err = std::max(err, std::abs(x[last + 3 * i + std::size_t(c)] - ref[c]));
        err = std::max(err, std::abs(u[last + 3 * i + std::size_t(c)] - ref[3 + c]));
        scale = std::max({scale, std::abs(ref[c]), std::abs(ref[3 + c])});
      }
    }
    CHECK(expected.good());
    CHECK(err <= (name == "legacy_sheared" ? 1e-6 : 1e-12) * scale);
    fs::remove_all(dir);
  }
}

TEST_CASE("a 0.1.0 run is still recognised by what it is: another scene or model is refused") {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const std::string name = "legacy_sd";
  const fs::path dir = copy_run(name);
  // A different force: the scene differs. (A different [time] dt alone is accepted on resume:
  // docs/reliability.md, "Failure policies during a run".)
  {
    std::string scene = read_text(dir / (name + ".toml"));
    scene.replace(scene.find("external_force = [0.0, 0.0, -1.0]"), 33, "external_force = [0.0, 0.0, -2.0]");
    std::ofstream(dir / "other_dt.toml") << scene;
  }
  CHECK(run_cli(dir, name, "other_dt.toml") == 4);
  CHECK(read_text(dir / "err.txt").find("scene differs") != std::string::npos);
  // The same scene resolved to another model (as a later engine might): the model key differs.
  {
    const auto info = io::inspect_trajectory((dir / (name + ".h5")).string());
    RunHeader h;
    h.particles = info.particles;
    h.particle_fields = info.particle_fields;
    h.scene_toml = info.scene_toml;
    h.model_key = "hydrodynamics=far_field;solver=mobility_cg;moments=FT;far_field=direct;brownian=no";
    io::Checkpoint restored;
    CHECK_THROWS_WITH_AS(io::RunOutput::resume((dir / (name + ".h5")).string(), h, restored),
                         doctest::Contains("the model differs"), IoError);
    h.model_key = info.model_key;  // the key read from the 0.1.0 description
    CHECK(h.model_key == "hydrodynamics=stokesian;solver=dense_sd;moments=FT;far_field=direct;brownian=no");
  }
  // Nothing was changed by the refusals: the original scene still resumes.
  CHECK(run_cli(dir, name, name + ".toml") == 0);
  fs::remove_all(dir);
}

TEST_CASE("the model key reads 0.1.0 descriptions by their structured lines, not their reasons") {
  // The description stored by 0.1.0 in tests/data/legacy/legacy_sd.h5.
  const std::string old = io::inspect_trajectory((kData / "legacy_sd.h5").string()).model;
  const ModelKey key = ModelKey::from_legacy_description(old);
  CHECK(key.text() == "hydrodynamics=stokesian;solver=dense_sd;moments=FT;far_field=direct;brownian=no");
  // Reworded reasons (the lines after the choices) leave the key unchanged.
  const std::string reworded = old.substr(0, old.find("\n  - ")) + "\n  - a different explanation\n  - another one";
  CHECK(ModelKey::from_legacy_description(reworded) == key);
  // A different choice changes it.
  std::string other = old;
  other.replace(other.find("moments: FT"), 11, "moments: FTS");
  CHECK(ModelKey::from_legacy_description(other) != key);
  // Text without the structured lines has no key; a key's own text reads back as itself.
  CHECK(ModelKey::from_legacy_description("stokesian FTS, far field direct").empty());
  CHECK(ModelKey::from_stored(key.text()) == key);
}

TEST_CASE("a run's scene is recognised through formatting, key order and comments, not through a changed value") {
  const std::string stored = io::inspect_trajectory((kData / "legacy_sd.h5").string()).scene_toml;
  // The same scene written by hand: other order, comments, defaults left out.
  const std::string by_hand = read_text(kData / "legacy_sd.toml");
  CHECK(by_hand != stored);
  CHECK(io::same_scene(stored, by_hand));
  std::string changed = by_hand;
  changed.replace(changed.find("dt = 0.05"), 9, "dt = 0.04");
  CHECK(!io::same_scene(stored, changed));
  CHECK(!io::same_scene(stored, "not = [toml"));
}
