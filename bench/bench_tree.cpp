// Benchmark and accuracy study of the octree far field (issue 16; trees/tree_mobility.hpp), rows by
// "kind" (plot_tree.py draws them):
//   kind 0  scaling: time per product y = M x against N, F and FTS, knobs from tolerances 1e-3, 1e-4,
//           1e-6, a uniform cube (phi = 0.1) and a dense spherical cloud (phi = 0.3), radii 0.5-1.5,
//           1 and 2 threads; phases set-up (tree, lists), upward, downward; achieved error against
//           the direct product (N <= 20000, ref 0) or, beyond, against the direct rows of 300
//           random particles (ref 2)
//   kind 1  the direct O(N^2) product, measured to N = 20000 (1 and 2 threads)
//   kind 2  error against theta for p = 0 ... 10 (FMM) and Barnes-Hut p = 0, 3000 spheres: uniform,
//           clustered (8 dense balls), polydisperse (radius ratio 10), F and FTS
//   kind 3  tolerance sweep 1e-2 ... 1e-10, F / FT / FTS, uniform and the dense ball, 4000 spheres:
//           achieved / requested error, theta and p chosen, time
//   BENCH_TREE_THESIS=1: only the thesis's table 3.1 set-up (chapter 3; docs/tree.md): 37^3 unit
//           spheres on a cubic grid at phi = 5e-5, 5e-3, 0.25, FT, each sphere pushed by F = -e_z;
//           Barnes-Hut at p = 0 with theta = theta_thesis / 2 (its criterion compares a group's
//           diameter with the distance) for theta_thesis = 1, 0.1, and the FMM at tolerances 1e-3,
//           1e-6: relative error of the mean velocity (the thesis's measure) and of the whole
//           product against the direct product; written to tree_thesis.json (quick: 11^3).
// Left out (minutes per product): FTS beyond N = 3e5, and beyond 1e5 at tolerance 1e-6.
// Environment: BENCH_MAX_N (default 1e6; quick 2000), BENCH_THREADS (default 2).
//   bench_tree [--quick] [--out DIR]
#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "trees/tree_mobility.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

using namespace stokesian;
using trees::TreeEvaluation;
using trees::TreeFarField;
using trees::TreeParameters;

namespace {

constexpr int kSampledRows = 300;  // rows of the sampled direct reference

struct Cloud {
  std::vector<Vec3> x;
  std::vector<double> a;
};

// kind 0: uniform cube at phi; 1: ball at phi; 2: 8 balls (phi 0.3 each) inside a cube 4x their
// radius; radii uniform in [a_lo, a_hi] (log-uniform when a_hi / a_lo > 3).
Cloud make_cloud(int kind, long n, double phi, double a_lo, double a_hi, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c;
  double volume = 0;
  for (long i = 0; i < n; ++i) {
    const double a = a_hi / a_lo > 3 ? a_lo * std::pow(a_hi / a_lo, u(rng)) : a_lo + (a_hi - a_lo) * u(rng);
    c.a.push_back(a);
    volume += 4.18879020478639 * a * a * a;
  }
  const double region = volume / phi;
  if (kind == 0) {
    const double L = std::cbrt(region);
    for (long i = 0; i < n; ++i) c.x.emplace_back(L * u(rng), L * u(rng), L * u(rng));
  } else {
    const int balls = kind == 1 ? 1 : 8;
    const double R = std::cbrt(region / balls / 4.18879020478639);
    for (long i = 0; i < n; ++i) {
      Vec3 p;
      do p = Vec3(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
      while (p.norm() > 1);
      Vec3 centre = Vec3::Zero();
      if (balls > 1) {
        const int b = int(i % balls);
        centre = 4 * R * Vec3(b & 1, (b >> 1) & 1, (b >> 2) & 1);
      }
      c.x.push_back(centre + R * p);
    }
  }
  return c;
}

VecX random_vector(long size, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  VecX v(size);
  for (long k = 0; k < size; ++k) v[k] = g(rng);
  return v;
}

double rel_error(const VecX& y, const VecX& ref) { return (y - ref).norm() / ref.norm(); }

// The direct product's rows at `count` random particles (the O(N) sum of the exact pair kernel of
// engine/kernels for each), and the relative 2-norm error of y over those rows: the reference
// where the whole direct product is too slow.
double sampled_error(const Cloud& c, Moments m, const VecX& x, const VecX& y, int count, unsigned seed, int threads) {
  const long n = long(c.x.size());
  const int d = dof_per_particle(m);
  std::mt19937_64 rng(seed);
  std::vector<long> rows(static_cast<std::size_t>(count));
  for (auto& i : rows) i = long(rng() % std::uint64_t(n));
  std::vector<double> ref(static_cast<std::size_t>(count * d), 0.0);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int s = 0; s < count; ++s) {
    const long i = rows[std::size_t(s)];
    double* yi = ref.data() + std::size_t(s * d);
    mobility::apply_self(c.a[std::size_t(i)], 1.0, m, x.data() + i * d, yi);
    for (long j = 0; j < n; ++j) {
      if (j == i) continue;
      const Vec3 rij = c.x[std::size_t(i)] - c.x[std::size_t(j)];
      const double r = rij.norm();
      const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
      mobility::apply_pair(mobility::pair_scalars(c.a[std::size_t(i)], c.a[std::size_t(j)], r, 1.0, m), e, m,
                           x.data() + j * d, yi);
    }
  }
  double num = 0, den = 0;
  for (int s = 0; s < count; ++s)
    for (int r = 0; r < d; ++r) {
      const double diff = y[rows[std::size_t(s)] * d + r] - ref[std::size_t(s * d + r)];
      num += diff * diff;
      den += ref[std::size_t(s * d + r)] * ref[std::size_t(s * d + r)];
    }
  return std::sqrt(num / den);
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  const bool quick = opt.quick;
  const double max_n = std::getenv("BENCH_MAX_N") ? std::atof(std::getenv("BENCH_MAX_N")) : (quick ? 3000 : 1e6);
  const int max_threads =
      std::min(std::getenv("BENCH_THREADS") ? std::atoi(std::getenv("BENCH_THREADS")) : 2, omp_get_max_threads());
  const long direct_max = quick ? 2000 : 20000;
  const Domain open;
  if (std::getenv("BENCH_TREE_THESIS")) {
    bench::Results th(quick ? "tree_thesis_quick" : "tree_thesis");
    const int side = quick ? 11 : 37;
    for (double phi : {5e-5, 5e-3, 0.25}) {
      const double h = std::cbrt(4.18879020478639 / phi);  // grid spacing: one unit sphere per h^3
      Cloud c;
      for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j)
          for (int k = 0; k < side; ++k) {
            c.x.emplace_back(h * i, h * j, h * k);
            c.a.push_back(1.0);
          }
      const long n = long(c.x.size());
      VecX f = VecX::Zero(6 * n);
      for (long i = 0; i < n; ++i) f[6 * i + 2] = -1.0;
      VecX ref, y;
      const double t_direct = bench::time_once([&] { mobility_product(c.x, c.a, 1.0, Moments::FT, f, ref); });
      auto mean_u = [&](const VecX& v) {
        Vec3 m = Vec3::Zero();
        for (long i = 0; i < n; ++i) m += Vec3(v[6 * i], v[6 * i + 1], v[6 * i + 2]);
        return Vec3(m / double(n));
      };
      const Vec3 uref = mean_u(ref);
      struct Case {
        double theta_thesis, tol;
      };
      for (const Case& cs : {Case{1.0, 0}, Case{0.1, 0}, Case{0, 1e-3}, Case{0, 1e-6}}) {
        MobilitySpec spec{Moments::FT, 1.0, cs.tol > 0 ? cs.tol : 1e-3};
        const TreeParameters tp = cs.tol > 0 ? trees::tree_parameters(cs.tol, Moments::FT)
                                             : TreeParameters{cs.theta_thesis / 2, 0, 16, TreeEvaluation::barnes_hut};
        TreeFarField op(spec, tp);
        op.set_configuration({c.x, c.a, open});
        const double t = bench::time_once([&] { op.apply(f, y); });
        const double err_mean = (mean_u(y) - uref).norm() / uref.norm();
        th.add({{"phi", phi}, {"N", double(n)}, {"theta_thesis", cs.theta_thesis}, {"tol", cs.tol},
                {"theta", tp.theta}, {"p", double(tp.order)}},
               {{"error_mean_velocity", err_mean}, {"error", rel_error(y, ref)}, {"product", t}, {"direct", t_direct}});
        std::printf("thesis grid %ld phi %.2g %s theta %.3f p %d: error of <U> %.2e, of the product %.2e, %.2f s (direct %.2f s)\n",
                    n, phi, cs.tol > 0 ? "fmm" : "barnes-hut", tp.theta, tp.order, err_mean, rel_error(y, ref), t, t_direct);
        std::fflush(stdout);
      }
    }
    std::printf("wrote %s\n", th.write(opt.out).c_str());
    return 0;
  }
  bench::Results res(quick ? "tree_quick" : "tree");

  // kind 2: error against theta and p.
  {
    const long n = quick ? 600 : 3000;
    const int p_max = quick ? 4 : 10;
    const std::vector<double> thetas = quick ? std::vector<double>{0.6, 0.4} : std::vector<double>{0.7, 0.6, 0.5, 0.4, 0.3, 0.2};
    struct Set {
      int cloud;
      double a_lo, a_hi;
      const char* name;
    };
    for (const Set& set : {Set{0, 1.0, 1.0, "uniform"}, Set{2, 1.0, 1.0, "clustered"}, Set{0, 0.3, 3.0, "poly10"}}) {
      const Cloud c = make_cloud(set.cloud, n, set.cloud == 0 ? 0.1 : 0.3, set.a_lo, set.a_hi, 41);
      for (Moments m : {Moments::F, Moments::FTS}) {
        const VecX x = random_vector(long(n) * dof_per_particle(m), 5);
        VecX ref, y;
        mobility_product(c.x, c.a, 1.0, m, x, ref);
        for (double theta : thetas) {
          for (int p = -1; p <= p_max; p += (p < 4 ? 1 : 2)) {
            // p = -1 stands for Barnes-Hut at order 0 (the thesis's monopole scheme)
            const TreeParameters tp{theta, std::max(p, 0), 16, p < 0 ? TreeEvaluation::barnes_hut : TreeEvaluation::fmm};
            MobilitySpec spec;
            spec.moments = m;
            TreeFarField op(spec, tp);
            op.set_configuration({c.x, c.a, open});
            op.apply(x, y);
            res.add({{"kind", 2}, {"set", double(set.cloud == 0 && set.a_hi > 1 ? 2 : set.cloud == 2 ? 1 : 0)},
                     {"N", double(n)}, {"dof", double(dof_per_particle(m))}, {"theta", theta}, {"p", double(p)}},
                    {{"error", rel_error(y, ref)}});
          }
        }
        std::printf("kind 2 %s %s done\n", set.name, to_string(m));
        std::fflush(stdout);
      }
    }
  }

  // kind 3: tolerance sweep.
  {
    const long n = quick ? 800 : 4000;
    const std::vector<double> tols = quick ? std::vector<double>{1e-2, 1e-4, 1e-6}
                                           : std::vector<double>{1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
    for (int cloud : {0, 1}) {
      const Cloud c = make_cloud(cloud, n, cloud == 0 ? 0.1 : 0.3, 0.5, 1.5, 43);
      for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
        const VecX x = random_vector(long(n) * dof_per_particle(m), 6);
        VecX ref, y;
        mobility_product(c.x, c.a, 1.0, m, x, ref);
        for (double tol : tols) {
          MobilitySpec spec{m, 1.0, tol};
          TreeFarField op(spec);
          op.set_configuration({c.x, c.a, open});
          const double t = bench::median_time([&] { op.apply(x, y); }, 1);
          const double err = rel_error(y, ref);
          res.add({{"kind", 3}, {"cloud", double(cloud)}, {"N", double(n)}, {"dof", double(dof_per_particle(m))},
                   {"tol", tol}, {"theta", op.parameters().theta}, {"p", double(op.parameters().order)},
                   {"threads", double(omp_get_max_threads())}},
                  {{"error", err}, {"product", t}});
          std::printf("kind 3 cloud %d %-3s tol %.0e theta %.2f p %2d error %.2e ratio %.3f time %.3f s\n", cloud,
                      to_string(m), tol, op.parameters().theta, op.parameters().order, err, err / tol, t);
          std::fflush(stdout);
        }
      }
    }
  }

  // kind 1: the direct product.
  for (Moments m : {Moments::F, Moments::FTS}) {
    for (long n : {1000L, 2000L, 5000L, 10000L, 20000L}) {
      if (n > direct_max) break;
      const Cloud c = make_cloud(0, n, 0.1, 0.5, 1.5, 47);
      const VecX x = random_vector(n * dof_per_particle(m), 7);
      VecX y;
      for (int threads = 1; threads <= max_threads; ++threads) {
        omp_set_num_threads(threads);
        const double t = bench::median_time([&] { mobility_product(c.x, c.a, 1.0, m, x, y); }, n <= 5000 ? 3 : 1);
        res.add({{"kind", 1}, {"N", double(n)}, {"dof", double(dof_per_particle(m))}, {"threads", double(threads)}},
                {{"product", t}});
        std::printf("kind 1 direct %-3s N %6ld threads %d product %.3f s\n", to_string(m), n, threads, t);
        std::fflush(stdout);
      }
    }
  }
  omp_set_num_threads(max_threads);

  // kind 0: scaling.
  const std::vector<long> sizes = quick ? std::vector<long>{1000, 2000}
                                        : std::vector<long>{1000, 3000, 10000, 30000, 100000, 300000, 1000000};
  const std::vector<double> scaling_tols = quick ? std::vector<double>{1e-3} : std::vector<double>{1e-3, 1e-4, 1e-6};
  for (Moments m : {Moments::F, Moments::FTS}) {
    for (int cloud : {0, 1}) {
      for (double tol : scaling_tols) {
        for (long n : sizes) {
          if (n > max_n) break;
          // Products of minutes are left out: FTS beyond 3e5, and beyond 1e5 at tolerance 1e-6.
          if (m == Moments::FTS && n > (tol < 1e-5 ? 100000 : 300000)) break;
          const Cloud c = make_cloud(cloud, n, cloud == 0 ? 0.1 : 0.3, 0.5, 1.5, 53);
          const VecX x = random_vector(n * dof_per_particle(m), 8);
          VecX ref, y;
          int ref_kind = 0;  // 0 direct, 2 direct at sampled rows
          if (n <= direct_max)
            mobility_product(c.x, c.a, 1.0, m, x, ref);
          else
            ref_kind = 2;
          double sampled = -1;
          for (int threads = 1; threads <= max_threads; ++threads) {
            omp_set_num_threads(threads);
            TreeFarField op(MobilitySpec{m, 1.0, tol});
            const double t_setup = bench::time_once([&] { op.set_configuration({c.x, c.a, open}); });
            const double t = bench::median_time([&] { op.apply(x, y); }, n <= 30000 ? 3 : 1);
            const auto& st = op.last_stats();
            std::map<std::string, double> phases{{"product", t},
                                                 {"setup", t_setup},
                                                 {"upward", st.upward_seconds},
                                                 {"downward", st.downward_seconds},
                                                 {"pairs", double(st.pair_interactions)},
                                                 {"conversions", double(st.m2l)}};
            if (ref_kind == 0)
              phases["error"] = rel_error(y, ref);
            else {
              if (sampled < 0) sampled = sampled_error(c, m, x, y, kSampledRows, 77, max_threads);  // once per product
              phases["error"] = sampled;
            }
            res.add({{"kind", 0}, {"cloud", double(cloud)}, {"N", double(n)}, {"dof", double(dof_per_particle(m))},
                     {"tol", tol}, {"threads", double(threads)}, {"ref", double(ref_kind)},
                     {"theta", op.parameters().theta}, {"p", double(op.parameters().order)},
                     {"leaf", double(op.leaf_size())}},
                    phases);
            std::printf("kind 0 %-3s cloud %d tol %.0e N %7ld threads %d: set-up %.3f product %.3f s (up %.3f down %.3f) "
                        "pairs/N %.0f conv/N %.1f error %.2e\n",
                        to_string(m), cloud, tol, n, threads, t_setup, t, st.upward_seconds, st.downward_seconds,
                        double(st.pair_interactions) / n, double(st.m2l) / n,
                        phases["error"]);
            std::fflush(stdout);
          }
          omp_set_num_threads(max_threads);
          res.write(opt.out);  // after every block: a long run killed midway keeps its rows
        }
      }
    }
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
