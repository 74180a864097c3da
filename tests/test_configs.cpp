// Every example scene in configs/ parses, resolves to a model the engine has, and its stored
// resolved scene re-parses to the same scene.
#include <doctest/doctest.h>

#include "engine/model.hpp"
#include "io/scene_toml.hpp"

#include <filesystem>

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
