#include "engine/simulation.hpp"

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
}  // namespace

Simulation::Simulation(Scene scene)
    : scene_(std::move(scene)),
      model_(resolve_model(scene_)),
      strain_rate_(lattice_strain_rate(scene_.flow, scene_.domain)),
      hydro_(model_, scene_.fluid.viscosity, ambient_flow(scene_.flow), scene_.hydro.tolerance,
             {scene_.hydro.lubrication_cutoff, scene_.hydro.lubrication_min_gap}),
      integrator_(integrators().find(model_.integrator)->make(scene_.time)),
      observers_(make_observers(scene_, model_)) {}

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
  return s;
}

Evaluation Simulation::evaluate(const State& s, const std::vector<Vec3>& x, double t, bool diagnostics) {
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
    if (!scene_.forces.pair.empty()) forces::add_pair_forces(scene_.forces.pair, x, s.radius, domain, ev.force, &ev.pair);
  });
  g.add("hydro_setup", hydro_.solver().prepare_uses_threads(n) ? Kind::team : Kind::single, [&] { hydro_.prepare(c); });
  if (diagnostics) g.add("diagnostics", search, [&] { ev.gaps = gap_statistics(x, s.radius, domain); });
  g.run(task_mode_);

  const auto t0 = std::chrono::steady_clock::now();
  ev.hydro = hydro_.solve(c, s.fixed, ev.force, ev.torque);
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

std::vector<Vec3> Simulation::brownian_displacement(const State& s, double dt, Rng& rng) {
  if (!model_.brownian) return {};
  std::vector<Vec3> dX = hydro_.brownian_displacement(s.position, s.radius, scene_.fluid.kT, dt, rng, s.domain);
  for (std::size_t i = 0; i < dX.size(); ++i)
    if (!s.fixed.empty() && s.fixed[i]) dX[i] = Vec3::Zero();
  return dX;
}

void Simulation::check_finite(const State& s) const {
  for (std::size_t i = 0; i < s.size(); ++i)
    if (!s.position[i].allFinite()) {
      std::ostringstream o;
      o << "step " << s.step << ": particle " << i << " has a non-finite position";
      throw PhysicsError(o.str());
    }
}

void Simulation::advance(State& s, const Evaluation& ev) {
  // The noise of step n is stream (brownian, n): the same on every machine and thread count, and
  // independent of where a run was interrupted and resumed.
  Rng rng = legacy_noise_ ? RandomStream::continuing_legacy(*legacy_noise_)
                          : RandomStream::for_purpose(scene_.seed, Purpose::brownian, std::uint64_t(s.step));
  StepResult r = integrator_->step(s, ev, *this, rng);
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
  h.particles = scene_.positions.size();
  h.domain = scene_.domain;
  h.sheared_box = strain_rate_ != 0.0;
  for (const auto& o : observers_) o->declare(h.particle_fields);
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
  const long last = long(scene_.time.last_step());
  progress::Progress progress(long(s.step), last, control.quiet);
  bool frame_done = control.frame_done;
  long taken = 0;
  Frame latest;
  bool have_latest = false;
  double max_overlaps = 0;
  for (;;) {
    const bool output_step = !frame_done && frame_step(s.step);
    const Evaluation ev = evaluate(s, s.position, 0.0, output_step);
    if (output_step) {
      Frame f = frame(s, ev);
      // Overlap policy: count every frame (observable "overlaps"), warn when a new maximum is reached,
      // continue (the far-field mobility is overlap-regularised and stays positive definite).
      if (f.scalar("overlaps") > max_overlaps) {
        max_overlaps = f.scalar("overlaps");
        if (!control.quiet)
          std::fprintf(stderr, "%sstep %ld: %.0f overlapping pair(s), smallest gap %.3g a (continuing: mobility is overlap-regularised)\n",
                       isatty(fileno(stderr)) ? "\n" : "", long(s.step), f.scalar("overlaps"), f.scalar("min_gap"));
      }
      out.record(f);
      latest = std::move(f);
      have_latest = true;
    }
    frame_done = false;
    const bool at_end = s.step >= last || (control.max_steps >= 0 && taken >= control.max_steps);
    const long ce = scene_.output.checkpoint_every;
    const std::int64_t since = s.step - scene_.time.start_step;
    if (at_end || (ce > 0 && since % ce == 0 && since > 0)) {
      if (legacy_noise_) {
        std::ostringstream o;
        o << *legacy_noise_;
        s.rng_state = o.str();
      } else {
        s.rng_state = kNoiseStreams;
      }
      out.checkpoint(s);
    }
    // Progress of the step reached, with the latest frame's diagnostics; the last step's line is
    // printed once, by finish() after the loop.
    if (at_end) break;
    if (taken > 0)
      progress.update(long(s.step), s.time, have_latest, have_latest ? latest.scalar("min_gap") : 0.0,
                      have_latest ? latest.scalar("overlaps") : 0.0);
    advance(s, ev);
    ++taken;
  }
  progress.finish(long(s.step), s.time, have_latest, have_latest ? latest.scalar("min_gap") : 0.0,
                  have_latest ? latest.scalar("overlaps") : 0.0);
  return taken;
}

}  // namespace stokesian
