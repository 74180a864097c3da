#pragma once
// Resolution of a scene to the cheapest adequate hydrodynamic model (shared/notes/method.md s.1):
// level (free draining -> far field -> Stokesian dynamics), moments (F -> FT -> FTS), far-field
// method, Brownian or not. Every choice carries its reason; explicit scene settings override the
// automatic choice, and a setting the engine cannot honour is a ConfigError, never a fallback.
#include "engine/scene.hpp"

#include <string>
#include <vector>

namespace stokesian {

struct ResolvedModel {
  HydroModel level = HydroModel::free_draining;
  Moments moments = Moments::F;
  FarFieldMethod far_field = FarFieldMethod::direct;  // meaningful for far_field / stokesian
  bool brownian = false;
  bool fixed_particles = false;
  std::vector<std::string> reasons;  // one line per decision
  std::string describe() const;      // multi-line, printed by `stokesian check` and stored in outputs
};

const char* to_string(HydroModel m);
const char* to_string(FarFieldMethod m);

// Throws ConfigError (naming scene.source and the key) when the scene asks for something the
// engine does not provide.
ResolvedModel resolve_model(const Scene& scene);

}  // namespace stokesian
