#pragma once
// Seeded random test data.
#include "engine/core/types.hpp"

namespace stokesian::test {

// n standard-normal entries from the test stream of seed.
inline VecX random_vector(Eigen::Index n, std::uint64_t seed) {
  Rng rng = RandomStream::for_purpose(seed, Purpose::test, 0);
  VecX v(n);
  for (auto& e : v) e = rng.normal();
  return v;
}

}  // namespace stokesian::test
