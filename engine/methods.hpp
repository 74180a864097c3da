#pragma once
// The registries of the engine's methods. Each entry names a method (its TOML value), says when
// it applies, and makes it; model resolution (engine/model.cpp) chooses among entries and the
// Simulation builds what was chosen. Adding a far-field method, a solver or an integrator is
// adding its class in its folder and one entry in engine/methods.cpp.
#include "engine/core/operators.hpp"
#include "engine/accuracy.hpp"
#include "engine/core/registry.hpp"
#include "engine/core/scene.hpp"
#include "engine/hydro_solver.hpp"
#include "engine/integrators.hpp"
#include "lubrication/near_field.hpp"

#include <functional>
#include <memory>
#include <string>

namespace stokesian {

struct FarFieldMethodEntry {
  std::string name;
  std::string description;     // one line, for `stokesian check` and docs
  bool periodic = false;       // works in periodic boxes (true) or open domains (false)
  bool dense = false;          // holds the dense matrix (MobilityOperator::dense), as dense SD needs
  bool auto_choice = false;    // the default for its domain kind
  std::function<std::unique_ptr<MobilityOperator>(const MobilitySpec&)> make;
  // The product is symmetric to round-off (x.My = y.Mx). Otherwise its asymmetry is bounded by the
  // requested tolerance (the tree: its products are not exact adjoints), which Krylov and Lanczos
  // methods tolerate at that level; tests/test_conformance.cpp checks the bound that applies.
  bool symmetric_to_roundoff = true;
};

struct SolverSetup {
  MobilitySpec spec;                      // moments, viscosity, tolerance
  std::unique_ptr<MobilityOperator> far_field;  // made from the chosen far-field entry (nullptr for free draining)
  std::function<std::unique_ptr<MobilityOperator>()> make_far_field;  // another of the same (empty without)
  lubrication::NearFieldParams near_field;
  AccuracyKnobs knobs;                    // inner tolerances from the scene's (engine/accuracy.hpp)
};

struct SolverEntry {
  std::string name;
  std::string description;
  HydroModel level;             // the level it solves
  bool needs_far_field = true;  // takes a far-field operator
  bool needs_dense = false;     // the operator must hold its dense matrix
  bool brownian = false;        // samples Brownian motion
  // Largest N it accepts in open domains and in periodic boxes (0 = unlimited).
  std::size_t max_open = 0, max_periodic = 0;
  std::function<std::unique_ptr<HydroSolver>(SolverSetup)> make;
};

struct IntegratorEntry {
  std::string name;
  std::string description;
  bool stochastic = true;  // accepts Brownian displacements
  bool drift = false;      // its Brownian steps include the thermal drift kT div(mobility)
  std::function<std::unique_ptr<Integrator>(const TimeParams&)> make;
};

const Registry<FarFieldMethodEntry>& far_field_methods();
const Registry<SolverEntry>& hydro_solvers();
const Registry<IntegratorEntry>& integrators();

}  // namespace stokesian
