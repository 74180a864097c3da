// Benchmark: PME at large N (F level, tol 1e-3 and 1e-4), N = 16000 ... 100000, 1 and 2 threads,
// with the direct O(N^2) product where it fits (N <= 32000) as the scale; extends bench_ewald
// (which stops at N = 8000) to the 10^5 end of the time-against-N chart. Phases: "setup", "product".
//   bench_pme_large [--quick] [--out DIR]      (--quick: N = 16000 only)
#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "ewald/pme.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

using namespace stokesian;

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  const std::vector<long> sizes = opt.quick ? std::vector<long>{16000} : std::vector<long>{16000, 32000, 64000, 100000};
  bench::Results res(opt.quick ? "pme_large_quick" : "pme_large");
  const int max_threads = std::min(2, omp_get_max_threads());
  const Moments m = Moments::F;
  for (long n : sizes) {
    // Same configuration family as bench_ewald: random centres, phi = 0.1, radii 0.5-1.5.
    const double L = std::cbrt(double(n) * 4.19 * 1.25 / 0.1);
    const bench::Cloud cloud = bench::random_cloud(n, L, std::uint64_t(n));
    const std::vector<Vec3>& x = cloud.x;
    const std::vector<double>& a = cloud.a;
    Domain dom;
    dom.kind = Domain::Kind::periodic;
    dom.box = Vec3(L, L, L);
    const VecX v = VecX::Random(n * 3);
    VecX y;
    for (int threads = 1; threads <= max_threads; ++threads) {
      omp_set_num_threads(threads);
      if (n <= 32000) {
        const double t = bench::time_once([&] { mobility_product(x, a, 1.0, m, v, y); });
        res.add({{"kind", 2}, {"N", double(n)}, {"threads", double(threads)}, {"dof", 3}}, {{"product", t}});
        std::printf("N=%6ld threads=%d direct %.3f s\n", n, threads, t);
      }
      for (double tol : {1e-3, 1e-4}) {
        std::unique_ptr<ewald::PmeFarField> pme;
        std::map<std::string, double> ph;
        ph["setup"] = bench::time_once([&] { pme = std::make_unique<ewald::PmeFarField>(x, a, 1.0, m, dom, tol); });
        ph["product"] = bench::median_time([&] { pme->apply(v, y); }, 1);
        res.add({{"kind", 0}, {"N", double(n)}, {"threads", double(threads)}, {"dof", 3}, {"tol", tol}}, ph);
        std::printf("N=%6ld threads=%d tol=%.0e PME setup %.3f product %.3f s\n", n, threads, tol, ph["setup"], ph["product"]);
        std::fflush(stdout);
      }
    }
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
