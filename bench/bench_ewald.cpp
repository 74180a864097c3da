// Benchmark: periodic far field by PME (ewald/pme.hpp) against N, F/FTS, tolerance and 1-2
// threads, with the open-domain direct product as the O(N^2) scale. Phases: "setup" (PmeFarField
// constructor: neighbour list, pair scalars, windows, FFTW plans), "wave" (spread, FFT, kernel,
// inverse FFT, interpolate), "real" (real-space pairs + self), "product" (apply = wave + real),
// "direct" (mobility_product, open domain, N <= 8000). Parameters stored per row: grid M0,
// support P, real-space pairs.
//   bench_ewald [--quick] [--out DIR]
#include "bench/harness.hpp"
#include "engine/far_field.hpp"
#include "ewald/pme.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

using namespace stokesian;

int main(int argc, char** argv) {
  bool quick = false;
  std::string out = "bench/results";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
  }
  const std::vector<long> sizes =
      quick ? std::vector<long>{500, 1000, 2000} : std::vector<long>{1000, 2000, 4000, 8000, 16000};
  bench::Results res(quick ? "ewald_pme_quick" : "ewald_pme");
  const int max_threads = std::min(2, omp_get_max_threads());
  for (Moments m : {Moments::F, Moments::FTS}) {
    for (long n : sizes) {
      // Random cloud (overlaps allowed) at volume fraction 0.1, radii 0.5-1.5, cubic periodic box.
      std::mt19937_64 rng(n);
      std::uniform_real_distribution<double> u(0, 1);
      const double L = std::cbrt(double(n) * 4.19 * 1.25 / 0.1);  // <a^3> = 1.25 for a in [0.5, 1.5]
      std::vector<Vec3> x;
      std::vector<double> a;
      for (long i = 0; i < n; ++i) {
        x.emplace_back(L * u(rng), L * u(rng), L * u(rng));
        a.push_back(0.5 + u(rng));
      }
      Domain dom;
      dom.kind = Domain::Kind::periodic;
      dom.box = Vec3(L, L, L);
      const VecX v = VecX::Random(n * dof_per_particle(m));
      VecX y;
      for (double tol : {1e-3, 1e-6}) {
        for (int threads = 1; threads <= max_threads; ++threads) {
          omp_set_num_threads(threads);
          const int reps = n <= 4000 ? 3 : 1;
          std::map<std::string, double> phases;
          std::unique_ptr<ewald::PmeFarField> pme;
          phases["setup"] = bench::time_once([&] { pme = std::make_unique<ewald::PmeFarField>(x, a, 1.0, m, dom, tol); });
          phases["wave"] = bench::median_time([&] { pme->apply_wave(v, y); }, reps);
          phases["real"] = bench::median_time([&] { pme->apply_real(v, y); }, reps);
          phases["product"] = bench::median_time([&] { pme->apply(v, y); }, reps);
          if (n <= 8000) phases["direct"] = bench::median_time([&] { mobility_product(x, a, 1.0, m, v, y); }, 1);
          const auto& p = pme->parameters();
          res.add({{"N", double(n)},
                   {"threads", double(threads)},
                   {"dof", double(dof_per_particle(m))},
                   {"tol", tol},
                   {"grid", double(p.grid[0])},
                   {"support", double(p.support)},
                   {"pairs", double(pme->real_pairs())}},
                  phases);
          std::printf("%-3s N=%5ld tol=%.0e threads=%d setup %.3f wave %.3f real %.3f product %.3f direct %.3f s"
                      " (M=%d P=%d)\n",
                      to_string(m), n, tol, threads, phases["setup"], phases["wave"], phases["real"],
                      phases["product"], n <= 8000 ? phases["direct"] : 0.0, p.grid[0], p.support);
          std::fflush(stdout);
        }
      }
    }
  }
  std::printf("wrote %s\n", res.write(out).c_str());
  return 0;
}
