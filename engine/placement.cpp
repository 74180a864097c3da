#include "engine/placement.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

namespace stokesian {

namespace {
std::vector<double> draw_radii(const PlacementParams& p, std::mt19937_64& rng) {
  std::vector<double> a(std::size_t(p.count), p.radius);
  if (p.sizes == PlacementParams::Sizes::bidisperse) {
    const long nlarge = std::lround(p.large_fraction * double(p.count));
    for (long i = 0; i < nlarge; ++i) a[std::size_t(i)] = p.radius * p.radius_ratio;
  } else if (p.sizes == PlacementParams::Sizes::lognormal) {
    std::lognormal_distribution<double> ln(std::log(p.radius), p.sigma);
    for (auto& v : a) v = ln(rng);
  }
  return a;
}
}  // namespace

Placement place_particles(const PlacementParams& p, const Vec3& box_in) {
  std::mt19937_64 rng(p.seed);
  Placement out;
  out.radius = draw_radii(p, rng);
  double vol = 0;
  for (double a : out.radius) vol += 4.0 / 3.0 * M_PI * a * a * a;
  const bool periodic = box_in.minCoeff() > 0;
  Vec3 box = box_in;
  if (!periodic) box = Vec3::Constant(std::cbrt(vol / p.volume_fraction));
  out.box = box;
  const Vec3 origin = periodic ? Vec3::Zero() : Vec3(-0.5 * box);
  const long n = p.count;
  out.position.assign(std::size_t(n), Vec3::Zero());

  auto overlaps = [&](const Vec3& x, double a, long upto, const std::vector<long>& order) {
    for (long k = 0; k < upto; ++k) {
      const long j = order[std::size_t(k)];
      Vec3 d = x - out.position[std::size_t(j)];
      if (periodic)
        for (int c = 0; c < 3; ++c) d[c] -= box[c] * std::round(d[c] / box[c]);
      if (d.norm() < a + out.radius[std::size_t(j)]) return true;
    }
    return false;
  };
  std::vector<long> order(static_cast<std::size_t>(n));
  for (long i = 0; i < n; ++i) order[std::size_t(i)] = i;
  std::stable_sort(order.begin(), order.end(), [&](long i, long j) { return out.radius[std::size_t(i)] > out.radius[std::size_t(j)]; });

  if (p.pattern == PlacementParams::Pattern::lattice) {
    const long side = std::lround(std::ceil(std::cbrt(double(n)) - 1e-9));
    const Vec3 h = box / double(side);
    for (long k = 0; k < n; ++k) {
      const long ix = k % side, iy = (k / side) % side, iz = k / (side * side);
      out.position[std::size_t(k)] = origin + Vec3((ix + 0.5) * h.x(), (iy + 0.5) * h.y(), (iz + 0.5) * h.z());
    }
    std::vector<long> identity(static_cast<std::size_t>(n));
    for (long k = 0; k < n; ++k) identity[std::size_t(k)] = k;
    for (long k = 0; k < n; ++k)
      if (overlaps(out.position[std::size_t(k)], out.radius[std::size_t(k)], k, identity)) {
        std::ostringstream o;
        o << "lattice spacing " << h.minCoeff() << " a is too small for particle " << k << " of radius "
          << out.radius[std::size_t(k)] << " a";
        throw std::invalid_argument(o.str());
      }
    return out;
  }
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const long max_tries = 20000;
  for (long k = 0; k < n; ++k) {
    const long i = order[std::size_t(k)];
    const double a = out.radius[std::size_t(i)];
    bool placed = false;
    for (long t = 0; t < max_tries && !placed; ++t) {
      Vec3 x;
      for (int c = 0; c < 3; ++c) {
        const double margin = periodic ? 0.0 : a;
        x[c] = origin[c] + margin + (box[c] - 2 * margin) * u(rng);
      }
      if (!overlaps(x, a, k, order)) {
        out.position[std::size_t(i)] = x;
        placed = true;
      }
    }
    if (!placed) {
      std::ostringstream o;
      o << "random placement failed after " << max_tries << " attempts for particle " << k << " of " << n
        << " (volume fraction " << p.volume_fraction << " is too close to the random-sequential-addition limit ~0.38)";
      throw std::invalid_argument(o.str());
    }
  }
  return out;
}

}  // namespace stokesian
