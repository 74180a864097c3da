#pragma once
// Scene files (TOML) -> Scene. Every key is documented in docs/scene.md with unit and default.
// Unknown keys, wrong types, out-of-range values and inconsistent combinations throw ConfigError
// with "file:line: [table] key = value: problem (allowed ...)"; nothing is written.
#include "engine/core/scene.hpp"

#include <string>
#include <vector>

namespace toml {
inline namespace v3 {
class table;
}
}  // namespace toml

namespace stokesian::io {

Scene load_scene(const std::string& path);
// `source` names the text in messages (a file name).
Scene parse_scene(const std::string& text, const std::string& source);
// The same from a parsed TOML table (e.g. a base scene with overrides applied).
Scene parse_scene(const toml::table& root, const std::string& source);

// The scene with every key explicit (defaults filled in, generated particles listed), as TOML
// that parse_scene accepts and that resolves to the same Scene. Stored in every output file.
std::string resolved_toml(const Scene& s);

// Whether two resolved scene texts describe the same scene: equal text, or equal after parsing
// and resolving both again (so that formatting, key order and keys added with their defaults by
// a later version do not matter). Used to recognise a run on resume.
bool same_scene(const std::string& a, const std::string& b);
// What differs between two scene texts `a` (stored) and `b` (this run), one entry per key after
// resolving both: "[table] key: <value in a> -> <value in b>" (long values shortened). Empty when
// same_scene(a, b). A text that does not parse gives one entry saying so.
std::vector<std::string> scene_differences(const std::string& a, const std::string& b);

}  // namespace stokesian::io
