#pragma once
// Accelerated Stokesian dynamics: the SD problem of engine/hydro_solver.hpp,
//     R V = f + f_B + M_inf^{-1} u_s,   R = M_inf^{-1} + R_nf,
// solved without forming M_inf or its inverse (Sierou & Brady 2001; the constrained form of
// Lee et al. 2024, s. 2.1.3, eqs. 2.45-2.47, rederived in ../shared/notes/seed1.md s. 1.10).
//
// Unknowns: the far-field moments X = M_inf^{-1}(V - u_s) of every entry and the motion V_v of the
// entries whose force is given (index sets v / k of engine/core/layout.hpp: V_k is the given
// motion: -E_inf for the stresslets, rest for fixed particles). The two conditions are
//     V = M_inf X + u_s                                  (far field, all entries)
//     X_v + R_vv V_v = g,  g = f_v + f_B,v - R_vk V_k     (given forces; R = R_nf here)
// With a positive diagonal shift B on the v entries, R~ = R_vv + B (sparse, positive definite,
// factorised once per configuration by CHOLMOD), and W = X - P_v B V_v, the second condition is
// V_v = R~^{-1} (g - W_v) and the first becomes, with Q = P_v R~^{-1} P_v^T and B^ = P_v B P_v^T,
//     [ M_inf (I - B^ Q) + Q ] W = (I - M_inf B^) Q g~ + P_k V_k - u_s            (eq. 2.47)
// An exact change of variables for ANY symmetric C = R~ - R_vv that leaves R~ positive definite
// (the derivation never uses that C is diagonal, only that R~ is what is factorised): V does not
// depend on C (tested); C only conditions the system and sets the cost of the factorisation.
// We factorise R~ = R_vv with the off-diagonal blocks of "weak" pairs dropped + B, B = shift D_v,
// D the diagonal of the self resistance (6 pi mu a, 8 pi mu a^3, 20 pi mu a^3/3 per
// translational, rotational, stresslet component); a pair is weak when its symmetric gap is at
// least `factor_gap` (its lubrication is not singular there). Dropping those blocks keeps R~
// positive definite (each pair block is PSD, and so is its block diagonal) and bounds the fill of
// the factor, which otherwise grows like N^1.5 at phi >= 0.3 (bench_asd, "fill"); the dropped part
// stays in the exact operator through C = B - R_weak,offdiag. The rows are scaled by D: with
// M_inf ~ D^{-1} (no interactions), no given motion and nothing dropped the operator is
// D (I + M R_nf)(R_nf + D)^{-1} = I exactly, so its eigenvalues cluster at 1 and the far-field
// interactions set the iteration count. Each iteration costs one far-field product, one pair of
// triangular solves and two sparse products.
// Afterwards V_v = R~^{-1}(g - W_v), X = W + B^ V, and the moments are F = X + R_nf V (the given
// force plus noise at v by construction, the stresslets and holding forces at k).
//
// Krylov method (bench/bench_asd.cpp, "krylov methods"): the operator is not symmetric, so CG does
// not apply; restarted GMRES takes one product per iteration and needed fewer products than
// BiCGStab (two per iteration) at every phi and N measured; see docs/accelerated_sd.md.
//
// Held particles (issue 17). Their rows of the operator are bare far-field rows D_k (M W)_k: a
// first-kind equation whose spread of eigenvalues (touching wall particles, clusters of held
// spheres) multiplies the iterations. The solve is right-preconditioned on those rows by a block
// Jacobi inverse: the held particles are split into spatial clusters of at most kHeldCluster
// (recursive bisection along the longest extent) and each cluster's block D_c M_c of the grand
// mobility is LU-factorised: the open-domain tensors (engine/kernels/far_field.hpp), or in periodic
// boxes the Ewald sum over the cluster (ewald/ewald_reference.hpp, truncated at kHeldEwaldTail).
// The factors are kept while the held particles, the box and (within kHeldStrainReuse) the
// Lees-Edwards strain stay. GMRES then solves A P^-1 y = b, W = P^-1 y (tested against the
// unpreconditioned twin, set_held_preconditioner(false), tests/test_sd_accelerated.cpp
// "held-row preconditioner"). Measured at tolerance 1e-3 (first pass, below): a wall of 100
// touching held spheres under 20 mobile ones 25 -> 16 iterations (FT) in an open domain, 19 -> 14 in
// a periodic slit; 90 % held at phi = 0.2 (N = 1000) 41 -> 34; random held spheres in a periodic
// box barely change (33 -> 33 at N = 300, 90 % held): their iterations come from the long-range
// coupling between clusters (with the whole held block as one cluster: 12).
// Long-wave part (periodic boxes): P^-1 = G B G, B the block-Jacobi inverse and G the long-wave
// deflation of the held particles alone (engine/brownian.hpp, at most kHeldWaveVectors wave
// vectors): on a held force wave of wave vector k, D M_kk acts as D lambda_k with lambda_k ~ n_held /
// (mu k^2) far above the self mobility, B as the inverse of D times about the self mobility, and G^2
// as lambda_self / lambda_k, so G B G inverts both. Any invertible P leaves the solution unchanged
// (tested against set_held_long_wave(false)). Measured (FT, phi = 0.2, 90 % held, tolerance 1e-3,
// solve at x0, all passes): 45 -> 30 iterations at N = 300, 67 -> 41 at 1000, 86 -> 57 at 3000; a
// periodic slit's walls are unchanged (no mode stands out).
// Coarse part (two-level): Z holds, per coarse cluster of held particles (the bisection with its
// cap doubled from kHeldCluster until the columns fit kHeldCoarseColumns), the force fields uniform
// (3) and linear in position along each principal direction of the cluster's extent (3 each; a
// sheet of wall particles has two) on the translational entries; E = Z^T A Z, A the
// unpreconditioned operator (on held entries D M: one far-field product per column). With
// c = E^-1 Z^T y: P^-1 y = Z c + G B G (y - Pi_H A Z c) (Pi_H: the held entries, so P depends on the
// held particles alone) when those rows have at most kHeldCoarseKept entries (multiplicative), else
// Z c + G B G y (additive).
// It targets the low tail G B G leaves (FT, phi = 0.2, 90 % held, N = 300: 76 of 1620 eigenvalues
// of G B G D M_HH below 0.3, down to 0.10; collective translations over many clusters), which no
// small set of vectors removes (its 30 slowest eigenvectors deflated exactly: 28 -> 21 iterations;
// bench/study_held_coarse.cpp). Built at the first solve with the held blocks in a box at zero
// strain (the blocks then last as long as the held particles, so resumed runs repeat the same
// solves); in a sheared box (blocks kept for a strain of kHeldStrainReuse) once the solves with
// these blocks have spent kHeldCoarseSaving of their iterations as many products as it costs.
// E and the kept rows come from an operator set to the held particles alone
// (set_far_field_factory), so P depends on them alone. Measured (docs/accelerated_sd.md, "Coarse
// part"): iterations per solve 21.4 -> 20.3 (configs/t_junction.toml), 45.5 -> 26.0
// (configs/slit_poiseuille.toml), about half per step at N = 1000-3000, 90 % held (bench_channel).
// Tested against set_held_coarse(false), dense SD and for its dependence on the held particles
// alone (tests/test_sd_accelerated.cpp).
// Accuracy with held particles: the residual is relative to |b|, and the held rows can make |b|
// far larger than some solved quantities (held particles in a flow, small holding forces on a
// wall); the error then exceeded the tolerance up to 3x (N = 1000, phi = 0.2, half held). After the
// first pass the solve continues to a tenth of the residual, and takes the change of every solved
// quantity as the estimate of its error, until that is below kHeldErrorTarget (solve()). A pass that
// stalls at the round-off floor (tolerances near 1e-10 ask residuals near kMinResidual) after
// meeting the GMRES tolerance keeps its iterate.
//
// Warm start: HydroProblem::warm (engine/core/layout.hpp) gives GMRES its initial iterate (the
// Fixman and midpoint steps pass the iterate of the solve at x0 to the midpoint solve), with or
// without held particles (tests/test_sd_accelerated.cpp, "warm start"; an iterate worse than zero is
// dropped). Measured in bench_brownian (docs/benchmarks.md, "Brownian SD step cost"); with 90 % held
// (bench_channel scene, N = 1000) the midpoint solve takes 16-18 GMRES iterations instead of 36.
//
// Fixed particles change the index set v; the factor of R~ is kept for the set of the last solve
// (prepare() factorises for the set last used, solve() refactorises when the set changes).
#include "engine/brownian.hpp"
#include "engine/core/krylov.hpp"
#include "engine/hydro_solver.hpp"
#include "lubrication/near_field.hpp"

#include <memory>

namespace stokesian {

struct AcceleratedSdStats {
  int iterations = 0;           // GMRES iterations of the last solve (all passes)
  int first_pass_iterations = 0;  // those of its first pass (to the GMRES tolerance)
  int far_field_products = 0;   // far-field products of the last solve (right-hand side + iterations)
  double relative_residual = 0.0;
  long factor_nonzeros = 0;     // fill of the CHOLMOD factor of R~
  double seconds_far_field_setup = 0.0, seconds_near_field_assembly = 0.0, seconds_factorisation = 0.0;
  double seconds_krylov = 0.0;  // last solve's Krylov iterations (products and triangular solves)
  int lanczos_iterations = 0;   // far-field products of the last Brownian force
  long deflated_wave_vectors = 0;  // of its long-wave deflation (engine/brownian.hpp)
  int held_clusters = 0;        // blocks of the held-row preconditioner (0: none)
  long held_coarse_columns = 0; // columns of its coarse part (0: none)
  double seconds_held_coarse = 0.0;  // building the coarse part (its far-field products), when built
  long held_wave_vectors = 0;   // wave vectors of its long-wave part (0: none)
  double seconds_held_preconditioner = 0.0;  // assembling and factorising them
  double held_error_estimate = 0.0;  // last solve with held particles: its estimated relative error
  double seconds_far_noise = 0.0, seconds_near_noise = 0.0;  // last Brownian force's two parts
  // Sums over every call since construction (benchmarks take differences over the steps they time).
  struct Totals {
    long solves = 0, iterations = 0, products = 0, lanczos_iterations = 0;
    double far_field_setup = 0, near_field_assembly = 0, factorisation = 0, held_preconditioner = 0, held_coarse = 0;
    double krylov = 0, far_noise = 0, near_noise = 0;  // seconds
  } totals;
};

// Clusters of at most `cap` points (indices into x) by recursive bisection at the median along the
// longest extent, in a fixed order: the held-row preconditioner's blocks and coarse clusters.
std::vector<std::vector<std::size_t>> bisect_clusters(const std::vector<Vec3>& x, std::size_t cap);

class AcceleratedStokesianDynamics final : public HydroSolver {
 public:
  enum class Method { gmres, bicgstab };
  // krylov_tolerance: relative residual of the row-scaled system (engine/accuracy.hpp);
  // shift: B = shift * D (any positive value gives the same answer).
  // factor_gap: pairs with a symmetric gap at or above it keep only their diagonal blocks in R~.
  AcceleratedStokesianDynamics(std::unique_ptr<MobilityOperator> far_field, double mu,
                               lubrication::NearFieldParams p, double krylov_tolerance, double shift = kShift,
                               Method method = Method::gmres, double factor_gap = kFactorGap,
                               double brownian_tolerance = 1e-6);
  // Measured with bench_asd ("krylov", periodic FTS, N = 500, tolerance 1e-4; docs/accelerated_sd.md):
  // at phi = 0.45 the shift 0.3 / 1 / 3 / 10 takes 31 / 27 / 24 / 26 iterations with factor_gap 0.1,
  // and factor_gap all / 0.5 / 0.1 / 0.02 takes 25 / 25 / 24 / 31 iterations at shift 3 with factor
  // fill 2.28e6 / 8.0e5 / 5.1e4 / 1.5e4 nonzeros; at phi = 0.3 shift 3 with 0.1: 18 iterations.
  static constexpr double kShift = 3.0;
  static constexpr double kFactorGap = 0.1;

  const char* name() const override { return "accelerated_sd"; }
  Moments moments() const override { return m_; }
  void prepare(const Configuration& c) override;
  HydroResult solve(const HydroProblem& p) override;
  std::vector<Vec3> brownian_displacement(double kT, double dt, Rng& rng) override;
  // engine/brownian.hpp: far field by Lanczos M_inf^{-1/2} psi (brownian_tolerance), near field by pairs.
  VecX brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) override;
  bool needs_drift() const override { return true; }
  bool prepare_uses_threads(long n) const override { return op_->set_configuration_uses_threads(n); }
  // far_field_setup | near_field_assembly -> factorisation (the factorisation runs on one thread
  // beside whatever single phases the step has).
  std::vector<PreparePhase> prepare_phases(const Configuration& c) override;
  const MobilityOperator* far_field() const override { return op_.get(); }

  // The block-Jacobi preconditioner of the held particles' rows (on by default; off: the plain
  // reference twin).
  void set_held_preconditioner(bool on) { held_precondition_ = on; }
  // Its long-wave part in periodic boxes (on by default; off: block-Jacobi alone, the twin).
  void set_held_long_wave(bool on) {
    held_long_wave_ = on;
    held_lu_.clear();  // rebuilt at the next factorisation
  }
  // Makes a far-field operator like the solver's: the coarse part's products then use one set to the
  // held particles alone, so that it depends on them alone (bitwise; without it the solver's own
  // operator, whose sums also visit the mobile particles, leaves round-off of where they were).
  void set_far_field_factory(std::function<std::unique_ptr<MobilityOperator>()> f) { make_far_field_ = std::move(f); }
  // Its coarse part (on by default; off: blocks and long waves alone, the twin).
  // at_once: built at the first solve with the held blocks instead of when it has paid (tests).
  void set_held_coarse(bool on, bool at_once = false) {
    held_coarse_ = on;
    coarse_at_once_ = at_once;
    held_lu_.clear();  // rebuilt at the next factorisation
  }
  static constexpr long kHeldCoarseColumns = 1200;
  static constexpr double kHeldCoarseSaving = 1.0 / 3.0;
  // The held rows of A Z are kept (multiplicative form) when they have at most this many entries (32 MB).
  static constexpr double kHeldCoarseKept = 4e6;
  static constexpr long kHeldWaveVectors = 64;
  static constexpr int kHeldCluster = 32;
  // Periodic boxes: the blocks are Ewald sums truncated at this tail (terms below exp(-tail^2)), and
  // kept while the Lees-Edwards strain moves by at most kHeldStrainReuse.
  static constexpr double kHeldEwaldTail = 3.0;
  static constexpr double kHeldStrainReuse = 0.01;
  const AcceleratedSdStats& stats() const { return stats_; }
  const lubrication::NearFieldStats& near_field_stats() const { return near_stats_; }
  static constexpr int kMaxIterations = 2000;
  static constexpr int kRestart = 40;
  // Solves with held particles continue until the estimated error of every solved quantity is at
  // most kHeldErrorTarget times the GMRES tolerance (engine/accuracy.cpp sets that at 0.02 t; the
  // estimate fell short of the error by up to 10x, so the target is 0.02 t), in at most kHeldPasses
  // further passes, the residual at least kMinResidual.
  static constexpr double kHeldErrorTarget = 1.0;
  static constexpr int kHeldPasses = 3;
  static constexpr double kMinResidual = 1e-13;
  // A solved quantity below this fraction of the largest (row-scaled norms) is held to that fraction.
  static constexpr double kNegligibleBlock = 1e-3;

 private:
  void factorise(const std::vector<long>& v);
  void set_far_field(const Configuration& c);
  void assemble_near_field(const Configuration& c);
  Moments m_;
  double mu_;
  std::unique_ptr<MobilityOperator> op_;
  lubrication::NearField near_;
  double tol_, shift_, factor_gap_, brownian_tol_;
  lubrication::SparseMatrix Rt_;  // R~ (upper triangle), the factorised matrix
  Method method_;
  StoredConfiguration config_;
  lubrication::SymmetricBlockMatrix Rnf_;
  lubrication::NearFieldStats near_stats_;
  VecX D_;                       // self resistance per entry
  std::vector<long> factored_v_;  // index set of the factor below
  bool factored_ = false;
  lubrication::CholmodFactor factor_;
  AcceleratedSdStats stats_;
  // Held-row preconditioner: per cluster, its entries and the LU factors of D_c M_c.
  void factorise_held(const std::vector<long>& v);
  void apply_held_inverse(VecX& z) const;
  double largest_relative_change(const HydroResult& r, const HydroResult& q, const std::vector<char>& fixed) const;
  bool held_precondition_ = true;
  bool held_long_wave_ = true;
  std::vector<long> held_ids_;  // the held particles, centres and radii the blocks belong to
  std::vector<Vec3> held_x_;
  std::vector<double> held_a_;
  Domain held_domain_;
  std::vector<std::vector<long>> held_entries_;
  std::unique_ptr<LongWaveDeflation> held_wave_;  // long-wave part of the held rows' inverse (periodic)
  std::vector<Eigen::PartialPivLU<MatX>> held_lu_;
  // Coarse part: per coarse cluster its held particles and their centroid; E's LU; built lazily.
  void build_held_coarse(const LinearOperator& A, long n);
  void coarse_restrict(const VecX& v, VecX& out) const;  // out = Z^T v
  void coarse_extend(const VecX& w, VecX& z) const;      // z += Z w
  void apply_held_preconditioner(const VecX& y, VecX& z) const;  // z = P^-1 y
  bool held_coarse_ = true;
  bool coarse_at_once_ = false;
  std::function<std::unique_ptr<MobilityOperator>()> make_far_field_;
  long held_iterations_ = 0;  // GMRES iterations of the solves since the held blocks were built
  // Per coarse cluster: (particle, its coordinates along the cluster's scaled directions), the
  // number of directions and the cluster's first column.
  std::vector<std::vector<std::pair<long, Vec3>>> coarse_members_;
  std::vector<long> coarse_dims_, coarse_offset_;
  long coarse_size_ = 0;      // columns of Z
  bool coarse_built_ = false;  // E factorised
  Eigen::PartialPivLU<MatX> coarse_lu_;
  MatX AZ_;  // held rows of A Z (multiplicative form; held_ids_ order), empty when too large (additive)
};

}  // namespace stokesian
