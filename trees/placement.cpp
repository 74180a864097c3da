#include "trees/placement.hpp"

#include "trees/neighbor_list.hpp"

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
  for (double a : out.radius) vol += 4.0 / 3.0 * kPi * a * a * a;
  const bool periodic = box_in.minCoeff() > 0;
  Vec3 box = box_in;
  if (!periodic) box = Vec3::Constant(std::cbrt(vol / p.volume_fraction));
  out.box = box;
  const Vec3 origin = periodic ? Vec3::Zero() : Vec3(-0.5 * box);
  const long n = p.count;
  out.position.assign(std::size_t(n), Vec3::Zero());

  // The filled box (unsheared); open domains: no images.
  Domain dom;
  if (periodic) {
    dom.kind = Domain::Kind::periodic;
    dom.box = box;
  }
  auto overlaps = [&](const Vec3& x, double a, long upto, const std::vector<long>& order) {
    for (long k = 0; k < upto; ++k) {
      const long j = order[std::size_t(k)];
      const Vec3 d = dom.minimum_image(x - out.position[std::size_t(j)]);
      if (d.norm() < a + out.radius[std::size_t(j)]) return true;
    }
    return false;
  };

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
  // Random: uniform positions, then overlaps removed by repeated pairwise separation (each
  // overlapping pair is pushed apart along its line of centres by 1.05 times its overlap, all
  // pairs at once per sweep). Works far beyond the random-sequential-addition limit (phi ~ 0.38).
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto clamp = [&](Vec3& x, double a) {
    if (periodic) dom.wrap(x);
    else
      for (int c = 0; c < 3; ++c) x[c] = std::clamp(x[c], origin[c] + a, origin[c] + box[c] - a);
  };
  for (long i = 0; i < n; ++i) {
    Vec3 x;
    for (int c = 0; c < 3; ++c) x[c] = origin[c] + box[c] * u(rng);
    clamp(x, out.radius[std::size_t(i)]);
    out.position[std::size_t(i)] = x;
  }
  const int max_sweeps = 20000;
  std::vector<Vec3> shift(static_cast<std::size_t>(n));
  for (int sweep = 0;; ++sweep) {
    const double reach = 2e-3 * *std::max_element(out.radius.begin(), out.radius.end());
    const auto pairs = periodic && 4.0 * *std::max_element(out.radius.begin(), out.radius.end()) + reach >= box.minCoeff()
                           ? trees::neighbor_pairs_bruteforce(out.position, out.radius, dom, reach)
                           : trees::neighbor_pairs(out.position, out.radius, dom, reach);
    std::fill(shift.begin(), shift.end(), Vec3::Zero());
    long overlapping = 0;
    for (const auto& pr : pairs) {
      // Separate to contact plus a margin of 1e-3 (a gap of 1e-3 (a_i + a_j)), so that generated
      // packings start outside the lubrication minimum gap.
      const double contact = (1.0 + 1e-3) * (out.radius[std::size_t(pr.i)] + out.radius[std::size_t(pr.j)]);
      if (pr.dist >= contact) continue;
      ++overlapping;
      Vec3 dir = pr.dist > 0 ? Vec3(pr.r / pr.dist) : Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
      const double push = 0.5 * 1.05 * (contact - pr.dist) + 1e-9 * contact;
      shift[std::size_t(pr.i)] += push * dir;
      shift[std::size_t(pr.j)] -= push * dir;
    }
    if (overlapping == 0) break;
    if (sweep == max_sweeps) {
      std::ostringstream o;
      o << "random placement: " << overlapping << " overlapping pairs remain after " << max_sweeps
        << " relaxation sweeps (volume fraction " << p.volume_fraction << " is too high for random packing)";
      throw std::invalid_argument(o.str());
    }
    for (long i = 0; i < n; ++i) {
      out.position[std::size_t(i)] += shift[std::size_t(i)];
      clamp(out.position[std::size_t(i)], out.radius[std::size_t(i)]);
    }
  }
  return out;
}

}  // namespace stokesian
