#pragma once
// Counter-based random numbers: every draw is a pure function of (seed, stream, index).
//
// Generator: Philox4x32-10 of Salmon, Moraes, Dror & Shaw, "Parallel random numbers: as easy as
// 1, 2, 3", SC'11 [S11] (Random123 headers). A block is Philox(key, counter) with
//   key     = (seed mod 2^32, seed div 2^32)
//   counter = (stream mod 2^32, stream div 2^32, block mod 2^32, block div 2^32)
// and yields four 32-bit words; two words make one 53-bit uniform u in (0, 1) (open at both
// ends). Normal variates use the Box–Muller transform (Box & Muller 1958) on pairs of uniforms:
//   z1 = sqrt(-2 ln u1) cos(2 pi u2),  z2 = sqrt(-2 ln u1) sin(2 pi u2).
// Neither step depends on the standard library's distributions, so a seed gives the same numbers
// with every compiler and library, and a draw's value does not depend on which thread makes it
// or on what was drawn before: stream s, index k is the same number in every run.
//
// Streams used by the engine (RandomStream::for_purpose):
//   brownian noise of step n, stage k  -> stream (Purpose::brownian, n, k)
//   initial configuration              -> stream (Purpose::placement, ...)
#include <Random123/philox.h>

#include <cmath>
#include <cstdint>
#include <random>

namespace stokesian {

enum class Purpose : std::uint32_t { brownian = 1, placement = 2, equilibration = 3, test = 4, inflow = 5 };

class RandomStream {
 public:
  // seed: the scene's seed; stream: any 64-bit label (use stream_id to compose one).
  RandomStream(std::uint64_t seed, std::uint64_t stream) : seed_(seed), stream_(stream) {}

  // Purpose, a 40-bit major index (e.g. step) and an 8-bit minor index (e.g. integrator stage).
  static std::uint64_t stream_id(Purpose p, std::uint64_t major, std::uint32_t minor = 0) {
    return (std::uint64_t(p) << 56) | ((major & ((std::uint64_t(1) << 48) - 1)) << 8) | (minor & 0xffu);
  }
  static RandomStream for_purpose(std::uint64_t seed, Purpose p, std::uint64_t major, std::uint32_t minor = 0) {
    return RandomStream(seed, stream_id(p, major, minor));
  }
  // Continues a run started by version 0.1.0, whose checkpoints hold a std::mt19937_64 state and
  // whose noise of each step came from a fresh std::normal_distribution on it: the same numbers
  // on the same standard library, so such runs resume exactly where they stopped.
  static RandomStream continuing_legacy(std::mt19937_64& engine) {
    RandomStream r(0, 0);
    r.legacy_ = &engine;
    return r;
  }

  // A new stream, independent of this one and of every purpose stream, whose identity is a hash
  // of this stream's identity and position; this stream moves on to its next block, so successive
  // forks differ. Used where a parallel loop needs its own stream (seek_normal) within a draw
  // (the near-field Brownian forces of one step). Stream ids of forks have purpose byte 0xff.
  RandomStream fork() {
    std::uint64_t h;
    if (legacy_) {
      h = (*legacy_)();
    } else {
      h = mix(stream_ ^ mix(block_ + 0x9e3779b97f4a7c15ull));  // block_: the next block to generate
      ++block_;  // skipped: the next fork (and the next draw) see another block
      used_ = 4;
      have_spare_ = false;
    }
    return RandomStream(legacy_ ? 0 : seed_, (std::uint64_t(0xff) << 56) | (h >> 8));
  }
  // Positions the stream so that the next normal() is variate k of the stream (k even): normal
  // variates 2m and 2m + 1 come from block m (two uniforms of two words each). Lets parallel loops
  // draw their own slice of one stream, the same numbers for every thread count.
  void seek_normal(std::uint64_t k) {
    block_ = k / 2;
    used_ = 4;
    have_spare_ = false;
  }
  // Uniform in the open interval (0, 1), 53 random bits.
  double uniform() {
    if (legacy_) return std::generate_canonical<double, 53>(*legacy_);
    const std::uint32_t hi = word(), lo = word();
    const std::uint64_t bits = ((std::uint64_t(hi) << 21) ^ (lo >> 11)) & ((std::uint64_t(1) << 53) - 1);
    return (double(bits) + 0.5) * 0x1.0p-53;
  }
  // Standard normal variate.
  double normal() {
    if (legacy_) return legacy_normal_(*legacy_);
    if (have_spare_) {
      have_spare_ = false;
      return spare_;
    }
    const double u1 = uniform(), u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double t = 2.0 * 3.14159265358979323846 * u2;
    spare_ = r * std::sin(t);
    have_spare_ = true;
    return r * std::cos(t);
  }
  // Uniform integer in [0, n), n >= 1 (scaled 53-bit uniform; bias below n / 2^53).
  std::uint64_t below(std::uint64_t n) { return std::uint64_t(uniform() * double(n)) % n; }

 private:
  // splitmix64's finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mix.
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  std::uint32_t word() {
    if (used_ == 4) refill();
    return out_[std::size_t(used_++)];
  }
  void refill() {
    using G = r123::Philox4x32;
    G g;
    G::key_type k = {{std::uint32_t(seed_), std::uint32_t(seed_ >> 32)}};
    G::ctr_type c = {{std::uint32_t(stream_), std::uint32_t(stream_ >> 32), std::uint32_t(block_),
                      std::uint32_t(block_ >> 32)}};
    const G::ctr_type r = g(c, k);
    for (int i = 0; i < 4; ++i) out_[std::size_t(i)] = r[std::size_t(i)];
    ++block_;
    used_ = 0;
  }

  std::uint64_t seed_, stream_;
  std::uint64_t block_ = 0;
  std::uint32_t out_[4] = {0, 0, 0, 0};
  int used_ = 4;
  bool have_spare_ = false;
  double spare_ = 0.0;
  std::mt19937_64* legacy_ = nullptr;
  std::normal_distribution<double> legacy_normal_;
};

}  // namespace stokesian
