// Benchmark: direct far-field mobility (open domain) against N, F/FT/FTS, 1 and 2 threads; dense
// assembly for small N as the reference cost. Phases: "step" (one full time step of a settling
// cloud through the run driver: forces, hydrodynamic solve -- for FTS the CG stresslet solve --
// and the Euler update), "product" (matrix-free y = M x), "dense_assembly" (dense_mobility),
// "dense_matvec" (M x with the assembled matrix).
//   bench_far_field [--quick] [--out DIR]
// BENCH_DIRECT=reference times the plain twin (mobility_product_reference, one apply_pair per
// ordered pair) instead of the vectorised product, into far_field_direct_reference.json.
#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>

using namespace stokesian;

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  const bool quick = opt.quick;
  const std::string out = opt.out;
  const std::vector<long> sizes = quick ? std::vector<long>{100, 200, 400} : std::vector<long>{100, 200, 400, 800, 1600, 3200, 6400};
  const char* which = std::getenv("BENCH_DIRECT");
  const bool reference = which && std::string(which) == "reference";
  if (reference) force_direct_kernels(DirectKernels::reference);
  bench::Results res(std::string(quick ? "far_field_direct_quick" : "far_field_direct") + (reference ? "_reference" : ""));
  const int max_threads = std::min(2, omp_get_max_threads());
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    for (long n : sizes) {
      // Random non-overlapping-ish cloud at volume fraction 0.1, radii 0.5-1.5.
      const double L = std::cbrt(double(n) * 4.19 / 0.1);
      const bench::Cloud cloud = bench::random_cloud(n, L, std::uint64_t(n));
      const std::vector<Vec3>& x = cloud.x;
      const std::vector<double>& a = cloud.a;
      VecX v = VecX::Random(n * dof_per_particle(m)), y;
      for (int threads = 1; threads <= max_threads; ++threads) {
        omp_set_num_threads(threads);
        const int reps = n <= 800 ? 5 : 3;
        std::map<std::string, double> phases;
        phases["product"] = bench::median_time([&] { mobility_product(x, a, 1.0, m, v, y); }, reps);
        if (n <= (m == Moments::FTS ? 800 : 3200)) {  // a CG stresslet solve costs ~40 products
          std::ostringstream t;
          t << "[particles]\ngenerate = \"random\"\ncount = " << n << "\nvolume_fraction = 0.1\nseed = 3\n"
            << "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n[hydrodynamics]\nmodel = \"far_field\"\nmoments = \""
            << to_string(m) << "\"\ntolerance = 1e-6\n[time]\ndt = 0.01\n";
          Simulation sim(io::parse_scene(t.str(), "bench.toml"));
          State s = sim.initial_state();
          phases["step"] = bench::median_time([&] { sim.advance(s, sim.evaluate(s, s.position)); }, n <= 800 ? 3 : 1);
        }
        if (n <= 1600 && threads == 1) {
          MatX M;
          phases["dense_assembly"] = bench::median_time([&] { M = dense_mobility(x, a, 1.0, m); }, 1);
          phases["dense_matvec"] = bench::median_time([&] { y = M * v; }, reps);
        }
        res.add({{"N", double(n)}, {"threads", double(threads)}, {"dof", double(dof_per_particle(m))}}, phases);
        std::printf("%-3s N=%5ld threads=%d product %.3e s", to_string(m), n, threads, phases["product"]);
        if (phases.count("step")) std::printf(" step %.3e s", phases["step"]);
        std::printf("\n");
        std::fflush(stdout);
      }
    }
  }
  std::printf("wrote %s\n", res.write(out).c_str());
  return 0;
}
