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
  const double inv_r2 = 1.0 / r2;
  d[0] = std::sqrt(inv_r2);
  for (int k = 1; k < set.size(); ++k) {
    const auto& al = set[k];
    const int n = set.total(k);
    double acc = 0;
    for (int c = 0; c < 3; ++c) {
      if (al[std::size_t(c)] == 0) continue;
      std::array<int, 3> b = al;
      --b[std::size_t(c)];
      acc += (2 * n - 1) * al[std::size_t(c)] * R[c] * d[set.index(b[0], b[1], b[2])];
      if (al[std::size_t(c)] >= 2) {
        --b[std::size_t(c)];
        acc += (n - 1) * al[std::size_t(c)] * (al[std::size_t(c)] - 1) * d[set.index(b[0], b[1], b[2])];
      }
    }
    d[k] = -acc * inv_r2 / n;
  }
}

void scaled_powers(const Vec3& s, const MultiIndexSet& set, double* w) {
  w[0] = 1;
  for (int k = 1; k < set.size(); ++k) {
    const auto& al = set[k];
    const int c = al[0] > 0 ? 0 : (al[1] > 0 ? 1 : 2);
    std::array<int, 3> b = al;
    --b[std::size_t(c)];
    w[k] = w[set.index(b[0], b[1], b[2])] * (-s[c]) / al[std::size_t(c)];
  }
}

}  // namespace stokesian::trees
