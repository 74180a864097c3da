#pragma once
// Observers: what a run records at its output steps. Each observer declares the fields it writes
// (per-particle fields once per run, in RunHeader::particle_fields) and fills them in the Frame;
// io/ stores every field generically (/particles/all/<name>, /observables/<name>). A new output is
// a new observer (or a new entry of the per-particle table in observers.cpp).
//
// Built-in outputs:
//   per particle: position, radius (always); image (periodic boxes: lattice vectors removed by
//                 wrapping, integers); velocity, angular_velocity, force, torque, stresslet
//                 (selected by [output] record, each when the model computes it);
//                 force of a fixed particle = the force holding it (exerted on the fluid);
//                 stresslet as 6 Cartesian components xx xy xz yy yz zz.
//   observables:  overlaps (integer), min_gap (the smallest surface gap of any pair, nearest periodic
//                 image; +inf for a single particle), pair_energy, krylov_iterations (integer), dt,
//                 stresslet_sum (FTS: sum of the stresslets, 6 components); periodic boxes: stress and
//                 stress_<part> (engine/stress.hpp), brownian_samples, and in simple shear
//                 relative_viscosity[_<part>], N1[_<part>], N2[_<part>]; scenes with [walls]:
//                 wall_force and (slit, duct, outline) pressure_drop_particles; outline:
//                 pressure_drop_branches, areal_fraction_branches (docs/output.md, docs/channels.md).
#include "engine/core/frame.hpp"
#include "engine/core/registry.hpp"
#include "engine/core/scene.hpp"
#include "engine/core/state.hpp"
#include "engine/dynamics.hpp"
#include "engine/model.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace stokesian {

class Observer {
 public:
  virtual ~Observer() = default;
  // Per-particle fields this observer writes (appended to the run header).
  virtual void declare(std::vector<FieldSpec>& particle_fields) const { (void)particle_fields; }
  virtual void observe(const State& s, const Evaluation& ev, Frame& f) const = 0;
};

// The optional per-particle outputs that [output] record selects from.
struct ParticleOutputEntry {
  std::string name;
  FieldSpec spec;
  std::function<bool(const ResolvedModel&)> available;  // the model computes it
  std::string needs;                                    // what `available` asks of the model, for messages
  std::function<void(const State&, const Evaluation&, Frame&)> fill;
};
const Registry<ParticleOutputEntry>& particle_outputs();

// The observers of a run: the always-present ones and the recorded per-particle outputs the model
// computes. Throws ConfigError naming [output] record for an unknown name.
std::vector<std::unique_ptr<Observer>> make_observers(const Scene& scene, const ResolvedModel& model);

// Surface-gap statistics: overlapping pairs, and the true smallest surface gap (searched within 1 a,
// then in doubling ranges until a pair is found; nearest periodic image). +inf for one particle.
// With `fixed`, pairs of two fixed particles (a wall's own spacing) are left out.
GapStats gap_statistics(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                        const std::vector<char>* fixed = nullptr);

// One pair of a gap survey: surface gap h = r - a_i - a_j [a], and the overlap depth -h as a
// fraction of the smaller radius (negative when the pair does not overlap).
struct PairGap {
  long i = 0, j = 0;
  double gap = 0.0;
  double depth = 0.0;  // -h / min(a_i, a_j)
};
// The pairs with a surface gap below `range` [a], the `keep` closest first (by depth, i.e. by the
// gap relative to the smaller radius), and their statistics (min_gap = +inf when none is in range).
struct GapSurvey {
  GapStats stats;
  std::vector<PairGap> worst;
  long within = 0;  // pairs found in range
};
GapSurvey survey_gaps(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain, double range,
                      std::size_t keep, const std::vector<char>* fixed = nullptr);
// Both at once (output steps of a run): the overlapping pairs, as survey_gaps(x, a, domain, 0, keep)
// returns them, and the gap statistics, as gap_statistics returns them, from one pair search
// unless no pair lies within 1 a.
GapSurvey survey_overlaps(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                          std::size_t keep, GapStats& stats, const std::vector<char>* fixed = nullptr);
// "(i, j) gap h a (d of the smaller radius), ..." for messages.
std::string describe_pairs(const std::vector<PairGap>& pairs);

}  // namespace stokesian
