#pragma once
// Conventional Stokesian dynamics with dense linear algebra: the reference solver.
//
//   R = (M_inf)^{-1} + R_nf          [Durlofsky, Brady & Bossis 1987, eq. 2.17; Brady & Bossis 1988]
//
// with M_inf the dense far-field grand mobility of a MobilityOperator that holds it (direct in
// open domains, Ewald in periodic boxes) and R_nf the pairwise near-field correction
// (lubrication/near_field.hpp). In the generalised layout of engine/core/layout.hpp,
// [F T S] = R [U - u_inf, Omega - Omega_inf, -E_inf]:
//   resistance problem: given velocities and E_inf -> F, T, S (one product with R);
//   mobility problem:   the unknown motion V_v of the entries with given forces solves
//     R_vv V_v = f_v - R_vk V_k (+ the noise terms of engine/hydro_solver.hpp), V_k the given
//     motion (fixed particles at rest, -E_inf); the remaining rows then give S and the holding
//     forces. R_vv is solved by dense Cholesky.
// Linear algebra (LAPACK, multithreaded through the BLAS): prepare() orders the entries as
// [t-complement, t] with t the force/torque entries (all entries below FTS), factors
// P M_inf P^T = L L^T (dpotrf, n^3/3 flops) and inverts only the trailing block:
//   (M_inf^{-1})_tt = (L_tt L_tt^T)^{-1}        (dpotri on L_tt, 2 n_t^3 / 3 flops)
// because L^{-1} is lower triangular, so its trailing block is L_tt^{-1} [block Cholesky; Golub &
// Van Loan, Matrix Computations, 4th ed., sec. 4.2]. L_tt L_tt^T is the Schur complement of the
// stresslet block, so R_tt = (M^{-1})_tt + R_nf,tt is exact, not an approximation. Products with
// M_inf^{-1} (the given-motion columns, the slip, the recovered moments) are two triangular solves
// with L, O(n^2). solve() factors R_vv (v within t, dpotrf) and keeps the factor while the set of
// fixed particles is unchanged. The full R (resistance()) is formed only when asked for.
// O(N^3): meant for small N and as the oracle of the accelerated solver.
//
// Held (fixed) particles: with the entries split into those of the mobile particles (I) and of the
// held ones (H),
//   M_inf = [A_II B; B^T A_HH],  S = A_II - B A_HH^{-1} B^T          (the Schur complement)
//   (M_inf^{-1})_II = S^{-1},  M_inf^{-1} x = [y_I; A_HH^{-1}(x_H - B^T y_I)],  y_I = S^{-1}(x_I - B A_HH^{-1} x_H)
// [Golub & Van Loan, sec. 4.2; Lee et al. 2024, eqs. 2.26-2.29, the constrained formulation]. Held
// particles do not move, so A_HH = L_H L_H^T is factored once and kept while its entries are
// unchanged (the held particles' centres and radii and the domain, box and strain, all equal).
// Only the mobile particles' block rows of M_inf are formed (MobilityOperator::dense_rows: N_I N
// pair blocks, not N^2), and a configuration costs n_H^2 n_I (W = L_H^{-1} B^T, dtrsm) +
// n_I^2 n_H (S = A_II - W^T W, dsyrk) + n_I^3/3 instead of n^3/3: with 90 % held about a third,
// with 99 % a thirtieth. R_vv = (S^{-1})_tt + R_nf,vv as before (the I entries ordered stresslets first), and
// the far-field noise is L_S^{-T} psi_I (covariance S^{-1} = (M_inf^{-1})_II exactly). The
// factorisation is made at the first solve or Brownian draw of a configuration, for the fixed
// flags it is given; without held particles it is the full factorisation above, bit for bit.
// set_held_blocks(false) forces the full factorisation (the reference twin of the held path).
#include "engine/core/flow.hpp"
#include "engine/hydro_solver.hpp"
#include "lubrication/near_field.hpp"

#include <memory>

namespace stokesian {

class DenseStokesianDynamics final : public HydroSolver {
 public:
  // far_field must provide dense() (direct, ewald).
  DenseStokesianDynamics(std::unique_ptr<MobilityOperator> far_field, double mu, lubrication::NearFieldParams p = {});
  // Reference use: direct far field in open domains, Ewald in periodic boxes (chosen per call).
  DenseStokesianDynamics(Moments m, double mu, const AmbientFlow& flow, lubrication::NearFieldParams p = {});

  const char* name() const override { return "dense_sd"; }
  Moments moments() const override { return m_; }
  void prepare(const Configuration& c) override;
  HydroResult solve(const HydroProblem& p) override;
  std::vector<Vec3> brownian_displacement(double kT, double dt, Rng& rng) override;
  // Reference sampler (engine/brownian.hpp): far field P^T L^{-T} psi with L the dense Cholesky
  // factor of P M_inf P^T (covariance M_inf^{-1} exactly), near field by pairs.
  VecX brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) override;
  bool needs_drift() const override { return true; }
  // Dense Cholesky and the near-field assembly use every thread.
  bool prepare_uses_threads(long) const override { return true; }
  const MobilityOperator* far_field() const override { return op_.get(); }
  // R of the prepared configuration (formed on first request), and its near-field statistics.
  const MatX& resistance() const;
  const lubrication::NearFieldStats& near_field_stats() const { return stats_; }
  // Whether held particles are eliminated by the Schur complement (default) or the whole far field
  // is factored (the reference twin).
  void set_held_blocks(bool on) {
    held_blocks_ = on;
    factor_ = Factor::none;
  }
  // Whether the last factorisation reused the kept factor of the held block (tests, benchmarks).
  bool reused_held_factor() const { return reused_held_; }

  // Conveniences for the reference use (prepare + one problem, the flow given at construction).
  MatX resistance(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain = Domain{},
                  lubrication::NearFieldStats* stats = nullptr);
  HydroResult mobility_problem(const std::vector<Vec3>& x, const std::vector<double>& a, const std::vector<char>& fixed,
                               const std::vector<Vec3>& F, const std::vector<Vec3>& T, const Domain& domain = Domain{},
                               lubrication::NearFieldStats* stats = nullptr);
  // Given particle velocities (absolute) -> F, T, S.
  HydroResult resistance_problem(const std::vector<Vec3>& x, const std::vector<double>& a, const std::vector<Vec3>& U,
                                 const std::vector<Vec3>& Omega, const Domain& domain = Domain{});

 private:
  void select_reference_operator(const Domain& domain);
  bool op_periodic_ = false;  // reference use: the domain kind op_ was made for
  Moments m_;
  double mu_;
  AmbientFlow flow_;         // reference use only
  bool reference_ = false;   // operator chosen per domain kind (reference constructor)
  std::unique_ptr<MobilityOperator> op_;
  lubrication::NearField near_;
  lubrication::NearFieldStats stats_;
  StoredConfiguration config_;  // the prepared configuration (near-field Brownian forces)
  mutable const MatX* M_ = nullptr;  // the operator's dense M_inf, once formed (full_mobility)
  enum class Factor { none, full, blocks };
  Factor factor_ = Factor::none;
  std::vector<char> factor_held_;  // held flags of the factorisation (one per particle)
  bool held_blocks_ = true;
  bool reused_held_ = false;
  // Full factorisation, and the mobile block of the held one: perm_[r] = generalised entry at row r
  // of the factored order (full: every entry; blocks: the mobile particles' entries), pos_ its
  // inverse (-1: not in the order).
  std::vector<long> perm_;
  std::vector<long> pos_;
  long n0_ = 0;              // rows before the trailing (force/torque) block
  MatX L_;                   // full: Cholesky factor of P M_inf P^T; blocks: of S (lower triangle)
  MatX Rtt_;                 // (M_inf^{-1})_tt + R_nf,tt over the force/torque rows of perm_, both triangles
  // Held block: its entries (particle order), the held particles' centres, radii and the domain
  // it was factored for, its factor L_H, and W = L_H^{-1} B^T.
  std::vector<long> held_entries_;
  std::vector<Vec3> held_x_;
  std::vector<double> held_a_;
  Domain held_domain_;
  MatX held_L_, W_;
  lubrication::SparseMatrix Rnf_;  // near-field resistance (symmetrised), generalised layout
  // Factor of R_vv for the set v of the last solve.
  std::vector<long> v_;
  MatX Rvv_;
  bool have_Rvv_ = false;
  mutable MatX R_;
  mutable bool have_R_ = false;
  void factor(const std::vector<char>& fixed);
  void order_entries(const std::vector<char>& held);  // perm_, n0_, pos_ of the particles not held
  void factor_full();
  void factor_blocks(const std::vector<char>& held);
  void add_near_field_tt();
  const MatX& full_mobility() const;  // M_inf of the prepared configuration, formed on first use
  [[noreturn]] void far_field_not_positive_definite() const;
  VecX apply_inverse_mobility(const VecX& x) const;  // M_inf^{-1} x through the factors
};

}  // namespace stokesian
