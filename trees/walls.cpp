#include "trees/walls.hpp"

#include "engine/core/channel.hpp"

#include <cmath>
#include <sstream>
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

}  // namespace

double wall_thickness(const ChannelParams& c) {
  return 2.0 * c.radius + double(c.layers - 1) * c.spacing() / std::sqrt(2.0);
}

std::vector<Vec3> wall_particles(const ChannelParams& c, const Domain& d) {
  std::vector<Vec3> out;
  if (!c.any()) return out;
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
    case ChannelParams::Kind::none: break;
  }
  return out;
}

}  // namespace stokesian
