#pragma once
// The one map between each closed set of choices (an enum) and its names. The names are the
// TOML values of the scene keys, the words in messages and the lists in docs/scene.md.
// A table is a specialisation Names<E> with `static constexpr NameTable<E, K> table` listing
// every enumerator once; name_of, parse_name and name_list below work for any such enum.
// Open sets (far-field methods, solvers, integrators, outputs) are registries instead
// (engine/core/registry.hpp): they are extended by registering a class, not by editing an enum.
#include "engine/core/types.hpp"

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace stokesian {

template <class E, std::size_t K>
using NameTable = std::array<std::pair<E, const char*>, K>;

template <class E>
struct Names;  // specialised next to each enum

template <class E>
const char* name_of(E e) {
  for (const auto& [v, n] : Names<E>::table)
    if (v == e) return n;
  return "?";
}

template <class E>
std::optional<E> parse_name(std::string_view s) {
  for (const auto& [v, n] : Names<E>::table)
    if (s == n) return v;
  return std::nullopt;
}

template <class E>
std::vector<std::string> name_list() {
  std::vector<std::string> out;
  for (const auto& e : Names<E>::table) out.emplace_back(e.second);
  return out;
}

// "\"a\", \"b\", \"c\"" for messages.
inline std::string quoted_list(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "\"" : ", \"") + n + "\"";
  return out;
}

template <>
struct Names<Moments> {
  static constexpr NameTable<Moments, 3> table{{{Moments::F, "F"}, {Moments::FT, "FT"}, {Moments::FTS, "FTS"}}};
};

}  // namespace stokesian
