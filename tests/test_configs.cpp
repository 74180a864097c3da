// Every example scene in configs/ parses, resolves to a model the engine has, and its stored
// resolved scene re-parses to the same scene.
#include <doctest/doctest.h>

#include "engine/model.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <algorithm>
#include <cmath>
#include <chrono>
#include <filesystem>
#include <limits>

using namespace stokesian;

TEST_CASE("example scenes in configs/ are valid") {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(STOKESIAN_SOURCE_DIR) + "/configs")) {
    if (entry.path().extension() != ".toml") continue;
    const std::string path = entry.path().string();
    CAPTURE(path);
    Scene s;
    CHECK_NOTHROW(s = io::load_scene(path));
    CHECK_NOTHROW(resolve_model(s));
    CHECK(io::parse_scene(s.toml, "resolved.toml").toml == s.toml);
    ++count;
  }
  CHECK(count >= 5);
}

// Every example runs briefly and stays physical: finite positions, no overlapping pairs beyond the
// small soft-contact overlap its Hertz law allows, and no pair closer than a tenth of its initial
// smallest gap unless a force law holds it there. The number of steps is chosen per example so that
// the unstable steps of earlier versions (sheared_suspension with dt = 0.2: smallest gap -0.03 a
// after 10 steps, -2.4 a after 100) are caught, while the whole suite stays short: examples of more
// than 5000 particles (the 10^4-particle accelerated-SD suspension) take 2 steps at full size, those
// of 500 or more (the Brownian hard-sphere rheology scene) 5.
TEST_CASE("example scenes run briefly and stay physical") {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(STOKESIAN_SOURCE_DIR) + "/configs")) {
    if (entry.path().extension() != ".toml") continue;
    const std::string path = entry.path().string();
    CAPTURE(path);
    Scene scene = io::load_scene(path);
    const long steps = std::min<long>(scene.time.steps, scene.positions.size() > 5000 ? 2 : scene.positions.size() >= 500 ? 5 : 20);
    // Through the run loop (as `stokesian run`), a frame every step: open channels insert and remove.
    scene.output.every = 1;
    Simulation sim(scene);
    State s = sim.initial_state();
    struct Frames final : OutputSink {
      std::vector<Frame> frames;
      void record(const Frame& f) override { frames.push_back(f); }
      void checkpoint(const State&) override {}
    } out;
    RunControl rc;
    rc.quiet = true;
    rc.max_steps = steps;
    const auto start = std::chrono::steady_clock::now();
    REQUIRE_NOTHROW(sim.run(s, out, rc));  // a PhysicsError (non-finite state, deep overlap) stops it
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    REQUIRE(long(out.frames.size()) == steps + 1);
    double min_gap = std::numeric_limits<double>::infinity();
    long overlaps = 0;
    for (const Frame& f : out.frames) {
      min_gap = std::min(min_gap, f.scalar("min_gap"));
      overlaps = std::max(overlaps, long(f.scalar("overlaps")));
      const auto& x = f.particles.at("position").values;
      const auto id = f.particles.find("id");  // open channels: empty slots (id -1) are NaN
      for (std::size_t i = 0; i < x.size(); ++i)
        if (id == f.particles.end() || id->second.values[i / 3] >= 0) REQUIRE(std::isfinite(x[i]));
      if (const auto u = f.particles.find("velocity"); u != f.particles.end())
        for (std::size_t i = 0; i < u->second.values.size(); ++i)
          if (id == f.particles.end() || id->second.values[i / 3] >= 0) REQUIRE(std::isfinite(u->second.values[i]));
    }
    MESSAGE(entry.path().filename().string() << ": " << steps << " steps (" << seconds << " s), smallest gap " << min_gap << " a, overlapping pairs " << overlaps);
    // Athermal examples: their repulsions keep surfaces apart (a Hertz backstop at their force
    // scale would overlap by < 0.01 a). Brownian examples: thermal kicks push into the Hertz contact;
    // at 0.05 a its energy (2/5) k d^(5/2) is 4.5 kT for the examples' k = 20000 kT/a^(5/2).
    const bool brownian = scene.fluid.kT > 0;
    CHECK(min_gap > (brownian ? -0.05 : -0.01));
    CHECK(overlaps <= (brownian ? 10 : 0));
    ++count;
  }
  CHECK(count >= 5);
}
