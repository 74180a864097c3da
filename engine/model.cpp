#include "engine/model.hpp"

#include "engine/errors.hpp"
#include "engine/flow.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace stokesian {

const char* to_string(HydroModel m) {
  switch (m) {
    case HydroModel::auto_: return "auto";
    case HydroModel::free_draining: return "free_draining";
    case HydroModel::far_field: return "far_field";
    case HydroModel::stokesian: return "stokesian";
  }
  return "?";
}

const char* to_string(FarFieldMethod m) {
  switch (m) {
    case FarFieldMethod::auto_: return "auto";
    case FarFieldMethod::direct: return "direct";
    case FarFieldMethod::ewald: return "ewald";
    case FarFieldMethod::pme: return "pme";
    case FarFieldMethod::tree: return "tree";
  }
  return "?";
}

std::string ResolvedModel::describe() const {
  std::ostringstream o;
  o << "hydrodynamics: " << to_string(level) << "\nmoments: " << to_string(moments);
  if (level != HydroModel::free_draining) o << "\nfar_field: " << to_string(far_field);
  o << "\nbrownian: " << (brownian ? "yes" : "no");
  for (const auto& r : reasons) o << "\n  - " << r;
  return o.str();
}

namespace {

// Smallest surface gap over all pairs (open or minimum image), O(N^2) but run once per scene.
double min_gap(const Scene& s) {
  double g = INFINITY;
  for (std::size_t i = 0; i < s.positions.size(); ++i)
    for (std::size_t j = i + 1; j < s.positions.size(); ++j)
      g = std::min(g, s.domain.minimum_image(s.positions[i] - s.positions[j]).norm() - s.radii[i] - s.radii[j]);
  return g;
}

[[noreturn]] void unavailable(const Scene& s, const std::string& key, const std::string& what) {
  throw ConfigError(s.source + ": [hydrodynamics] " + key + ": " + what);
}

}  // namespace

ResolvedModel resolve_model(const Scene& s) {
  ResolvedModel m;
  const std::size_t n = s.positions.size();
  const AmbientFlow flow = ambient_flow(s.flow);
  m.brownian = s.fluid.kT > 0.0;
  m.fixed_particles = std::any_of(s.fixed.begin(), s.fixed.end(), [](char c) { return c != 0; });
  m.reasons.push_back(m.brownian ? "fluid.kT > 0: Brownian motion on" : "fluid.kT = 0: athermal");

  // Level.
  // Dense SD is O(N^3) in time and O(N^2) memory; in periodic boxes M_inf is the dense Ewald sum.
  const std::size_t kDenseSdLimit = s.domain.periodic() ? 500 : 2000;
  if (s.hydro.model == HydroModel::auto_) {
    if (n <= 1) {
      m.level = HydroModel::free_draining;
      m.reasons.push_back("auto level: a single particle has no hydrodynamic interactions -> free_draining");
    } else {
      const double g = min_gap(s);
      std::ostringstream r;
      const bool near = g < 0.5 || !s.forces.pair.empty();
      if (near && !m.brownian && n <= kDenseSdLimit) {
        m.level = HydroModel::stokesian;
        r << "auto level: " << (g < 0.5 ? "close pairs (smallest gap " : "pair forces bring particles together (smallest gap ")
          << g << " a) -> stokesian (far field + lubrication, dense solver for N = " << n << ")";
      } else {
        m.level = HydroModel::far_field;
        r << "auto level: " << n << " particles interact hydrodynamically -> far_field";
        if (near) {
          r << " (lubrication would be more accurate";
          if (m.brownian) r << ", but Brownian Stokesian dynamics is not in this version";
          else r << ", but N > " << kDenseSdLimit << " needs the accelerated solver, not in this version";
          r << "; set model = \"far_field\" to silence)";
        }
      }
      m.reasons.push_back(r.str());
    }
  } else {
    m.level = s.hydro.model;
    m.reasons.push_back(std::string("level set by scene: ") + to_string(m.level));
  }
  if (m.level == HydroModel::stokesian) {
    if (m.brownian)
      unavailable(s, "model", "\"stokesian\" with fluid.kT > 0 needs near-field Brownian forces and drift, not in this "
                              "version; use \"far_field\" or kT = 0");
    if (n > kDenseSdLimit)
      unavailable(s, "model", "\"stokesian\" uses the dense reference solver, limited to N <= " +
                              std::to_string(kDenseSdLimit) + " in this version (N = " + std::to_string(n) + ")");
  }

  // Moments.
  const bool torques = std::any_of(s.forces.external_torque.begin(), s.forces.external_torque.end(),
                                   [](const Vec3& t) { return t.norm() > 0; });
  if (s.hydro.moments == MomentChoice::auto_) {
    if (flow.has_strain() && m.level != HydroModel::free_draining) {
      m.moments = Moments::FTS;
      m.reasons.push_back("auto moments: the ambient flow has a rate of strain -> FTS (rigid-particle stresslets)");
    } else if (torques || (m.level != HydroModel::free_draining && flow.any())) {
      m.moments = Moments::FT;
      m.reasons.push_back("auto moments: torques or ambient vorticity present -> FT");
    } else if (m.level == HydroModel::stokesian) {
      m.moments = Moments::FT;
      m.reasons.push_back("auto moments: torque-free spheres rotate near contact; F-level lubrication would hold "
                          "them non-rotating -> FT");
    } else if (m.level == HydroModel::free_draining && flow.has_strain()) {
      m.moments = Moments::FTS;
      m.reasons.push_back("auto moments: free-draining stresslets of isolated spheres in the strain -> FTS");
    } else {
      m.moments = Moments::F;
      m.reasons.push_back("auto moments: forces only, no torques or ambient flow -> F");
    }
  } else {
    m.moments = s.hydro.moments == MomentChoice::F ? Moments::F
              : s.hydro.moments == MomentChoice::FT ? Moments::FT : Moments::FTS;
    m.reasons.push_back(std::string("moments set by scene: ") + to_string(m.moments));
    if (torques && m.moments == Moments::F)
      unavailable(s, "moments", "\"F\" ignores the scene's external torques; use \"FT\" or \"FTS\"");
    if (m.level == HydroModel::stokesian && m.moments == Moments::F)
      m.reasons.push_back("note: F-level Stokesian dynamics treats the spheres as non-rotating");
  }

  // Far-field method.
  if (m.level != HydroModel::free_draining) {
    const FarFieldMethod want = s.hydro.far_field;
    if (want == FarFieldMethod::tree)
      unavailable(s, "far_field", "\"tree\" is not in this version; available: \"direct\" (open), \"pme\" and "
                                  "\"ewald\" (periodic), \"auto\"");
    if (s.domain.periodic()) {
      if (want == FarFieldMethod::direct)
        unavailable(s, "far_field", "\"direct\" has no periodic images; periodic boxes use \"pme\" or \"ewald\"");
      if (m.level == HydroModel::stokesian) {
        m.far_field = FarFieldMethod::ewald;
        m.reasons.push_back("far_field: dense Stokesian dynamics inverts the dense Ewald-summed mobility");
      } else if (want == FarFieldMethod::ewald) {
        m.far_field = FarFieldMethod::ewald;
        m.reasons.push_back("far_field set by scene: ewald (dense reference, O(N^2) memory)");
      } else {
        m.far_field = FarFieldMethod::pme;
        m.reasons.push_back(want == FarFieldMethod::auto_
                                ? "auto far_field: periodic box -> pme (O(N log N), accuracy from tolerance)"
                                : "far_field set by scene: pme");
      }
    } else {
      if (want == FarFieldMethod::ewald || want == FarFieldMethod::pme)
        unavailable(s, "far_field", std::string("\"") + to_string(want) +
                                        "\" needs a periodic domain; open domains use \"direct\" or \"auto\"");
      m.far_field = FarFieldMethod::direct;
      m.reasons.push_back(want == FarFieldMethod::auto_
                              ? "auto far_field: open domain -> direct O(N^2) summation (the tree method is not in this version)"
                              : "far_field set by scene: direct");
    }
    if (m.level == HydroModel::stokesian)
      m.reasons.push_back("near field: exact two-sphere resistance minus the two-body far field, pairs with "
                          "2r/(a_i+a_j) < lubrication_cutoff");
    if (m.brownian && m.moments == Moments::FTS)
      unavailable(s, "moments", "Brownian motion with rigid-particle stresslets (FTS) needs the Stokesian-dynamics "
                                "Brownian solver of a later version; use moments = \"FT\" or kT = 0");
    if (m.brownian && m.fixed_particles)
      unavailable(s, "model", "Brownian motion with fixed particles at the far-field level is not in this version");
  }
  if (m.brownian && s.time.integrator == Integrator::rkf45)
    throw ConfigError(s.source + ": [time] integrator: \"rkf45\" is deterministic; with fluid.kT > 0 use "
                                 "\"euler\" or \"midpoint\"");
  return m;
}

}  // namespace stokesian
