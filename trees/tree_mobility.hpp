#pragma once
// Barnes-Hut far field for open domains: y = M_inf x for forces, torques and stresslets of N
// spheres of any radii, with multipole expansions of order p about the octree's nodes.
//
// Mathematics (docs/tree.md). For two separated spheres (r >= a_t + a_s) every block of the grand
// mobility derives from Psi = (1 + w_t a_t^2 Lap)(1 + w_s a_s^2 Lap) r / (8 pi mu), w = 1/6 for
// force/velocity and 1/10 for torque/stresslet/rotation/strain (engine/kernels/mobility_pair.hpp).
// Sources. A force F, torque T and stresslet S of a sphere of radius a at y act on the fluid as a
// Stokeslet F and a Stokeslet doublet D_jl = S_jl - 1/2 eps_jlm T_m (u_i = D_jl d/dy_l J_ij), plus
// the source-side Laplacians (a^2/6 for F, a^2/10 for S; zero for the rotlet). With the Laplace
// kernel G = 1/|x - y| the disturbance velocity is [the harmonic form of Tornberg & Greengard 2008 for the
// Stokeslet; extended here to doublets and the finite-size terms]
//     8 pi mu u_i(x) = phi_i - (x - c)_j d_i phi_j + d_i psi,
// with four harmonic potentials, all about one centre c:
//     phi_j = sum [ F_j G + D_jl d/dy_l G ],
//     psi   = sum [ ((y - c).F) G + ((y - c)_j D_jl + a^2/3 F_l) d/dy_l G + a^2/5 S_jl d/dy_j d/dy_l G ].
// Responses at a sphere of radius a_t at x (target-side Laplacians; Lap u_i = -2 d_i d_j phi_j):
//     U_i = u_i - (a_t^2/3) d_i d_j phi_j,
//     Omega = 1/2 curl u,
//     E_ik = sym(d_k u_i) - (a_t^2/5) d_i d_k d_j phi_j.
// Expansion. Each node holds the Taylor moments of its four potentials about its centre to order
// p (trees/harmonic_expansion.hpp), so d^beta Phi(x) = sum_{|g| <= p} M_g d^(g + beta) G(x - c).
// The truncation error of a node seen at distance |x - c| with radius rho is O((rho/|x - c|)^(p+1)).
// Traversal. A node is used through its expansion when rho < theta |x - c| and every sphere in it
// is separated from the target's (|x - c| - rho > a_t + a_max); otherwise its children are
// visited, and the pairs of a leaf are summed with the exact pair kernel of engine/kernels (any
// separation, overlapping spheres included). Self terms are exact.
// Each target accumulates its own output, so the result does not depend on the thread count.
#include "engine/core/operators.hpp"
#include "engine/core/types.hpp"
#include "trees/harmonic_expansion.hpp"
#include "trees/octree.hpp"

#include <array>
#include <vector>

namespace stokesian::trees {

// How node expansions reach the targets.
//   fmm         - dual-tree traversal: a well-separated node pair (rho_T + rho_S < theta |c_T - c_S|)
//                 converts the source node's moments into a Taylor (local) expansion of order p
//                 about the target node's centre (terms |gamma| + |beta| <= p), passed down the
//                 tree and evaluated at each target (the fast path);
//   barnes_hut  - each target visits the tree and evaluates the moments of every accepted node
//                 (rho < theta |x - c|) itself (the plain twin; at p = 0 the monopole scheme of
//                 the thesis, chapter 3).
enum class TreeEvaluation { fmm, barnes_hut };

struct TreeParameters {
  double theta = 0.5;  // opening angle
  int order = 4;       // expansion order p >= 0
  int leaf_size = 32;  // largest particle count of a leaf; 0: tuned per configuration (fmm)
  TreeEvaluation evaluation = TreeEvaluation::fmm;
};

// The knobs from the requested relative accuracy t of a product (MobilitySpec::tolerance), the one
// place where they are derived (docs/tree.md, "Knobs from the tolerance"). FMM evaluation;
// theta in {0.15, 0.2, ..., 0.6} and the smallest p in [0, 20] whose error model
//     e(theta, p) = C(p) theta^(p+1),  C(p) = max(0.2 / (p + 1), 0.025) (F), 4 times that (FT),
//     0.05 (p + 1) (FTS)
// stays at or below t, choosing the pair of least modelled cost per particle
//     n_pair(theta) c_pair + n_conv(theta) (c_conv + terms(p) c_term) + c_index (p+k+1)(p+k+2)(p+k+3)/6,
// n_pair = 1770 (theta/0.5)^-2.5 near pairs and n_conv = 10.8 (theta/0.5)^-2.05 conversions per
// particle (geometric means of the counts at N = 1e4 ... 3e5, phi = 0.1, tuned leaves), terms(p)
// the terms of one conversion after the harmonic reduction, c_pair = 3.1/5.1/11.3 ns (F/FT/FTS),
// c_conv = 0.05 us, c_term = 0.40 ns and c_index = 22/25/29 ns (moments and evaluation per
// particle; one thread, fitted within 2.5 %). Leaf size 0: tuned per configuration among 32, 64,
// 128 by the same unit costs on the counted pairs and conversions (TreeFarField::set_configuration).
// C(p) bounds the largest error measured for theta 0.2-0.7 on uniform, clustered and radius-ratio-10
// clouds with leaves of 16 (bench_tree kind 2; F: 0.19, 0.094, 0.052, 0.036, 0.029, 0.023, 0.021,
// 0.021 at p = 0, 1, 2, 3, 4, 6, 8, 10). FT's factor 4: with F's C(p) a dense ball (phi = 0.3,
// N = 1200-2000) with leaves of 32 reached 1.0-1.8 times the requested error (FT only; 0.6 at
// N = 4000-8000). tests/test_tree_mobility.cpp checks achieved <= requested from 1e-2 to 1e-12
// for every leaf size the tuning can pick. Throws std::invalid_argument for t outside [1e-14, 0.5]
// (1e-14 is the floor of the engine's knobs, engine/accuracy.cpp).
TreeParameters tree_parameters(double tolerance, Moments m);

// `far_field = "auto"` in open domains picks the tree from this N on (0: never), with t the
// products' tolerance: the measured crossover of set-up plus one product with the vectorised
// direct sum (engine/kernels/direct_fast.cpp; uniform cloud, phi = 0.1, radii 0.5-1.5, overlaps
// allowed, 2 threads, 2026-11-28; docs/tree.md "Crossover"), rounded up:
//     t >= 5e-5: F 8000, FT 5000, FTS 7000;  t >= 5e-7: 20000, 15000, 12000;  smaller: 30000, 20000, 23000.
long tree_auto_from(double tolerance, Moments m);

// Modelled relative error of a product with these parameters (the model above).
double tree_error_model(const TreeParameters& p, Moments m);

// Modelled time of one product for n particles on one thread (the cost model above, fmm), and the
// operator's memory: the octree, moments and locals of at most n / 4 nodes, interaction lists.
double tree_product_seconds(const TreeParameters& p, Moments m, double n);
double tree_memory_bytes(const TreeParameters& p, Moments m, double n);

// Work counters of the last product (interactions per kind).
struct TreeProductStats {
  long node_interactions = 0;  // target-node multipole evaluations
  long pair_interactions = 0;  // exact pair kernel evaluations
  long m2l = 0;                // node-node conversions (fmm)
  double upward_seconds = 0;   // moments of every node
  double downward_seconds = 0; // conversions, shifts, evaluation at the targets and near pairs
};

// Positions, radii and inputs (F, T, S) in tree order, one array per component (the near-pair loop).
struct SortedSources {
  std::vector<double> x, y, z, a;
  std::vector<double> in[11];
};

class TreeFarField final : public stokesian::MobilityOperator {
 public:
  // Knobs from spec.tolerance (tree_parameters), or given explicitly.
  explicit TreeFarField(const MobilitySpec& spec);
  TreeFarField(const MobilitySpec& spec, const TreeParameters& parameters);
  const char* name() const override { return "tree"; }
  Moments moments() const override { return m_; }
  Eigen::Index size() const override { return Eigen::Index(x_.size()) * dof_per_particle(m_); }
  void set_configuration(const Configuration& c) override;
  void apply(const VecX& in, VecX& out) const override;
  bool set_configuration_uses_threads(long) const override { return false; }

  const TreeParameters& parameters() const { return p_; }
  const Octree& tree() const { return tree_; }
  int leaf_size() const { return leaf_size_; }
  const TreeProductStats& last_stats() const { return stats_; }

 private:
  void compute_moments(const VecX& in) const;
  void apply_barnes_hut(const VecX& in, VecX& out) const;
  void apply_fmm(const VecX& in, VecX& out) const;
  void build_interaction_lists();
  void downward(int node, const VecX& in, VecX& out) const;

  Moments m_;
  double mu_;
  int leaf_size_ = 32;          // in use (tuned when p_.leaf_size == 0)
  std::size_t tuned_n_ = 0;     // N of the last tuning
  long since_tuned_ = 0;        // configurations since
  TreeParameters p_;
  MultiIndexSet moment_set_;  // order p
  MultiIndexSet deriv_set_;   // order p + k (k = 2 for F, FT; 3 for FTS)
  MultiIndexSet beta_set_;    // order k
  std::vector<int> sum_index_;  // index in deriv_set_ of (gamma + beta), gamma x beta
  // Local expansions have the order q of deriv_set_. Shift terms (beta, delta, beta + delta) with
  // |beta + delta| <= q, grouped by beta; conversion terms (gamma, beta + gamma), |gamma| <= p,
  // grouped by beta.
  std::vector<std::array<int, 3>> shift_terms_;
  std::vector<std::array<int, 2>> m2l_terms_;
  std::vector<int> shift_begin_;     // terms of beta: shift_terms_[shift_begin_[beta] ..)
  std::vector<std::array<int, 3>> m2m_terms_;  // moment shift (gamma, delta, gamma - delta), by gamma
  std::vector<int> m2m_begin_;
  std::vector<int> m2l_term_begin_;  // terms of beta: m2l_terms_[m2l_term_begin_[beta] ..)
  std::vector<int> moment_keep_;     // gamma with gamma_z <= 1 (the moments the reduction keeps)
  std::vector<std::array<int, 2>> m2l_terms4_;  // m2l_terms_ with gamma as its position in moment_keep_
  // harmonic reduction: (gamma, gamma - 2e_z + 2e_x, gamma - 2e_z + 2e_y), likewise for beta
  std::vector<std::array<int, 3>> moment_fold_, local_rebuild_;
  // fmm interaction lists per target node (CSR): sources converted (m2l) and leaf pairs (p2p)
  std::vector<int> m2l_begin_, m2l_source_, p2p_begin_, p2p_source_;
  std::vector<int> parent_;
  mutable std::vector<double> locals_;   // per node: deriv_set_.size() x 4 potentials (interleaved)
  std::vector<Vec3> x_;
  std::vector<double> a_;
  Octree tree_;
  mutable SortedSources sorted_;
  mutable std::vector<double> moments_;  // per node: moment_set_.size() x 4 potentials (interleaved)
  mutable TreeProductStats stats_;
  mutable long pair_count_ = 0;
};

}  // namespace stokesian::trees
