// Cluster detection and cluster shapes; the definitions are stated in clusters.hpp.
#include "trees/clusters.hpp"

#include "trees/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace stokesian::trees {
namespace {

bool skipped(const std::vector<char>* skip, std::size_t i) { return skip && !skip->empty() && (*skip)[i]; }

void check_sizes(const std::vector<Vec3>& x, const std::vector<double>& radius, const std::vector<char>* skip) {
  if (radius.size() != x.size()) throw std::invalid_argument("clusters: positions and radii differ in number");
  if (skip && !skip->empty() && skip->size() != x.size())
    throw std::invalid_argument("clusters: the skip mask and the positions differ in number");
}

// Number clusters by decreasing size, ties by their lowest member; root[i] is any per-component
// representative (or -1 for skipped spheres).
Clusters number_components(const std::vector<int>& root, std::vector<Clusters::Bond> bonds) {
  const std::size_t n = root.size();
  std::vector<int> first(n, -1);  // component representative -> its lowest member
  std::vector<long> count(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (root[i] < 0) continue;
    const auto r = std::size_t(root[i]);
    if (first[r] < 0) first[r] = int(i);
    ++count[r];
  }
  std::vector<int> reps;
  for (std::size_t r = 0; r < n; ++r)
    if (count[r] > 0) reps.push_back(int(r));
  std::sort(reps.begin(), reps.end(), [&](int u, int v) {
    return count[std::size_t(u)] != count[std::size_t(v)] ? count[std::size_t(u)] > count[std::size_t(v)]
                                                          : first[std::size_t(u)] < first[std::size_t(v)];
  });
  std::vector<int> number(n, -1);
  for (std::size_t k = 0; k < reps.size(); ++k) number[std::size_t(reps[k])] = int(k);
  Clusters c;
  c.label.assign(n, -1);
  c.members.resize(reps.size());
  for (std::size_t i = 0; i < n; ++i)
    if (root[i] >= 0) {
      c.label[i] = number[std::size_t(root[i])];
      c.members[std::size_t(c.label[i])].push_back(int(i));
    }
  c.bonds = std::move(bonds);
  return c;
}

Clusters components(const std::vector<NeighborPair>& pairs, const std::vector<double>& radius, double bond_gap,
                    const std::vector<char>* skip) {
  const std::size_t n = radius.size();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[std::size_t(i)] != i) {
      parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];  // path halving
      i = parent[std::size_t(i)];
    }
    return i;
  };
  std::vector<Clusters::Bond> bonds;
  for (const NeighborPair& p : pairs) {
    if (skipped(skip, std::size_t(p.i)) || skipped(skip, std::size_t(p.j))) continue;
    if (!(p.dist - radius[std::size_t(p.i)] - radius[std::size_t(p.j)] <= bond_gap)) continue;
    bonds.push_back({p.i, p.j, p.r});
    const int ri = find(p.i), rj = find(p.j);
    if (ri != rj) parent[std::size_t(std::max(ri, rj))] = std::min(ri, rj);
  }
  std::vector<int> root(n, -1);
  for (std::size_t i = 0; i < n; ++i)
    if (!skipped(skip, i)) root[i] = find(int(i));
  return number_components(root, std::move(bonds));
}

}  // namespace

Clusters find_clusters(const std::vector<Vec3>& x, const std::vector<double>& radius, const Domain& domain,
                       double bond_gap, const std::vector<char>* skip) {
  check_sizes(x, radius, skip);
  if (!(bond_gap >= 0.0) || !std::isfinite(bond_gap))
    throw std::invalid_argument("clusters: the bond gap must be finite and >= 0");
  // Search a little beyond the criterion so that pairs exactly at bond_gap are found.
  const double search = bond_gap + 1e-9 * (1.0 + bond_gap);
  return components(nearest_image_pairs(x, radius, domain, search), radius, bond_gap, skip);
}

Clusters link_by_centres(const std::vector<Vec3>& x, const Domain& domain, double link, const std::vector<char>* skip) {
  if (!(link > 0.0) || !std::isfinite(link))
    throw std::invalid_argument("clusters: the linking length must be finite and > 0");
  return find_clusters(x, std::vector<double>(x.size(), 0.0), domain, link, skip);
}

Clusters find_clusters_reference(const std::vector<Vec3>& x, const std::vector<double>& radius, const Domain& domain,
                                 double bond_gap, const std::vector<char>* skip) {
  check_sizes(x, radius, skip);
  const std::size_t n = x.size();
  std::vector<Clusters::Bond> bonds;
  std::vector<std::vector<int>> adj(n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (skipped(skip, i) || skipped(skip, j)) continue;
      const Vec3 r = domain.periodic() ? domain.minimum_image(x[i] - x[j]) : Vec3(x[i] - x[j]);
      if (r.norm() - radius[i] - radius[j] <= bond_gap) {
        bonds.push_back({int(i), int(j), r});
        adj[i].push_back(int(j));
        adj[j].push_back(int(i));
      }
    }
  // Label propagation: every sphere takes the smallest label among itself and its neighbours until
  // nothing changes.
  std::vector<int> root(n);
  for (std::size_t i = 0; i < n; ++i) root[i] = skipped(skip, i) ? -1 : int(i);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t i = 0; i < n; ++i)
      for (int j : adj[i])
        if (root[std::size_t(j)] < root[i]) {
          root[i] = root[std::size_t(j)];
          changed = true;
        }
  }
  return number_components(root, std::move(bonds));
}

std::vector<ClusterShape> cluster_shapes(const Clusters& c, const std::vector<Vec3>& x,
                                         const std::vector<double>& radius, const Domain& domain,
                                         const std::vector<Vec3>& velocity) {
  const std::size_t n = x.size();
  if (c.label.size() != n || radius.size() != n) throw std::invalid_argument("cluster_shapes: sizes differ");
  if (!velocity.empty() && velocity.size() != n)
    throw std::invalid_argument("cluster_shapes: velocities differ in number");
  // Unwrap each cluster along its bonds (breadth first from its lowest member); a bond that closes a
  // cycle with a different lattice vector marks the cluster as spanning.
  std::vector<Vec3> u(x.begin(), x.end());
  std::vector<char> spanning(c.members.size(), 0);
  if (domain.periodic()) {
    std::vector<std::vector<std::pair<int, Vec3>>> adj(n);
    for (const auto& b : c.bonds) {
      adj[std::size_t(b.i)].push_back({b.j, b.r});  // u_i = u_j + r  =>  u_j = u_i - r
      adj[std::size_t(b.j)].push_back({b.i, -b.r});
    }
    std::vector<char> seen(n, 0);
    const double eps = 1e-6 * domain.box.minCoeff();
    for (std::size_t k = 0; k < c.members.size(); ++k) {
      std::vector<int> queue{c.members[k].front()};
      seen[std::size_t(queue[0])] = 1;
      for (std::size_t q = 0; q < queue.size(); ++q) {
        const auto i = std::size_t(queue[q]);
        for (const auto& [j, r] : adj[i]) {
          const Vec3 uj = u[i] - r;
          if (!seen[std::size_t(j)]) {
            seen[std::size_t(j)] = 1;
            u[std::size_t(j)] = uj;
            queue.push_back(j);
          } else if ((u[std::size_t(j)] - uj).norm() > eps) {
            spanning[k] = 1;
          }
        }
      }
    }
  }
  std::vector<ClusterShape> out(c.members.size());
  for (std::size_t k = 0; k < c.members.size(); ++k) {
    ClusterShape& s = out[k];
    const auto& m = c.members[k];
    s.size = long(m.size());
    Vec3 mx = Vec3::Zero(), mv = Vec3::Zero();
    for (int i : m) {
      const double w = std::pow(radius[std::size_t(i)], 3);
      s.mass += w;
      mx += w * u[std::size_t(i)];
      if (!velocity.empty()) mv += w * velocity[std::size_t(i)];
    }
    s.velocity = mv / s.mass;
    if (spanning[k]) {
      s.spanning = true;
      s.centre = Vec3::Constant(NAN);
      s.radius_of_gyration = s.feret = NAN;
      continue;
    }
    s.centre = mx / s.mass;
    double rg2 = 0.0;
    for (int i : m) {
      const double a = radius[std::size_t(i)];
      rg2 += std::pow(a, 3) * ((u[std::size_t(i)] - s.centre).squaredNorm() + 0.6 * a * a);
    }
    s.radius_of_gyration = std::sqrt(rg2 / s.mass);
    double feret = 0.0;
    for (std::size_t p = 0; p < m.size(); ++p) {
      const auto i = std::size_t(m[p]);
      feret = std::max(feret, 2.0 * radius[i]);
      for (std::size_t q = p + 1; q < m.size(); ++q) {
        const auto j = std::size_t(m[q]);
        feret = std::max(feret, (u[i] - u[j]).norm() + radius[i] + radius[j]);
      }
    }
    s.feret = feret;
    if (domain.periodic())
      s.centre = [&] {  // report the centre inside the box
        Vec3 cc = s.centre;
        domain.wrap(cc);
        return cc;
      }();
  }
  return out;
}

std::vector<long> size_histogram(const Clusters& c) {
  std::vector<long> h(1, 0);
  for (const auto& m : c.members) {
    if (m.size() >= h.size()) h.resize(m.size() + 1, 0);
    ++h[m.size()];
  }
  return h;
}

FractalFit fractal_dimension(const std::vector<ClusterShape>& shapes, double mean_radius, long min_size) {
  FractalFit f;
  f.dimension = f.prefactor = NAN;
  std::vector<double> lx, ly;
  for (const ClusterShape& s : shapes)
    if (s.size >= min_size && !s.spanning && s.radius_of_gyration > 0) {
      lx.push_back(std::log(s.radius_of_gyration / mean_radius));
      ly.push_back(std::log(double(s.size)));
    }
  f.clusters = long(lx.size());
  if (lx.size() < 3) return f;
  const auto [lo, hi] = std::minmax_element(lx.begin(), lx.end());
  if (*hi - *lo < std::log(kFractalMinSpan)) return f;
  const double n = double(lx.size());
  const double mx = std::accumulate(lx.begin(), lx.end(), 0.0) / n, my = std::accumulate(ly.begin(), ly.end(), 0.0) / n;
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k < lx.size(); ++k) {
    sxx += (lx[k] - mx) * (lx[k] - mx);
    sxy += (lx[k] - mx) * (ly[k] - my);
  }
  f.dimension = sxy / sxx;
  f.prefactor = std::exp(my - f.dimension * mx);
  return f;
}

}  // namespace stokesian::trees
