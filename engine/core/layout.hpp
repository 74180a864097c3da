#pragma once
// Generalised vectors and the rigid-body constraints of a hydrodynamic solve: the one place that
// decides which entries are known and which are solved for.
//
// Layout: per particle, interleaved, [F(3) T(3) S(5)] (forces, torques, stresslets the particles
// exert on the fluid; the F / FT prefix at lower moments) paired with the relative motion
// [U - u_inf, Omega - Omega_inf, -E_inf] (Durlofsky, Brady & Bossis 1987, eq. 2.13).
// Constraints: every entry has either its force or its motion prescribed.
//   mobile particle:   F, T given (non-hydrodynamic loads)         -> U, Omega solved for
//   fixed particle:    U = Omega = 0, i.e. motion -u_inf, -Omega_inf -> F, T solved for
//   every particle at FTS: rigid, E = 0, i.e. motion -E_inf         -> S solved for
// Index lists are in increasing order.
#include "engine/core/flow.hpp"
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian {

// Whether any particle is held fixed (fixed: empty or one flag per particle).
inline bool any_fixed(const std::vector<char>& fixed) {
  for (char f : fixed)
    if (f != 0) return true;
  return false;
}

struct RigidConstraints {
  Moments moments = Moments::F;
  long n = 0;
  std::vector<long> force_given;   // entries with a prescribed force (motion unknown)
  std::vector<long> motion_given;  // entries with a prescribed relative motion (force unknown)
  VecX force;   // length n d: the given forces at force_given, 0 elsewhere
  VecX motion;  // length n d: the given relative motion at motion_given, 0 elsewhere

  // fixed: empty or one flag per particle; T ignored at F level (may be empty).
  static RigidConstraints of(Moments m, const std::vector<char>& fixed, const std::vector<Vec3>& F,
                             const std::vector<Vec3>& T, const FlowSample& flow);
};

// Per-particle result of a hydrodynamic solve.
struct HydroResult {
  std::vector<Vec3> U, Omega;  // velocities, angular velocities (Omega empty at F level)
  std::vector<Vec5> S;         // stresslets exerted on the fluid (empty below FTS)
  std::vector<Vec3> F, T;      // forces/torques exerted on the fluid (fixed particles: holding force)
  int iterations = 0;          // Krylov iterations of the solve
  long regularised_pairs = -1; // lubrication pairs evaluated at the regularised minimum gap (-1: no near field)
};

// An iterative solver's last iterate, carried from one solve to a related one (a warm start: the
// next stage of an integrator step solves the same kind of problem at nearby positions). Opaque to
// callers: a solver starts from `iterate` when it has the solver's size and leaves its own final
// iterate there; direct solvers ignore it. The answer does not depend on it beyond the solver's
// tolerance; the iterations do. Callers keep it within one step, so that a run resumed from a
// checkpoint repeats the same sequence of solves.
struct WarmStart {
  VecX iterate;
};

// Per-particle results from the full generalised motion `relative` = [U - u_inf, Omega - Omega_inf,
// ...] and forces `moments` = [F, T, S]. Fixed particles get U = Omega = 0.
HydroResult unpack_solution(Moments m, const FlowSample& flow, const VecX& relative, const VecX& moments,
                            const std::vector<char>& fixed);

}  // namespace stokesian
