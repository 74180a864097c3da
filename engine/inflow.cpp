#include "engine/inflow.hpp"

#include "engine/core/types.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace stokesian {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Everything of a state but its particles: time, step, box, noise state and the Brownian sums.
void copy_clock(const State& from, State& to) {
  to.time = from.time;
  to.step = from.step;
  to.dt = from.dt;
  to.domain = from.domain;
  to.rng_state = from.rng_state;
  to.brownian_samples = from.brownian_samples;
  to.brownian_stresslet_sum = from.brownian_stresslet_sum;
}
}  // namespace

Inflow::Inflow(const Scene& scene) {
  const InflowParams& p = scene.inflow;
  if (scene.walls.kind != ChannelParams::Kind::outline)
    throw std::invalid_argument("[inflow] needs [walls] kind = \"outline\"");
  o_ = make_outline(scene.walls);
  capacity_ = std::size_t(p.capacity);
  walls_ = scene.wall_count;
  if (scene.interior_count() > capacity_)
    throw std::invalid_argument("[inflow] capacity " + std::to_string(p.capacity) + " is below the " +
                                std::to_string(scene.interior_count()) + " particles of the scene");
  radius_ = p.radius;
  gap_ = p.min_gap;
  mean_ = scene.flow.mean_velocity;
  const std::size_t k = std::size_t(o_.inlet);
  width_ = o_.length(k);
  start_ = o_.a(k);
  tangent_ = (o_.b(k) - o_.a(k)) / width_;
  inward_ = -o_.outward_normal(k);
  s0_ = (radius_ + gap_) / width_;
  if (s0_ >= 0.5) throw std::invalid_argument("[inflow] radius + min_gap leaves no room across the inlet");
  const double n_area = p.areal_fraction / (kPi * radius_ * radius_);
  auto F = [](double s) { return 3.0 * s * s - 2.0 * s * s * s; };
  rate_ = n_area * mean_ * width_ * (F(1.0 - s0_) - F(s0_));
}

void Inflow::initialise(State& s) const {
  const std::size_t n0 = s.size() - walls_;
  State out = s;
  const std::size_t total = capacity_ + walls_;
  out.position.assign(total, Vec3(kNaN, kNaN, kNaN));
  out.radius.assign(total, radius_);
  out.fixed.assign(total, 0);
  out.id.assign(total, -1);
  for (std::size_t i = 0; i < n0; ++i) {
    out.position[i] = s.position[i];
    out.radius[i] = s.radius[i];
    out.id[i] = std::int64_t(i);
  }
  for (std::size_t w = 0; w < walls_; ++w) {
    out.position[capacity_ + w] = s.position[n0 + w];
    out.radius[capacity_ + w] = s.radius[n0 + w];
    out.fixed[capacity_ + w] = 1;
    out.id[capacity_ + w] = std::int64_t(n0 + w);  // walls: serial numbers after the first particles'
  }
  out.inflow = {};
  out.inflow.next_id = std::int64_t(n0 + walls_);
  s = std::move(out);
}

std::vector<std::size_t> Inflow::present(const State& s) const {
  std::vector<std::size_t> idx;
  idx.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.id[i] >= 0) idx.push_back(i);
  return idx;
}

State Inflow::compact(const State& s, const std::vector<std::size_t>& idx) {
  State c;
  c.position.reserve(idx.size());
  for (std::size_t i : idx) {
    c.position.push_back(s.position[i]);
    c.radius.push_back(s.radius[i]);
    c.fixed.push_back(s.fixed[i]);
  }
  copy_clock(s, c);
  return c;
}

void Inflow::scatter(const State& c, const std::vector<std::size_t>& idx, State& s) {
  for (std::size_t k = 0; k < idx.size(); ++k) s.position[idx[k]] = c.position[k];
  copy_clock(c, s);
}

Frame Inflow::expand(const Frame& f, const State& s, const std::vector<std::size_t>& idx) const {
  Frame out;
  out.step = f.step;
  out.time = f.time;
  out.shear_strain = f.shear_strain;
  out.observables = f.observables;
  for (const auto& [name, field] : f.particles) {
    const std::size_t per = std::size_t(item_size(field.shape));
    Field full = field;
    full.values.assign(s.size() * per, field.integer ? 0.0 : kNaN);
    for (std::size_t k = 0; k < idx.size(); ++k)
      for (std::size_t c = 0; c < per; ++c) full.values[idx[k] * per + c] = field.values[k * per + c];
    out.particles[name] = std::move(full);
  }
  std::vector<double> id(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) id[i] = double(s.id[i]);
  out.particles["id"] = Field{{}, std::move(id), "", true};
  out.set_count("particles_present", std::int64_t(idx.size() - walls_));
  out.set_count("inflow_inserted", s.inflow.inserted);
  out.set_count("inflow_removed", s.inflow.removed);
  out.set_count("inflow_deferred", s.inflow.deferred);
  out.set_count("inflow_redrawn", s.inflow.redrawn);
  return out;
}

double Inflow::sample_inlet_coordinate(Rng& rng) const {
  for (;;) {
    const double s = s0_ + (1.0 - 2.0 * s0_) * rng.uniform();
    if (rng.uniform() * 0.25 < s * (1.0 - s)) return s;  // u(s)/u_max = s (1 - s) / (1/4)
  }
}

void Inflow::exchange(State& s, double dt, std::uint64_t seed) const {
  for (std::size_t i = 0; i < capacity_; ++i) {
    if (s.id[i] < 0) continue;
    const Vec3& x = s.position[i];
    if (o_.contains(Vec2(x.x(), x.y()))) continue;
    s.id[i] = -1;
    s.position[i] = Vec3(kNaN, kNaN, kNaN);
    ++s.inflow.removed;
  }
  s.inflow.credit += rate_ * dt;
  if (s.inflow.credit < 1.0) return;
  Rng rng = RandomStream::for_purpose(seed, Purpose::inflow, std::uint64_t(s.step));
  std::size_t slot = 0;
  while (s.inflow.credit >= 1.0) {
    while (slot < capacity_ && s.id[slot] >= 0) ++slot;
    if (slot == capacity_) {
      ++s.inflow.deferred;
      return;
    }
    // The due particle keeps its place along the inlet until it fits (resampling a blocked place
    // would favour the fast centre of the inlet, where neighbours clear away sooner), for at most
    // (2r + g)/u(s); then it passes a stuck blocker at up to kPasses new places (inflow.hpp).
    if (s.inflow.pending < 0.0) s.inflow.pending = sample_inlet_coordinate(rng);
    auto place = [&](double sc) {
      const double speed = 6.0 * mean_ * sc * (1.0 - sc);
      const Vec2 c2 = start_ + tangent_ * (sc * width_) + inward_ * (radius_ + gap_ + rng.uniform() * speed * dt);
      return Vec3(c2.x(), c2.y(), 0.0);
    };
    auto fits = [&](const Vec3& c) {
      if (o_.distance(Vec2(c.x(), c.y()), true) < radius_ + gap_ - 1e-12) return false;
      for (std::size_t j = 0; j < s.size(); ++j)
        if (s.id[j] >= 0 && (s.position[j] - c).norm() < radius_ + s.radius[j] + gap_) return false;
      return true;
    };
    Vec3 c = place(s.inflow.pending);
    if (!fits(c)) {
      ++s.inflow.deferred;
      s.inflow.waited += dt;
      const double sc = s.inflow.pending;
      if (s.inflow.waited < (2.0 * radius_ + gap_) / (6.0 * mean_ * sc * (1.0 - sc))) return;
      ++s.inflow.redrawn;
      s.inflow.waited = 0.0;
      constexpr int kPasses = 20;
      bool placed = false;
      for (int k = 0; k < kPasses && !placed; ++k) {
        s.inflow.pending = sample_inlet_coordinate(rng);
        c = place(s.inflow.pending);
        placed = fits(c);
      }
      if (!placed) return;  // waits at the last place drawn
    }
    s.position[slot] = c;
    s.radius[slot] = radius_;
    s.id[slot] = s.inflow.next_id++;
    s.inflow.pending = -1.0;
    s.inflow.waited = 0.0;
    s.inflow.credit -= 1.0;
    ++s.inflow.inserted;
  }
}

}  // namespace stokesian
