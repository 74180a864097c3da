#pragma once
// `stokesian check`: what a scene will do before it runs. Geometry problems of the initial state
// (overlapping pairs, particles outside a periodic box), the resolved model, forces, outputs, the
// measured cost of one evaluation and the run's estimated wall time, and step-size warnings.
//
// Step-size criteria (derived in docs/cli.md):
//  Stiffness. Near a pair's stiffest separation the overdamped relative motion along the line of
//    centres obeys d(delta r)/dt = -m_rel k delta r, with k = d^2U/dr^2 summed over the pair laws and
//    m_rel the relative mobility along the line of centres. Euler and explicit midpoint are stable
//    for this linear test equation when m_rel k dt <= 2 (both have the interval [-2, 0] of the
//    negative real axis), so dt_max = 2 / max_h [k(h) m_rel(h)] over the gap range the run can
//    reach. Free draining: m_rel = m_S = 1/(6 pi mu a_i) + 1/(6 pi mu a_j). Far field:
//    m_rel = m_S - 2 M_ij, M_ij = [1 - (a_i^2 + a_j^2)/(3 r^2)] / (4 pi mu r) the Rotne-Prager-
//    Yamakawa pair mobility along the line of centres (at contact when overlapping). Stokesian
//    dynamics: the squeeze resistance 6 pi mu a_eff^2 / h (a_eff = a_i a_j / (a_i + a_j), h floored
//    at the lubrication minimum gap) adds to the far-field resistance:
//    m_rel = 1 / (1/m_far + 6 pi mu a_eff^2 / h).
//    The gap range: from h_lo to the largest pair cut-off, where h_lo is the smaller of the
//    smallest initial gap and the gap at which the summed repulsion balances the largest driving
//    force (largest external force, plus 6 pi mu a_max |rate| 2 a_max for an ambient flow, plus
//    the largest pair attraction) and, with kT > 0, the repulsive energy above the well reaches
//    10 kT.
//  Displacement. With the velocities U of the initial state, every pair closer than 1 a closes by
//    at most a tenth of its gap in one step: v_ij dt <= 0.1 h_ij with the closing speed
//    v_ij = -(U_i - U_j) . r_ij / |r_ij|. Relative, not absolute, speeds: a suspension translating
//    as a whole (settling) closes no gap.
#include "engine/core/scene.hpp"
#include "engine/core/types.hpp"
#include "engine/simulation.hpp"

#include <cstdio>
#include <string>
#include <vector>

namespace stokesian::app {

struct Overlap {
  int i = 0, j = 0;   // particle indices, i < j
  double gap = 0.0;   // surface gap r - a_i - a_j < 0 [a]
};
// Every pair of the initial state with a negative surface gap (minimum image in periodic boxes).
std::vector<Overlap> initial_overlaps(const Scene& scene);

struct OutsideBox {
  int i = 0;
  Vec3 position, wrapped;  // as given, and its image in the primary box
};
// Particles of a periodic scene outside the primary box [0, L)^3 (none for open domains).
std::vector<OutsideBox> outside_box(const Scene& scene);

// d^2U/dr^2 [kT/a^2] of the summed pair laws (each with its resolved cut-off, as the run applies
// them) at centre distance r, by a central difference of dU/dr.
double pair_stiffness(const std::vector<PairForceParams>& laws, double a_max, double r, double ai, double aj);

struct StiffnessBound {
  bool applies = false;     // false: no pair laws, or an integrator without a fixed stability bound
  std::string reason;       // why not applied, when it does not
  double dt_max = 0.0;      // stable step bound
  double k = 0.0;           // stiffness at the limiting gap [kT/a^2]
  double m_rel = 0.0;       // relative mobility there [a/(kT time)]
  double gap = 0.0;         // the limiting gap [a]
  double ai = 0.0, aj = 0.0;  // the radius pair that limits
  double h_lo = 0.0, h_hi = 0.0;  // gap range considered [a]
};
// The stiffness criterion for the scene's pair laws, radii (smallest and largest), viscosity,
// driving forces, hydrodynamic level and integrator.
StiffnessBound stiffness_bound(const Scene& scene, const ResolvedModel& model);

struct DisplacementBound {
  int pair_i = -1, pair_j = -1;  // the limiting pair (-1: no pair closer than 1 a is closing)
  double gap = 0.0, closing_speed = 0.0, dt_max = 0.0;
};
// The displacement criterion for velocities u (one per particle) at the scene's initial positions.
DisplacementBound displacement_bound(const Scene& scene, const std::vector<Vec3>& u);

struct CheckOptions {
  std::string out;        // trajectory path the run would write
  bool estimate = true;   // measure evaluations (cost and displacement criterion)
  int threads = 0;        // threads used (0 = OpenMP default)
};

// Prints the report to `out`; returns the exit status (0, or 2 when the initial state has
// overlapping pairs).
int check(Simulation& sim, const CheckOptions& opt, std::FILE* out);

}  // namespace stokesian::app
