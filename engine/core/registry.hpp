#pragma once
// Registries: the open sets of methods (far-field methods, hydrodynamic solvers, integrators,
// outputs) as named entries instead of enum switches. A name is the TOML value that selects the
// entry and the word used in messages and docs; adding a method is adding one entry. Entries are
// registered explicitly by one function per registry (no static-initialisation order).
#include "engine/core/names.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace stokesian {

template <class Entry>  // Entry has a member `std::string name`
class Registry {
 public:
  explicit Registry(std::string what) : what_(std::move(what)) {}
  void add(Entry e) { entries_.push_back(std::move(e)); }
  const Entry* find(std::string_view name) const {
    for (const auto& e : entries_)
      if (e.name == name) return &e;
    return nullptr;
  }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& e : entries_) out.push_back(e.name);
    return out;
  }
  const std::vector<Entry>& entries() const { return entries_; }
  // "what" names the kind of entry in messages ("far-field method", "integrator", ...).
  const std::string& what() const { return what_; }

 private:
  std::string what_;
  std::vector<Entry> entries_;
};

}  // namespace stokesian
