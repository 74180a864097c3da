#include "engine/hydrodynamics.hpp"

#include "engine/methods.hpp"

#include <stdexcept>

namespace stokesian {

Hydrodynamics::Hydrodynamics(const ResolvedModel& model, double viscosity, std::shared_ptr<const AmbientField> flow,
                             double tolerance, lubrication::NearFieldParams near_field, double radius_ratio)
    : model_(model), flow_(std::move(flow)) {
  const SolverEntry* solver = hydro_solvers().find(solver_of(model_));
  if (!solver) throw std::invalid_argument("Hydrodynamics: no solver \"" + solver_of(model_) + "\"");
  SolverSetup setup;
  setup.knobs = derive_knobs(tolerance, model_.level, radius_ratio, model_.fixed_particles);
  setup.spec = MobilitySpec{model_.moments, viscosity, setup.knobs.far_field,
                            far_field_products_per_configuration(model_)};
  setup.near_field = near_field;
  if (solver->needs_far_field) {
    const FarFieldMethodEntry* ff = far_field_methods().find(model_.far_field);
    if (!ff) throw std::invalid_argument("Hydrodynamics: no far-field method \"" + model_.far_field + "\"");
    setup.far_field = ff->make(setup.spec);
    setup.make_far_field = [ff, spec = setup.spec] { return ff->make(spec); };
  }
  solver_ = solver->make(std::move(setup));
}

void Hydrodynamics::prepare(const Configuration& c) {
  if (prepared_.same_as(c)) return;
  prepared_.valid = false;
  solver_->prepare(c);
  prepared_.store(c);
}

std::vector<PreparePhase> Hydrodynamics::prepare_phases(const Configuration& c) {
  if (prepared_.same_as(c)) return {};
  prepared_.valid = false;
  std::vector<PreparePhase> ph = solver_->prepare_phases(c);
  std::vector<int> all;
  for (int k = 0; k < int(ph.size()); ++k) all.push_back(k);
  ph.push_back({"hydro_prepared", false, [this, &c] { prepared_.store(c); }, all});
  return ph;
}

HydroResult Hydrodynamics::solve(const Configuration& c, const std::vector<char>& fixed, const std::vector<Vec3>& F,
                                 const std::vector<Vec3>& T, const VecX* noise, WarmStart* warm) {
  FlowSample sample;
  flow_->sample(c.x, sample);
  return solver_->solve(HydroProblem{c, fixed, sample, F, T, noise && noise->size() ? noise : nullptr, nullptr, warm});
}

VecX Hydrodynamics::brownian_force(const Configuration& c, const std::vector<char>& fixed, double kT, double dt,
                                   Rng& rng) {
  prepare(c);
  return solver_->brownian_force(kT, dt, fixed, rng);
}

HydroResult Hydrodynamics::noise_velocity(const Configuration& c, const std::vector<char>& fixed, const VecX& xi,
                                          WarmStart* warm) {
  const std::size_t n = c.x.size();
  FlowSample still;
  AmbientFlow{}.sample(c.x, still);
  const std::vector<Vec3> zero(n, Vec3::Zero());
  return solver_->solve(HydroProblem{c, fixed, still, zero, zero, &xi, nullptr, warm});
}

HydroResult Hydrodynamics::solve(const std::vector<Vec3>& x, const std::vector<double>& a,
                                 const std::vector<char>& fixed, const std::vector<Vec3>& F,
                                 const std::vector<Vec3>& T, const Domain& domain) {
  const Configuration c{x, a, domain};
  prepare(c);
  return solve(c, fixed, F, T);
}

std::vector<Vec3> Hydrodynamics::brownian_displacement(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                       double kT, double dt, Rng& rng, const Domain& domain) {
  prepare({x, a, domain});
  return solver_->brownian_displacement(kT, dt, rng);
}

}  // namespace stokesian
