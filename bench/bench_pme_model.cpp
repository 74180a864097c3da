// What the PME cost model (ewald/pme_parameters.hpp) chooses from N = 10^4 to 10^6, and what a
// real-space scalar-cache budget that grows with N would change (issue 12: the measured time per
// product grows faster than N log N from 10^5 on). No timing: the model's parameters, its estimated
// cost per particle (one thread) and the real-space memory they imply, for three budgets:
//   budget 0: the engine's fixed 256 MB (RealSpaceSum::kDefaultCacheBytes);
//   budget 1: 8 kB per particle (at least 256 MB);
//   budget 2: unbounded.
// Real-space memory per particle: RealSpaceSum::pair_bytes_for and cache_bytes_for (the counts of
// engine/resources.cpp's estimate: the pair data twice, and the scalar cache when it fits).
// Configurations as bench_pme (unit spheres, cubic box, phi 0.1 and 0.4); F and FTS; tolerances
// 1e-3, 1e-4, 1e-6. Rows: moments (3 = F, 11 = FTS), phi, tol, N, budget; grid, support,
// neighbours (particles within the cutoff sphere), cached (0/1), cost_per_particle_us,
// real_bytes_per_particle. The driver prints the fitted exponent of the modelled cost over
// 10^4 ... 10^6 per series and budget.
//   bench_pme_model [--quick] [--out DIR]   (--quick: N = 10^4 and 10^5 only)
#include "bench/harness.hpp"
#include "ewald/lattice.hpp"
#include "ewald/pme_parameters.hpp"
#include "ewald/real_space.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

using namespace stokesian;

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "pme_model_quick" : "pme_model");
  const std::vector<long> sizes =
      opt.quick ? std::vector<long>{10000, 100000} : std::vector<long>{10000, 30000, 100000, 300000, 1000000};
  const double fixed = double(ewald::RealSpaceSum::kDefaultCacheBytes);
  std::printf("moments phi tol budget: modelled us per particle at N = ...; exponent; real-space kB per particle at the largest N\n");
  for (Moments m : {Moments::F, Moments::FTS})
    for (double phi : {0.1, 0.4})
      for (double tol : {1e-3, 1e-4, 1e-6})
        for (int budget = 0; budget < 3; ++budget) {
          std::printf("%-3s %.1f %.0e b%d:", m == Moments::F ? "F" : "FTS", phi, tol, budget);
          double first = 0, last = 0, bytes_last = 0;
          for (long n : sizes) {
            const double L = std::cbrt(double(n) * 4.0 * M_PI / 3.0 / phi);
            const ewald::Lattice lattice = ewald::Lattice::from_domain(Domain::periodic_box(Vec3(L, L, L)));
            ewald::PmeOptions o;
            o.cache_bytes = budget == 0 ? fixed : budget == 1 ? std::max(fixed, 8192.0 * double(n)) : 1e30;
            const ewald::PmeParameters p = ewald::pme_parameters(tol, lattice, int(n), 1.0, 1.0, m, o);
            const double rho = double(n) / lattice.volume;
            const double nb = std::min(double(n - 1), rho * 4.0 / 3.0 * M_PI * std::pow(p.cutoff_gap + 2.0, 3));
            const double cache = ewald::RealSpaceSum::cache_bytes_for(double(n) * nb, m);
            const bool cached = cache <= p.cache_bytes;
            const double bytes = (ewald::RealSpaceSum::pair_bytes_for(double(n) * nb) + (cached ? cache : 0.0)) / double(n);
            const double us = 1e6 * p.est_cost / double(n);
            std::printf("  %.2f", us);
            if (n == sizes.front()) first = p.est_cost;
            last = p.est_cost;
            bytes_last = bytes;
            res.add({{"moments", double(m == Moments::F ? 3 : 11)},
                     {"phi", phi},
                     {"tol", tol},
                     {"N", double(n)},
                     {"budget", double(budget)},
                     {"grid", double(p.grid[0])},
                     {"support", double(p.support)},
                     {"neighbours", nb},
                     {"cached", cached ? 1.0 : 0.0},
                     {"real_bytes_per_particle", bytes}},
                    {{"cost_per_particle_us", us}});
          }
          const double exponent = std::log(last / first) / std::log(double(sizes.back()) / double(sizes.front()));
          std::printf("; exponent %.3f; %.1f kB\n", exponent, bytes_last / 1024.0);
        }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
