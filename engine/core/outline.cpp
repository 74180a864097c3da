#include "engine/core/outline.hpp"

#include <Eigen/SparseLU>
#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace stokesian {

namespace {

// Fluid nodes closer than kSnap h to an oblique wall are set to the wall's psi (header).
constexpr double kSnap = 0.25;

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Sutherland-Hodgman: the part of polygon `in` where n . p >= c (n any vector).
std::vector<Vec2> clip_half_plane(const std::vector<Vec2>& in, const Vec2& n, double c) {
  std::vector<Vec2> out;
  for (std::size_t k = 0; k < in.size(); ++k) {
    const Vec2 P = in[k], Q = in[(k + 1) % in.size()];
    const double fp = n.dot(P) - c, fq = n.dot(Q) - c;
    if (fp >= 0) out.push_back(P);
    if ((fp >= 0) != (fq >= 0)) out.push_back(P + fp / (fp - fq) * (Q - P));
  }
  return out;
}

double polygon_area(const std::vector<Vec2>& p) {
  double A2 = 0;
  for (std::size_t k = 0; k < p.size(); ++k) A2 += cross2(p[k], p[(k + 1) % p.size()]);
  return 0.5 * std::abs(A2);
}

double segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - a - t * d).norm();
}

// Proper intersection of segments ab and cd (shared end points excluded).
bool segments_cross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double d1 = cross2(b - a, c - a), d2 = cross2(b - a, d - a);
  const double d3 = cross2(d - c, a - c), d4 = cross2(d - c, b - c);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

}  // namespace

Vec2 Outline::outward_normal(std::size_t k) const {
  const Vec2 t = (b(k) - a(k)).normalized();
  // Counter-clockwise: the fluid lies to the left of each edge, so outward is to the right.
  return orientation * Vec2(t.y(), -t.x());
}

bool Outline::contains(const Vec2& p) const {
  if (distance(p) < 1e-12 * (1.0 + p.norm())) return false;
  bool in = false;
  for (std::size_t k = 0; k < v.size(); ++k) {
    const Vec2 A = a(k), B = b(k);
    if ((A.y() > p.y()) != (B.y() > p.y())) {
      const double x = A.x() + (p.y() - A.y()) * (B.x() - A.x()) / (B.y() - A.y());
      if (p.x() < x) in = !in;
    }
  }
  return in;
}

double Outline::distance(const Vec2& p, bool walls_only) const {
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < v.size(); ++k)
    if (!walls_only || !open[k]) d = std::min(d, segment_distance(p, a(k), b(k)));
  return d;
}

std::size_t Outline::nearest_wall(const Vec2& p) const {
  std::size_t best = 0;
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < v.size(); ++k)
    if (!open[k]) {
      const double e = segment_distance(p, a(k), b(k));
      if (e < d) {
        d = e;
        best = k;
      }
    }
  return best;
}

double Outline::area_between(double x0, double x1) const {
  return polygon_area(clip_half_plane(clip_half_plane(v, Vec2(1, 0), x0), Vec2(-1, 0), -x1));
}

Outline make_outline(const ChannelParams& c) {
  Outline o;
  for (const auto& p : c.outline) o.v.emplace_back(p[0], p[1]);
  const std::size_t n = o.v.size();
  if (n < 3) throw std::invalid_argument("an outline needs at least 3 vertices (got " + std::to_string(n) + ")");
  for (std::size_t k = 0; k < n; ++k)
    if (o.length(k) <= 1e-9) {
      std::ostringstream s;
      s << "outline edge " << k << " (vertices " << k << " and " << (k + 1) % n << ") has zero length";
      throw std::invalid_argument(s.str());
    }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      if (segments_cross(o.a(i), o.b(i), o.a(j), o.b(j))) {
        std::ostringstream s;
        s << "outline edges " << i << " and " << j << " cross (the outline must be a simple polygon)";
        throw std::invalid_argument(s.str());
      }
  double A2 = 0;
  for (std::size_t k = 0; k < n; ++k) A2 += cross2(o.a(k), o.b(k));
  o.area = 0.5 * std::abs(A2);
  o.orientation = A2 > 0 ? 1.0 : -1.0;
  o.open.assign(n, 0);
  for (long e : c.openings) {
    if (e < 0 || std::size_t(e) >= n) {
      std::ostringstream s;
      s << "opening " << e << " is not an edge of the outline (edges 0 to " << n - 1 << ")";
      throw std::invalid_argument(s.str());
    }
    if (o.open[std::size_t(e)]) throw std::invalid_argument("opening " + std::to_string(e) + " is listed twice");
    o.open[std::size_t(e)] = 1;
  }
  o.inlet = c.inlet;
  if (o.inlet < 0 || std::size_t(o.inlet) >= n || !o.open[std::size_t(o.inlet)]) {
    std::ostringstream s;
    s << "the inlet (edge " << c.inlet << ") must be one of the openings";
    throw std::invalid_argument(s.str());
  }
  return o;
}

long OutlineBranches::of_point(const Vec2& p, bool on_wall) const {
  const double e = on_wall ? eps : 0.0;
  for (std::size_t b = 0; b < branch.size(); ++b) {
    const OutlineBranch& B = branch[b];
    if (!B.holds(p, e)) continue;
    for (double at : B.at) {
      // The path p + t d, t between 0 and T, to the opening's line; does it enter a strip S_c that
      // does not hold p? s_c(p + t d) = s_c(p) + t s_c(d) (s_c linear).
      const double T = at - B.direction.dot(p);
      const double t0 = std::min(0.0, T), t1 = std::max(0.0, T);
      bool blocked = false;
      for (std::size_t c = 0; c < branch.size() && !blocked; ++c) {
        const OutlineBranch& C = branch[c];
        if (c == b || C.holds(p, e)) continue;
        const double g0 = C.across(p), g1 = C.across(B.direction);
        if (std::abs(g1) < 1e-12) continue;  // parallel to the strip: never enters it
        double ta = (C.lo - g0) / g1, tb = (C.hi - g0) / g1;
        if (ta > tb) std::swap(ta, tb);
        blocked = std::min(tb, t1) - std::max(ta, t0) > eps;
      }
      if (!blocked) return long(b);
    }
  }
  return -1;
}

long OutlineBranches::of_wall_particle(const Outline& o, const Vec2& p, std::size_t k) const {
  const Vec2 A = o.a(k), D = o.b(k) - A;
  const double t = std::clamp((p - A).dot(D) / D.squaredNorm(), 0.0, 1.0);
  return of_point(A + t * D, true);
}

OutlineBranches outline_branches(const Outline& o) {
  OutlineBranches r;
  const std::size_t n = o.edges();
  Vec2 lo = o.v[0], hi = o.v[0];
  for (const Vec2& p : o.v) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  r.eps = 1e-9 * (1.0 + std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()));
  // The inlet first, then the outlets in edge order.
  std::vector<std::size_t> order{std::size_t(o.inlet)};
  for (std::size_t k = 0; k < n; ++k)
    if (o.open[k] && long(k) != o.inlet) order.push_back(k);
  double narrowest = std::numeric_limits<double>::infinity();
  for (std::size_t k : order) {
    narrowest = std::min(narrowest, o.length(k));
    OutlineBranch ob;
    ob.direction = long(k) == o.inlet ? Vec2(-o.outward_normal(k)) : o.outward_normal(k);
    const double s0 = ob.across(o.a(k)), s1 = ob.across(o.b(k));
    ob.lo = std::min(s0, s1);
    ob.hi = std::max(s0, s1);
    const double at = ob.direction.dot(0.5 * (o.a(k) + o.b(k)));
    bool merged = false;
    for (OutlineBranch& b : r.branch)
      if (b.direction.dot(ob.direction) > 1.0 - 1e-9 && ob.lo <= b.hi + r.eps && ob.hi >= b.lo - r.eps) {
        b.lo = std::min(b.lo, ob.lo);
        b.hi = std::max(b.hi, ob.hi);
        b.openings.push_back(k);
        b.at.push_back(at);
        merged = true;
        break;
      }
    if (merged) continue;
    ob.width = o.length(k);
    ob.openings.push_back(k);
    ob.at.push_back(at);
    r.branch.push_back(ob);
  }
  // Areas by cell-centre sampling (header).
  const double h = std::max(narrowest / 200.0, std::sqrt((hi.x() - lo.x()) * (hi.y() - lo.y()) / 4e6));
  const long nx = long(std::ceil((hi.x() - lo.x()) / h)), ny = long(std::ceil((hi.y() - lo.y()) / h));
  std::vector<double> area(r.branch.size(), 0.0);
  for (long j = 0; j < ny; ++j)
    for (long i = 0; i < nx; ++i) {
      const Vec2 p = lo + h * Vec2(double(i) + 0.5, double(j) + 0.5);
      if (!o.contains(p)) continue;
      if (const long b = r.of_point(p); b >= 0) area[std::size_t(b)] += h * h;
    }
  for (std::size_t b = 0; b < r.branch.size(); ++b) r.branch[b].area = area[b];
  return r;
}

namespace {

// Greatest common divisor of non-negative lengths, to a relative tolerance.
double real_gcd(double a, double b, double tol) {
  if (a < b) std::swap(a, b);
  while (b > tol) {
    const double r = std::fmod(a, b);
    a = b;
    b = (r > b - tol) ? 0.0 : r;
  }
  return a;
}

}  // namespace

double outline_grid_spacing(const Outline& o, double h) {
  const Vec2 lo = o.v[0];
  Vec2 mn = lo;
  for (const Vec2& p : o.v) mn = mn.cwiseMin(p);
  for (std::size_t k = 0; k < o.edges(); ++k) {
    const Vec2 d = o.b(k) - o.a(k);
    if (o.open[k] && std::abs(d.x()) > 1e-9 && std::abs(d.y()) > 1e-9) {
      std::ostringstream s;
      s << "the flow through an outline takes openings parallel to x or y (walls may be oblique); opening " << k
        << " from (" << o.a(k).transpose() << ") to (" << o.b(k).transpose() << ") is oblique";
      throw std::invalid_argument(s.str());
    }
  }
  if (h > 0) {
    for (std::size_t k = 0; k < o.edges(); ++k)
      for (int ax = 0; ax < 2; ++ax) {
        const double t = (o.v[k][ax] - mn[ax]) / h;
        if (std::abs(t - std::round(t)) > 1e-6) {
          std::ostringstream s;
          s << "vertex " << k << " (" << o.v[k].transpose() << ") is not on the grid of spacing " << h
            << " a (every vertex coordinate minus the smallest must be a multiple of grid_spacing)";
          throw std::invalid_argument(s.str());
        }
      }
    return h;
  }
  double g = 0;
  for (const Vec2& p : o.v)
    for (int ax = 0; ax < 2; ++ax) {
      const double d = p[ax] - mn[ax];
      if (d > 1e-9) g = g == 0 ? d : real_gcd(g, d, 1e-7 * d);
    }
  const double target = o.length(std::size_t(o.inlet)) / 40.0;
  const double k = std::max(1.0, std::ceil(g / target - 1e-9));
  return g / k;
}

OutlineFlow solve_outline_flow(const Outline& o, double mean_velocity, double h_req) {
  OutlineFlow out;
  const double h = outline_grid_spacing(o, h_req);
  out.h = h;
  Vec2 mn = o.v[0], mx = o.v[0];
  for (const Vec2& p : o.v) {
    mn = mn.cwiseMin(p);
    mx = mx.cwiseMax(p);
  }
  const long nx = long(std::lround((mx.x() - mn.x()) / h)) + 1, ny = long(std::lround((mx.y() - mn.y()) / h)) + 1;
  if (double(nx) * double(ny) > 2e7) {
    std::ostringstream s;
    s << "the flow grid would have " << nx << " x " << ny << " nodes (at most 2e7); give a larger grid_spacing";
    throw std::invalid_argument(s.str());
  }
  auto pos = [&](long i, long j) { return Vec2(mn.x() + double(i) * h, mn.y() + double(j) * h); };
  auto id = [&](long i, long j) { return std::size_t(j * nx + i); };
  const std::size_t N = std::size_t(nx * ny);

  // Oblique wall edges, and for each wall edge a grid node on it (its first vertex) whose psi is the
  // wall's constant.
  std::vector<char> oblique(o.edges(), 0);
  std::vector<std::size_t> wall_node(o.edges(), N);
  for (std::size_t k = 0; k < o.edges(); ++k) {
    const Vec2 d = o.b(k) - o.a(k);
    oblique[k] = std::abs(d.x()) > 1e-9 * h && std::abs(d.y()) > 1e-9 * h;
    wall_node[k] = id(std::lround((o.a(k).x() - mn.x()) / h), std::lround((o.a(k).y() - mn.y()) / h));
  }
  // Node roles: 0 outside, 1 fluid, 2 boundary (on an edge, or snapped to an oblique wall; `edge`
  // names one).
  std::vector<signed char> role(N, 0);
  std::vector<int> edge(N, -1);
  for (long j = 0; j < ny; ++j)
    for (long i = 0; i < nx; ++i) {
      const Vec2 p = pos(i, j);
      for (std::size_t k = 0; k < o.edges(); ++k)
        if (segment_distance(p, o.a(k), o.b(k)) < 1e-7 * h) {
          // A vertex belongs to both its edges; prefer a wall (psi constant there either way).
          if (edge[id(i, j)] < 0 || !o.open[k]) edge[id(i, j)] = int(k);
          role[id(i, j)] = 2;
        }
      if (role[id(i, j)] == 0 && o.contains(p)) {
        role[id(i, j)] = 1;
        // A fluid node closer than kSnap h to an oblique wall takes the wall's value (header).
        for (std::size_t k = 0; k < o.edges(); ++k)
          if (oblique[k] && segment_distance(p, o.a(k), o.b(k)) < kSnap * h) {
            role[id(i, j)] = 2;
            edge[id(i, j)] = int(k);
            break;
          }
      }
    }
  std::vector<long> unknown(N, -1);
  long nu = 0;
  for (std::size_t k = 0; k < N; ++k)
    if (role[k] == 1) unknown[k] = nu++;
  out.fluid_nodes = std::size_t(nu);
  if (nu == 0) throw std::invalid_argument("the outline holds no grid node inside it; give a smaller grid_spacing");

  // Stream function on the boundary for edge fluxes q (outward, per unit depth).
  auto boundary_psi = [&](const std::vector<double>& q) {
    std::vector<double> pv(o.edges() + 1, 0.0);
    for (std::size_t k = 0; k < o.edges(); ++k) pv[k + 1] = pv[k] + (o.open[k] ? o.orientation * q[k] : 0.0);
    std::vector<double> psi(N, 0.0);
    for (std::size_t n = 0; n < N; ++n)
      if (role[n] == 2) {
        const std::size_t k = std::size_t(edge[n]);
        double val = pv[k];
        if (o.open[k]) {
          const Vec2 p = pos(long(n % std::size_t(nx)), long(n / std::size_t(nx)));
          const double s = std::clamp((p - o.a(k)).norm() / o.length(k), 0.0, 1.0);
          val += o.orientation * q[k] * (3 * s * s - 2 * s * s * s);
        }
        psi[n] = val;
      }
    return psi;
  };

  // Matrix of the 13-point stencil with ghost closures; rhs from known boundary values.
  struct Tap {
    int di, dj;
    double c;
  };
  const Tap taps[] = {{0, 0, 20},  {1, 0, -8}, {-1, 0, -8}, {0, 1, -8}, {0, -1, -8}, {1, 1, 2},  {1, -1, 2},
                      {-1, 1, 2},  {-1, -1, 2}, {2, 0, 1},   {-2, 0, 1}, {0, 2, 1},   {0, -2, 1}};
  auto role_at = [&](long i, long j) -> int { return (i < 0 || j < 0 || i >= nx || j >= ny) ? 0 : role[id(i, j)]; };
  std::vector<Eigen::Triplet<double>> trip;
  // Per row, the known-value contributions: rhs_row = sum w * psi_known[node].
  std::vector<std::vector<std::pair<std::size_t, double>>> known(static_cast<std::size_t>(nu));
  auto narrow = [&](long i, long j) {
    std::ostringstream s;
    s << "the outline is narrower than three grid spacings near (" << pos(i, j).transpose() << "); give a smaller grid_spacing";
    return std::invalid_argument(s.str());
  };
  // The ghost value at node (i + di, j + dj), outside the fluid, seen from fluid node (i, j): the
  // cubic along the ray with psi = psi_b and zero slope where the ray leaves the fluid (distance d
  // in steps of the ray, d in (0, m], m = max(|di|, |dj|)) through the two nodes behind that point
  // (header); as weights on grid nodes, the boundary value by a node holding it.
  struct Weight {
    std::size_t node = 0;
    double w = 0;
  };
  struct Ghost {
    std::array<Weight, 3> weight;
    int count = 0;
    const Weight* begin() const { return weight.data(); }
    const Weight* end() const { return weight.data() + count; }
  };
  auto ghost = [&](long i, long j, int di, int dj) {
    const int m = std::max(std::abs(di), std::abs(dj));
    const Vec2 P = pos(i, j), T = pos(i + di, j + dj);
    double d = std::numeric_limits<double>::infinity();
    std::size_t crossed = o.edges();
    for (std::size_t k = 0; k < o.edges(); ++k) {
      // P + t (T - P) on edge k, t in [0, 1].
      const Vec2 r = T - P, sdir = o.b(k) - o.a(k);
      const double den = cross2(r, sdir);
      if (std::abs(den) < 1e-14 * r.norm() * sdir.norm()) continue;
      const double t = cross2(o.a(k) - P, sdir) / den, u = cross2(o.a(k) - P, r) / den;
      if (t < -1e-12 || t > 1 + 1e-12 || u < -1e-9 || u > 1 + 1e-9) continue;
      if (t * m < d) {
        d = t * m;
        crossed = k;
      }
    }
    if (crossed == o.edges()) throw narrow(i, j);
    std::size_t boundary = N;
    const long dr = std::lround(d);
    if (std::abs(d - double(dr)) < 1e-9 && dr >= 1 && role_at(i + dr * di / m, j + dr * dj / m) == 2)
      boundary = id(i + dr * di / m, j + dr * dj / m);  // the ray leaves through a boundary node
    else if (!o.open[crossed]) boundary = wall_node[crossed];
    else throw narrow(i, j);  // an opening between grid nodes (openings run along grid lines)
    long s1 = long(std::ceil(d - 1e-9)) - 1;
    if (d - double(s1) < kSnap) --s1;
    const long s2 = s1 - 1;
    auto node_at = [&](long s) { return std::pair<long, long>{i + s * di / m, j + s * dj / m}; };
    const auto [i1, j1] = node_at(s1);
    const auto [i2, j2] = node_at(s2);
    if (role_at(i1, j1) == 0) throw narrow(i, j);
    const double x1 = double(s1) - d, xg = double(m) - d;
    Ghost g;
    if (role_at(i2, j2) == 0) {
      // No second node behind (an acute corner): the quadratic with zero slope at the wall.
      const double c1 = (xg * xg) / (x1 * x1);
      g.weight[0] = {id(i1, j1), c1};
      g.weight[1] = {boundary, 1.0 - c1};
      g.count = 2;
    } else {
      // psi_g - psi_b = c1 (psi_1 - psi_b) + c2 (psi_2 - psi_b), from a2 x^2 + a3 x^3 through both.
      const double x2 = double(s2) - d;
      const double det = x1 * x1 * x2 * x2 * x2 - x1 * x1 * x1 * x2 * x2;
      const double c1 = (xg * xg * x2 * x2 * x2 - xg * xg * xg * x2 * x2) / det;
      const double c2 = (xg * xg * xg * x1 * x1 - xg * xg * x1 * x1 * x1) / det;
      g.weight[0] = {id(i1, j1), c1};
      g.weight[1] = {id(i2, j2), c2};
      g.weight[2] = {boundary, 1.0 - c1 - c2};
      g.count = 3;
    }
    return g;
  };
  for (long j = 0; j < ny; ++j)
    for (long i = 0; i < nx; ++i) {
      if (role[id(i, j)] != 1) continue;
      const long row = unknown[id(i, j)];
      auto add = [&](std::size_t n, double c) {
        if (role[n] == 1) trip.emplace_back(row, unknown[n], c);
        else if (role[n] == 2) known[std::size_t(row)].push_back({n, -c});
        else throw narrow(i, j);
      };
      for (const Tap& t : taps) {
        const long ii = i + t.di, jj = j + t.dj;
        if (role_at(ii, jj) != 0) {
          add(id(ii, jj), t.c);
          continue;
        }
        for (const Weight& g : ghost(i, j, t.di, t.dj)) add(g.node, t.c * g.w);
      }
    }
  Eigen::SparseMatrix<double> A(nu, nu);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  lu.analyzePattern(A);
  lu.factorize(A);
  if (lu.info() != Eigen::Success) throw std::runtime_error("solve_outline_flow: the stream-function system is singular");

  auto solve = [&](const std::vector<double>& q) {
    std::vector<double> psi = boundary_psi(q);
    Eigen::VectorXd rhs(nu);
    for (long r = 0; r < nu; ++r) {
      double s = 0;
      for (const auto& [n, w] : known[std::size_t(r)]) s += w * psi[n];
      rhs[r] = s;
    }
    const Eigen::VectorXd x = lu.solve(rhs);
    for (std::size_t n = 0; n < N; ++n)
      if (role[n] == 1) psi[n] = x[unknown[n]];
    return psi;
  };

  // lap psi at fluid nodes whose four neighbours are fluid or boundary (5-point).
  auto laplacian_known = [&](long i, long j) {
    return i >= 1 && j >= 1 && i + 1 < nx && j + 1 < ny && role[id(i, j)] == 1 && role[id(i + 1, j)] != 0 &&
           role[id(i - 1, j)] != 0 && role[id(i, j + 1)] != 0 && role[id(i, j - 1)] != 0;
  };
  auto laplacian = [&](const std::vector<double>& psi) {
    std::vector<double> L(N, std::numeric_limits<double>::quiet_NaN());
    for (long j = 1; j + 1 < ny; ++j)
      for (long i = 1; i + 1 < nx; ++i)
        if (laplacian_known(i, j))
          L[id(i, j)] = (psi[id(i + 1, j)] + psi[id(i - 1, j)] + psi[id(i, j + 1)] + psi[id(i, j - 1)] - 4 * psi[id(i, j)]) / (h * h);
    return L;
  };
  // Deep nodes: fluid with all eight neighbours fluid and lap psi known at the four beside them.
  std::vector<char> deep(N, 0);
  for (long j = 1; j + 1 < ny; ++j)
    for (long i = 1; i + 1 < nx; ++i) {
      bool d = role[id(i, j)] == 1;
      for (int dj = -1; d && dj <= 1; ++dj)
        for (int di = -1; d && di <= 1; ++di) d = role[id(i + di, j + dj)] == 1;
      d = d && laplacian_known(i + 1, j) && laplacian_known(i - 1, j) && laplacian_known(i, j + 1) && laplacian_known(i, j - 1);
      deep[id(i, j)] = d;
    }
  // The deep node nearest each opening's centre and its distance to the opening's line.
  std::vector<std::size_t> port(o.edges(), N);
  std::vector<double> port_depth(o.edges(), 0.0);
  for (std::size_t k = 0; k < o.edges(); ++k) {
    if (!o.open[k]) continue;
    const Vec2 c = 0.5 * (o.a(k) + o.b(k));
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t n = 0; n < N; ++n)
      if (deep[n]) {
        const double d = (pos(long(n % std::size_t(nx)), long(n / std::size_t(nx))) - c).norm();
        if (d < best) {
          best = d;
          port[k] = n;
        }
      }
    if (port[k] == N) throw std::invalid_argument("the outline is too narrow for its grid; give a smaller grid_spacing");
    port_depth[k] = -(pos(long(port[k] % std::size_t(nx)), long(port[k] / std::size_t(nx))) - c).dot(o.outward_normal(k));
  }
  // Pressure / mu at the openings relative to the inlet's (breadth-first over deep nodes).
  auto opening_pressures = [&](const std::vector<double>& psi, const std::vector<double>& q) {
    const std::vector<double> L = laplacian(psi);
    auto gx = [&](long i, long j) { return (L[id(i, j + 1)] - L[id(i, j - 1)]) / (2 * h); };   // dp/dx / mu
    auto gy = [&](long i, long j) { return -(L[id(i + 1, j)] - L[id(i - 1, j)]) / (2 * h); };  // dp/dy / mu
    std::vector<double> p(N, std::numeric_limits<double>::quiet_NaN());
    std::deque<std::size_t> queue{port[std::size_t(o.inlet)]};
    p[queue.front()] = 0.0;
    while (!queue.empty()) {
      const std::size_t n = queue.front();
      queue.pop_front();
      const long i = long(n % std::size_t(nx)), j = long(n / std::size_t(nx));
      const int step[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
      for (const auto& s : step) {
        const long ii = i + s[0], jj = j + s[1];
        if (ii < 0 || jj < 0 || ii >= nx || jj >= ny) continue;
        const std::size_t m = id(ii, jj);
        if (!deep[m] || !std::isnan(p[m])) continue;
        const double g = s[0] != 0 ? 0.5 * (gx(i, j) + gx(ii, jj)) * double(s[0]) : 0.5 * (gy(i, j) + gy(ii, jj)) * double(s[1]);
        p[m] = p[n] + g * h;
        queue.push_back(m);
      }
    }
    std::vector<double> P(o.edges(), 0.0);
    for (std::size_t k = 0; k < o.edges(); ++k) {
      if (!o.open[k]) continue;
      if (std::isnan(p[port[k]]))
        throw std::invalid_argument("opening " + std::to_string(k) + " is not connected to the inlet through the fluid");
      const double w = o.length(k);
      // Fully developed: dp/dn (outward) = -12 mu q / w^3, from the port node out to the opening.
      P[k] = p[port[k]] - 12.0 * q[k] / (w * w * w) * port_depth[k];
    }
    return P;
  };

  const double Q = mean_velocity * o.length(std::size_t(o.inlet));
  std::vector<std::size_t> outlets;
  for (std::size_t k = 0; k < o.edges(); ++k)
    if (o.open[k] && long(k) != o.inlet) outlets.push_back(k);
  if (outlets.empty()) throw std::invalid_argument("an outline with flow needs at least one outlet besides the inlet");
  std::vector<double> share(outlets.size(), 1.0);
  if (outlets.size() > 1 && Q != 0.0) {
    // P(j, m): pressure at outlet m with all of Q through outlet j.
    const std::size_t m = outlets.size();
    Eigen::MatrixXd P(m, m);
    for (std::size_t j = 0; j < m; ++j) {
      std::vector<double> q(o.edges(), 0.0);
      q[std::size_t(o.inlet)] = -Q;
      q[outlets[j]] = Q;
      const std::vector<double> Pj = opening_pressures(solve(q), q);
      for (std::size_t k = 0; k < m; ++k) P(long(j), long(k)) = Pj[outlets[k]];
    }
    // sum_j alpha_j (P(j, k) - P(j, 0)) = 0 for k >= 1; sum_j alpha_j = 1.
    Eigen::MatrixXd M(m, m);
    Eigen::VectorXd r = Eigen::VectorXd::Zero(long(m));
    for (std::size_t j = 0; j < m; ++j) {
      M(0, long(j)) = 1.0;
      for (std::size_t k = 1; k < m; ++k) M(long(k), long(j)) = P(long(j), long(k)) - P(long(j), 0);
    }
    r[0] = 1.0;
    const Eigen::VectorXd alpha = M.fullPivLu().solve(r);
    for (std::size_t j = 0; j < m; ++j) share[j] = alpha[long(j)];
  }
  out.flux.assign(o.edges(), 0.0);
  out.flux[std::size_t(o.inlet)] = -Q;
  for (std::size_t j = 0; j < outlets.size(); ++j) out.flux[outlets[j]] = share[j] * Q;
  const std::vector<double> psi = solve(out.flux);
  const std::vector<double> P = opening_pressures(psi, out.flux);
  out.pressure_drop_over_mu = P[std::size_t(o.inlet)] - P[outlets[0]];

  // Nodal velocities.
  FlowGrid& G = out.grid;
  for (long i = 0; i < nx; ++i) G.axis[0].push_back(pos(i, 0).x());
  for (long j = 0; j < ny; ++j) G.axis[1].push_back(pos(0, j).y());
  G.axis[2] = {0.0};
  G.u.assign(N, Vec3::Zero());
  for (long j = 0; j < ny; ++j)
    for (long i = 0; i < nx; ++i) {
      const std::size_t n = id(i, j);
      if (role[n] == 1) {
        // A neighbour outside the fluid (beside an oblique wall) takes its ghost value.
        auto value = [&](int di, int dj) {
          if (role_at(i + di, j + dj) != 0) return psi[id(i + di, j + dj)];
          double v = 0;
          for (const Weight& g : ghost(i, j, di, dj)) v += g.w * psi[g.node];
          return v;
        };
        G.u[n] = Vec3((value(0, 1) - value(0, -1)) / (2 * h), -(value(1, 0) - value(-1, 0)) / (2 * h), 0.0);
      } else if (role[n] == 2 && o.open[std::size_t(edge[n])]) {
        const std::size_t k = std::size_t(edge[n]);
        const double s = (pos(i, j) - o.a(k)).norm() / o.length(k);
        const double w = o.length(k);
        const Vec2 un = out.flux[k] / w * 6.0 * s * (1.0 - s) * o.outward_normal(k);
        G.u[n] = Vec3(un.x(), un.y(), 0.0);
      }
    }
  G.path = "(solved: stokes 2D on the outline)";
  return out;
}

}  // namespace stokesian
