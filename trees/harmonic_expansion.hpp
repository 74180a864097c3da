#pragma once
// Cartesian Taylor machinery for the Laplace kernel G(R) = 1/|R|, the building block of the tree
// far field (trees/tree_mobility.hpp).
//
// Multi-indices alpha = (a1, a2, a3), |alpha| = a1 + a2 + a3, alpha! = a1! a2! a3!, are listed in
// graded order (all of order 0, then 1, ...), identically for every maximum order, so a set of
// order p is a prefix of any set of higher order.
//
// Derivatives D_alpha = d^alpha G(R) follow from the recurrence of Cartesian treecodes for the
// Taylor coefficients of 1/|R| (Duan & Krasny 2001), written here for derivatives with respect to
// R (tests/test_tree_mobility.cpp checks it against closed forms and finite differences): for
// n = |alpha| >= 1,
//   n |R|^2 D_alpha = -(2n - 1) sum_d alpha_d R_d D_{alpha - e_d} - (n - 1) sum_d alpha_d (alpha_d - 1) D_{alpha - 2 e_d},
// D_0 = 1/|R|. A source at offset s from an expansion centre then has G(R - s) =
// sum_alpha ((-s)^alpha / alpha!) D_alpha(R), convergent for |s| < |R|.
#include "engine/core/types.hpp"

#include <array>
#include <vector>

namespace stokesian::trees {

constexpr int multi_index_count(int n) { return (n + 1) * (n + 2) * (n + 3) / 6; }

class MultiIndexSet {
 public:
  explicit MultiIndexSet(int order);
  int order() const { return n_; }
  int size() const { return int(alpha_.size()); }
  const std::array<int, 3>& operator[](int k) const { return alpha_[std::size_t(k)]; }
  int total(int k) const { return total_[std::size_t(k)]; }
  double factorial(int k) const { return fact_[std::size_t(k)]; }  // alpha!
  // Position of (i, j, k) in the list, -1 when i + j + k exceeds the order (or any is negative).
  int index(int i, int j, int k) const {
    if (i < 0 || j < 0 || k < 0 || i + j + k > n_) return -1;
    return lookup_[std::size_t((i * (n_ + 1) + j) * (n_ + 1) + k)];
  }
  // Position of alpha_k + e_d, -1 beyond the order.
  int plus(int k, int d) const { return plus_[std::size_t(3 * k + d)]; }
  // The recurrence below for alpha_k as a table: D_alpha = -(sum_d first_weight_d R_d D_first_d +
  // sum_d second_weight_d D_second_d) / |R|^2 (absent neighbours have weight 0 and index 0).
  struct Recurrence {
    int first[3] = {0, 0, 0}, second[3] = {0, 0, 0};
    double first_weight[3] = {0, 0, 0}, second_weight[3] = {0, 0, 0};
  };
  const Recurrence& recurrence(int k) const { return recurrence_[std::size_t(k)]; }
  // alpha_k = alpha_prev + e_c with c the first non-zero component (scaled_powers: w_k = w_prev
  // (-s_c) / alpha_c); k >= 1.
  struct PowerStep {
    int prev = 0, c = 0;
    double inv = 0;  // 1 / (alpha_k)_c
  };
  const PowerStep& power_step(int k) const { return power_step_[std::size_t(k)]; }

 private:
  int n_;
  std::vector<std::array<int, 3>> alpha_;
  std::vector<int> total_;
  std::vector<double> fact_;
  std::vector<int> lookup_;
  std::vector<int> plus_;
  std::vector<Recurrence> recurrence_;
  std::vector<PowerStep> power_step_;
};

// d[k] = d^{alpha_k} (1/|R|) for every alpha_k of `set` (d has set.size() entries); R != 0.
void inverse_distance_derivatives(const Vec3& R, const MultiIndexSet& set, double* d);

// w[k] = (-s)^{alpha_k} / alpha_k! for every alpha_k of `set`.
void scaled_powers(const Vec3& s, const MultiIndexSet& set, double* w);

}  // namespace stokesian::trees
