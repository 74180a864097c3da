#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "trees/tree_mobility.hpp"
#include <omp.h>
#include <cstdio>
#include <cstdlib>
using namespace stokesian;
int main(int argc, char** argv) {
  long n = std::atol(argv[1]);
  Moments m = argv[2][0]=='F' && argv[2][1]==0 ? Moments::F : (std::string(argv[2])=="FT"? Moments::FT: Moments::FTS);
  double phi = std::atof(argv[3]);
  const double L = std::cbrt(double(n) * 4.19*1.25 / phi);
  auto cloud = bench::random_cloud(n, L, 5);
  VecX v = VecX::Random(n * dof_per_particle(m)), yd, yt;
  double td = n <= 20000 ? bench::time_once([&]{ mobility_product(cloud.x, cloud.a, 1.0, m, v, yd); }) : 0;
  if (n > 20000) { trees::TreeParameters pr{0.3, 10, 32}; MobilitySpec sp; sp.moments = m; trees::TreeFarField tr(sp, pr); Domain o; tr.set_configuration({cloud.x, cloud.a, o}); tr.apply(v, yd); }
  std::printf("direct %.3f s\n", td);
  Domain open;
  for (int i = 4; i + 3 < argc; i += 4) {
    trees::TreeParameters p{std::atof(argv[i]), std::atoi(argv[i+1]), std::atoi(argv[i+2]), argv[i+3][0]=='b' ? trees::TreeEvaluation::barnes_hut : trees::TreeEvaluation::fmm};
    MobilitySpec spec; spec.moments = m;
    trees::TreeFarField t(spec, p);
    double tb = bench::time_once([&]{ t.set_configuration({cloud.x, cloud.a, open}); });
    double ta = bench::time_once([&]{ t.apply(v, yt); });
    std::printf("theta %.2f p %d leaf %d: build %.3f apply %.3f err %.2e nodes %ld pairs %ld m2l %ld up %.3f down %.3f\n", p.theta, p.order, p.leaf_size, tb, ta,
      (yt-yd).norm()/yd.norm(), t.last_stats().node_interactions, t.last_stats().pair_interactions, t.last_stats().m2l, t.last_stats().upward_seconds, t.last_stats().downward_seconds);
  }
}
