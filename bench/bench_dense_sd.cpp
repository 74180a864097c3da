// Benchmark: one dense Stokesian-dynamics solve (engine/sd_dense.hpp), FTS, open domain, the
// reference solver `auto` gives small scenes. Phases (seconds, median of repeats):
//   "assembly"      dense far-field mobility M_inf (DirectFarField::dense()) on its own;
//   "near_field"    the pairwise lubrication matrix R_nf (NearField::assemble) on its own;
//   "prepare"       DenseStokesianDynamics::prepare (assembly + near field + factorisation);
//   "factorisation" prepare - assembly - near_field (the dense linear algebra of prepare);
//   "solve"         the first DenseStokesianDynamics::solve after prepare (mobility problem: given
//                   forces and torques, E_inf = 0), including any factorisation it does;
//   "total"         prepare + solve, the cost of one configuration.
// Medians over 5 repeats (2 at N = 800) after an untimed warm-up; the solver persists across
// repeats (its storage is reused, as in a run) while the configuration alternates.
// Scene: N equal spheres (a = 1) placed at random (trees/placement.hpp, Monte Carlo equilibrated)
// in an open sphere at volume fraction 0.1, constant force on every particle, shear-free.
// Rows: N, threads (the OpenMP thread count; OpenBLAS-OpenMP follows it).
//   bench_dense_sd [--quick] [--out DIR]
#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "engine/sd_dense.hpp"
#include "lubrication/near_field.hpp"
#include "trees/placement.hpp"

#include <omp.h>

#include <algorithm>
#include <cstdio>

using namespace stokesian;

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "dense_sd_quick" : "dense_sd");
  const std::vector<long> sizes = opt.quick ? std::vector<long>{100} : std::vector<long>{100, 200, 400, 800};
  const int max_threads = std::min(2, omp_get_max_threads());
  const Moments m = Moments::FTS;
  for (long n : sizes) {
    PlacementParams pp;
    pp.count = n;
    pp.volume_fraction = 0.1;
    pp.seed = 7;
    pp.equilibration_sweeps = 20;
    const Placement pl = place_particles(pp, Vec3::Zero());
    const Configuration c{pl.position, pl.radius, Domain{}};
    std::vector<Vec3> x1 = pl.position;
    for (Vec3& p : x1) p += Vec3(1e-6, -1e-6, 1e-6);  // a nearby configuration: set-up is redone
    const Configuration c1{x1, pl.radius, Domain{}};
    const std::vector<char> fixed;
    FlowSample flow;
    flow.u.assign(std::size_t(n), Vec3::Zero());
    flow.omega.assign(std::size_t(n), Vec3::Zero());
    flow.E.assign(std::size_t(n), Vec5::Zero());
    const std::vector<Vec3> F(std::size_t(n), Vec3(0.0, 0.0, -1.0)), T(std::size_t(n), Vec3::Zero());
    const int reps = n <= 400 ? 5 : 2;
    for (int threads = 1; threads <= max_threads; ++threads) {
      omp_set_num_threads(threads);
      std::map<std::string, double> ph;
      // One solver (and far-field operator) kept across repeats, as in a run; the configuration
      // alternates between two nearby ones so that every repeat redoes the whole set-up, and each
      // solve is the first at its configuration (a solver may keep factors between solves at one
      // configuration; those are not what is measured).
      bool flip = false;
      DirectFarField ff(MobilitySpec{m, 1.0, 0.0});
      ph["assembly"] = bench::median_time(
          [&] {
            flip = !flip;
            ff.set_configuration(flip ? c1 : c);
            (void)ff.dense();
          },
          reps);
      lubrication::NearField near(m, 1.0);
      ph["near_field"] = bench::median_time([&] { (void)near.assemble(c.x, c.a, c.domain); }, reps);
      HydroResult r;
      std::vector<double> tp, ts, tt;
      DenseStokesianDynamics sd(m, 1.0, AmbientFlow{});
      for (int rep = 0; rep <= reps; ++rep) {  // repeat 0: warm-up, not counted
        flip = !flip;
        const Configuration& cf = flip ? c1 : c;
        const double p = bench::time_once([&] { sd.prepare(cf); });
        const double q = bench::time_once([&] { r = sd.solve(HydroProblem{cf, fixed, flow, F, T}); });
        if (rep == 0) continue;
        tp.push_back(p);
        ts.push_back(q);
        tt.push_back(p + q);
      }
      auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
      };
      ph["prepare"] = median(tp);
      ph["solve"] = median(ts);
      ph["total"] = median(tt);
      ph["factorisation"] = ph["prepare"] - ph["assembly"] - ph["near_field"];
      res.add({{"N", double(n)}, {"threads", double(threads)}}, ph);
      std::printf("N=%5ld threads=%d total %.3e s: assembly %.2e, near field %.2e, factorisation %.2e, solve %.2e "
                  "(U_z[0] = %.12f)\n",
                  n, threads, ph["total"], ph["assembly"], ph["near_field"], ph["factorisation"], ph["solve"],
                  r.U[0].z());
      std::fflush(stdout);
    }
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
