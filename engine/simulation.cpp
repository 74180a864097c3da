#include "engine/simulation.hpp"

#include "engine/core/channel.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/parallel.hpp"
#include "engine/methods.hpp"
#include "engine/progress.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <unistd.h>

namespace stokesian {

namespace {
// Stored as State::rng_state: the noise needs no saved state, only the seed and the step
// (checkpoints of 0.1.0 hold a Mersenne-Twister state here instead; see run()).
const char* const kNoiseStreams = "philox4x32-10 streams (seed, brownian, step)";

// Pairs named in overlap warnings and failure reports.
constexpr std::size_t kReportedPairs = 5;

std::string vec_text(const Vec3& v) {
  char b[96];
  std::snprintf(b, sizeof b, "(%.4g, %.4g, %.4g)", v[0], v[1], v[2]);
  return b;
}

// First entry with a non-finite component, or -1.
long first_non_finite(const std::vector<Vec3>& v) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!v[i].allFinite()) return long(i);
  return -1;
}

// "; closest pairs: ..." of configuration x (pairs within 1 a), for failures that name no particle.
std::string closest_pairs(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& d) {
  if (first_non_finite(x) >= 0 || x.size() < 2) return "";
  const GapSurvey g = survey_gaps(x, a, d, 1.0, 3);
  return g.worst.empty() ? "; no pair is closer than 1 a" : "; closest pairs: " + describe_pairs(g.worst);
}
}  // namespace

namespace {
double radius_ratio(const std::vector<double>& a) {
  if (a.empty()) return 1.0;
  const auto [lo, hi] = std::minmax_element(a.begin(), a.end());
  return *lo > 0.0 ? *hi / *lo : 1.0;
}
}  // namespace

Simulation::Simulation(Scene scene)
    : scene_(std::move(scene)),
      model_(resolve_model(scene_)),
      strain_rate_(lattice_strain_rate(scene_.flow, scene_.domain)),
      hydro_(model_, scene_.fluid.viscosity, make_ambient_field(scene_.flow, scene_.walls, scene_.domain), scene_.hydro.tolerance,
             lubrication::near_field_params(scene_.hydro, model_.moments), radius_ratio(scene_.radii)),
      integrator_(integrators().find(model_.integrator)->make(scene_.time)),
      observers_(make_observers(scene_, model_)),
      monolayer_(scene_.walls.kind == ChannelParams::Kind::outline) {
  if (scene_.inflow.enabled) inflow_.emplace(scene_);
}

void Simulation::keep_in_plane(HydroResult& r) const {
  if (!monolayer_) return;
  for (Vec3& u : r.U) u.z() = 0.0;
  for (Vec3& w : r.Omega) w.x() = w.y() = 0.0;
}

State Simulation::initial_state() const {
  State s;
  s.position = scene_.positions;
  s.radius = scene_.radii;
  s.fixed = scene_.fixed;
  s.domain = scene_.domain;
  s.dt = scene_.time.dt;
  s.step = scene_.time.start_step;
  s.time = scene_.time.start_time;
  s.rng_state = kNoiseStreams;
  if (inflow_) inflow_->initialise(s);
  return s;
}

Evaluation Simulation::evaluate(const State& s, const std::vector<Vec3>& x, double t, bool diagnostics) {
  return evaluate_checked(s, x, t, diagnostics, nullptr);
}

Evaluation Simulation::evaluate_step_start(const State& s, bool output_step, GapSurvey* overlaps) {
  GapSurvey local;
  // The deterministic solve at the state is needed for its frame, and by integrators that read it
  // (fixman with noise solves with F + xi itself: one solve per step saved).
  const bool solve = output_step || integrator_->reads_start_solve(model_.brownian);
  return evaluate_checked(s, s.position, 0.0, output_step, overlaps ? overlaps : &local, nullptr, solve);
}

Evaluation Simulation::evaluate(const State& s, const std::vector<Vec3>& x, double t, const VecX* noise,
                                WarmStart* warm) {
  return evaluate_checked(s, x, t, false, nullptr, noise, true, warm);
}

Evaluation Simulation::evaluate_checked(const State& s, const std::vector<Vec3>& x, double t, bool diagnostics,
                                        GapSurvey* overlaps, const VecX* noise, bool solve, WarmStart* warm) {
  // Where this evaluation is, for messages: the state of a step, or an integrator stage within it.
  auto at = [&] {
    std::ostringstream o;
    o << "step " << s.step;
    if (t != 0.0) o << " (integrator stage at t + " << t << ")";
    return o.str();
  };
  if (const long i = first_non_finite(x); i >= 0)
    throw PhysicsError(at() + ": particle " + std::to_string(i) + " has a non-finite position " +
                       vec_text(x[std::size_t(i)]));
  // Stage t of a step: in a sheared box the lattice strain has advanced by rate * t (Lees &
  // Edwards 1972), so stages see the box of their own time.
  const Domain domain = strain_rate_ == 0.0 || t == 0.0 ? s.domain : s.domain.strained_by(strain_rate_ * t);
  const Configuration c{x, s.radius, domain};
  const long n = long(x.size());
  Evaluation ev;

  // The step's phases before the solve; each runs alone when its kernels use every thread.
  using Kind = TaskGraph::Kind;
  const Kind search = n >= parallel::kNeighborParticles ? Kind::team : Kind::single;
  TaskGraph g;
  g.add("forces", search, [&] {
    ev.force.assign(std::size_t(n), Vec3::Zero());
    ev.torque.assign(std::size_t(n), Vec3::Zero());
    const auto& fe = scene_.forces.external_force;
    const auto& te = scene_.forces.external_torque;
    for (std::size_t i = 0; i < std::size_t(n); ++i) {
      if (!fe.empty()) ev.force[i] += fe.size() == 1 ? fe[0] : fe[i];
      if (!te.empty()) ev.torque[i] += te.size() == 1 ? te[0] : te[i];
    }
    ev.pair.per_particle = has_stresslet(model_.moments);  // the per-particle stress (engine/observers.cpp)
    if (!scene_.forces.pair.empty()) forces::add_pair_forces(scene_.forces.pair, x, s.radius, domain, ev.force, &ev.pair);
  });
  // The solver's set-up phases (far-field operator, near-field assembly, factorisation).
  const std::vector<PreparePhase> setup = hydro_.prepare_phases(c);
  std::vector<int> node(setup.size());
  for (std::size_t k = 0; k < setup.size(); ++k) {
    std::vector<int> after;
    for (int j : setup[k].after) after.push_back(node[std::size_t(j)]);
    node[k] = g.add(setup[k].name, setup[k].uses_threads ? Kind::team : Kind::single, setup[k].body, after);
  }
  // Output steps find the overlapping pairs within the gap diagnostics' search (one pair search).
  if (diagnostics && overlaps)
    g.add("diagnostics", search, [&] {
      GapStats stats;
      *overlaps = survey_overlaps(x, s.radius, domain, kReportedPairs, stats, &s.fixed);
      ev.gaps = stats;
    });
  else if (diagnostics)
    g.add("diagnostics", search, [&] { ev.gaps = gap_statistics(x, s.radius, domain, &s.fixed); });
  else if (overlaps)
    g.add("overlaps", search, [&] { *overlaps = survey_gaps(x, s.radius, domain, 0.0, kReportedPairs, &s.fixed); });
  // Overlap policy ([run] max_overlap): a pair deeper than the threshold stops the run before the
  // solve, and explains a set-up failure (factorisation) that the overlap caused.
  const double max_overlap = scene_.run.max_overlap;
  auto too_deep = [&] {
    return overlaps && overlap_policy_applies() && !overlaps->worst.empty() && overlaps->worst[0].depth > max_overlap;
  };
  auto overlap_report = [&] {
    std::vector<PairGap> deep;
    for (const PairGap& p : overlaps->worst)
      if (p.depth > max_overlap) deep.push_back(p);
    std::ostringstream o;
    o << at() << ": " << overlaps->stats.overlaps << " overlapping pair(s), the deepest beyond [run] max_overlap = "
      << max_overlap << " of the smaller radius: " << describe_pairs(deep)
      << " (surfaces must not interpenetrate this far: a smaller [time] dt or a stiffer short-range repulsion keeps "
         "them apart)";
    return o.str();
  };
  try {
    g.run(task_mode_);
  } catch (const PhysicsError& e) {
    if (too_deep()) throw PhysicsError(overlap_report() + "; then: " + e.what());
    throw PhysicsError(at() + ": " + e.what() + closest_pairs(x, s.radius, domain));
  }
  if (too_deep()) throw PhysicsError(overlap_report());
  for (const auto* f : {&ev.force, &ev.torque})
    if (const long i = first_non_finite(*f); i >= 0)
      throw PhysicsError(at() + ": particle " + std::to_string(i) + " has a non-finite " +
                         (f == &ev.force ? "force " : "torque ") + vec_text((*f)[std::size_t(i)]) +
                         " (pair forces at these positions)" + closest_pairs(x, s.radius, domain));

  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (solve) ev.hydro = hydro_.solve(c, s.fixed, ev.force, ev.torque, noise, warm ? warm : &ev.warm);
    if (solve) keep_in_plane(ev.hydro);
  } catch (const PhysicsError& e) {
    throw PhysicsError(at() + ": " + e.what() + closest_pairs(x, s.radius, domain));
  }
  for (const auto* v : {&ev.hydro.U, &ev.hydro.Omega})
    if (const long i = first_non_finite(*v); i >= 0)
      throw PhysicsError(at() + ": particle " + std::to_string(i) + " has a non-finite " +
                         (v == &ev.hydro.U ? "velocity " : "angular velocity ") + vec_text((*v)[std::size_t(i)]) +
                         " from the hydrodynamic solve" + closest_pairs(x, s.radius, domain));
  const double solve_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  phases_.names.clear();
  phases_.seconds.clear();
  for (std::size_t k = 0; k < g.size(); ++k) {
    phases_.names.push_back(g.name(k));
    phases_.seconds.push_back(g.seconds(k));
  }
  phases_.names.push_back("solve");
  phases_.seconds.push_back(solve_s);
  return ev;
}

VecX Simulation::brownian_force(const State& s, double dt, Rng& rng) {
  if (!model_.brownian) return {};
  try {
    return hydro_.brownian_force({s.position, s.radius, s.domain}, s.fixed, scene_.fluid.kT, dt, rng);
  } catch (const PhysicsError& e) {
    throw PhysicsError("step " + std::to_string(s.step) + ": " + e.what() + closest_pairs(s.position, s.radius, s.domain));
  }
}

HydroResult Simulation::noise_response(const State& s, const std::vector<Vec3>& x, double t, const VecX& xi,
                                       WarmStart* warm) {
  const Domain domain = strain_rate_ == 0.0 || t == 0.0 ? s.domain : s.domain.strained_by(strain_rate_ * t);
  const Configuration c{x, s.radius, domain};
  try {
    hydro_.prepare(c);  // the stage's set-up, kept from its evaluation
    HydroResult r = hydro_.noise_velocity(c, s.fixed, xi, warm);
    keep_in_plane(r);
    return r;
  } catch (const PhysicsError& e) {
    throw PhysicsError("step " + std::to_string(s.step) + ": " + e.what() + closest_pairs(x, s.radius, domain));
  }
}

std::vector<Vec3> Simulation::brownian_displacement(const State& s, double dt, Rng& rng) {
  if (!model_.brownian) return {};
  std::vector<Vec3> dX;
  if (model_.drift) {  // a resistance solver: dt R^{-1} xi (no drift; tests of the drift use this)
    const Configuration c{s.position, s.radius, s.domain};
    const VecX xi = brownian_force(s, dt, rng);
    dX = hydro_.noise_velocity(c, s.fixed, xi).U;
    for (auto& v : dX) v *= dt;
  } else {
    dX = hydro_.brownian_displacement(s.position, s.radius, scene_.fluid.kT, dt, rng, s.domain);
  }
  for (std::size_t i = 0; i < dX.size(); ++i) {
    if (!s.fixed.empty() && s.fixed[i]) dX[i] = Vec3::Zero();
    if (monolayer_) dX[i].z() = 0.0;
  }
  return dX;
}

void Simulation::check_finite(const State& s) const {
  if (const long i = first_non_finite(s.position); i >= 0) {
    std::ostringstream o;
    o << "step " << s.step << ": particle " << i << " has a non-finite position " << vec_text(s.position[std::size_t(i)])
      << " after the step from " << s.step - 1;
    throw PhysicsError(o.str());
  }
}

void Simulation::advance(State& s, const Evaluation& ev) {
  // The noise of step n is stream (brownian, n): the same on every machine and thread count, and
  // independent of where a run was interrupted and resumed.
  Rng rng = legacy_noise_ ? RandomStream::continuing_legacy(*legacy_noise_)
                          : RandomStream::for_purpose(scene_.seed, Purpose::brownian, std::uint64_t(s.step));
  StepResult r = integrator_->step(s, ev, *this, rng);
  if (r.brownian_stresslet) {
    s.brownian_stresslet_sum += *r.brownian_stresslet;
    s.brownian_samples += 1;
  }
  s.position = std::move(r.x);
  s.time += r.dt_used;
  s.step += 1;
  s.dt = r.dt_next;
  const double unreduced_strain = s.domain.shear_strain + strain_rate_ * r.dt_used;
  if (strain_rate_ != 0.0) s.domain = s.domain.strained_by(strain_rate_ * r.dt_used);
  wrap_positions(s, unreduced_strain);  // wraps into the box and counts images (state.hpp)
  check_finite(s);
}

RunHeader Simulation::header() const {
  RunHeader h;
  h.particles = inflow_ ? inflow_->slots() + scene_.wall_count : scene_.positions.size();
  h.domain = scene_.domain;
  h.sheared_box = strain_rate_ != 0.0;
  for (const auto& o : observers_) o->declare(h.particle_fields);
  if (inflow_) h.particle_fields.push_back({"id", {}, {}, "", true});  // -1: an empty slot (engine/inflow.hpp)
  h.scene_toml = scene_.toml;
  h.model = model_.describe();
  h.model_key = model_.key().text();
  h.author = "stokesian";
  return h;
}

Frame Simulation::frame(const State& s, const Evaluation& ev) const {
  Frame f;
  f.step = s.step;
  f.time = s.time;
  f.shear_strain = s.domain.shear_strain;
  for (const auto& o : observers_) o->observe(s, ev, f);
  return f;
}

Frame Simulation::frame_of_present(const State& s, const Evaluation& ev) const {
  if (!inflow_) return frame(s, ev);
  const std::vector<std::size_t> idx = inflow_->present(s);
  return inflow_->expand(frame(Inflow::compact(s, idx), ev), s, idx);
}

bool Simulation::samples_brownian_stress(std::int64_t step) const {
  const std::int64_t every = model_.brownian_stress_every;
  return every > 0 && (step - scene_.time.start_step) % every == 0;
}

bool Simulation::frame_step(std::int64_t step) const {
  return (step - scene_.time.start_step) % scene_.output.every == 0 || step == scene_.time.last_step();
}

long Simulation::run(State& s, OutputSink& out, const RunControl& control) {
  legacy_noise_.reset();
  if (!s.rng_state.empty() && s.rng_state != kNoiseStreams) {  // a checkpoint of 0.1.0
    std::istringstream in(s.rng_state);
    std::mt19937_64 engine;
    in >> engine;
    if (!in) throw PhysicsError("checkpoint holds an unknown random-number state: " + s.rng_state.substr(0, 60));
    legacy_noise_ = engine;
  }
  // The noise state to store with a checkpoint of s.
  auto store_noise = [&](State& st, const std::optional<std::mt19937_64>& noise) {
    if (noise) {
      std::ostringstream o;
      o << *noise;
      st.rng_state = o.str();
    } else {
      st.rng_state = kNoiseStreams;
    }
  };
  const long last = long(scene_.time.last_step());
  progress::Progress progress(long(s.step), last, control.quiet);
  bool frame_done = control.frame_done;
  long taken = 0;
  Frame latest;
  bool have_latest = false;
  long max_overlaps = 0;
  // The state before the step being taken (and its legacy noise): the checkpoint on a failure.
  std::optional<State> before;
  std::optional<std::mt19937_64> noise_before;
  auto stop = [&](const PhysicsError& e) -> RunStopped {
    if (!control.quiet && isatty(fileno(stderr))) std::fputc('\n', stderr);  // end the progress line
    std::ostringstream o;
    if (!before) {
      o << e.what() << "\n  this is the first evaluation of the run (step " << s.step
        << "): there is no earlier good state to keep";
      return RunStopped(o.str(), s.step, -1);
    }
    State good = *before;
    store_noise(good, noise_before);
    out.checkpoint(good);
    o << "the step from " << good.step << " to " << good.step + 1 << " (t = " << good.time << ", dt = " << good.dt
      << ") failed: " << e.what() << "\n  stopped with the last good state, step " << good.step
      << ", as the checkpoint";
    s = std::move(good);
    return RunStopped(o.str(), s.step, s.step);
  };
  // Open channels: the solvers and the integrator see only the present particles (view), whose
  // results go back to their slots in s (engine/inflow.hpp).
  std::vector<std::size_t> slots;
  State view;
  for (;;) {
    if (inflow_) {
      slots = inflow_->present(s);
      view = Inflow::compact(s, slots);
    }
    State& cur = inflow_ ? view : s;
    const bool output_step = !frame_done && frame_step(s.step);
    GapSurvey overlaps;
    Evaluation ev;
    try {
      ev = evaluate_step_start(cur, output_step, &overlaps);
    } catch (const RunStopped&) {
      throw;
    } catch (const PhysicsError& e) {
      throw stop(e);
    }
    // Overlaps below [run] max_overlap: warn, naming the deepest pairs, whenever their count reaches
    // a new maximum, and continue (the far-field mobility is overlap-regularised and stays positive
    // definite); beyond it evaluate_checked has stopped the run.
    if (overlaps.stats.overlaps > max_overlaps) {
      max_overlaps = overlaps.stats.overlaps;
      char why[160];
      if (overlap_policy_applies())
        std::snprintf(why, sizeof why, "below [run] max_overlap = %g", scene_.run.max_overlap);
      else
        std::snprintf(why, sizeof why, "without pair forces or lubrication the spheres are penetrable; [run] max_overlap does not apply");
      if (!control.quiet)
        std::fprintf(stderr, "%sstep %ld: %ld overlapping pair(s), deepest %s (continuing: %s)\n",
                     isatty(fileno(stderr)) ? "\n" : "", long(s.step), overlaps.stats.overlaps,
                     describe_pairs(overlaps.worst).c_str(), why);
    }
    if (output_step) {
      Frame f = inflow_ ? inflow_->expand(frame(cur, ev), s, slots) : frame(s, ev);
      out.record(f);
      latest = std::move(f);
      have_latest = true;
      // The frame has consumed the sums over the steps since the previous one.
      for (State* st : {&s, &cur}) {
        st->brownian_samples = 0;
        st->brownian_stresslet_sum.setZero();
      }
    }
    frame_done = false;
    const bool at_end = s.step >= last || (control.max_steps >= 0 && taken >= control.max_steps);
    const long ce = scene_.output.checkpoint_every;
    const std::int64_t since = s.step - scene_.time.start_step;
    if (at_end || (ce > 0 && since % ce == 0 && since > 0)) {
      store_noise(s, legacy_noise_);
      out.checkpoint(s);
    }
    // Progress of the step reached, with the latest frame's diagnostics; the last step's line is
    // printed once, by finish() after the loop.
    if (at_end) break;
    if (taken > 0)
      progress.update(long(s.step), s.time, have_latest, have_latest ? latest.scalar("min_gap") : 0.0,
                      have_latest ? latest.scalar("overlaps") : 0.0);
    before = s;
    noise_before = legacy_noise_;
    ev.sample_brownian_stress = samples_brownian_stress(s.step);
    try {
      advance(cur, ev);
      if (inflow_) {
        const double dt_used = view.time - s.time;
        Inflow::scatter(view, slots, s);
        inflow_->exchange(s, dt_used, scene_.seed);
      }
    } catch (const PhysicsError& e) {
      throw stop(e);
    }
    ++taken;
  }
  progress.finish(long(s.step), s.time, have_latest, have_latest ? latest.scalar("min_gap") : 0.0,
                  have_latest ? latest.scalar("overlaps") : 0.0);
  return taken;
}

}  // namespace stokesian
