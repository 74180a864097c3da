#pragma once
// Resource estimates: peak memory per component and a rough time per step, from the resolved
// model and the scene (N, radii, box, tolerance), made before anything large is allocated, so
// that a scene the machine cannot hold is refused up front with the figure (docs/reliability.md,
// "Resources: memory and time estimates").
//
// Notation: N particles, d = 3 / 6 / 11 generalised entries per particle (F / FT / FTS), n = d N,
// 8 bytes per double. rho = N / V is the number density (V: the periodic box, or in an open domain
// the bounding box of the centres widened by the largest radius a_max), and the expected number of
// neighbours within centre distance r is nb(r) = min(N - 1, rho 4/3 pi r^3).
//
// Memory components (bytes):
//  scene and particle arrays   kBytesPerParticle N: positions, radii, the resolved TOML text stored
//                              in every output, state, forces and the per-stage evaluation arrays
//                              (measured: about 0.85 KB per particle through loading, checking and
//                              one evaluation of a free-draining scene at N = 10^6; 1 KB is used).
//  pair-force neighbour list   48 N nb(h_c + 2 a_max) bytes (half the pairs, 48 bytes each, twice:
//                              per-thread buffers and the merged list); h_c the largest cut-off gap.
//  far-field matrix            dense far fields (ewald, and direct when the solver needs the dense
//                              matrix): 8 n^2.
//  PME grid                    the grid M0 M1 M2 of ewald::pme_parameters (the operator's own
//                              parameters, from the tolerance, box, N and radii): 8 d M0 M1 M2
//                              (real) + 16 d M0 M1 (M2/2 + 1) (spectrum).
//  PME windows and pairs       windows 8 (9 P + 4) N + 12 N (P support points per direction, values
//                              and two derivatives per direction); real-space pairs
//                              p = N nb(r_c + 2 a_max) / 2 (r_c the PME cut-off gap): 48 p bytes for
//                              the pairs and their list, plus the scalar cache 2 p * 120 bytes when
//                              it fits its 128 MB cap.
//  Krylov vectors              mobility_cg: 8 n (8 + (Brownian ? 202 : 0)): CG vectors and, with
//                              kT > 0, the Lanczos basis (at most 200 vectors) of M^{1/2} W.
//  SD resistance and factors   dense_sd: 8 * 3 n^2: while solving, the resistance R = M^{-1} + R_nf,
//                              the constrained block R_vv and its Cholesky factor live beside the
//                              far-field matrix (4 n^2 in all; preparing holds M, its factor, the
//                              identity and the inverse: also 4 n^2).
//  near-field sparse matrix    Stokesian level: (N + 2 p_nf) d^2 entries at 28 bytes (value and
//                              index of the matrix, the assembly triplet), p_nf = N nb(r_nf) / 2 with
//                              r_nf = lubrication_cutoff * a_max. No registered solver factorises the
//                              near field alone (dense_sd adds it to the dense matrix), so there is
//                              no separate CHOLMOD factor to count.
// The peak is the sum of the components (they coexist during a step).
//
// Time per step (rough, one thread; measured constants of bench/results, docs/benchmarks.md):
//  evaluations per step e = 1 (euler), 2 (midpoint), 6 (rkf45); per evaluation
//  free draining 0.1 us N; pair forces 0.05 us per pair; far-field products: direct
//  t_pair N^2 with t_pair = 11 / 18 / 50 ns (F / FT / FTS); ewald 1 ns n^2 per product and 40 us
//  per pair to build the matrix; PME 2 ns per window point and entry (2 N P^3 d) + 2.5 ns
//  d G log2 G for the FFTs (G = M0 M1 M2) + 30 ns per real-space pair entry; CG takes
//  about 20 products and, with kT > 0, the Lanczos square root about 30 more; dense SD
//  (5/3) n^3 flops at 5 GFLOP/s plus the dense far field (7 us per pair at FTS, scaled by d^2).
//  These are order-of-magnitude figures for planning; `stokesian check` also measures a step.
#include "engine/core/memory.hpp"
#include "engine/core/scene.hpp"
#include "engine/model.hpp"

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace stokesian {

// Warn when the estimated peak exceeds this fraction of the available memory.
inline constexpr double kMemoryWarnFraction = 0.5;

struct ResourceComponent {
  std::string name;     // e.g. "far-field matrix (ewald, dense)"
  double bytes = 0.0;
  std::string formula;  // how it was computed, with the numbers
  std::vector<std::pair<std::string, std::string>> keys;  // scene (table, key) that drive it
};

struct ResourceEstimate {
  std::vector<ResourceComponent> components;
  double peak_bytes = 0.0;        // sum of the components
  double seconds_per_step = 0.0;  // rough (see above)
  const ResourceComponent& largest() const;
  // One line per component, then the total and the time, each prefixed by `indent`.
  std::string describe(const std::string& indent) const;
  const ResourceComponent* find(const std::string& name_prefix) const;
};

ResourceEstimate estimate_resources(const Scene& scene, const ResolvedModel& model);

// "[particles] count (line 5), [hydrodynamics] far_field (line 9)": the keys with their lines.
std::string scene_keys(const Scene& scene, const std::vector<std::pair<std::string, std::string>>& keys);

// Throws ConfigError when the estimate exceeds the budget, naming the estimate, the largest
// component, the budget and the scene keys that drive it. Above kMemoryWarnFraction of the budget
// prints a warning to `warn` (when not null). An unknown budget is said on `warn` and not refused.
void require_resources(const Scene& scene, const ResourceEstimate& est, const MemoryBudget& budget, std::FILE* warn);

}  // namespace stokesian
