#include "engine/methods.hpp"

#include "engine/kernels/far_field.hpp"
#include "engine/mobility_solver.hpp"
#include "engine/sd_accelerated.hpp"
#include "engine/sd_dense.hpp"
#include "ewald/ewald_reference.hpp"
#include "ewald/pme.hpp"
#include "trees/tree_mobility.hpp"

namespace stokesian {

namespace {

// Dense SD is O(N^3) in time and O(N^2) in memory; in periodic boxes M_inf is the dense Ewald sum.
constexpr std::size_t kDenseSdMaxOpen = 2000, kDenseSdMaxPeriodic = 500;
// rkf45 gives up when its step falls below this fraction of the scene's dt.
constexpr double kRkfMinStepFraction = 1e-12;

Registry<FarFieldMethodEntry> make_far_field_methods() {
  Registry<FarFieldMethodEntry> r("far-field method");
  r.add({"direct", "direct O(N^2) summation", false, true, true,
         [](const MobilitySpec& s) { return std::make_unique<DirectFarField>(s); }});
  r.add({"ewald", "dense Ewald sum (reference, O(N^2) memory)", true, true, false,
         [](const MobilitySpec& s) { return std::make_unique<ewald::EwaldFarField>(s); }});
  r.add({"pme", "PME Ewald sum, O(N log N), accuracy from tolerance", true, false, true,
         [](const MobilitySpec& s) { return std::make_unique<ewald::PmeFarField>(s); }});
  r.add({"tree", "octree fast multipole method, open domains, accuracy from tolerance", false, false, false,
         [](const MobilitySpec& s) { return std::make_unique<trees::TreeFarField>(s); }, false});
  return r;
}

Registry<SolverEntry> make_solvers() {
  Registry<SolverEntry> r("hydrodynamic solver");
  r.add({"free_draining", "self mobilities only", HydroModel::free_draining, false, false, true, 0, 0,
         [](SolverSetup s) { return std::make_unique<FreeDrainingSolver>(s.spec); }});
  r.add({"mobility_cg", "far-field mobility, constrained entries by conjugate gradients", HydroModel::far_field,
         true, false, true, 0, 0,
         [](SolverSetup s) { return std::make_unique<MobilitySolver>(std::move(s.far_field), s.knobs.mobility_cg); }});
  r.add({"dense_sd", "far field + lubrication, dense Cholesky (reference)", HydroModel::stokesian, true, true, true,
         kDenseSdMaxOpen, kDenseSdMaxPeriodic, [](SolverSetup s) {
           return std::make_unique<DenseStokesianDynamics>(std::move(s.far_field), s.spec.viscosity, s.near_field);
         }});
  r.add({"accelerated_sd", "far field + lubrication, matrix-free GMRES preconditioned by the CHOLMOD factor of the near field",
         HydroModel::stokesian, true, false, true, 0, 0, [](SolverSetup s) {
           auto solver = std::make_unique<AcceleratedStokesianDynamics>(
               std::move(s.far_field), s.spec.viscosity, s.near_field, s.knobs.krylov, AcceleratedStokesianDynamics::kShift,
               AcceleratedStokesianDynamics::Method::gmres, AcceleratedStokesianDynamics::kFactorGap, s.knobs.brownian);
           solver->set_far_field_factory(std::move(s.make_far_field));
           return solver;
         }});
  return r;
}

Registry<IntegratorEntry> make_integrators() {
  Registry<IntegratorEntry> r("integrator");
  r.add({"euler", "Euler-Maruyama, first order", true, false,
         [](const TimeParams&) { return std::make_unique<EulerIntegrator>(); }});
  r.add({"midpoint", "explicit midpoint, second order (deterministic part)", true, false,
         [](const TimeParams&) { return std::make_unique<MidpointIntegrator>(); }});
  r.add({"fixman", "Fixman midpoint: one Brownian force for both stages, gives the thermal drift", true, true,
         [](const TimeParams&) { return std::make_unique<FixmanIntegrator>(); }});
  r.add({"rkf45", "Runge-Kutta-Fehlberg 4(5), adaptive step", false, false, [](const TimeParams& t) {
           return std::make_unique<Rkf45Integrator>(t.rkf_tolerance, kRkfMinStepFraction * t.dt);
         }});
  return r;
}

}  // namespace

const Registry<FarFieldMethodEntry>& far_field_methods() {
  static const Registry<FarFieldMethodEntry> r = make_far_field_methods();
  return r;
}
const Registry<SolverEntry>& hydro_solvers() {
  static const Registry<SolverEntry> r = make_solvers();
  return r;
}
const Registry<IntegratorEntry>& integrators() {
  static const Registry<IntegratorEntry> r = make_integrators();
  return r;
}

}  // namespace stokesian
