#include "engine/simulation.hpp"

#include "engine/errors.hpp"
#include "engine/integrators.hpp"
#include "io/checkpoint.hpp"
#include "io/xyz.hpp"
#include "trees/neighbor_list.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace stokesian {

Simulation::Simulation(Scene scene)
    : scene_(std::move(scene)),
      model_(resolve_model(scene_)),
      flow_(ambient_flow(scene_.flow)),
      hydro_(model_, scene_.fluid.viscosity, flow_, scene_.hydro.tolerance, scene_.hydro.lubrication_cutoff,
             scene_.hydro.lubrication_min_gap) {}

State Simulation::initial_state() const {
  State s;
  s.position = scene_.positions;
  s.radius = scene_.radii;
  s.fixed = scene_.fixed;
  s.domain = scene_.domain;
  s.dt = scene_.time.dt;
  std::mt19937_64 rng(scene_.seed);
  std::ostringstream o;
  o << rng;
  s.rng_state = o.str();
  return s;
}

Evaluation Simulation::evaluate(const State& s, const std::vector<Vec3>& x) const {
  Evaluation ev;
  const std::size_t n = x.size();
  ev.force.assign(n, Vec3::Zero());
  ev.torque.assign(n, Vec3::Zero());
  const auto& fe = scene_.forces.external_force;
  const auto& te = scene_.forces.external_torque;
  for (std::size_t i = 0; i < n; ++i) {
    if (!fe.empty()) ev.force[i] += fe.size() == 1 ? fe[0] : fe[i];
    if (!te.empty()) ev.torque[i] += te.size() == 1 ? te[0] : te[i];
  }
  if (!scene_.forces.pair.empty()) forces::add_pair_forces(scene_.forces.pair, x, s.radius, s.domain, ev.force, &ev.pair);
  ev.hydro = hydro_.solve(x, s.radius, s.fixed, ev.force, ev.torque, s.domain);
  return ev;
}

void Simulation::wrap(State& s) const {
  if (!s.domain.periodic()) return;
  const Vec3& L = s.domain.box;
  for (Vec3& x : s.position) {
    // Lees-Edwards: leaving through a y face shifts x by the lattice strain.
    const double ny = std::floor(x.y() / L.y());
    x.x() -= ny * s.domain.shear_strain * L.y();
    x.y() -= ny * L.y();
    x.x() -= std::floor(x.x() / L.x()) * L.x();
    x.z() -= std::floor(x.z() / L.z()) * L.z();
  }
}

void Simulation::check_finite(const State& s) const {
  for (std::size_t i = 0; i < s.size(); ++i)
    if (!s.position[i].allFinite()) {
      std::ostringstream o;
      o << "step " << s.step << ": particle " << i << " has a non-finite position";
      throw PhysicsError(o.str());
    }
}

namespace {
// The sheared lattice repeats when the image shift strain * Ly is a multiple of Lx: reduce the
// strain to [-Lx/(2 Ly), Lx/(2 Ly)] (Lees-Edwards remap).
double reduce_strain(double strain, const Vec3& box) {
  const double period = box.x() / box.y();
  return strain - period * std::round(strain / period);
}
}  // namespace

void Simulation::advance(State& s, const Evaluation& ev, std::mt19937_64& rng) const {
  // Stage velocities at time t into the step: in a sheared box the lattice strain has advanced by
  // rate * t (shared/notes/method.md s.4), so stages see the box of their own time.
  const bool sheared = s.domain.periodic() && scene_.flow.kind == FlowParams::Kind::simple_shear;
  const auto velocity = [&](const std::vector<Vec3>& x, double t) {
    if (!sheared || t == 0.0) return evaluate(s, x).hydro.U;
    State staged = s;
    staged.domain.shear_strain += scene_.flow.rate * t;
    staged.domain.shear_strain = reduce_strain(staged.domain.shear_strain, s.domain.box);
    return evaluate(staged, x).hydro.U;
  };
  const double dt = s.dt;
  std::vector<Vec3> x1;
  double dt_used = dt;
  switch (scene_.time.integrator) {
    case Integrator::euler: x1 = axpy(s.position, dt, ev.hydro.U); break;
    case Integrator::midpoint:
      x1 = axpy(s.position, dt, velocity(axpy(s.position, 0.5 * dt, ev.hydro.U), 0.5 * dt));
      break;
    case Integrator::rkf45: {
      const RkfStep r = rkf45_step(velocity, s.position, ev.hydro.U, dt, scene_.time.rkf_tolerance, 1e-12 * scene_.time.dt);
      x1 = r.x;
      dt_used = r.dt_used;
      s.dt = r.dt_next;
      break;
    }
  }
  if (model_.brownian) {
    const auto dX = hydro_.brownian_displacement(s.position, s.radius, scene_.fluid.kT, dt, rng, s.domain);
    for (std::size_t i = 0; i < x1.size(); ++i)
      if (s.fixed.empty() || !s.fixed[i]) x1[i] += dX[i];
  }
  s.position = std::move(x1);
  s.time += dt_used;
  s.step += 1;
  if (s.domain.periodic() && scene_.flow.kind == FlowParams::Kind::simple_shear) {
    s.domain.shear_strain += scene_.flow.rate * dt_used;
    s.domain.shear_strain = reduce_strain(s.domain.shear_strain, s.domain.box);
  }
  wrap(s);
  check_finite(s);
}

io::TrajectoryHeader Simulation::header() const {
  io::TrajectoryHeader h;
  h.particles = scene_.positions.size();
  h.domain = scene_.domain;
  h.sheared_box = scene_.domain.periodic() && scene_.flow.kind == FlowParams::Kind::simple_shear;
  h.record.velocity = scene_.output.velocity;
  h.record.force = scene_.output.force;
  h.record.angular_velocity = scene_.output.angular_velocity && has_torque(model_.moments);
  h.record.torque = scene_.output.torque && has_torque(model_.moments);
  h.record.stresslet = scene_.output.stresslet && has_stresslet(model_.moments);
  h.scene_toml = scene_.toml;
  h.model = model_.describe();
  h.author = "stokesian";
  return h;
}

io::Frame Simulation::frame(const State& s, const Evaluation& ev) const {
  io::Frame f;
  f.step = s.step;
  f.time = s.time;
  f.shear_strain = s.domain.shear_strain;
  f.position = s.position;
  f.radius = s.radius;
  f.velocity = ev.hydro.U;
  f.force = ev.force;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (!s.fixed.empty() && s.fixed[i]) f.force[i] = ev.hydro.F[i];  // holding force of fixed particles
  if (has_torque(model_.moments)) {
    f.angular_velocity = ev.hydro.Omega;
    f.torque = ev.torque;
  }
  if (has_stresslet(model_.moments)) {
    Mat3 total = Mat3::Zero();
    for (const Vec5& S : ev.hydro.S) {
      f.stresslet.push_back(io::six_components(S));
      total += from_vec5(S);
    }
    const io::Vec6 t6 = io::six_components(total);
    f.vectors["stresslet_sum"] = std::vector<double>(t6.data(), t6.data() + 6);
  }
  // Overlap and gap diagnostics (shared/notes/method.md s.3: count and report overlaps).
  // Gap range of the search: 1 a, reduced in small periodic boxes to what the minimum image allows.
  double range = 1.0;
  if (s.domain.periodic()) {
    const double amax = *std::max_element(s.radius.begin(), s.radius.end());
    range = std::min(range, 0.5 * s.domain.box.minCoeff() - 2.0 * amax - 1e-9);
  }
  const auto pairs = range >= 0 ? trees::neighbor_pairs(s.position, s.radius, s.domain, range)
                                : trees::neighbor_pairs_bruteforce(s.position, s.radius, s.domain, 0.0);
  double min_gap = INFINITY;
  long overlaps = 0;
  for (const auto& p : pairs) {
    const double g = p.dist - s.radius[std::size_t(p.i)] - s.radius[std::size_t(p.j)];
    min_gap = std::min(min_gap, g);
    overlaps += g < 0;
  }
  f.scalars["overlaps"] = double(overlaps);
  f.scalars["min_gap"] = std::isfinite(min_gap) ? min_gap : 1.0;
  f.scalars["pair_energy"] = ev.pair.energy;
  f.scalars["krylov_iterations"] = ev.hydro.iterations;
  f.scalars["dt"] = s.dt;
  return f;
}

namespace {

// Terminal progress (steps/s, ETA, diagnostics) or plain log lines when not a terminal.
class Progress {
 public:
  Progress(long first, long last, bool quiet)
      : first_(first), last_(last), quiet_(quiet), tty_(isatty(fileno(stderr))), start_(clock::now()), shown_(start_) {}
  void update(long step, double time, const io::Frame* f, bool force = false) {
    if (quiet_) return;
    const auto now = clock::now();
    const double since = std::chrono::duration<double>(now - shown_).count();
    if (!force && since < (tty_ ? 0.5 : 10.0)) return;
    shown_ = now;
    const double el = std::chrono::duration<double>(now - start_).count();
    const double rate = el > 0 ? double(step - first_) / el : 0.0;
    const double eta = rate > 0 ? double(last_ - step) / rate : 0.0;
    char buf[256];
    std::snprintf(buf, sizeof buf, "step %ld/%ld  t=%.4g  %.3g steps/s  ETA %.0fs", step, last_, time, rate, eta);
    std::string line = buf;
    if (f) {
      std::snprintf(buf, sizeof buf, "  min_gap=%.3g overlaps=%.0f", f->scalars.at("min_gap"), f->scalars.at("overlaps"));
      line += buf;
    }
    if (tty_) std::fprintf(stderr, "\r%-100s", line.c_str());
    else std::fprintf(stderr, "%s\n", line.c_str());
    if (tty_ && force) std::fprintf(stderr, "\n");
  }

 private:
  using clock = std::chrono::steady_clock;
  long first_, last_;
  bool quiet_, tty_;
  clock::time_point start_, shown_;
};

}  // namespace

long Simulation::run(const RunOptions& opt) const {
  State s;
  io::Checkpoint restored;
  std::optional<io::RunOutput> out;
  bool frame_done = false;  // the frame of the current step is already in the trajectory
  if (opt.resume) {
    out.emplace(io::RunOutput::resume(opt.out, header(), restored));
    s = restored.state;
    frame_done = s.step % scene_.output.every == 0;
  } else {
    s = initial_state();
    out.emplace(io::RunOutput::start(opt.out, header()));
  }
  std::mt19937_64 rng;
  {
    std::istringstream in(s.rng_state);
    in >> rng;
  }
  std::optional<io::XyzWriter> xyz;
  if (!scene_.output.xyz.empty())
    xyz.emplace(scene_.output.xyz, s.domain, std::vector<std::string>{},
                opt.resume ? std::optional<std::int64_t>(s.step) : std::nullopt);

  const long last = scene_.time.steps;
  Progress progress(s.step, last, opt.quiet);
  long taken = 0;
  io::Frame latest;
  double max_overlaps = 0;
  for (;;) {
    const Evaluation ev = evaluate(s, s.position);
    if (!frame_done && s.step % scene_.output.every == 0) {
      io::Frame f = frame(s, ev);
      // Overlap policy: count every frame (observable "overlaps"), warn when a new maximum is reached,
      // continue (the far-field mobility is overlap-regularised and stays positive definite).
      if (f.scalars["overlaps"] > max_overlaps) {
        max_overlaps = f.scalars["overlaps"];
        if (!opt.quiet)
          std::fprintf(stderr, "%sstep %ld: %.0f overlapping pair(s), smallest gap %.3g a (continuing: mobility is overlap-regularised)\n",
                       isatty(fileno(stderr)) ? "\n" : "", long(s.step), f.scalars["overlaps"], f.scalars["min_gap"]);
      }
      if (xyz) xyz->write(f);
      latest = f;
      out->record(std::move(f));
    }
    frame_done = false;
    const bool at_end = s.step >= last || (opt.max_steps >= 0 && taken >= opt.max_steps);
    const long ce = scene_.output.checkpoint_every;
    if (at_end || (ce > 0 && s.step % ce == 0 && s.step > 0)) {
      std::ostringstream o;
      o << rng;
      s.rng_state = o.str();
      out->checkpoint(s);
      if (xyz) xyz->flush();
    }
    if (at_end) break;
    advance(s, ev, rng);
    ++taken;
    progress.update(s.step, s.time, latest.position.empty() ? nullptr : &latest);
  }
  progress.update(s.step, s.time, latest.position.empty() ? nullptr : &latest, true);
  return taken;
}

void Simulation::solve(const std::string& path) const {
  const State s = initial_state();
  const Evaluation ev = evaluate(s, s.position);
  io::Trajectory t = io::Trajectory::create(path, header());
  t.append(frame(s, ev));
  t.commit();
}

}  // namespace stokesian
