#include "engine/model.hpp"

#include "engine/accuracy.hpp"
#include "engine/core/errors.hpp"
#include "engine/core/channel.hpp"
#include "engine/core/flow.hpp"
#include "engine/core/layout.hpp"
#include "engine/methods.hpp"
#include "engine/pair_forces.hpp"
#include "lubrication/cutoff.hpp"
#include "lubrication/near_field.hpp"
#include "trees/neighbor_list.hpp"
#include "trees/tree_mobility.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace stokesian {

namespace {

// A pair closer than this surface gap [a] makes the auto level choose Stokesian dynamics: below
// about half a radius the far field alone misses the lubrication forces by more than a few percent.
constexpr double kNearGap = 0.5;

// Pairs of two fixed particles (e.g. neighbouring wall particles) never move relative to each other:
// they need no lubrication for the motion and are left out of the level choice.
bool both_fixed(const Scene& s, std::size_t i, std::size_t j) {
  return !s.fixed.empty() && s.fixed[i] && s.fixed[j];
}

// Smallest surface gap over all pairs (open or minimum image), O(N^2) but run once per scene.
double min_gap(const Scene& s) {
  double g = INFINITY;
  for (std::size_t i = 0; i < s.positions.size(); ++i)
    for (std::size_t j = i + 1; j < s.positions.size(); ++j)
      if (!both_fixed(s, i, j))
        g = std::min(g, s.domain.minimum_image(s.positions[i] - s.positions[j]).norm() - s.radii[i] - s.radii[j]);
  return g;
}

// Smallest surface gap among pairs closer than `gap` (INFINITY if none), by the cell list.
double min_gap_below(const Scene& s, double gap) {
  double g = INFINITY;
  for (const auto& p : trees::nearest_image_pairs(s.positions, s.radii, s.domain, gap))
    if (!both_fixed(s, std::size_t(p.i), std::size_t(p.j)))
      g = std::min(g, p.dist - s.radii[std::size_t(p.i)] - s.radii[std::size_t(p.j)]);
  return g;
}

// The most particles the run holds at once, which the N-based choices use: the scene's, or with
// [inflow] its slots plus the walls (the open channel fills up after the start).
std::size_t particles_at_most(const Scene& s) {
  return s.inflow.enabled ? std::size_t(s.inflow.capacity) + s.wall_count : s.positions.size();
}

[[noreturn]] void unavailable(const Scene& s, const std::string& table, const std::string& key, const std::string& what) {
  throw ConfigError(s.where(table, key) + ": " + what);
}

// Why `e` cannot solve this scene ("" if it can).
std::string unusable(const SolverEntry& e, const Scene& s, bool brownian) {
  const std::size_t n = particles_at_most(s);
  const std::size_t limit = s.domain.periodic() ? e.max_periodic : e.max_open;
  if (brownian && !e.brownian) return "it does not sample Brownian motion";
  if (limit > 0 && n > limit) return "it is limited to N <= " + std::to_string(limit) + " (N = " + std::to_string(n) + ")";
  return "";
}

// `[hydrodynamics] solver = "auto"` picks dense SD up to these N and accelerated SD beyond, by
// measured cost per deterministic FTS solve at phi = 0.3, tolerance 1e-4, 2 threads (bench_asd,
// section "crossover"): open domain, with the vectorised direct product (2026-11-28),
// accelerated / dense = 0.99 at N = 25 and 50, 0.68 at 75, 0.49 at 100; periodic box (2026-11-24)
// 0.88 at N = 50, 0.29 at 100 (docs/benchmarks.md). At equal cost the dense reference is kept.
constexpr std::size_t kAutoDenseUpToOpen = 50, kAutoDenseUpToPeriodic = 40;

// The registered solver a `[hydrodynamics] solver` value names ("" for auto).
std::string solver_named(const std::string& key) {
  return key == "dense" ? "dense_sd" : key == "accelerated" ? "accelerated_sd" : "";
}

const SolverEntry* usable_solver(HydroModel level, const Scene& s, bool brownian, std::string* why) {
  std::string all;
  const std::string named = level == HydroModel::stokesian ? solver_named(s.hydro.solver) : "";
  const std::size_t n = particles_at_most(s), dense_up_to = s.domain.periodic() ? kAutoDenseUpToPeriodic : kAutoDenseUpToOpen;
  for (const auto& e : hydro_solvers().entries()) {
    if (e.level != level) continue;
    if (!named.empty() && e.name != named) continue;
    // auto at the SD level: dense up to the crossover, accelerated beyond.
    if (named.empty() && level == HydroModel::stokesian && (e.name == "dense_sd") != (n <= dense_up_to)) {
      all += (all.empty() ? "" : "; ") + e.name + ": not the cheaper one for N = " + std::to_string(n) +
             " (dense up to " + std::to_string(dense_up_to) + ")";
      continue;
    }
    const std::string u = unusable(e, s, brownian);
    if (u.empty()) return &e;
    all += (all.empty() ? "" : "; ") + e.name + ": " + u;
  }
  if (why) *why = all;
  return nullptr;
}

}  // namespace

std::string solver_of(const ResolvedModel& m) {
  if (!m.solver.empty()) return m.solver;
  for (const auto& e : hydro_solvers().entries())
    if (e.level == m.level) return e.name;
  return "";
}

double far_field_products_per_solve(const ResolvedModel& m) {
  if (m.level == HydroModel::free_draining) return 0.0;
  const bool given_velocities = m.moments == Moments::FTS || m.fixed_particles;
  return solver_of(m) == "mobility_cg" && !given_velocities ? 1.0 : 20.0;
}

double far_field_products_per_configuration(const ResolvedModel& m) {
  if (m.level == HydroModel::free_draining) return 0.0;
  return far_field_products_per_solve(m) + (m.brownian ? 15.0 : 0.0);
}

std::string ResolvedModel::describe() const {
  std::ostringstream o;
  o << "hydrodynamics: " << name_of(level) << "\nsolver: " << solver_of(*this) << "\nmoments: " << name_of(moments);
  if (level != HydroModel::free_draining) o << "\nfar_field: " << far_field;
  o << "\nbrownian: " << (brownian ? "yes" : "no") << "\nintegrator: " << integrator;
  for (const auto& r : reasons) o << "\n  - " << r;
  return o.str();
}

ModelKey ResolvedModel::key() const {
  ModelKey k;
  k.entries = {{"hydrodynamics", name_of(level)},
               {"solver", solver_of(*this)},
               {"moments", name_of(moments)},
               {"far_field", level == HydroModel::free_draining ? "none" : far_field},
               {"brownian", brownian ? "yes" : "no"}};
  return k;
}

ResolvedModel resolve_model(const Scene& s) {
  ResolvedModel m;
  const std::size_t n = particles_at_most(s);
  // A pair law in a periodic box reaches at most half the smallest edge (one image per pair, the
  // minimum-image pair search): gap cut-off + 2 a_max <= L_min / 2.
  if (s.domain.periodic() && n >= 2) {
    const double a_max = *std::max_element(s.radii.begin(), s.radii.end());
    const double half = 0.5 * s.domain.box.minCoeff();
    for (std::size_t l = 0; l < s.forces.pair.size(); ++l) {
      const double cut = forces::resolved_cutoff(s.forces.pair[l], a_max);
      if (cut + 2 * a_max > half) {
        const std::string table = "forces.pair." + std::to_string(l);
        const bool given = s.lines.count(table + ".cutoff") > 0;
        std::ostringstream o;
        o << "law " << l << " (" << name_of(s.forces.pair[l].kind) << ") reaches centre distance " << cut + 2 * a_max
          << " a (gap cut-off " << cut << (given ? "" : ", the law's default") << " + 2 a_max = " << 2 * a_max
          << " a), beyond half the smallest box edge (" << half << " a) (allowed: gap cut-off at most "
          << std::max(0.0, half - 2 * a_max) << " a in this box; set cutoff, or enlarge [domain] box)";
        unavailable(s, table, given ? "cutoff" : "kind", o.str());
      }
    }
  }
  const std::shared_ptr<const AmbientField> field = make_ambient_field(s.flow, s.walls, s.domain);
  const AmbientField& flow = *field;
  m.brownian = s.fluid.kT > 0.0;
  m.fixed_particles = any_fixed(s.fixed);
  m.reasons.push_back(m.brownian ? "fluid.kT > 0: Brownian motion on" : "fluid.kT = 0: athermal");
  if (s.inflow.enabled)
    m.reasons.push_back("[inflow]: up to N = " + std::to_string(n) + " particles at once (capacity " +
                        std::to_string(s.inflow.capacity) + " + " + std::to_string(s.wall_count) +
                        " wall particles); the choices below use that N, and inserted particles come within "
                        "min_gap of the others");
  if (s.walls.kind == ChannelParams::Kind::outline)
    m.reasons.push_back("[walls] outline: a monolayer at z = 0; the motion out of the plane (U_z, Omega_x, Omega_y) is "
                        "removed (exact for coplanar spheres, whose in- and out-of-plane motions decouple; docs/channels.md)");

  // Level and solver.
  if (s.hydro.model == HydroModel::auto_) {
    if (n <= 1) {
      m.level = HydroModel::free_draining;
      m.reasons.push_back("auto level: a single particle has no hydrodynamic interactions -> free_draining");
    } else {
      // The exact smallest gap is printed only where Stokesian dynamics can apply (N <= 2000, a
      // cheap O(N^2) loop); beyond, only whether a gap is below kNearGap matters: a cell-list
      // search over pairs within that gap (O(N); the double loop took minutes at N = 3e5).
      const double g = s.positions.size() <= 2000 ? min_gap(s) : min_gap_below(s, kNearGap);
      std::ostringstream r;
      const bool inserted_close = s.inflow.enabled && s.inflow.min_gap < kNearGap;
      const bool near = g < kNearGap || !s.forces.pair.empty() || inserted_close;
      std::string why;
      const SolverEntry* sd = near ? usable_solver(HydroModel::stokesian, s, m.brownian, &why) : nullptr;
      if (sd) {
        m.level = HydroModel::stokesian;
        r << "auto level: "
          << (g < kNearGap               ? "close pairs (smallest gap "
              : !s.forces.pair.empty() ? "pair forces bring particles together (smallest gap "
                                       : "[inflow] inserts particles within min_gap of others (smallest gap now ")
          << g << " a) -> stokesian (far field + lubrication, solver " << sd->name << " for N = " << n << ")";
      } else {
        m.level = HydroModel::far_field;
        r << "auto level: " << n << " particles interact hydrodynamically -> far_field";
        if (near)
          r << " (lubrication would be more accurate, but no Stokesian-dynamics solver applies: " << why
            << "; set model = \"far_field\" to silence)";
      }
      m.reasons.push_back(r.str());
    }
  } else {
    m.level = s.hydro.model;
    m.reasons.push_back(std::string("level set by scene: ") + name_of(m.level));
  }
  {
    std::string why;
    const SolverEntry* e = usable_solver(m.level, s, m.brownian, &why);
    if (!e) {
      if (m.level == HydroModel::stokesian && m.brownian)
        unavailable(s, "hydrodynamics", "model",
                    "\"stokesian\" with fluid.kT > 0 needs near-field Brownian forces and drift, which no solver "
                    "provides (" + why + "); use \"far_field\" or kT = 0");
      unavailable(s, "hydrodynamics", "model", std::string("no solver for \"") + name_of(m.level) + "\": " + why);
    }
    m.solver = e->name;
    m.reasons.push_back("solver: " + e->name + " (" + e->description + ")");
    if (m.level == HydroModel::stokesian) {
      const std::size_t up_to = s.domain.periodic() ? kAutoDenseUpToPeriodic : kAutoDenseUpToOpen;
      if (s.hydro.solver == "auto")
        m.reasons.push_back("auto solver: N = " + std::to_string(n) + (n <= up_to ? " <= " : " > ") +
                            std::to_string(up_to) + " -> " + e->name + " (the cheaper per solve in " +
                            (s.domain.periodic() ? "periodic boxes" : "open domains") +
                            ", bench_asd/bench_dense_sd; set solver = \"dense\" or \"accelerated\" to choose)");
      else
        m.reasons.push_back("solver set by scene: " + s.hydro.solver);
      if (m.fixed_particles)
        m.reasons.push_back("held particles: far-field products asked a tenth of the usual tolerance and, in the "
                            "accelerated solver, GMRES continued until its error estimate meets the tolerance "
                            "(engine/accuracy.cpp, docs/accelerated_sd.md)");
    } else if (s.hydro.lubrication != Lubrication::exact) {
      m.reasons.push_back(std::string("note: lubrication = \"") + name_of(s.hydro.lubrication) +
                          "\" applies to the stokesian level only; the level here is " + name_of(m.level));
    }
    if (m.level != HydroModel::stokesian && s.hydro.solver != "auto") {
      m.reasons.push_back("note: solver = \"" + s.hydro.solver + "\" applies to the stokesian level only; the level here is " +
                          name_of(m.level));
    }
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
    m.reasons.push_back(std::string("moments set by scene: ") + name_of(m.moments));
    if (torques && m.moments == Moments::F)
      unavailable(s, "hydrodynamics", "moments", "\"F\" ignores the scene's external torques; use \"FT\" or \"FTS\"");
    if (m.level == HydroModel::stokesian && m.moments == Moments::F)
      m.reasons.push_back("note: F-level Stokesian dynamics treats the spheres as non-rotating");
  }

  // Far-field method.
  if (m.level != HydroModel::free_draining) {
    const auto& methods = far_field_methods();
    const SolverEntry& solver = *hydro_solvers().find(m.solver);
    const bool periodic = s.domain.periodic();
    const std::string& want = s.hydro.far_field;
    const FarFieldMethodEntry* asked = nullptr;
    std::vector<std::string> fitting;  // methods for this domain kind
    for (const auto& e : methods.entries())
      if (e.periodic == periodic) fitting.push_back(e.name);
    if (want != "auto") {
      asked = methods.find(want);
      std::vector<std::string> all{"auto"};
      for (const auto& e : methods.names()) all.push_back(e);
      if (!asked) unavailable(s, "hydrodynamics", "far_field", "\"" + want + "\" is not in this version (available: " + quoted_list(all) + ")");
      if (asked->periodic != periodic)
        unavailable(s, "hydrodynamics", "far_field",
                    "\"" + want + (periodic ? "\" has no periodic images; periodic boxes use " : "\" needs a periodic domain; open domains use ") +
                        quoted_list(fitting) + " or \"auto\"");
    }
    const FarFieldMethodEntry* chosen = nullptr;
    if (solver.needs_dense && !(asked && asked->dense)) {
      for (const auto& e : methods.entries())
        if (e.periodic == periodic && e.dense && !chosen) chosen = &e;
      m.reasons.push_back("far_field: " + solver.name + " inverts the dense matrix of " + chosen->name +
                          (asked ? " (\"" + want + "\" has no dense matrix)" : ""));
    } else if (asked) {
      chosen = asked;
      m.reasons.push_back("far_field set by scene: " + chosen->name);
    } else {
      for (const auto& e : methods.entries())
        if (e.periodic == periodic && e.auto_choice && !chosen) chosen = &e;
      std::string why;
      if (!periodic && !s.radii.empty()) {
        // the octree beyond its measured crossover with the direct sum at the products' tolerance
        const auto [a_lo, a_hi] = std::minmax_element(s.radii.begin(), s.radii.end());
        const double ff_tol = derive_knobs(s.hydro.tolerance, m.level, *a_hi / *a_lo, m.fixed_particles).far_field;
        const long from = trees::tree_auto_from(ff_tol, m.moments);
        std::ostringstream o;
        if (from > 0 && long(n) >= from) {
          chosen = methods.find("tree");
          o << ", N = " << n << " >= " << from << ", the measured crossover with direct at product tolerance " << ff_tol;
        } else if (from > 0) {
          o << ", N = " << n << " < " << from << ", the octree's measured crossover at product tolerance " << ff_tol;
        }
        why = o.str();
      }
      m.reasons.push_back(std::string("auto far_field: ") + (periodic ? "periodic box" : "open domain") + " -> " +
                          chosen->name + " (" + chosen->description + why + ")");
    }
    m.far_field = chosen->name;
    if (m.level == HydroModel::stokesian) {
      const lubrication::NearFieldParams np = lubrication::near_field_params(s.hydro, m.moments);
      // The near-field pair search is minimum-image: pairs reach centre distance cutoff * a_max,
      // which must stay within half the smallest box edge (one image per pair).
      if (s.domain.periodic() && !s.radii.empty()) {
        const double a_max = *std::max_element(s.radii.begin(), s.radii.end());
        const double reach = np.cutoff * a_max, half = 0.5 * s.domain.box.minCoeff();
        if (reach > half) {
          std::ostringstream o;
          o << "the lubrication pairs reach centre distance " << reach << " a (cutoff " << np.cutoff
            << " x largest radius " << a_max << " a), beyond half the smallest box edge (" << half
            << " a) (allowed: a box edge of at least " << 2 * reach
            << " a for these radii; enlarge [domain] box or lower lubrication_cutoff)";
          unavailable(s, "domain", "box", o.str());
        }
      }
      std::ostringstream r;
      if (np.model == Lubrication::squeeze)
        r << "near field: the thesis's normal squeeze force (lubrication = \"squeeze\": slip below "
          << np.squeeze.slip_gap << " a, no slip from " << np.squeeze.transition_gap << " a, evaluated at "
          << np.squeeze.contact_gap << " a or more; no torque, tangential or stresslet coupling; added to the far field "
          << "without subtracting its two-body part), ";
      else
        r << "near field: exact two-sphere resistance minus the two-body far field, ";
      if (np.taper > 0)
        r << "full for 2r/(a_i+a_j) <= " << np.cutoff - np.taper << ", switched off smoothly to zero at " << np.cutoff;
      else
        r << "pairs with 2r/(a_i+a_j) < " << np.cutoff << " (hard step";
      if (s.hydro.lubrication_cutoff_auto) {
        const double floor = lubrication::tolerance_floor(m.moments);
        r << " (lubrication_cutoff = \"auto\" from tolerance " << s.hydro.tolerance;
        if (s.hydro.tolerance < floor)
          r << "; the cutoff is capped, so the two-sphere error is bounded by " << floor << ", not the tolerance";
        r << ")";
      } else if (np.taper == 0 && np.model == Lubrication::exact) {
        r << ", published SD: the two-sphere mobility jumps there by up to "
          << (m.moments == Moments::FTS ? "2.3e-3" : "2.3e-2") << "; lubrication_cutoff = \"auto\" makes it continuous)";
      } else if (np.taper == 0) {
        r << ": the squeeze force jumps to zero there; a lubrication_taper switches it off smoothly)";
      }
      m.reasons.push_back(r.str());
    }
  }

  // Integrator.
  const bool auto_integrator = s.time.integrator == "auto";
  const IntegratorEntry* integ = integrators().find(auto_integrator ? "euler" : s.time.integrator);
  if (!integ)
    unavailable(s, "time", "integrator",
                "\"" + s.time.integrator + "\" is not \"auto\" or one of " + quoted_list(integrators().names()));
  m.integrator = integ->name;
  // Thermal drift kT div(R^{-1}) (engine/integrators.hpp): needed wherever the sampled mobility is
  // not divergence free: any near-field resistance, or far-field mobilities constrained by rigid
  // stresslets or fixed particles (Schur complements of M_inf). Free draining and the plain far
  // field (F, FT, no fixed particles) have none.
  m.drift = m.brownian && (m.level == HydroModel::stokesian ||
                           (m.level == HydroModel::far_field && (m.moments == Moments::FTS || m.fixed_particles)));
  if (m.drift && !integ->drift) {
    const std::string why = m.level == HydroModel::stokesian ? "the near-field resistance"
                            : m.moments == Moments::FTS      ? "the rigid-stresslet constraint"
                                                             : "the fixed particles";
    if (auto_integrator) {
      m.integrator = "fixman";
      m.reasons.push_back("auto integrator: Brownian motion with " + why +
                          " needs the thermal drift kT div(R^-1) -> fixman (Fixman midpoint; set [time] integrator to choose)");
    } else {
      unavailable(s, "time", "integrator",
                  "\"" + integ->name + "\" omits the thermal drift kT div(R^-1), which Brownian motion with " + why +
                      " needs for the right equilibrium; use \"fixman\"");
    }
  }
  // Brownian stress (engine/stress.hpp): recorded in periodic boxes with FTS and the Fixman step.
  if (s.domain.periodic() && m.brownian && m.moments == Moments::FTS && m.integrator == "fixman") {
    if (s.brownian_stress_every >= 0) {
      m.brownian_stress_every = long(s.brownian_stress_every);
      m.reasons.push_back("Brownian stress: [brownian] stress_every = " + std::to_string(m.brownian_stress_every) +
                          (m.brownian_stress_every ? " (two solves more on each sampled step)" : ": not sampled"));
    } else {
      // A linear flow (the bulk viscosity); a channel flow has no uniform rate to refer it to.
      const bool flow = s.flow.kind == FlowParams::Kind::simple_shear || s.flow.kind == FlowParams::Kind::planar_extension;
      m.brownian_stress_every = flow ? 1 : 0;
      m.reasons.push_back(flow ? "auto Brownian stress: linear ambient flow -> sampled every step for the viscosity (two solves "
                                 "more per step; [brownian] stress_every = 0 to skip)"
                               : "auto Brownian stress: no linear ambient flow -> not sampled ([brownian] stress_every = 1 to "
                                 "sample it every step)");
    }
  }
  if (m.level != HydroModel::free_draining && m.far_field == "pme") {
    std::ostringstream o;
    const double np = far_field_products_per_configuration(m);
    o << "pme cost model: a new configuration's set-up priced against about " << np << " far-field product"
      << (np == 1.0 ? "" : "s") << " per configuration (engine/model.hpp; cost only, not accuracy)";
    m.reasons.push_back(o.str());
  }
  if (m.brownian && !integ->stochastic)
    unavailable(s, "time", "integrator", "\"" + integ->name + "\" is deterministic; with fluid.kT > 0 use " +
                                             [] {
                                               std::vector<std::string> ok;
                                               for (const auto& e : integrators().entries())
                                                 if (e.stochastic) ok.push_back(e.name);
                                               return quoted_list(ok);
                                             }());
  return m;
}

}  // namespace stokesian
