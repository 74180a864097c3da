#include "engine/core/output.hpp"

#include <sstream>

namespace stokesian {

std::string ModelKey::text() const {
  std::string out;
  for (const auto& [k, v] : entries) out += (out.empty() ? "" : ";") + k + "=" + v;
  return out;
}

ModelKey ModelKey::parse(const std::string& text) {
  ModelKey key;
  if (text.empty() || text.find('\n') != std::string::npos) return key;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ';');) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) return ModelKey{};
    key.entries.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return key;
}

ModelKey ModelKey::from_legacy_description(const std::string& description) {
  // 0.1.0 wrote "hydrodynamics: L\nmoments: M[\nfar_field: F]\nbrownian: yes|no\n  - reason...".
  // Its solver followed from the level: dense Stokesian dynamics for "stokesian", the mobility
  // form otherwise.
  std::string level, moments, far_field, brownian;
  std::stringstream ss(description);
  for (std::string line; std::getline(ss, line);) {
    auto take = [&](const std::string& label, std::string& into) {
      const std::string l = label + ": ";
      if (line.rfind(l, 0) == 0 && into.empty()) into = line.substr(l.size());
    };
    take("hydrodynamics", level);
    take("moments", moments);
    take("far_field", far_field);
    take("brownian", brownian);
  }
  ModelKey key;
  if (level.empty() || moments.empty() || brownian.empty()) return key;
  key.entries = {{"hydrodynamics", level},
                 {"solver", level == "stokesian" ? "dense_sd" : level == "free_draining" ? "free_draining" : "mobility_cg"},
                 {"moments", moments},
                 {"far_field", level == "free_draining" ? "none" : far_field},
                 {"brownian", brownian == "yes" ? "yes" : "no"}};
  return key;
}

ModelKey ModelKey::from_stored(const std::string& text) {
  ModelKey k = parse(text);
  return k.empty() ? from_legacy_description(text) : k;
}

}  // namespace stokesian
