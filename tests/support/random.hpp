#pragma once
// Seeded random test data.
#include "engine/core/types.hpp"

#include <random>

namespace stokesian::test {

// n standard-normal entries from Rng(seed).
inline VecX random_vector(Eigen::Index n, std::uint64_t seed) {
  Rng rng(seed);
  std::normal_distribution<double> g;
  VecX v(n);
  for (auto& e : v) e = g(rng);
  return v;
}

}  // namespace stokesian::test
