#pragma once
// Open channels ([inflow]; docs/channels.md, "Open channels"): particles enter an outline channel
// through its inlet and leave through its openings, as in the fouling simulations of Lee et al.
// 2024 [L24] §3.3, which feed particles at the inlet and drop those that leave.
//
// Slots. The state holds `capacity` particle slots, then the wall particles. A slot is either a
// particle (State::id >= 0, its serial number) or empty (id = -1, position NaN). The solvers never
// see empty slots: every step works on the present particles (slots in order, walls last), and the
// results go back to their slots. Trajectories keep `capacity + walls` entries per frame, with
// H5MD's convention for a changing number of particles (H5MD 1.0, the particles group: the largest
// number is stored, absent particles carry a fill value) and an `id` element (-1 = absent).
//
// Incoming suspension. Upstream of the inlet the particles form a monolayer of n_A centres per unit
// area over the band their centres can reach, |y'| <= w/2 - r - g (w the inlet width, r the
// particle radius, g = min_gap from the walls); phi_A = n_A pi r^2 is the scene's areal_fraction.
// The inlet profile is fully developed, u(s) = 6 U s (1 - s), s = y/w in [0, 1], U the mean inlet
// velocity ([flow] mean_velocity). Centres that move with the flow cross the inlet at the rate
//   Ndot = n_A \int_band u dy = n_A U w [3 s^2 - 2 s^3]_{s0}^{s1},   s0 = (r + g)/w, s1 = 1 - s0,
// with their positions along the inlet distributed as u(s) on the band (the flux-weighted
// distribution): a particle at s is sampled by rejection from the uniform band, accepted with
// probability u(s)/u_max. Each step adds Ndot dt to a credit; while it reaches 1 the due particle
// is placed at its s, a distance r + g + xi u(s) dt inside the inlet (xi uniform in [0, 1): where a
// particle that crossed during the step would be), if it keeps a surface gap g from every particle
// and wall particle present. If it does not fit, or no slot is empty, it waits for the next step at
// the same s (State::InflowTally::pending; a new s for a blocked one would favour the inlet's fast
// centre, which neighbours leave sooner) and the step counts as deferred (inflow_deferred). A
// neighbour carried by the flow clears the place within about (2r + g)/u(s), the time the flow at s
// takes to move it by a diameter and the gap. A place still blocked after that wait is held by a
// particle stuck at the inlet (deposited on its corner or a wall): the due particle then passes it
// at a new s, drawn up to 20 times in that step until one fits (inflow_redrawn), as the incoming
// suspension's streamlines pass an obstacle; if none fits it waits at the last one. The
// wait keeps the bias towards the centre small; without a bound, one deposit at the inlet would
// stop the inflow for good (it did in the fouling runs of 2026-11-28 from t ~ 65).
// The draws of step n use the stream (seed, inflow, n): runs are reproducible and resumable.
//
// Removal. A particle whose centre is outside the outline after a step has left through an
// opening (the wall particles keep it from crossing a wall): its slot is emptied. This includes
// particles carried or diffusing back through the inlet.
#include "engine/core/frame.hpp"
#include "engine/core/outline.hpp"
#include "engine/core/scene.hpp"
#include "engine/core/state.hpp"

#include <cstdint>
#include <vector>

namespace stokesian {

class Inflow {
 public:
  // Throws std::invalid_argument when the scene cannot have an inflow (io/scene_toml.cpp checks first).
  explicit Inflow(const Scene& scene);

  // The scene's particles in the first slots, the remaining slots empty, the walls last.
  void initialise(State& s) const;
  // Slots holding a particle, in order, then the wall particles.
  std::vector<std::size_t> present(const State& s) const;
  // The state of the present particles only (what the solvers see), and its way back.
  static State compact(const State& s, const std::vector<std::size_t>& idx);
  static void scatter(const State& c, const std::vector<std::size_t>& idx, State& s);
  // A frame of the compact state written into the slots (absent: NaN, integer fields 0, id -1), with
  // the inflow observables.
  Frame expand(const Frame& f, const State& s, const std::vector<std::size_t>& idx) const;
  // After a step of dt: removes the particles outside the outline and places the due ones.
  void exchange(State& s, double dt, std::uint64_t seed) const;

  double rate() const { return rate_; }  // Ndot [particles / time]
  std::size_t slots() const { return capacity_; }
  // Position along the inlet (s in [0, 1]) of a sampled insertion (tests), and the inlet's frame.
  double sample_inlet_coordinate(Rng& rng) const;
  const Outline& outline() const { return o_; }

 private:
  Outline o_;
  std::size_t capacity_ = 0, walls_ = 0;
  double radius_ = 1.0, gap_ = 0.1, mean_ = 0.0, width_ = 0.0, rate_ = 0.0, s0_ = 0.0;
  Vec2 start_, tangent_, inward_;
};

}  // namespace stokesian
