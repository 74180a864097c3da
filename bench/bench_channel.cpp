// Benchmark (issue 17): wall time per Brownian SD step of constrained Stokesian dynamics against
// the number of particles N = N_I + N_W, with interior fractions N_I/N = 1, 0.1, 0.01 (Lee et al.
// 2024 [L24] fig. 6; docs/channels.md).
//
// Scene (as [L24] fig. 6): a random hard-sphere dispersion at phi = 0.2 in a periodic box, radius 1,
// Brownian (kT = 1) in simple shear at Pe = 6 pi mu a^3 rate / kT = 1 (Lees-Edwards), no pair force
// but a Hertz backstop; the first N - N_I particles (in the generator's order, spread through the
// box) are held fixed, as [L24]'s "fraction of particles held at zero velocity". Model: Stokesian
// dynamics, FT, tolerance 1e-3, the Fixman integrator (two solves, near- and far-field noise),
// solver dense (N <= 500) and accelerated (all N), PME far field. One step = what Simulation::run
// does on a step without a frame: Simulation::evaluate_step_start (pair forces, overlap check; no
// deterministic solve, which the Fixman step with noise does not read) + advance (the solves at x0
// and at the midpoint, the second warm-started from the first); the first step (set-up) is not
// timed, then `steps` steps are averaged.
// Dense SD also runs the same scenes without the shear ("still": Brownian only), where the held
// particles' far-field block stays the same from one configuration to the next and its factor is
// kept (engine/sd_dense.hpp); under shear the Lees-Edwards strain changes it at every stage.
// Rows: solver (0 dense, 1 accelerated), N, fraction, N_I, threads, shear (1 sheared, 0 still);
// phases: seconds (per step); accelerated SD also its named phases per step from the solver's sums
// (AcceleratedSdStats::totals): far_field_setup, near_field_assembly, factorisation,
// held_preconditioner, krylov, far_noise, near_noise [s], and solves, gmres_iterations,
// far_field_products, lanczos_iterations; held_coarse_once [s], held_coarse_columns and
// warmup_steps: the held preconditioner's coarse part, built once it has paid
// (engine/sd_accelerated.hpp) during untimed steps before the timed ones (warmup_steps beyond the
// first). The plot script fits exponents per solver, shear and fraction and
// the speed-up from the constraint (time at fraction 1 over time at fraction f, same N).
// Usage: bench_channel [--quick] [--out DIR]; full: N = 100 ... 10000 (dense to 500), 3 steps;
// --quick: N = 60, 150, 1 step. BENCH_SOLVERS=dense (or accelerated) runs one solver only;
// BENCH_N=n runs that N only.
#include "bench/harness.hpp"
#include "engine/sd_accelerated.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>

using namespace stokesian;

namespace {

Scene make_scene(long n, double fraction, const std::string& solver, bool shear) {
  const double L = std::cbrt(double(n) * 4.0 / 3.0 * kPi / 0.2);
  std::ostringstream o;
  o.precision(10);
  o << "[domain]\nkind = \"periodic\"\nbox = [" << L << ", " << L << ", " << L << "]\n"
    << "[fluid]\nkT = 1.0\n[particles]\ngenerate = \"random\"\ncount = " << n << "\nseed = 5\n"
    << "[[forces.pair]]\nkind = \"hertz\"\nstiffness = 20000.0\n"
    << (shear ? "[flow]\nkind = \"simple_shear\"\npeclet = 1.0\n" : "")
    << "[hydrodynamics]\nmodel = \"stokesian\"\nsolver = \"" << solver << "\"\nmoments = \"FT\"\ntolerance = 1e-3\n"
    << "[brownian]\nstress_every = 0\n[time]\ndt = 1e-4\nsteps = 100\n";
  Scene s = io::parse_scene(o.str(), "bench_channel.toml");
  const long interior = std::max(1L, std::lround(fraction * double(n)));
  for (long i = 0; i < n - interior; ++i) s.fixed[std::size_t(i)] = 1;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "channel_quick" : "channel");
  std::vector<long> sizes = opt.quick ? std::vector<long>{60, 150} : std::vector<long>{100, 300, 500, 1000, 3000, 10000};
  if (const char* e = std::getenv("BENCH_N")) {
    const long n = std::atol(e);
    if (n < 10 || n > 1000000) {
      std::fprintf(stderr, "bench_channel: BENCH_N = \"%s\" must be a particle count from 10 to 1000000\n", e);
      return 1;
    }
    sizes = {n};
  }
  const int steps = opt.quick ? 1 : 3;
  const char* only = std::getenv("BENCH_SOLVERS");
  struct Series {
    const char* solver;
    bool shear;
  };
  for (const Series& se : {Series{"dense", true}, Series{"dense", false}, Series{"accelerated", true}}) {
    const std::string solver = se.solver;
    if (only && solver != only) continue;
    for (long n : sizes) {
      if (solver == "dense" && n > 500) continue;   // the dense solver's limit
      if (solver == "accelerated" && n == 500) continue;
      for (double f : {1.0, 0.1, 0.01}) {
        const Scene scene = make_scene(n, f, solver, se.shear);
        Simulation sim(scene);
        State s = sim.initial_state();
        {
          const Evaluation ev = sim.evaluate_step_start(s);
          sim.advance(s, ev);
        }
        // Accelerated SD: the solver's sums over the timed steps (named phases, GMRES iterations).
        const auto* asd = dynamic_cast<const AcceleratedStokesianDynamics*>(&sim.hydro_solver());
        // With held particles in more than one block the held preconditioner's coarse part is built
        // once it has paid (engine/sd_accelerated.hpp): untimed steps until then (at most 400), so the
        // timed steps are the run's steady state; the build and these steps are recorded.
        int warmup = 0;
        while (asd && asd->stats().held_clusters > 1 && asd->stats().held_coarse_columns == 0 && warmup < 400) {
          const Evaluation ev = sim.evaluate_step_start(s);
          sim.advance(s, ev);
          ++warmup;
        }
        const AcceleratedSdStats::Totals before = asd ? asd->stats().totals : AcceleratedSdStats::Totals{};
        const auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < steps; ++k) {
          const Evaluation ev = sim.evaluate_step_start(s);
          sim.advance(s, ev);
        }
        const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / steps;
        long ni = 0;
        for (char c : scene.fixed) ni += c == 0;
        std::printf("%-11s %-7s N %5ld  interior fraction %.2f (N_I %5ld): %.4f s per step\n", se.solver,
                    se.shear ? "sheared" : "still", n, f, ni, sec);
        std::fflush(stdout);
        std::map<std::string, double> ph{{"seconds", sec}};
        if (asd) {
          using T = AcceleratedSdStats::Totals;
          const T& a = asd->stats().totals;
          auto per_step = [&](auto T::*field) { return double(a.*field - before.*field) / double(steps); };
          for (auto [name, field] : {std::pair{"far_field_setup", &T::far_field_setup},
                                     {"near_field_assembly", &T::near_field_assembly},
                                     {"factorisation", &T::factorisation}, {"held_preconditioner", &T::held_preconditioner},
                                     {"krylov", &T::krylov}, {"far_noise", &T::far_noise}, {"near_noise", &T::near_noise}})
            ph[name] = per_step(field);
          for (auto [name, field] : {std::pair{"solves", &T::solves}, {"gmres_iterations", &T::iterations},
                                     {"far_field_products", &T::products}, {"lanczos_iterations", &T::lanczos_iterations}})
            ph[name] = per_step(field);
          // The held preconditioner's coarse part is built once, in the untimed step (its far-field
          // products), and kept while the held blocks are (a strain of 0.01 here: ~1900 steps).
          ph["held_coarse_once"] = a.held_coarse;
          ph["held_coarse_columns"] = double(asd->stats().held_coarse_columns);
          ph["warmup_steps"] = warmup;
          std::printf("    per step: %.1f solves, %.1f GMRES iterations (%.4f s), Lanczos %.1f (%.4f s), near noise %.4f s, "
                      "set-up %.4f s, held preconditioner %.4f s; coarse part: %.0f columns built in %.3f s after %d "
                      "untimed steps\n",
                      ph["solves"], ph["gmres_iterations"], ph["krylov"], ph["lanczos_iterations"], ph["far_noise"],
                      ph["near_noise"], ph["far_field_setup"] + ph["near_field_assembly"] + ph["factorisation"],
                      ph["held_preconditioner"], ph["held_coarse_columns"], ph["held_coarse_once"], warmup + 1);
        }
        res.add({{"solver", solver == "dense" ? 0.0 : 1.0}, {"N", double(n)}, {"fraction", f}, {"N_I", double(ni)},
                 {"threads", double(omp_get_max_threads())}, {"shear", se.shear ? 1.0 : 0.0}},
                ph);
      }
    }
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
