#include "trees/harmonic_expansion.hpp"

#include <cassert>
#include <stdexcept>

namespace stokesian::trees {

MultiIndexSet::MultiIndexSet(int order) : n_(order) {
  if (order < 0) throw std::invalid_argument("multi-index set: negative order");
  const int side = n_ + 1;
  lookup_.assign(std::size_t(side * side * side), -1);
  for (int t = 0; t <= n_; ++t)
    for (int i = t; i >= 0; --i)
      for (int j = t - i; j >= 0; --j) {
        const int k = t - i - j;
        lookup_[std::size_t((i * side + j) * side + k)] = int(alpha_.size());
        alpha_.push_back({i, j, k});
        total_.push_back(t);
        double f = 1;
        for (int q = 2; q <= i; ++q) f *= q;
        for (int q = 2; q <= j; ++q) f *= q;
        for (int q = 2; q <= k; ++q) f *= q;
        fact_.push_back(f);
      }
  // recurrence of inverse_distance_derivatives as a table (absent neighbours: index 0, weight 0)
  recurrence_.resize(alpha_.size());
  for (std::size_t k = 1; k < alpha_.size(); ++k) {
    const auto& al = alpha_[k];
    const int n = total_[k];
    Recurrence& rc = recurrence_[k];
    for (int c = 0; c < 3; ++c) {
      const int ac = al[std::size_t(c)];
      std::array<int, 3> b = al;
      if (ac >= 1) {
        --b[std::size_t(c)];
        rc.first[c] = index(b[0], b[1], b[2]);
        rc.first_weight[c] = double((2 * n - 1) * ac) / n;
      }
      if (ac >= 2) {
        --b[std::size_t(c)];
        rc.second[c] = index(b[0], b[1], b[2]);
        rc.second_weight[c] = double((n - 1) * ac * (ac - 1)) / n;
      }
    }
  }
  power_step_.resize(alpha_.size());
  for (std::size_t k = 1; k < alpha_.size(); ++k) {
    const auto& al = alpha_[k];
    const int c = al[0] > 0 ? 0 : (al[1] > 0 ? 1 : 2);
    std::array<int, 3> b = al;
    --b[std::size_t(c)];
    power_step_[k] = {index(b[0], b[1], b[2]), c, 1.0 / al[std::size_t(c)]};
  }
  plus_.resize(3 * alpha_.size());
  for (std::size_t k = 0; k < alpha_.size(); ++k)
    for (int d = 0; d < 3; ++d) {
      std::array<int, 3> b = alpha_[k];
      ++b[std::size_t(d)];
      plus_[3 * k + std::size_t(d)] = index(b[0], b[1], b[2]);
    }
}

void inverse_distance_derivatives(const Vec3& R, const MultiIndexSet& set, double* d) {
  const double r2 = R.squaredNorm();
  assert(r2 > 0);
  const double inv_r2 = 1.0 / r2, x = R[0], y = R[1], z = R[2];
  d[0] = std::sqrt(inv_r2);
  const int size = set.size();
  for (int k = 1; k < size; ++k) {
    const MultiIndexSet::Recurrence& rc = set.recurrence(k);
    const double acc = rc.first_weight[0] * x * d[rc.first[0]] + rc.first_weight[1] * y * d[rc.first[1]] +
                       rc.first_weight[2] * z * d[rc.first[2]] + rc.second_weight[0] * d[rc.second[0]] +
                       rc.second_weight[1] * d[rc.second[1]] + rc.second_weight[2] * d[rc.second[2]];
    d[k] = -acc * inv_r2;
  }
}

void scaled_powers(const Vec3& s, const MultiIndexSet& set, double* w) {
  const double ms[3] = {-s[0], -s[1], -s[2]};
  w[0] = 1;
  for (int k = 1; k < set.size(); ++k) {
    const MultiIndexSet::PowerStep& st = set.power_step(k);
    w[k] = w[st.prev] * ms[st.c] * st.inv;
  }
}

}  // namespace stokesian::trees
