#include "trees/walls.hpp"

#include "engine/core/channel.hpp"
#include "engine/core/outline.hpp"
#include "engine/core/random.hpp"

#include <cmath>
#include <cstdint>
#include <sstream>
#include <unordered_map>
#include <stdexcept>

namespace stokesian {

namespace {

// Lattice coordinates along one wall direction: periodic edge L (sites k L/n, n = floor(L/s),
// shifted by `shift` of a spacing) or open extent e centred on `mid` (floor(e/s) + 1 sites).
std::vector<double> line_sites(bool periodic, double L, double extent, double mid, double s, double shift,
                               const char* what, bool stretch = false, double radius = 0.0) {
  std::vector<double> v;
  if (periodic) {
    const long n = long(std::floor(L / s + 1e-9));
    if (n < 1) {
      std::ostringstream o;
      o << "the box edge " << L << " a along the wall's " << what << " holds no wall particle of spacing " << s << " a";
      throw std::invalid_argument(o.str());
    }
    const double h = L / double(n);
    for (long k = 0; k < n; ++k) v.push_back((double(k) + shift) * h);
  } else {
    long n = long(std::floor(extent / s + 1e-9)) + 1;
    // stretch: the end sites sit exactly at mid -+ extent/2, spacing extent/(n-1): the tighter count
    // ceil(extent/s) + 1 while it keeps a surface gap of at least gap/2, else floor(extent/s) + 1
    // (spacing between s and 2 s).
    if (stretch) {
      const double r2 = 2.0 * radius, gap = s - r2;
      const long tight = long(std::ceil(extent / s - 1e-9)) + 1;
      if (tight > 1 && extent / double(tight - 1) >= r2 + 0.5 * gap - 1e-12) n = tight;
      if (n > 1) s = extent / double(n - 1);
    }
    const double first = mid - 0.5 * double(n - 1) * s;
    // A shifted layer takes the n - 1 midpoints (symmetric about the centre).
    for (long k = 0; k < (shift > 0 ? n - 1 : n); ++k) v.push_back(first + (double(k) + shift) * s);
  }
  return v;
}

// Points in the plane binned on square cells of side `cell`, for "is any within d <= cell" queries.
class PlaneBins {
 public:
  explicit PlaneBins(double cell) : cell_(cell) {}
  bool any_within(const Vec2& p, double d) const {
    const std::int64_t ix = index(p.x()), iy = index(p.y());
    for (std::int64_t a = ix - 1; a <= ix + 1; ++a)
      for (std::int64_t b = iy - 1; b <= iy + 1; ++b) {
        const auto it = bins_.find(key(a, b));
        if (it == bins_.end()) continue;
        for (const Vec2& q : it->second)
          if ((q - p).norm() < d) return true;
      }
    return false;
  }
  void add(const Vec2& p) { bins_[key(index(p.x()), index(p.y()))].push_back(p); }

 private:
  std::int64_t index(double v) const { return std::int64_t(std::floor(v / cell_)); }
  static std::uint64_t key(std::int64_t a, std::int64_t b) { return (std::uint64_t(a) << 32) ^ std::uint64_t(std::uint32_t(b)); }
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<Vec2>> bins_;
};

// Wall sites of an outline (header).
std::vector<Vec3> outline_walls(const ChannelParams& c) {
  const Outline o = make_outline(c);
  const double s = c.spacing(), r = c.radius, dn = s * std::sqrt(3.0) / 2.0, min_d = 2.0 * r + 0.5 * c.gap;
  const std::size_t n = o.edges();
  // Turning angle of the fluid boundary at vertex k (between edges k-1 and k), positive where the
  // fluid's interior angle is below 180 degrees.
  auto turn = [&](std::size_t k) {
    const Vec2 t0 = (o.b((k + n - 1) % n) - o.a((k + n - 1) % n)).normalized(), t1 = (o.b(k) - o.a(k)).normalized();
    return o.orientation * std::atan2(t0.x() * t1.y() - t0.y() * t1.x(), t0.dot(t1));
  };
  std::vector<Vec2> sites;
  for (long layer = 0; layer < c.layers; ++layer)
    for (std::size_t k = 0; k < n; ++k) {
      if (o.open[k]) continue;
      const double d = r + double(layer) * dn;
      const Vec2 A = o.a(k), t = (o.b(k) - o.a(k)).normalized(), nrm = o.outward_normal(k);
      auto ext = [&](std::size_t vertex, std::size_t other_edge) {
        const double phi = turn(vertex);
        // Past a convex fluid corner the rows run on to meet the next edge's; before a reflex one
        // they stop where the next edge's rows begin (negative extension).
        return (!o.open[other_edge] && std::abs(phi) > 1e-9) ? d * std::tan(0.5 * phi) : 0.0;
      };
      const double t0 = -ext(k, (k + n - 1) % n), t1 = o.length(k) + ext((k + 1) % n, (k + 1) % n);
      const double len = t1 - t0;
      long m = long(std::floor(len / s + 1e-9)) + 1;
      const long tight = long(std::ceil(len / s - 1e-9)) + 1;
      if (tight > 1 && len / double(tight - 1) >= min_d - 1e-12) m = tight;
      const double step = m > 1 ? len / double(m - 1) : 0.0;
      const bool shifted = layer % 2 == 1 && m > 1;
      for (long q = 0; q < (shifted ? m - 1 : m); ++q) {
        const double along = t0 + (double(q) + (shifted ? 0.5 : 0.0)) * step;
        sites.push_back(A + along * t + d * nrm);
      }
    }
  std::vector<Vec3> out;
  PlaneBins taken(min_d);
  for (const Vec2& p : sites) {
    if (o.contains(p) || o.distance(p) < r - 1e-9 || taken.any_within(p, min_d - 1e-9)) continue;
    taken.add(p);
    out.emplace_back(p.x(), p.y(), 0.0);
  }
  return out;
}

}  // namespace

std::vector<Vec3> fill_outline(const ChannelParams& c, long count, double a, double min_gap, std::uint64_t seed) {
  const Outline o = make_outline(c);
  Vec2 lo = o.v[0], hi = o.v[0];
  for (const Vec2& p : o.v) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // Random sequential adsorption of discs jams at an areal fraction of 0.547 in the plane (Feder
  // 1980, J. Theor. Biol. 87, 237; 0.547069, Hinrichsen, Feder & Jossang 1986), less beside walls:
  // a request above it cannot be met, so it fails at once instead of after 1000 trials per particle.
  constexpr double kRsaJamming = 0.547;
  const double asked = double(count) * kPi * a * a / o.area;
  if (asked > kRsaJamming) {
    std::ostringstream e;
    e << "only about " << long(kRsaJamming * o.area / (kPi * a * a)) << " of " << count << " particles of radius " << a
      << " a fit at random in the outline's " << o.area << " a^2 of fluid (areal fraction " << asked
      << " asked; random placement jams at " << kRsaJamming << ")";
    throw std::invalid_argument(e.str());
  }
  RandomStream rs = RandomStream::for_purpose(seed, Purpose::placement, 2);
  std::vector<Vec3> out;
  PlaneBins taken(2.0 * a + min_gap);
  const long max_trials = 1000 * std::max<long>(count, 1);
  for (long trial = 0; long(out.size()) < count && trial < max_trials; ++trial) {
    const Vec2 p(lo.x() + (hi.x() - lo.x()) * rs.uniform(), lo.y() + (hi.y() - lo.y()) * rs.uniform());
    if (!o.contains(p) || o.distance(p) < a || o.distance(p, true) < a + c.gap || taken.any_within(p, 2.0 * a + min_gap))
      continue;
    taken.add(p);
    out.emplace_back(p.x(), p.y(), 0.0);
  }
  if (long(out.size()) < count) {
    std::ostringstream e;
    e << "only " << out.size() << " of " << count << " particles of radius " << a << " a fit at random in the outline's "
      << o.area << " a^2 of fluid (areal fraction " << double(count) * kPi * a * a / o.area << " asked)";
    throw std::invalid_argument(e.str());
  }
  return out;
}

double wall_thickness(const ChannelParams& c) {
  const double row = c.kind == ChannelParams::Kind::outline ? std::sqrt(3.0) / 2.0 : 1.0 / std::sqrt(2.0);
  return 2.0 * c.radius + double(c.layers - 1) * c.spacing() * row;
}

std::vector<Vec3> wall_particles(const ChannelParams& c, const Domain& d) {
  std::vector<Vec3> out;
  if (!c.any()) return out;
  if (c.kind == ChannelParams::Kind::outline) {
    if (d.periodic()) throw std::invalid_argument("an outline channel lies in an open domain (its monolayer is not periodic)");
    return outline_walls(c);
  }
  const bool per = d.periodic();
  const Vec3 ctr = channel_centre(d);
  const double s = c.spacing(), dn = s / std::sqrt(2.0), r = c.radius, T = wall_thickness(c);
  if (per) {
    // The box must hold the fluid and the walls across y (and z for a duct).
    // The box must hold the fluid and the walls across y (and z for a duct), the walls keeping
    // their gap to their periodic images (back to back across the box face).
    const double need_y = c.height + 2.0 * T + c.gap;
    if (need_y > d.box.y() + 1e-9) {
      std::ostringstream o;
      o << "the box edge Ly = " << d.box.y() << " a is smaller than the channel and its walls need (" << need_y
        << " a: height + 2 x wall thickness " << T << " a + gap)";
      throw std::invalid_argument(o.str());
    }
    if (c.kind == ChannelParams::Kind::duct && c.width + 2.0 * T + c.gap > d.box.z() + 1e-9) {
      std::ostringstream o;
      o << "the box edge Lz = " << d.box.z() << " a is smaller than the duct and its walls need ("
        << c.width + 2.0 * T + c.gap << " a: width + 2 x wall thickness " << T << " a + gap)";
      throw std::invalid_argument(o.str());
    }
  }
  // One wall: normal axis `nax` (1 = y, 2 = z), side +-1, boundary at ctr[nax] + side * half;
  // in-plane axes x and `tax`; along tax either the periodic edge or the extent `ext` about ctr.
  auto wall = [&](int nax, double side, double half, int tax, bool tax_periodic, double ext, bool stretch = false) {
    for (long k = 0; k < c.layers; ++k) {
      const double shift = (k % 2) ? 0.5 : 0.0;
      const double pos = ctr[nax] + side * (half + r + double(k) * dn);
      const std::vector<double> xs = line_sites(per, d.box.x(), c.length, ctr.x(), s, shift, "flow direction (x)");
      const std::vector<double> ts =
          line_sites(tax_periodic, d.box[tax], ext, ctr[tax], s, shift, tax == 2 ? "span (z)" : "span (y)", stretch, r);
      for (double x : xs)
        for (double t : ts) {
          Vec3 p;
          p.x() = x;
          p[nax] = pos;
          p[tax] = t;
          out.push_back(p);
        }
    }
  };
  switch (c.kind) {
    case ChannelParams::Kind::plane: wall(1, -1.0, 0.0, 2, per, c.depth); break;
    case ChannelParams::Kind::slit:
      wall(1, -1.0, 0.5 * c.height, 2, per, c.depth);
      wall(1, +1.0, 0.5 * c.height, 2, per, c.depth);
      break;
    case ChannelParams::Kind::duct: {
      // Walls normal to y reach across the width to the side walls' outer layer (their end sites sit
      // in the side walls' planes: the corners are closed); the side walls span the height between
      // them, their end sites `gap` from the corner sites.
      const double span_z = c.width + 2.0 * T - 2.0 * r;
      wall(1, -1.0, 0.5 * c.height, 2, false, span_z, true);
      wall(1, +1.0, 0.5 * c.height, 2, false, span_z, true);
      const double span_y = std::max(0.0, c.height - 2.0 * r - 2.0 * c.gap);
      wall(2, -1.0, 0.5 * c.width, 1, false, span_y, true);
      wall(2, +1.0, 0.5 * c.width, 1, false, span_y, true);
      break;
    }
    case ChannelParams::Kind::none:
    case ChannelParams::Kind::outline: break;
  }
  return out;
}

}  // namespace stokesian
