#pragma once
// Resolution of a scene to the cheapest adequate hydrodynamic model (docs/stokesian_dynamics.md):
// level (free draining -> far field -> Stokesian dynamics), solver, moments (F -> FT -> FTS),
// far-field method, integrator, Brownian or not. Choices are made over the registries of
// engine/methods.hpp; every choice carries its reason; explicit scene settings override the
// automatic choice, and a setting the engine cannot honour is a ConfigError naming file, line and
// key, never a fallback.
#include "engine/core/output.hpp"
#include "engine/core/scene.hpp"

#include <string>
#include <vector>

namespace stokesian {

struct ResolvedModel {
  HydroModel level = HydroModel::free_draining;
  std::string solver;                // registered solver; empty = the level's first solver
  Moments moments = Moments::F;
  std::string far_field = "direct";  // registered far-field method (unused at free draining)
  std::string integrator = "euler";
  bool brownian = false;
  bool fixed_particles = false;
  bool drift = false;  // Brownian with a mobility that is not divergence free: fixman integrator
  // Steps between samples of the Brownian stresslet of the bulk stress, 0 = none ([brownian]
  // stress_every resolved). Nonzero only where the stress records it: periodic box, Brownian FTS,
  // Fixman integrator.
  long brownian_stress_every = 0;
  std::vector<std::string> reasons;  // one line per decision
  std::string describe() const;      // multi-line, printed by `stokesian check` and stored in outputs
  ModelKey key() const;              // the run's identity for resume
};

// Throws ConfigError when the scene asks for something the engine does not provide.
ResolvedModel resolve_model(const Scene& scene);

// The solver a model names, or the first registered solver of its level.
std::string solver_of(const ResolvedModel& m);

// Far-field products of one deterministic solve: 1 for a mobility product with given forces, 20
// for an iterative solve (CG with given velocities: fixed particles or FTS; accelerated SD: 20-30
// GMRES products per solve, bench_asd); 0 at free draining. Used by the resource estimate.
double far_field_products_per_solve(const ResolvedModel& m);
// Far-field products per configuration: a solve, plus 15 with Brownian motion (a Lanczos force of
// 26-65 products at the first of the Fixman step's two configurations, bench_brownian). A cost hint
// (MobilitySpec::products_per_configuration), not an accuracy knob; 0 at free draining.
double far_field_products_per_configuration(const ResolvedModel& m);

}  // namespace stokesian
