// Counter-based random numbers (engine/core/random.hpp): the generator against the published
// known-answer vectors of Philox4x32-10 [S11], our uniform and normal maps against their
// definitions and moments, stream independence, and Brownian runs that do not depend on the
// thread count or on the standard library's distributions.
#include <doctest/doctest.h>

#include "engine/core/random.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <omp.h>

#include <cmath>
#include <cstdint>
#include <vector>

using namespace stokesian;

namespace {
// The 53-bit uniform built from two words, written out independently of RandomStream.
double uniform_from(std::uint32_t hi, std::uint32_t lo) {
  const std::uint64_t bits = ((std::uint64_t(hi) << 21) ^ (std::uint64_t(lo) >> 11)) & ((std::uint64_t(1) << 53) - 1);
  return (double(bits) + 0.5) / 9007199254740992.0;
}
}  // namespace

TEST_CASE("Philox4x32-10 known answers and the uniform map") {
  // Random123 kat_vectors: counter 0, key 0 -> 6627e8d5 e169c58d bc57ac4c 9b00dbd8.
  RandomStream zero(0, 0);
  CHECK(zero.uniform() == uniform_from(0x6627e8d5u, 0xe169c58du));
  CHECK(zero.uniform() == uniform_from(0xbc57ac4cu, 0x9b00dbd8u));
  // Our layout: key = (seed low, seed high), counter = (stream low, stream high, block low, block
  // high). Stream 1 of seed 0 is counter (1, 0, 0, 0), key (0, 0).
  r123::Philox4x32 g;
  const r123::Philox4x32::ctr_type c = {{1u, 0u, 0u, 0u}};
  const r123::Philox4x32::key_type k = {{0u, 0u}};
  const auto r = g(c, k);
  RandomStream one(0, 1);
  CHECK(one.uniform() == uniform_from(r[0], r[1]));
  // The installed generator itself: counter and key from the hex digits of pi
  // -> d16cfe09 94fdcceb 5001e420 24126ea1 (Random123 kat_vectors).
  const r123::Philox4x32::ctr_type cpi = {{0x243f6a88u, 0x85a308d3u, 0x13198a2eu, 0x03707344u}};
  const r123::Philox4x32::key_type kpi = {{0xa4093822u, 0x299f31d0u}};
  const auto rpi = g(cpi, kpi);
  CHECK(rpi[0] == 0xd16cfe09u);
  CHECK(rpi[1] == 0x94fdccebu);
  CHECK(rpi[2] == 0x5001e420u);
  CHECK(rpi[3] == 0x24126ea1u);
  // Second block of a stream: counter (stream, 0, 1, 0).
  RandomStream s(7, 3);
  for (int i = 0; i < 2; ++i) s.uniform();
  const r123::Philox4x32::ctr_type c1 = {{3u, 0u, 1u, 0u}};
  const r123::Philox4x32::key_type k7 = {{7u, 0u}};
  const auto r1 = g(c1, k7);
  CHECK(s.uniform() == uniform_from(r1[0], r1[1]));
}

TEST_CASE("uniform and normal variates have the moments of their distributions (5-sigma bounds)") {
  RandomStream r = RandomStream::for_purpose(2026, Purpose::test, 1);
  const int n = 1000000;
  double su = 0, su2 = 0, sz = 0, sz2 = 0, sz4 = 0, umin = 1, umax = 0;
  for (int i = 0; i < n; ++i) {
    const double u = r.uniform();
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    su += u;
    su2 += u * u;
    const double z = r.normal();
    sz += z;
    sz2 += z * z;
    sz4 += z * z * z * z;
  }
  CHECK(umin > 0.0);
  CHECK(umax < 1.0);
  // uniform: mean 1/2 (sd 1/sqrt(12 n)), E u^2 = 1/3 (sd sqrt(4/45)/sqrt(n))
  CHECK(std::abs(su / n - 0.5) < 5 * std::sqrt(1.0 / 12 / n));
  CHECK(std::abs(su2 / n - 1.0 / 3) < 5 * std::sqrt(4.0 / 45 / n));
  // normal: mean 0 (sd 1/sqrt n), E z^2 = 1 (sd sqrt(2/n)), E z^4 = 3 (sd sqrt(96/n))
  CHECK(std::abs(sz / n) < 5 / std::sqrt(double(n)));
  CHECK(std::abs(sz2 / n - 1) < 5 * std::sqrt(2.0 / n));
  CHECK(std::abs(sz4 / n - 3) < 5 * std::sqrt(96.0 / n));
}

TEST_CASE("streams: the same (seed, purpose, index) repeats, a different one does not") {
  auto first = [](RandomStream r) { return r.normal(); };
  CHECK(first(RandomStream::for_purpose(5, Purpose::brownian, 10)) == first(RandomStream::for_purpose(5, Purpose::brownian, 10)));
  CHECK(first(RandomStream::for_purpose(5, Purpose::brownian, 10)) != first(RandomStream::for_purpose(5, Purpose::brownian, 11)));
  CHECK(first(RandomStream::for_purpose(5, Purpose::brownian, 10)) != first(RandomStream::for_purpose(6, Purpose::brownian, 10)));
  CHECK(first(RandomStream::for_purpose(5, Purpose::brownian, 10)) != first(RandomStream::for_purpose(5, Purpose::placement, 10)));
  CHECK(first(RandomStream::for_purpose(5, Purpose::brownian, 10, 0)) != first(RandomStream::for_purpose(5, Purpose::brownian, 10, 1)));
  // Correlation of neighbouring streams (steps n and n+1) is that of independent samples.
  double c = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) c += first(RandomStream::for_purpose(1, Purpose::brownian, std::uint64_t(k))) *
                                   first(RandomStream::for_purpose(1, Purpose::brownian, std::uint64_t(k + 1)));
  CHECK(std::abs(c / n) < 5 / std::sqrt(double(n)));
}

TEST_CASE("a Brownian run is the same with 1 and 2 threads and pinned by its seed") {
  const char* scene = R"(
[domain]
kind = "periodic"
box = [20.0, 20.0, 20.0]
[fluid]
kT = 1.0
[particles]
positions = [[1.0, 2.0, 3.0], [6.0, 2.0, 3.0], [1.0, 9.0, 3.0], [11.0, 12.0, 13.0]]
[hydrodynamics]
model = "free_draining"
[brownian]
seed = 20261124
[time]
dt = 0.01
steps = 50
)";
  auto run = [&](int threads) {
    omp_set_num_threads(threads);
    Simulation sim(io::parse_scene(scene, "brownian.toml"));
    State s = sim.initial_state();
    for (int k = 0; k < 50; ++k) sim.advance(s, sim.evaluate(s, s.position));
    return s.position;
  };
  const auto one = run(1), two = run(2);
  omp_set_num_threads(2);
  CHECK(one == two);
  // Regression pin (not a reference): particle 0 after 50 steps with this seed, as computed by this
  // version. It changes only if the noise streams or their use change, which must be deliberate:
  // a seed means the same trajectory on every machine.
  CHECK(one[0].x() == doctest::Approx(1.2891609876559402).epsilon(1e-12));
}

TEST_CASE("fork: a new stream per call, reproducible, independent of the parent's next draws") {
  RandomStream a = RandomStream::for_purpose(5, Purpose::brownian, 3), b = RandomStream::for_purpose(5, Purpose::brownian, 3);
  (void)a.normal();
  (void)b.normal();
  RandomStream fa1 = a.fork(), fb1 = b.fork();
  RandomStream fa2 = a.fork();
  const double x1 = fa1.normal(), y1 = fb1.normal(), x2 = fa2.normal();
  CHECK(x1 == y1);   // same parent state, same fork
  CHECK(x1 != x2);   // successive forks differ (the near-field forces of repeated draws)
  const double parent_next = a.normal(), fork_next = b.fork().normal();
  CHECK(parent_next != fork_next);  // parent and fork streams differ
  // Sample correlation between a fork and its parent over 20000 draws: |r| < 4.5 / sqrt(n).
  RandomStream p = RandomStream::for_purpose(9, Purpose::test, 1);
  RandomStream c = p.fork();
  const int n = 20000;
  double sxy = 0, sxx = 0, syy = 0;
  for (int k = 0; k < n; ++k) {
    const double x = p.normal(), y = c.normal();
    sxy += x * y;
    sxx += x * x;
    syy += y * y;
  }
  CHECK(std::abs(sxy / std::sqrt(sxx * syy)) < 4.5 / std::sqrt(double(n)));
}
