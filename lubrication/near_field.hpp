#pragma once
// Near-field (lubrication) resistance of Stokesian dynamics (docs/stokesian_dynamics.md):
//
//     R_nf = sum over pairs with s < s_cut of  w(s) [ R2B_exact(pair) - R2B_inf(pair) ],
//
// w(s): the switch of lubrication/cutoff.hpp, 1 for s <= s_in = cutoff - taper, 0 from s_cut = cutoff
// on, C2 in between (taper = 0: the hard step of published SD);
// R2B_exact: the exact two-sphere resistance at the solve's moment level (F, FT or the full FTS
//   matrix of lubrication/resistance_functions.hpp; F and FT are principal sub-blocks of FTS,
//   since with E_inf = 0 the stresslet does not enter the force/torque rows);
// R2B_inf: the inverse of the engine's own two-body far-field mobility (engine/kernels/far_field.hpp) at
//   the same level, so that for two particles R_inf^{-1} + R_nf = R2B_exact exactly.
// s = 2 r / (a_i + a_j) is the symmetric separation, xi = s - 2 the symmetric gap (the same for
// both spheres, so the pair block obeys Newton's third law and the lambda <-> 1/lambda relations).
// Pairs with xi < xi_min are evaluated at xi_min along their line of centres (regularised
// minimum gap) and counted; overlaps (xi < 0) are counted separately.
// With the squeeze level ([hydrodynamics] lubrication = "squeeze"), the pair block is instead the
// thesis's normal squeeze resistance c(h) [[n n, -n n], [-n n, n n]] on the force rows, with no
// R2B_inf subtracted (lubrication/squeeze.hpp), under the same switch w(s).
#include "engine/core/domain.hpp"
#include "engine/core/scene.hpp"
#include "engine/core/types.hpp"
#include "lubrication/block_matrix.hpp"
#include "lubrication/cholmod_factor.hpp"
#include "lubrication/cutoff.hpp"
#include "lubrication/far_pair_inverse.hpp"
#include "lubrication/resistance_table.hpp"
#include "lubrication/squeeze.hpp"
#include "trees/neighbor_list.hpp"

#include <vector>

namespace stokesian::lubrication {

struct NearFieldParams {
  double cutoff = kDefaultLubricationCutoff;   // s_cut: pairs with 2 r / (a_i + a_j) < cutoff [1]
  double min_gap = kDefaultLubricationMinGap;  // regularised minimum symmetric gap xi_min [1]
  double taper = 0.0;  // width of the switch band [cutoff - taper, cutoff] [1]; 0 = hard step (published SD)
  Lubrication model = Lubrication::exact;  // exact two-sphere lubrication or the thesis's squeeze force
  SqueezeParams squeeze;                   // gaps of the squeeze model [a]
  CutoffBand band() const { return {cutoff - taper, cutoff}; }
};

/// The near-field parameters of a scene: the one place where [hydrodynamics] lubrication_cutoff,
/// lubrication_taper and lubrication_min_gap become NearFieldParams.  "auto" cutoff: the band of
/// cutoff_for_tolerance(h.tolerance, moments, max_cutoff) (an explicit taper replaces its width);
/// explicit cutoff: that s_cut with the explicit taper, or none ("auto" taper: hard step).
/// `moments` is the resolved moment level of the solve.
NearFieldParams near_field_params(const HydroParams& h, Moments moments, double max_cutoff = kDefaultMaxAutoCutoff);

struct NearFieldStats {
  long pairs = 0;                 // pairs inside the cutoff
  long tapered = 0;               // of those, pairs in the switch band (0 < w < 1)
  long regularised = 0;           // pairs evaluated at xi_min (including overlaps)
  long overlaps = 0;              // pairs with xi < 0
  double min_xi = 1e300;          // smallest symmetric gap seen
  int worst_i = -1, worst_j = -1; // the pair with the smallest gap
};

class NearField {
 public:
  NearField(Moments m, double mu, NearFieldParams p = {});

  // R_nf over the pairs found by trees::neighbor_pairs as symmetric d x d blocks (block_matrix.hpp),
  // reusing R's storage when it is large enough (a solver assembling every step keeps its pages:
  // fresh pages were a third of the assembly's time at 10^4 spheres).
  void assemble(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                SymmetricBlockMatrix& R, NearFieldStats* stats = nullptr) const;
  // The same as a sparse d N x d N matrix with both triangles stored (dense SD, references).
  SparseMatrix assemble(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                        NearFieldStats* stats = nullptr) const;
  // Reference twin: dense R_nf from an O(N^2) loop over all pairs (open domains).
  MatX assemble_dense(const std::vector<Vec3>& x, const std::vector<double>& a) const;

  // The 2d x 2d pair block R2B_exact - R2B_inf (squeeze level: the squeeze block) for sphere i at the
  // origin and sphere j at r_vec = x_j - x_i (pair order i, j), without the switch w(s). R2B_inf
  // comes as two-sphere scalars (far_pair_inverse.hpp), subtracted from the exact ones before the
  // one tensor assembly.
  MatX pair_block(const Vec3& r_vec, double ai, double aj) const;
  // Reference twin: R2B_inf by inverting the 2d x 2d two-body far-field mobility in the global frame.
  MatX pair_block_reference(const Vec3& r_vec, double ai, double aj) const;
  // The switch w(s) of this near field at symmetric separation s = 2 r / (a_i + a_j).
  double weight(double s) const { return cutoff_weight(s, p_.band()); }
  // The exact two-sphere resistance at the solve's moment level (2d x 2d).
  MatX exact_pair(const Vec3& r_vec, double ai, double aj) const;

  // Near-field Brownian force of unit temperature scale: f = sum over pairs p of L_p w_p, with
  // L_p L_p^T the pair's weighted block w(s) B_p restricted to the entries flagged in `given`
  // (length d N: the entries whose force is given, i.e. the mobile particles' F and T) and w_p
  // standard normal, independent for every pair (Banchio & Brady 2003, eq. 2.11; seed 1 eq. 2.51,
  // with the per-pair vectors of method notes P13). Its covariance is exactly R_nf restricted to
  // `given` (each restricted pair block is a principal sub-matrix of a positive definite block).
  // L_p from a pivoted LDL^T, so that a block that is positive semi-definite to round-off works;
  // a pivot below -1e-10 of the largest is a PhysicsError naming the pair. Pair m (in the pair
  // order of assemble()) draws normals 2 d m .. 2 d m + 2 d - 1 of `rng`: the same numbers for
  // every thread count. Zero at entries not given.
  VecX brownian_force(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                      const std::vector<char>& given, const RandomStream& rng) const;

  // Factorises R (R_nf plus whatever the caller added, e.g. the preconditioner's diagonal) with
  // CHOLMOD. A failure is reported as PhysicsError naming the particle of the failing column and
  // its closest neighbour with their symmetric gap.
  // entries: the generalised entry of each row/column of R when R is a principal sub-matrix
  // (nullptr: R is the whole d N x d N matrix).
  void factorize(const SparseMatrix& R, CholmodFactor& factor, const std::vector<Vec3>& x,
                 const std::vector<double>& a, const Domain& domain,
                 const std::vector<long>* entries = nullptr) const;

  const NearFieldParams& params() const { return p_; }
  Moments moments() const { return m_; }

 private:
  // The pairs inside the cutoff with a non-zero switch, in the pair order of trees::neighbor_pairs
  // (the order assemble() and brownian_force() share), with their weights; prepares the tables.
  struct WeightedPairs {
    std::vector<trees::NeighborPair> pairs;
    std::vector<std::size_t> in;  // indices into pairs
    std::vector<double> w;        // w(s) of pairs[in[m]]
  };
  WeightedPairs weighted_pairs(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain) const;

  Moments m_;
  double mu_;
  NearFieldParams p_;
  mutable ResistanceTableCache tables_;
  FarPairInverse far_inverse_;
};

}  // namespace stokesian::lubrication
