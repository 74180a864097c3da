// Benchmark: periodic far field by PME (ewald/pme.hpp) against N, F/FTS, tolerance and 1-2
// threads, with the achieved error of every product, the dense Ewald sum (ewald_reference.hpp) for
// small N, and the open-domain direct product as the O(N^2) scale. Charted by bench/plot_ewald.py.
//
// Rows (Results params are numbers; "kind" tells them apart):
//   kind 0, PME: params N, threads, dof, tol, grid M0, support P, pairs, error, reference;
//     phases "setup" (PmeFarField constructor: neighbour list, pair scalars, windows, FFTW plans),
//     "wave" (spread, FFT, kernel, inverse FFT, interpolate), "real" (real-space pairs + self),
//     "product" (apply = wave + real), "direct" (the kind-2 time at the same N and threads, kept
//     in the PME rows as before).
//     error = ||M_pme x - M_ref x|| / ||M_ref x|| for a random x (uniform in [-1, 1]^dN);
//     reference 0: M_ref = dense Ewald matrix (the N of the kind-1 rows, N <= 400);
//     reference 1: M_ref x = PME product at tolerance 1e-12. tests/test_ewald.cpp shows the PME
//     meets its tolerance against the Ewald sum from 1e-2 to 1e-10 (errors 0.01-0.15 x tol), so
//     a 1e-12 product is a reference to ~1e-12; the kind-1 rows record its error against Ewald
//     ("pme12_error") at the small N where both exist.
//   kind 1, dense Ewald (1 thread): phases "build" (ewald_mobility, the whole matrix) and
//     "product" (dense matvec); params N, threads, dof, pme12_error.
//   kind 2, direct open-domain mobility_product (N <= 8000): phase "product"; params N, threads, dof.
// Configuration: random centres (overlaps allowed), volume fraction 0.1, radii 0.5-1.5, cubic box.
//   bench_ewald [--quick] [--out DIR]
// --quick (~1 minute on one free core): N = 50, 100 (Ewald and PME), 500, 1000, 2000 (PME);
// tol 1e-2, 1e-4, 1e-6; one timed repeat. The dense Ewald build costs ~N^2 (measured on one busy
// core: about 0.1 ms per pair for F, 0.6 ms for FTS), so its quick sizes stop at 100; the full run
// goes to 400 (FTS build there: ~1-2 minutes).
#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "ewald/ewald_reference.hpp"
#include "ewald/pme.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

using namespace stokesian;

namespace {
double rel_error(const VecX& y, const VecX& ref) { return (y - ref).norm() / ref.norm(); }
}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  const bool quick = opt.quick;
  const std::string out = opt.out;
  const std::vector<long> sizes = quick ? std::vector<long>{50, 100, 500, 1000, 2000}
                                        : std::vector<long>{100, 200, 1000, 2000, 4000, 8000};
  const std::vector<long> ewald_sizes = quick ? std::vector<long>{50, 100} : std::vector<long>{100, 200};
  const std::vector<double> tolerances =
      quick ? std::vector<double>{1e-2, 1e-4, 1e-6} : std::vector<double>{1e-2, 1e-3, 1e-4, 1e-6, 1e-8};
  constexpr double kReferenceTol = 1e-12;
  bench::Results res(quick ? "ewald_pme_quick" : "ewald_pme");
  const int max_threads = std::min(2, omp_get_max_threads());
  for (Moments m : {Moments::F, Moments::FTS}) {
    const int dof = dof_per_particle(m);
    for (long n : sizes) {
      const double L = std::cbrt(double(n) * 4.19 * 1.25 / 0.1);  // <a^3> = 1.25 for a in [0.5, 1.5]
      const bench::Cloud cloud = bench::random_cloud(n, L, std::uint64_t(n));
      const std::vector<Vec3>& x = cloud.x;
      const std::vector<double>& a = cloud.a;
      Domain dom;
      dom.kind = Domain::Kind::periodic;
      dom.box = Vec3(L, L, L);
      const VecX v = VecX::Random(n * dof);
      VecX y, yref;

      // Reference product (and, for small N, the timed dense Ewald rows).
      const bool ewald = std::find(ewald_sizes.begin(), ewald_sizes.end(), n) != ewald_sizes.end();
      if (ewald) {
        omp_set_num_threads(1);
        MatX M;
        const double build = bench::time_once([&] { M = ewald::ewald_mobility(x, a, 1.0, m, dom); });
        const double product = bench::median_time([&] { yref.noalias() = M * v; }, quick ? 3 : 5);
        omp_set_num_threads(max_threads);
        ewald::PmeFarField(x, a, 1.0, m, dom, kReferenceTol).apply(v, y);
        const double pme12 = rel_error(y, yref);
        res.add({{"kind", 1}, {"N", double(n)}, {"threads", 1}, {"dof", double(dof)}, {"pme12_error", pme12}},
                {{"build", build}, {"product", product}});
        std::printf("%-3s N=%5ld ewald (1 thread) build %.3f product %.5f s; PME %.0e vs Ewald %.2e\n",
                    to_string(m), n, build, product, kReferenceTol, pme12);
      } else {
        omp_set_num_threads(max_threads);  // untimed
        ewald::PmeFarField(x, a, 1.0, m, dom, kReferenceTol).apply(v, yref);
      }
      std::fflush(stdout);

      // Direct open-domain product, the O(N^2) scale.
      std::map<int, double> direct;
      if (n <= 8000) {
        for (int threads = 1; threads <= max_threads; ++threads) {
          omp_set_num_threads(threads);
          direct[threads] = bench::median_time([&] { mobility_product(x, a, 1.0, m, v, y); }, 1);
          res.add({{"kind", 2}, {"N", double(n)}, {"threads", double(threads)}, {"dof", double(dof)}},
                  {{"product", direct[threads]}});
        }
      }

      for (double tol : tolerances) {
        for (int threads = 1; threads <= max_threads; ++threads) {
          omp_set_num_threads(threads);
          const int reps = quick ? 1 : n <= 4000 ? 3 : 1;
          std::map<std::string, double> phases;
          std::unique_ptr<ewald::PmeFarField> pme;
          phases["setup"] = bench::time_once([&] { pme = std::make_unique<ewald::PmeFarField>(x, a, 1.0, m, dom, tol); });
          phases["wave"] = bench::median_time([&] { pme->apply_wave(v, y); }, reps);
          phases["real"] = bench::median_time([&] { pme->apply_real(v, y); }, reps);
          phases["product"] = bench::median_time([&] { pme->apply(v, y); }, reps);  // leaves y = M_pme v
          if (direct.count(threads)) phases["direct"] = direct[threads];
          const double err = rel_error(y, yref);
          const auto& p = pme->parameters();
          res.add({{"kind", 0},
                   {"N", double(n)},
                   {"threads", double(threads)},
                   {"dof", double(dof)},
                   {"tol", tol},
                   {"grid", double(p.grid[0])},
                   {"support", double(p.support)},
                   {"pairs", double(pme->real_pairs())},
                   {"error", err},
                   {"reference", ewald ? 0.0 : 1.0}},
                  phases);
          std::printf("%-3s N=%5ld tol=%.0e threads=%d setup %.3f wave %.3f real %.3f product %.3f direct %.3f s"
                      " (M=%d P=%d) error %.2e vs %s\n",
                      to_string(m), n, tol, threads, phases["setup"], phases["wave"], phases["real"],
                      phases["product"], direct.count(threads) ? direct[threads] : 0.0, p.grid[0], p.support, err,
                      ewald ? "Ewald" : "PME 1e-12");
          std::fflush(stdout);
        }
      }
    }
  }
  std::printf("wrote %s\n", res.write(out).c_str());
  return 0;
}
