// Benchmark: one step's phase graph (engine/simulation.cpp) run as OpenMP tasks against the same
// phases one after another, on the existing solvers. Phases: "forces" (external + pair forces,
// neighbour search), "hydro_setup" (far-field operator set-up, near-field assembly, dense
// factorisation), "diagnostics" (gap statistics of an output step), "solve"; "evaluation" is the
// whole evaluation at one configuration (the configuration alternates between two nearby ones so
// that every evaluation pays its set-up). Rows: scene, N, threads, mode (0 serial, 1 tasks).
//   bench_step [--quick] [--out DIR]
#include "bench/harness.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <sstream>

using namespace stokesian;

namespace {

struct SceneCase {
  const char* name;
  std::vector<long> sizes, quick_sizes;
  std::string (*toml)(long n);
};

double box_side(long n, double phi) { return std::cbrt(double(n) * 4.0 / 3.0 * kPi / phi); }

std::string dense_sd(long n) {
  std::ostringstream t;
  t << "[particles]\ngenerate = \"random\"\ncount = " << n << "\nvolume_fraction = 0.1\nseed = 7\n"
    << "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n[[forces.pair]]\nkind = \"hertz\"\n"
    << "[hydrodynamics]\nmodel = \"stokesian\"\n";
  return t.str();
}
std::string pme_shear(long n) {
  const double L = box_side(n, 0.2);
  std::ostringstream t;
  t << "[domain]\nkind = \"periodic\"\nbox = [" << L << ", " << L << ", " << L << "]\n"
    << "[particles]\ngenerate = \"random\"\ncount = " << n << "\nseed = 7\n[[forces.pair]]\nkind = \"hertz\"\n"
    << "[flow]\nkind = \"simple_shear\"\nrate = 0.1\n[hydrodynamics]\nmodel = \"far_field\"\nmoments = \"FT\"\n"
    << "tolerance = 1e-4\n";
  return t.str();
}
std::string direct_morse(long n) {
  std::ostringstream t;
  t << "[particles]\ngenerate = \"random\"\ncount = " << n << "\nvolume_fraction = 0.1\nseed = 7\n"
    << "[[forces.pair]]\nkind = \"morse\"\n[[forces.pair]]\nkind = \"hertz\"\n"
    << "[hydrodynamics]\nmodel = \"far_field\"\nmoments = \"F\"\n";
  return t.str();
}
std::string free_draining_dlvo(long n) {
  const double L = box_side(n, 0.2);
  std::ostringstream t;
  t << "[domain]\nkind = \"periodic\"\nbox = [" << L << ", " << L << ", " << L << "]\n"
    << "[fluid]\nkT = 1.0\n[particles]\ngenerate = \"random\"\ncount = " << n << "\nseed = 7\n"
    << "[[forces.pair]]\nkind = \"dlvo\"\n[[forces.pair]]\nkind = \"hertz\"\n"
    << "[hydrodynamics]\nmodel = \"free_draining\"\nmoments = \"F\"\n";
  return t.str();
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "step_graph_quick" : "step_graph");
  const SceneCase cases[] = {{"dense_sd", {64, 128, 256}, {64}, dense_sd},
                             {"pme_shear", {500, 2000, 8000}, {500}, pme_shear},
                             {"direct_morse", {500, 1000, 2000}, {500}, direct_morse},
                             {"free_draining_dlvo", {2000, 8000, 32000}, {2000}, free_draining_dlvo}};
  const int max_threads = std::min(2, omp_get_max_threads());
  int scene_id = 0;
  for (const SceneCase& sc : cases) {
    for (long n : opt.quick ? sc.quick_sizes : sc.sizes) {
      Simulation sim(io::parse_scene(sc.toml(n), std::string(sc.name) + ".toml"));
      const State s = sim.initial_state();
      std::vector<Vec3> x1 = s.position;
      for (Vec3& p : x1) p += Vec3(1e-6, -1e-6, 1e-6);  // a nearby configuration: set-up is redone
      for (int threads = 1; threads <= max_threads; ++threads) {
        omp_set_num_threads(threads);
        for (int mode = 0; mode < (threads > 1 ? 2 : 1); ++mode) {
          sim.set_task_mode(mode ? TaskGraph::Mode::automatic : TaskGraph::Mode::serial);
          bool flip = false;
          std::map<std::string, double> phases;
          const int reps = n <= 2000 ? 5 : 3;
          phases["evaluation"] = bench::median_time(
              [&] {
                flip = !flip;
                sim.evaluate(s, flip ? x1 : s.position, 0.0, true);
              },
              reps);
          const PhaseTimes& pt = sim.phase_times();
          for (std::size_t k = 0; k < pt.names.size(); ++k) phases[pt.names[k]] = pt.seconds[k];
          res.add({{"scene", double(scene_id)}, {"N", double(n)}, {"threads", double(threads)}, {"mode", double(mode)}},
                  phases);
          std::printf("%-19s N=%6ld threads=%d %-6s evaluation %.3e s (forces %.2e, setup %.2e, diagnostics %.2e, solve %.2e)\n",
                      sc.name, n, threads, mode ? "tasks" : "serial", phases["evaluation"], phases["forces"],
                      phases["hydro_setup"], phases["diagnostics"], phases["solve"]);
          std::fflush(stdout);
        }
      }
    }
    ++scene_id;
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
