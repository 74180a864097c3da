// Benchmark: the real-space part of the PME far field, ewald::RealSpaceSum (ewald/real_space.hpp)
// against the reference path of PmeFarField::apply_real today (trees::neighbor_pairs, exact
// real_scalars per neighbour-list entry cached when they fit in 128 MB, mobility::apply_pair).
// Configurations: monodisperse spheres (a = 1) on a jittered simple cubic lattice (no overlaps)
// at phi = 0.1 and 0.4, N = 22^3 = 10648 and 46^3 = 97336, periodic cube; xi and cutoff_gap from
// ewald::pme_parameters(tol, ...) with PmeOptions::neighbours = 25, 50, 100 (particles inside the
// cutoff sphere). Moments F and FTS (FT at the smaller N), tol 1e-4 and 1e-6, 1 and 2 threads.
// Phases [s]: "build" (constructor; reference: pair list + scalars), "update" (update_positions),
// "apply" (median product). Params: kind 0 = RealSpaceSum (scalar cache on when it fits in the default
// 256 MB), 2 = RealSpaceSum without the cache (tables evaluated per product; equal radii, so the
// tables of the pair scalars), 3 = as 2 with the general tables (force_general_tables), 1 = reference; pairs; ns_per_pair =
// apply / pairs. The reference runs at the smaller N only (several seconds per product at N ~ 10^5).
//   bench_pme_real [--quick] [--out DIR]      (--quick: N = 10648, phi 0.1, tol 1e-4, 50 neighbours)
#include "bench/harness.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/lattice.hpp"
#include "ewald/pme_parameters.hpp"
#include "ewald/real_space.hpp"
#include "trees/neighbor_list.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

using namespace stokesian;

namespace {

// The real part as PmeFarField computes it today (ewald/pme.cpp at the time of writing).
struct Reference {
  long n = 0;
  Moments m = Moments::F;
  std::vector<trees::NeighborPair> pairs;
  std::vector<int> start, list;  // CSR: entries of particle i, 2 * pair + role
  std::vector<mobility::PairScalars> cache;
  std::vector<double> self_f, self_t, self_s;

  Reference(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& dom, double gap, double xi,
            double mu, Moments mo)
      : n(long(x.size())), m(mo) {
    pairs = trees::neighbor_pairs(x, a, dom, gap);
    start.assign(n + 1, 0);
    for (const auto& p : pairs) {
      ++start[p.i + 1];
      ++start[p.j + 1];
    }
    for (long i = 0; i < n; ++i) start[i + 1] += start[i];
    list.resize(2 * pairs.size());
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int q = 0; q < int(pairs.size()); ++q) {
      list[fill[pairs[q].i]++] = 2 * q;
      list[fill[pairs[q].j]++] = 2 * q + 1;
    }
    if (list.size() * sizeof(mobility::PairScalars) <= (std::size_t(128) << 20)) {
      cache.resize(list.size());
#pragma omp parallel for schedule(dynamic, 64)
      for (long i = 0; i < n; ++i)
        for (int t = start[i]; t < start[i + 1]; ++t) {
          const auto& p = pairs[list[t] / 2];
          const long j = list[t] % 2 == 0 ? p.j : p.i;
          cache[t] = ewald::real_scalars(a[i], a[j], p.dist, xi, mu, m);
        }
    }
    self_f.resize(n);
    self_t.resize(n);
    self_s.resize(n);
    for (long i = 0; i < n; ++i) {
      const auto s = ewald::self_correction(a[i], xi, mu);
      self_f[i] = s.xa;
      self_t[i] = s.xc;
      self_s[i] = s.xm;
    }
    radius = a;
    xi_ = xi;
    mu_ = mu;
  }
  std::vector<double> radius;
  double xi_ = 1.0, mu_ = 1.0;

  void apply(const VecX& in, VecX& out) const {
    const int d = dof_per_particle(m);
    out.setZero(n * d);
#pragma omp parallel for schedule(dynamic, 64)
    for (long i = 0; i < n; ++i) {
      double* yi = out.data() + i * d;
      const double* xi = in.data() + i * d;
      for (int c = 0; c < 3; ++c) yi[c] += self_f[i] * xi[c];
      for (int c = 3; c < std::min(d, 6); ++c) yi[c] += self_t[i] * xi[c];
      for (int c = 6; c < d; ++c) yi[c] += self_s[i] * xi[c];
      for (int t = start[i]; t < start[i + 1]; ++t) {
        const auto& p = pairs[list[t] / 2];
        const bool first = list[t] % 2 == 0;
        const long j = first ? p.j : p.i;
        const Vec3 e = p.dist > 0.0 ? Vec3(p.r / p.dist) : Vec3::UnitZ();
        const mobility::PairScalars s =
            cache.empty() ? ewald::real_scalars(radius[i], radius[j], p.dist, xi_, mu_, m) : cache[t];
        mobility::apply_pair(s, first ? e : Vec3(-e), m, in.data() + j * d, yi);
      }
    }
  }
};

// n^3 spheres of radius 1 on a simple cubic lattice of spacing s = (4 pi / (3 phi))^(1/3), each
// displaced uniformly by at most (s - 2) / 2 * 0.98 per axis (no overlaps).
std::vector<Vec3> jittered_lattice(int n, double phi, double& L, std::uint64_t seed) {
  const double s = std::cbrt(4.0 * kPi / (3.0 * phi));
  L = n * s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double amp = 0.49 * (s - 2.0);
  std::vector<Vec3> x;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        x.emplace_back((i + 0.5) * s + amp * u(rng), (j + 0.5) * s + amp * u(rng), (k + 0.5) * s + amp * u(rng));
  return x;
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "pme_real_quick" : "pme_real");
  const int max_threads = std::min(2, omp_get_max_threads());
  const std::vector<int> sides = opt.quick ? std::vector<int>{22} : std::vector<int>{22, 46};
  const std::vector<double> phis = opt.quick ? std::vector<double>{0.1} : std::vector<double>{0.1, 0.4};
  const std::vector<double> tols = opt.quick ? std::vector<double>{1e-4} : std::vector<double>{1e-4, 1e-6};
  const std::vector<double> nbs = opt.quick ? std::vector<double>{50} : std::vector<double>{25, 50, 100};
  const double mu = 1.0;
  for (int side : sides)
    for (double phi : phis) {
      double L = 0.0;
      const std::vector<Vec3> x = jittered_lattice(side, phi, L, 7);
      const long n = long(x.size());
      const std::vector<double> a(n, 1.0);
      Domain dom;
      dom.kind = Domain::Kind::periodic;
      dom.box = Vec3(L, L, L);
      const ewald::Lattice lat = ewald::Lattice::from_domain(dom);
      // Moved positions for update_positions: every particle displaced by up to 0.01.
      std::vector<Vec3> x2 = x;
      for (long i = 0; i < n; ++i) x2[i] += 0.01 * Vec3(std::sin(1.0 * i), std::cos(2.0 * i), std::sin(3.0 * i));
      std::vector<Moments> ms{Moments::F, Moments::FTS};
      if (side <= 22 && !opt.quick) ms.insert(ms.begin() + 1, Moments::FT);
      for (Moments m : ms)
        for (double tol : tols)
          for (double nb : nbs) {
            ewald::PmeOptions po;
            po.neighbours = nb;
            const ewald::PmeParameters p = ewald::pme_parameters(tol, lat, int(n), 1.0, 1.0, m, po);
            const int d = dof_per_particle(m);
            const VecX v = VecX::Random(n * d);
            VecX y, yref;
            for (int threads = 1; threads <= max_threads; ++threads) {
              omp_set_num_threads(threads);
              std::unique_ptr<ewald::RealSpaceSum> fast;
              std::map<std::string, double> ph;
              ph["build"] = bench::time_once(
                  [&] { fast = std::make_unique<ewald::RealSpaceSum>(x, a, dom, p.cutoff_gap, p.xi, mu, m, tol); });
              ph["apply"] = bench::median_time([&] { fast->apply(v, y); }, 3);
              ph["update"] = bench::time_once([&] { fast->update_positions(x2); });
              fast->update_positions(x);
              const double pairs = double(fast->pairs());
              std::map<std::string, double> par{{"kind", 0},        {"N", double(n)},         {"phi", phi},
                                                {"dof", double(d)}, {"tol", tol},             {"neighbours", nb},
                                                {"threads", double(threads)}, {"pairs", pairs},
                                                {"xi", p.xi},       {"cutoff_gap", p.cutoff_gap},
                                                {"intervals", double(fast->table_intervals())},
                                                {"ns_per_pair", 1e9 * ph["apply"] / pairs}};
              res.add(par, ph);
              std::printf("N=%6ld phi=%.1f dof=%2d tol=%.0e nb=%3.0f thr=%d pairs=%8.0f  fast: build %.3f update %.3f apply %.4f s = %5.1f ns/pair (intervals %d%s)",
                          n, phi, d, tol, nb, threads, pairs, ph["build"], ph["update"], ph["apply"],
                          1e9 * ph["apply"] / pairs, fast->table_intervals(), fast->cached() ? ", cached" : "");
              fast.reset();
              {
                // Without the scalar cache: every product evaluates the tables.
                std::unique_ptr<ewald::RealSpaceSum> tab;
                std::map<std::string, double> pt;
                pt["build"] = bench::time_once(
                    [&] { tab = std::make_unique<ewald::RealSpaceSum>(x, a, dom, p.cutoff_gap, p.xi, mu, m, tol, 0); });
                pt["apply"] = bench::median_time([&] { tab->apply(v, y); }, opt.quick ? 3 : 1);
                par["kind"] = 2;
                par["ns_per_pair"] = 1e9 * pt["apply"] / pairs;
                res.add(par, pt);
                std::printf("  tables: build %.3f apply %.4f s = %5.1f ns/pair", pt["build"], pt["apply"],
                            1e9 * pt["apply"] / pairs);
                // The general tables (any radii), the reference twin of the equal-radius tables above.
                ewald::RealSpaceSum::force_general_tables(true);
                std::map<std::string, double> pg;
                pg["build"] = bench::time_once(
                    [&] { tab = std::make_unique<ewald::RealSpaceSum>(x, a, dom, p.cutoff_gap, p.xi, mu, m, tol, 0); });
                ewald::RealSpaceSum::force_general_tables(false);
                pg["apply"] = bench::median_time([&] { tab->apply(v, y); }, opt.quick ? 3 : 1);
                par["kind"] = 3;
                par["ns_per_pair"] = 1e9 * pg["apply"] / pairs;
                res.add(par, pg);
                std::printf("  general tables: %5.1f ns/pair", 1e9 * pg["apply"] / pairs);
              }
              if (side <= 22) {
                std::unique_ptr<Reference> ref;
                std::map<std::string, double> pr;
                pr["build"] = bench::time_once(
                    [&] { ref = std::make_unique<Reference>(x, a, dom, p.cutoff_gap, p.xi, mu, m); });
                pr["apply"] = bench::median_time([&] { ref->apply(v, yref); }, 1);
                par["kind"] = 1;
                par["ns_per_pair"] = 1e9 * pr["apply"] / pairs;
                res.add(par, pr);
                std::printf("  ref: build %.3f apply %.4f s = %5.1f ns/pair  rel.diff %.1e", pr["build"], pr["apply"],
                            1e9 * pr["apply"] / pairs, (y - yref).norm() / yref.norm());
              }
              std::printf("\n");
              std::fflush(stdout);
            }
          }
    }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
