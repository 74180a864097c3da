// Benchmark: accelerated Stokesian dynamics (engine/sd_accelerated.hpp) in periodic boxes with the
// PME far field, FTS, under the simple-shear ambient flow (one deterministic mobility solve: loads
// on every particle, the ambient strain, stresslets solved for).
//   "krylov"  GMRES vs BiCGStab and the shift B = s D (s = 0.1 ... 3): iterations and far-field
//             products per solve against phi (the evidence for the choice in sd_accelerated.hpp);
//   "crossover" dense vs accelerated per solve (open and periodic, phi = 0.3): the N where
//             `solver = "auto"` switches (engine/model.cpp);
//   "scaling" time per solve against N (phases: far-field set-up, near-field assembly, CHOLMOD
//             factorisation, Krylov iterations), iterations, products, factor fill, 1 vs 2 threads,
//             phi = 0.1, 0.3, 0.45; the dense SD solver beside it where it fits (N <= dense_max).
// Rows carry `section` (0 krylov, 1 scaling, 2 crossover), N, phi, threads, method (0 gmres, 1 bicgstab),
// shift, dense (1 for the dense solver). Usage: bench_asd [--quick] [--out DIR]; BENCH_MAX_N=N caps the
// sizes; BENCH_MIN_N=N runs only the scaling section from N on (results asd_from_<N>.json)
#include "bench/harness.hpp"
#include "engine/accuracy.hpp"
#include "engine/core/flow.hpp"
#include "engine/methods.hpp"
#include "engine/sd_accelerated.hpp"
#include "engine/sd_dense.hpp"
#include "trees/placement.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

using namespace stokesian;
using bench::Results;

namespace {

struct Suspension {
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain domain;
};

Suspension suspension(long n, double phi, std::uint64_t seed, bool periodic = true) {
  PlacementParams p;
  p.count = n;
  p.seed = seed;
  p.min_gap = 1e-3;
  p.equilibration_sweeps = 20;
  const double L = std::cbrt(double(n) * 4.0 / 3.0 * kPi / phi);
  const Placement pl = place_particles(p, Vec3(L, L, L));
  Suspension s;
  s.x = pl.position;
  s.a = pl.radius;
  if (periodic) {
    s.domain.kind = Domain::Kind::periodic;
    s.domain.box = pl.box;
  }
  return s;
}

struct Run {
  AcceleratedSdStats stats;
  double seconds = 0.0;  // prepare + solve
};

Run run_accelerated(const Suspension& s, double tol, double shift, AcceleratedStokesianDynamics::Method method,
                    double factor_gap = AcceleratedStokesianDynamics::kFactorGap) {
  const double mu = 1.0;
  const AccuracyKnobs k = derive_knobs(tol, HydroModel::stokesian, 1.0, false);
  auto op = far_field_methods().find(s.domain.periodic() ? "pme" : "direct")->make(MobilitySpec{Moments::FTS, mu, k.far_field});
  AcceleratedStokesianDynamics sd(std::move(op), mu, lubrication::NearFieldParams{}, k.krylov, shift, method,
                                  factor_gap);
  FlowParams fp;
  fp.kind = FlowParams::Kind::simple_shear;
  fp.rate = 1.0;
  const AmbientFlow flow = ambient_flow(fp);
  FlowSample sample;
  flow.sample(s.x, sample);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  std::vector<Vec3> F, T(s.x.size(), Vec3::Zero());
  for (std::size_t i = 0; i < s.x.size(); ++i) F.emplace_back(g(rng), g(rng), g(rng));
  const std::vector<char> fixed;
  const Configuration c{s.x, s.a, s.domain};
  Run r;
  r.seconds = bench::time_once([&] {
    sd.prepare(c);
    sd.solve(HydroProblem{c, fixed, sample, F, T});
  });
  r.stats = sd.stats();
  return r;
}

double run_dense(const Suspension& s) {
  const double mu = 1.0;
  FlowParams fp;
  fp.kind = FlowParams::Kind::simple_shear;
  fp.rate = 1.0;
  const AmbientFlow flow = ambient_flow(fp);
  DenseStokesianDynamics sd(Moments::FTS, mu, flow);
  std::vector<Vec3> F(s.x.size(), Vec3(0, 0, 1)), T(s.x.size(), Vec3::Zero());
  return bench::time_once([&] { sd.mobility_problem(s.x, s.a, {}, F, T, s.domain); });
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  long max_n = opt.quick ? 2000 : 100000, dense_max = opt.quick ? 0 : 400;
  if (const char* e = std::getenv("BENCH_MAX_N")) max_n = std::atol(e);
  long min_n = 0;  // BENCH_MIN_N: skip the krylov and crossover sections and smaller sizes
  if (const char* e = std::getenv("BENCH_MIN_N")) min_n = std::atol(e);
  const int max_threads = omp_get_max_threads();
  Results res(opt.quick ? "asd_quick" : std::getenv("BENCH_MIN_N") ? "asd_from_" + std::string(std::getenv("BENCH_MIN_N")) : "asd");
  const double tol = 1e-4;

  // Krylov method, shift and the gap beyond which pairs leave the factorised matrix.
  for (double phi : {0.1, 0.3, 0.45}) {
    if (std::getenv("BENCH_SKIP_KRYLOV") || min_n > 0) break;
    const long n = opt.quick ? 500 : 2000;
    const Suspension s = suspension(n, phi, 11);
    for (int method = 0; method < 2; ++method)
      for (double shift : {0.3, 1.0, 3.0, 10.0})
        for (double gap : {1e300, 0.5, 0.1, 0.02}) {
          if (opt.quick && ((shift != 1.0 && shift != 3.0) || gap == 0.5 || gap == 0.02)) continue;
          if (method == 1 && (shift != 1.0 || gap < 1e300)) continue;
          const Run r = run_accelerated(s, tol, shift,
                                        method ? AcceleratedStokesianDynamics::Method::bicgstab
                                               : AcceleratedStokesianDynamics::Method::gmres,
                                        gap);
          const double g = gap < 1e300 ? gap : -1.0;  // -1: every pair inside the cutoff
          std::printf("krylov phi %.2f N %ld %s shift %.1f factor_gap %g: iterations %d products %d fill %ld "
                      "factor %.3f s krylov %.3f s\n",
                      phi, n, method ? "bicgstab" : "gmres", shift, g, r.stats.iterations, r.stats.far_field_products,
                      r.stats.factor_nonzeros, r.stats.seconds_factorisation, r.stats.seconds_krylov);
          res.add({{"section", 0}, {"N", double(n)}, {"phi", phi}, {"threads", max_threads}, {"method", method},
                   {"shift", shift}, {"factor_gap", g}, {"dense", 0}, {"tolerance", tol}},
                  {{"krylov", r.stats.seconds_krylov}, {"factorisation", r.stats.seconds_factorisation},
                   {"iterations", r.stats.iterations}, {"products", r.stats.far_field_products},
                   {"factor_nonzeros", double(r.stats.factor_nonzeros)}});
        }
  }
  // Scaling.
  std::vector<long> sizes = opt.quick ? std::vector<long>{500, 1000}
                                      : std::vector<long>{1000, 2000, 5000, 10000, 20000, 50000, 100000};
  for (double phi : {0.1, 0.3, 0.45})
    for (long n : sizes) {
      if (n > max_n || n < min_n) continue;
      const Suspension s = suspension(n, phi, 13);
      for (int threads : {1, max_threads}) {
        if (threads == 1 && max_threads == 1) continue;
        if (threads == 1 && n > 20000) continue;  // the thread ratio is measured up to 2e4
        omp_set_num_threads(threads);
        const Run r = run_accelerated(s, tol, 1.0, AcceleratedStokesianDynamics::Method::gmres);
        std::printf("scaling phi %.2f N %6ld threads %d: %.3f s (far %.3f, near %.3f, factor %.3f, krylov %.3f), "
                    "iterations %d, products %d, fill %ld\n",
                    phi, n, threads, r.seconds, r.stats.seconds_far_field_setup, r.stats.seconds_near_field_assembly,
                    r.stats.seconds_factorisation, r.stats.seconds_krylov, r.stats.iterations,
                    r.stats.far_field_products, r.stats.factor_nonzeros);
        res.add({{"section", 1}, {"N", double(n)}, {"phi", phi}, {"threads", threads}, {"method", 0}, {"shift", 1.0},
                 {"dense", 0}, {"tolerance", tol}},
                {{"total", r.seconds},
                 {"far_field_setup", r.stats.seconds_far_field_setup},
                 {"near_field_assembly", r.stats.seconds_near_field_assembly},
                 {"factorisation", r.stats.seconds_factorisation},
                 {"krylov", r.stats.seconds_krylov},
                 {"iterations", r.stats.iterations},
                 {"products", r.stats.far_field_products},
                 {"factor_nonzeros", double(r.stats.factor_nonzeros)}});
        if (n <= dense_max) {
          const double t = run_dense(s);
          std::printf("dense   phi %.2f N %6ld threads %d: %.3f s\n", phi, n, threads, t);
          res.add({{"section", 1}, {"N", double(n)}, {"phi", phi}, {"threads", threads}, {"dense", 1}},
                  {{"total", t}});
        }
      }
      omp_set_num_threads(max_threads);
    }
  // Crossover of `solver = "auto"` (engine/model.cpp): dense vs accelerated per solve, FTS, phi 0.3.
  for (int periodic = 0; periodic < (min_n > 0 ? 0 : 2); ++periodic)
    for (long n : periodic ? std::vector<long>{50, 100, 150, 200, 300} : std::vector<long>{25, 50, 75, 100, 200, 300, 400, 600}) {
      if (opt.quick && n > 200) continue;
      const Suspension s = suspension(n, 0.3, 17, periodic != 0);
      const Run r = run_accelerated(s, tol, AcceleratedStokesianDynamics::kShift, AcceleratedStokesianDynamics::Method::gmres);
      const double t = run_dense(s);
      std::printf("crossover %s N %4ld: accelerated %.3f s, dense %.3f s, ratio %.2f\n", periodic ? "periodic" : "open", n,
                  r.seconds, t, r.seconds / t);
      res.add({{"section", 2}, {"N", double(n)}, {"phi", 0.3}, {"periodic", double(periodic)}, {"threads", max_threads}},
              {{"accelerated", r.seconds}, {"dense", t}});
    }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
