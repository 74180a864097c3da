#include "trees/placement.hpp"

#include "engine/core/random.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace stokesian {

namespace {

// RSA of the growth route runs at this volume fraction (fast: far below the RSA jamming limit).
constexpr double kRsaStartFraction = 0.25;
constexpr double kRsaFullSizeBudget = 0.05;
// Random placement is refused above this: the hard-sphere fluid ends near 0.55 and random close
// packing of equal spheres is ~0.64.
constexpr double kRandomMaxVolumeFraction = 0.6;
constexpr long kRsaAttemptsPerParticle = 2000000;
constexpr long kMaxGrowthSweeps = 10000;
constexpr long kStallWindow = 500;
// Growth pass: a particle's scale grows by at most growth_rate per sweep and by at most this
// fraction of the room its neighbours leave (larger fractions jam the fluid near phi ~ 0.5).
constexpr double growth_rate = 0.01;
constexpr double room_fraction = 0.02;

[[noreturn]] void fail(const std::string& msg) { throw std::invalid_argument(msg); }

// Radii, and which particles belong to the large species (bidisperse, bimodal).
std::vector<double> draw_radii(const PlacementParams& p, std::vector<char>& large) {
  RandomStream rs = RandomStream::for_purpose(p.seed, Purpose::placement, 0);
  const std::size_t n = std::size_t(p.count);
  std::vector<double> a(n, p.radius);
  large.assign(n, 0);
  if (p.sizes == PlacementParams::Sizes::bidisperse || p.sizes == PlacementParams::Sizes::bimodal) {
    // Exactly round(f N) large particles at random indices: the first of a random permutation
    // (Fisher–Yates with the counter-based stream).
    std::vector<std::size_t> perm(n);
    std::iota(perm.begin(), perm.end(), std::size_t(0));
    for (std::size_t i = n; i > 1; --i) std::swap(perm[i - 1], perm[std::size_t(rs.below(i))]);
    const std::size_t nlarge = std::size_t(std::lround(p.large_fraction * double(p.count)));
    for (std::size_t k = 0; k < nlarge; ++k) {
      a[perm[k]] = p.radius * p.radius_ratio;
      large[perm[k]] = 1;
    }
    // Bimodal: each species' radii lognormal about its median (drawn after the species, in index order).
    if (p.sizes == PlacementParams::Sizes::bimodal)
      for (auto& v : a) v *= std::exp(p.sigma * rs.normal());
  } else if (p.sizes == PlacementParams::Sizes::lognormal) {
    const double mu = std::log(p.radius);
    for (auto& v : a) v = std::exp(mu + p.sigma * rs.normal());
  }
  return a;
}

// The region particles are confined to: a periodic box [0, L), or an open sphere / cube centred at
// the origin with hard walls.
struct Region {
  bool periodic = false;
  bool sphere = false;
  ChannelParams channel;  // periodic boxes: the fluid region of these walls (kind none: the whole box)
  Vec3 box = Vec3::Zero();  // periodic box, or edge of the (bounding) cube
  double R = 0.0;           // sphere radius
  Vec3 lo() const { return periodic ? Vec3::Zero() : Vec3(-0.5 * box); }
  // Nearest-image separation x_i - x_j (rectangular box: componentwise nearest is nearest overall).
  Vec3 sep(const Vec3& xi, const Vec3& xj) const {
    Vec3 d = xi - xj;
    if (periodic)
      for (int c = 0; c < 3; ++c) d[c] -= box[c] * std::round(d[c] / box[c]);
    return d;
  }
  void wrap(Vec3& x) const {
    if (!periodic) return;
    for (int c = 0; c < 3; ++c) {
      x[c] -= box[c] * std::floor(x[c] / box[c]);
      if (x[c] >= box[c]) x[c] = 0.0;  // rounding of tiny negative values
    }
  }
  // Largest radius a sphere centred at x may have inside the walls (infinite for periodic boxes).
  double room(const Vec3& x) const {
    if (periodic) {
      if (!channel.any()) return 1e300;
      const Vec3 r = x - 0.5 * box;
      switch (channel.kind) {
        case ChannelParams::Kind::plane: return r.y();
        case ChannelParams::Kind::slit: return 0.5 * channel.height - std::abs(r.y());
        case ChannelParams::Kind::duct:
          return std::min(0.5 * channel.height - std::abs(r.y()), 0.5 * channel.width - std::abs(r.z()));
        default: return 1e300;
      }
    }
    if (sphere) return R - x.norm();
    return (0.5 * box - x.cwiseAbs()).minCoeff();
  }
};

// Uniform cell grid; particle j is registered in every cell touched by its bounding cube
// [x_j - r_j, x_j + r_j]. If two spheres (radii r_i + g and r_j) intersect, a point of the
// intersection lies in a cell both cubes touch, so visiting the cells of i's cube finds j.
class Grid {
 public:
  Grid(const Region& reg, double h_min, std::size_t n_particles) : reg_(reg) {
    // Cells of edge >= h_min, at most max(64, N) of them (fewer, fuller cells are faster than many
    // empty ones in dilute systems).
    const double cap = std::max(64.0, 1.0 * double(n_particles));
    double h = h_min;
    for (;;) {
      for (int c = 0; c < 3; ++c) n_[c] = std::max(1L, long(std::floor(reg.box[c] / h)));
      if (double(n_[0]) * double(n_[1]) * double(n_[2]) <= cap) break;
      h *= 1.1;
    }
    for (int c = 0; c < 3; ++c) hc_[c] = reg.box[c] / double(n_[c]);
    cells_.resize(std::size_t(n_[0] * n_[1] * n_[2]));
    boxes_.resize(n_particles);
  }

  void clear() {
    for (auto& c : cells_) c.clear();
  }
  // Linear index of the cell holding point x (for ordering particles in space).
  long cell_of(const Vec3& x) const {
    const Box b = range(x, 0.0);
    long k = 0;
    for (int c = 0; c < 3; ++c) k = k * n_[c] + ((b.lo[c] % n_[c]) + n_[c]) % n_[c];
    return k;
  }
  void insert(int i, const Vec3& x, double r) {
    Box& b = boxes_[std::size_t(i)];
    b = range(x, r);
    visit(b, [&](std::vector<int>& cell) { cell.push_back(i); });
  }
  // Re-registers i at x with radius r (nothing to do when its cells are unchanged).
  void move(int i, const Vec3& x, double r) {
    const Box b = range(x, r), &old = boxes_[std::size_t(i)];
    if (std::equal(b.lo, b.lo + 3, old.lo) && std::equal(b.hi, b.hi + 3, old.hi)) return;
    remove(i);
    insert(i, x, r);
  }
  void remove(int i) {
    visit(boxes_[std::size_t(i)], [&](std::vector<int>& cell) {
      auto it = std::find(cell.begin(), cell.end(), i);
      *it = cell.back();
      cell.pop_back();
    });
  }
  // f(j) for every j registered in a cell touched by [x - r, x + r] (a j may come more than once).
  template <class F>
  void candidates(const Vec3& x, double r, F&& f) const {
    const Box b = range(x, r);
    visit(b, [&](const std::vector<int>& cell) {
      for (int j : cell) f(j);
    });
  }

 private:
  struct Box {
    long lo[3], hi[3];
  };
  Box range(const Vec3& x, double r) const {
    Box b;
    const Vec3 o = reg_.lo();
    for (int c = 0; c < 3; ++c) {
      b.lo[c] = long(std::floor((x[c] - r - o[c]) / hc_[c]));
      b.hi[c] = long(std::floor((x[c] + r - o[c]) / hc_[c]));
      if (reg_.periodic) {
        if (b.hi[c] - b.lo[c] + 1 >= n_[c]) b.lo[c] = 0, b.hi[c] = n_[c] - 1;
      } else {
        b.lo[c] = std::clamp(b.lo[c], 0L, n_[c] - 1);
        b.hi[c] = std::clamp(b.hi[c], 0L, n_[c] - 1);
      }
    }
    return b;
  }
  // Calls f(cell) once for every cell of the box (indices wrapped in periodic boxes).
  template <class Self, class F>
  static void visit_cells(Self& self, const Box& b, F&& f) {
    long idx[3][64];
    long* ids[3];
    long cnt[3];
    std::vector<long> spill[3];
    for (int c = 0; c < 3; ++c) {
      cnt[c] = b.hi[c] - b.lo[c] + 1;
      ids[c] = cnt[c] <= 64 ? idx[c] : (spill[c].resize(std::size_t(cnt[c])), spill[c].data());
      for (long k = 0; k < cnt[c]; ++k) {
        long w = b.lo[c] + k;
        if (w < 0) w += self.n_[c] * ((-w + self.n_[c] - 1) / self.n_[c]);
        if (w >= self.n_[c]) w %= self.n_[c];
        ids[c][k] = w;
      }
    }
    for (long ix = 0; ix < cnt[0]; ++ix)
      for (long iy = 0; iy < cnt[1]; ++iy) {
        const long base = (ids[0][ix] * self.n_[1] + ids[1][iy]) * self.n_[2];
        for (long iz = 0; iz < cnt[2]; ++iz) f(self.cells_[std::size_t(base + ids[2][iz])]);
      }
  }
  template <class F>
  void visit(const Box& b, F&& f) const { visit_cells(*this, b, f); }
  template <class F>
  void visit(const Box& b, F&& f) { visit_cells(*this, b, f); }

  const Region& reg_;
  long n_[3] = {1, 1, 1};
  Vec3 hc_ = Vec3::Ones();
  std::vector<std::vector<int>> cells_;
  std::vector<Box> boxes_;
};

// The hard-sphere system: positions, target radii a_i, current scales s_i (radius r_i = s_i a_i).
struct HardSpheres {
  const Region& reg;
  double gap;
  std::vector<Vec3> x;
  std::vector<double> a, s;
  // Segregation: +1 confines the particle to the half z >= 0 of the region, -1 to z <= 0, 0 none.
  std::vector<signed char> side;
  Grid grid;

  HardSpheres(const Region& r, double g, const std::vector<double>& radii, double h)
      : reg(r), gap(g), x(radii.size(), Vec3::Zero()), a(radii), s(radii.size(), 1.0), side(radii.size(), 0),
        grid(r, h, radii.size()) {}

  double r(std::size_t i) const { return s[i] * a[i]; }
  // Largest radius particle i may have at y (walls, and its half of the region).
  double room(std::size_t i, const Vec3& y) const {
    const double w = reg.room(y);
    return side[i] == 0 ? w : std::min(w, double(side[i]) * y.z());
  }
  // Would particle `who` of radius ri at y overlap a wall or another registered particle (except i;
  // i = -1 while `who` is not registered yet)?
  bool blocked(long i, std::size_t who, const Vec3& y, double ri) const {
    if (room(who, y) < ri) return true;
    bool hit = false;
    grid.candidates(y, ri + gap, [&](int j) {
      if (hit || j == i) return;
      const double c = ri + r(std::size_t(j)) + gap;
      if (reg.sep(y, x[std::size_t(j)]).squaredNorm() < c * c) hit = true;
    });
    return hit;
  }
  // Uniform random point of the region where particle `who` of radius ri fits the walls.
  Vec3 trial_point(RandomStream& rs, std::size_t who, double ri) const {
    for (;;) {
      Vec3 y;
      for (int c = 0; c < 3; ++c) y[c] = reg.lo()[c] + reg.box[c] * rs.uniform();
      if (room(who, y) >= ri) return y;
    }
  }
};

void check_fits(const Region& reg, const std::vector<double>& a, double gap) {
  const double amax = *std::max_element(a.begin(), a.end());
  if (reg.periodic && reg.channel.any() && amax > reg.room(0.5 * reg.box)) {
    std::ostringstream o;
    o << "the largest particle (radius " << amax << " a) does not fit in the channel (half-gap "
      << reg.room(0.5 * reg.box) << " a)";
    fail(o.str());
  }
  if (reg.periodic) {
    if (2.0 * amax + gap >= reg.box.minCoeff()) {
      std::ostringstream o;
      o << "the largest particle (radius " << amax << " a) with min_gap " << gap
        << " a does not fit in the periodic box (smallest edge " << reg.box.minCoeff() << " a)";
      fail(o.str());
    }
  } else if (amax > (reg.sphere ? reg.R : 0.5 * reg.box.minCoeff())) {
    std::ostringstream o;
    o << "the largest particle (radius " << amax << " a) does not fit in the region (volume fraction too high "
      << "for so few particles)";
    fail(o.str());
  }
}

// Random sequential addition with radii s0 * a_i, largest first.
void rsa(HardSpheres& hs, double s0, std::uint64_t seed, double phi_target) {
  const std::size_t n = hs.a.size();
  double volume_sum_a3 = 0.0;
  for (double a : hs.a) volume_sum_a3 += a * a * a;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return hs.a[i] > hs.a[j]; });
  RandomStream rs = RandomStream::for_purpose(seed, Purpose::placement, 1);
  // The largest particles start at full size while the RSA volume fraction stays below
  // kRsaStartFraction + kRsaFullSizeBudget (large particles are the slowest to grow).
  std::fill(hs.s.begin(), hs.s.end(), s0);
  double extra = 0.0;
  for (std::size_t k = 0; k < n && s0 < 1.0; ++k) {
    const std::size_t i = order[k];
    extra += phi_target * (1.0 - s0 * s0 * s0) * std::pow(hs.a[i], 3) / volume_sum_a3;
    if (extra > kRsaFullSizeBudget) break;
    hs.s[i] = 1.0;
  }
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = order[k];
    const double ri = hs.r(i);
    long attempt = 0;
    Vec3 y;
    do {
      if (++attempt > kRsaAttemptsPerParticle) {
        std::ostringstream o;
        o << "random sequential addition found no room for particle " << k + 1 << " of " << n << " after "
          << kRsaAttemptsPerParticle << " attempts (volume fraction " << phi_target
          << "); use equilibration_sweeps > 0 or a lower volume fraction";
        fail(o.str());
      }
      y = hs.trial_point(rs, i, ri);
    } while (hs.blocked(-1, i, y, ri));
    hs.x[i] = y;
    hs.grid.insert(int(i), y, ri);
  }
}

// One Metropolis sweep: a trial move of every particle in turn (sequential updating keeps the
// hard-sphere distribution stationary), displacement uniform in [-delta, delta]^3; returns the
// number accepted.
long mc_sweep(HardSpheres& hs, RandomStream& rs, double delta) {
  const std::size_t n = hs.a.size();
  long accepted = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 y = hs.x[i];
    for (int c = 0; c < 3; ++c) y[c] += delta * (2.0 * rs.uniform() - 1.0);
    hs.reg.wrap(y);
    const double ri = hs.r(i);
    if (hs.blocked(long(i), i, y, ri)) continue;
    hs.x[i] = y;
    hs.grid.move(int(i), y, ri);
    ++accepted;
  }
  return accepted;
}

// Each particle grows its scale towards 1: to 1 if its walls and neighbours leave room, else by half
// of the room left. Returns the number of particles still below their target size.
long grow(HardSpheres& hs, double rate, double room_fraction, double a_median) {
  long below = 0;
  for (std::size_t i = 0; i < hs.a.size(); ++i) {
    if (hs.s[i] >= 1.0) continue;
    double smax = hs.room(i, hs.x[i]) / hs.a[i];
    hs.grid.candidates(hs.x[i], hs.a[i] + hs.gap, [&](int j) {
      if (std::size_t(j) == i) return;
      const double d = hs.reg.sep(hs.x[i], hs.x[std::size_t(j)]).norm();
      smax = std::min(smax, (d - hs.r(std::size_t(j)) - hs.gap) / hs.a[i]);
    });
    // Large particles take a larger share of their room (their relative growth is slower).
    const double share = std::min(5.0 * room_fraction, room_fraction * std::max(1.0, hs.a[i] / a_median));
    const double s_new = std::min({1.0, hs.s[i] + rate, hs.s[i] + share * (smax - hs.s[i])});
    if (s_new > hs.s[i]) {
      hs.s[i] = s_new;
      hs.grid.move(int(i), hs.x[i], hs.r(i));
    }
    if (hs.s[i] < 1.0) ++below;
  }
  return below;
}

// Relabels the particles in the order of their cells (memory locality of the sweeps); returns the
// permutation: new label k is old label perm[k].
std::vector<std::size_t> sort_in_space(HardSpheres& hs) {
  const std::size_t n = hs.a.size();
  std::vector<long> key(n);
  for (std::size_t i = 0; i < n; ++i) key[i] = hs.grid.cell_of(hs.x[i]);
  std::vector<std::size_t> perm(n);
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::stable_sort(perm.begin(), perm.end(), [&](std::size_t i, std::size_t j) { return key[i] < key[j]; });
  std::vector<Vec3> x(n);
  std::vector<double> a(n), s(n);
  std::vector<signed char> side(n);
  for (std::size_t k = 0; k < n; ++k)
    x[k] = hs.x[perm[k]], a[k] = hs.a[perm[k]], s[k] = hs.s[perm[k]], side[k] = hs.side[perm[k]];
  hs.x = x, hs.a = a, hs.s = s, hs.side = side;
  hs.grid.clear();
  for (std::size_t k = 0; k < n; ++k) hs.grid.insert(int(k), hs.x[k], hs.r(k));
  return perm;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

double fluid_volume(const ChannelParams& c, const Vec3& box) {
  switch (c.kind) {
    case ChannelParams::Kind::slit: return box.x() * c.height * box.z();
    case ChannelParams::Kind::duct: return box.x() * c.height * c.width;
    default: return box.prod();
  }
}

Placement place_particles(const PlacementParams& p, const Vec3& box_in) {
  if (p.channel.any() && !(box_in.minCoeff() > 0)) fail("particles are placed in a channel only in a periodic box");
  if (p.channel.any() && p.pattern == PlacementParams::Pattern::lattice)
    fail("generate = \"lattice\" fills the whole box; in a channel use generate = \"random\"");
  if (p.channel.kind == ChannelParams::Kind::plane) fail("particles are placed in a slit or duct, not beside a plane wall");
  if (p.count < 1) fail("count must be >= 1");
  if (p.segregation != PlacementParams::Segregation::none && p.pattern == PlacementParams::Pattern::lattice)
    fail("segregation needs generate = \"random\"");
  if (!(p.radius > 0)) fail("radius must be > 0");
  if (!(p.min_gap >= 0)) fail("min_gap must be >= 0");
  if (p.equilibration_sweeps < 0) fail("equilibration_sweeps must be >= 0");
  Placement out;
  std::vector<char> large;
  out.radius = draw_radii(p, large);
  const std::size_t n = out.radius.size();
  double vol = 0;
  for (double a : out.radius) vol += 4.0 / 3.0 * kPi * a * a * a;

  Region reg;
  reg.periodic = box_in.minCoeff() > 0;
  double phi = p.volume_fraction;
  if (reg.periodic) {
    reg.box = box_in;
    reg.channel = p.channel;
    phi = vol / fluid_volume(p.channel, box_in);
  } else {
    if (!(phi > 0 && phi < 1)) fail("volume fraction must be in (0, 1)");
    const double V = vol / phi;
    reg.sphere = p.region == PlacementParams::Region::sphere;
    if (reg.sphere) {
      reg.R = std::cbrt(3.0 * V / (4.0 * kPi));
      reg.box = Vec3::Constant(2.0 * reg.R);
      out.sphere_radius = reg.R;
    } else {
      reg.box = Vec3::Constant(std::cbrt(V));
    }
  }
  out.box = reg.box;
  check_fits(reg, out.radius, p.min_gap);
  const double a_median = median(out.radius);
  const double h = 2.0 * a_median + p.min_gap;

  if (p.pattern == PlacementParams::Pattern::lattice) {
    const double spacing = reg.periodic ? 0.0 : std::cbrt(vol / phi / double(n));
    std::vector<Vec3> sites;
    if (reg.periodic) {
      const long side = std::lround(std::ceil(std::cbrt(double(n)) - 1e-9));
      const Vec3 hl = reg.box / double(side);
      for (long k = 0; k < long(n); ++k) {
        const long ix = k % side, iy = (k / side) % side, iz = k / (side * side);
        sites.emplace_back((ix + 0.5) * hl.x(), (iy + 0.5) * hl.y(), (iz + 0.5) * hl.z());
      }
    } else if (!reg.sphere) {
      const long side = std::lround(std::ceil(std::cbrt(double(n)) - 1e-9));
      const Vec3 hl = reg.box / double(side);
      for (long k = 0; k < long(n); ++k) {
        const long ix = k % side, iy = (k / side) % side, iz = k / (side * side);
        sites.push_back(reg.lo() + Vec3((ix + 0.5) * hl.x(), (iy + 0.5) * hl.y(), (iz + 0.5) * hl.z()));
      }
    } else {
      // The n sites of the lattice spacing * Z^3 nearest the centre (ties by lattice order).
      const long m = long(std::ceil(std::cbrt(double(n) * 6.0 / kPi) / 2.0)) + 2;
      for (long ix = -m; ix <= m; ++ix)
        for (long iy = -m; iy <= m; ++iy)
          for (long iz = -m; iz <= m; ++iz) sites.emplace_back(double(ix), double(iy), double(iz));
      std::stable_sort(sites.begin(), sites.end(),
                       [](const Vec3& u, const Vec3& v) { return u.squaredNorm() < v.squaredNorm(); });
      sites.resize(n);
      for (auto& y : sites) y *= spacing;
    }
    // Lattice clusters in an open domain are not confined by walls; only the pairs are checked.
    Grid lattice_grid(reg, h, n);
    for (std::size_t i = 0; i < n; ++i) {
      const double ai = out.radius[i];
      bool hit = false;
      lattice_grid.candidates(sites[i], ai + p.min_gap, [&](int j) {
        const double c = ai + out.radius[std::size_t(j)] + p.min_gap;
        if (reg.sep(sites[i], sites[std::size_t(j)]).squaredNorm() < c * c) hit = true;
      });
      if (hit) {
        std::ostringstream o;
        o << "lattice spacing " << (reg.periodic ? (reg.box / std::ceil(std::cbrt(double(n)) - 1e-9)).minCoeff() : spacing)
          << " a is too small for particle " << i << " of radius " << ai << " a (with min_gap " << p.min_gap << " a)";
        fail(o.str());
      }
      lattice_grid.insert(int(i), sites[i], ai);
    }
    out.position = sites;
    return out;
  }

  if (phi > kRandomMaxVolumeFraction * (1 + 1e-9)) {
    std::ostringstream o;
    o << "random placement supports volume fractions up to " << kRandomMaxVolumeFraction << " (requested " << phi
      << "; the hard-sphere fluid ends near 0.55, random close packing is ~0.64); use generate = \"lattice\"";
    fail(o.str());
  }
  HardSpheres hs(reg, p.min_gap, out.radius, h);
  if (p.segregation != PlacementParams::Segregation::none) {
    if (reg.periodic || !reg.sphere) fail("segregation needs the open sphere region (region = \"sphere\")");
    if (p.sizes != PlacementParams::Sizes::bidisperse && p.sizes != PlacementParams::Sizes::bimodal)
      fail("segregation needs two species (size_distribution = \"bidisperse\" or \"bimodal\")");
    const signed char up = p.segregation == PlacementParams::Segregation::large_up ? 1 : -1;
    for (std::size_t i = 0; i < n; ++i) hs.side[i] = large[i] ? up : static_cast<signed char>(-up);
  }
  if (p.equilibration_sweeps == 0) {
    if (phi > kRsaMaxVolumeFraction * (1 + 1e-9)) {
      std::ostringstream o;
      o << "plain random sequential addition (equilibration_sweeps = 0) is limited to volume fraction "
        << kRsaMaxVolumeFraction << " (requested " << phi
        << "; it jams near 0.38); give equilibration_sweeps > 0 for an equilibrated hard-sphere fluid";
      fail(o.str());
    }
    rsa(hs, 1.0, p.seed, phi);
    out.position = hs.x;
    return out;
  }

  // RSA at reduced size, then Monte Carlo with growth, then Monte Carlo at the target size.
  const double s0 = std::min(1.0, std::cbrt(kRsaStartFraction / phi));
  rsa(hs, s0, p.seed, phi);
  const std::vector<std::size_t> perm = sort_in_space(hs);
  double delta = 0.2 * a_median;
  const double delta_max = 0.5 * h;
  std::uint64_t sweep = 0;
  auto run_sweep = [&](bool adapt) {
    RandomStream rs = RandomStream::for_purpose(p.seed, Purpose::equilibration, sweep++);
    const double acc = double(mc_sweep(hs, rs, delta)) / double(n);
    // Step adapted towards acceptance ~0.4 (only during growth and the first half of equilibration).
    if (adapt) delta = std::min(delta_max, delta * (acc > 0.4 ? 1.1 : 0.9));
  };
  auto reached = [&] {
    double v = 0;
    for (std::size_t i = 0; i < n; ++i) v += 4.0 / 3.0 * kPi * std::pow(hs.r(i), 3);
    return v / (reg.periodic ? fluid_volume(reg.channel, reg.box) : vol / phi);
  };
  long below = grow(hs, growth_rate, room_fraction, a_median);
  double last = reached();
  for (long g = 1; below > 0; ++g) {
    run_sweep(true);
    below = grow(hs, growth_rate, room_fraction, a_median);
    // Stalled: less than 1% of the remaining deficit gained in the last kStallWindow sweeps.
    if (below > 0 && (g % kStallWindow == 0 || g == kMaxGrowthSweeps)) {
      const double now = reached();
      if (phi - now > 0.99 * (phi - last) || g == kMaxGrowthSweeps) {
        std::ostringstream o;
        o << "random placement: compression to volume fraction " << phi << " reached only " << now << " after " << g
          << " Monte Carlo sweeps (" << below << " particles below full size; the hard-sphere fluid ends near "
          << "0.55, less in small open regions, whose walls pack less densely); lower volume_fraction or min_gap";
        fail(o.str());
      }
      last = now;
    }
  }
  out.growth_sweeps = long(sweep);
  for (long k = 0; k < p.equilibration_sweeps; ++k) run_sweep(k < p.equilibration_sweeps / 2);
  out.position.resize(n);
  for (std::size_t k = 0; k < n; ++k) out.position[perm[k]] = hs.x[k];
  return out;
}

}  // namespace stokesian
