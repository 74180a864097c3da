#pragma once
// Scene files (TOML) -> Scene. Every key is documented in docs/scene.md with unit and default.
// Unknown keys, wrong types, out-of-range values and inconsistent combinations throw ConfigError
// with "file:line: [table] key = value: problem (allowed ...)"; nothing is written.
#include "engine/scene.hpp"

#include <string>

namespace stokesian::io {

Scene load_scene(const std::string& path);
// `source` names the text in messages (a file name).
Scene parse_scene(const std::string& text, const std::string& source);

// The scene with every key explicit (defaults filled in, generated particles listed), as TOML
// that parse_scene accepts and that resolves to the same Scene. Stored in every output file.
std::string resolved_toml(const Scene& s);

}  // namespace stokesian::io
