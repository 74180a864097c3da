// Benchmark: cost of one Brownian Stokesian-dynamics step (issue 13) with the Fixman midpoint
// integrator (engine/integrators.hpp) and the accelerated solver (engine/sd_accelerated.hpp):
// random hard-sphere suspension (trees/placement.hpp, equilibrium generator, 20 sweeps at full
// size), phi = 0.4, monodisperse a = 1, periodic cube under simple shear (Lees-Edwards, rate 1),
// FTS, PME far field, kT = 1, dt = 1e-3, no pair forces, tolerance TOL ([hydrodynamics] tolerance).
//
// One step, as FixmanIntegrator::step does it, each part timed on its own (Hydrodynamics built
// exactly as the Simulation builds it, the solver's stats read after each call):
//   setup          prepare(x0): far-field set-up, near-field assembly, CHOLMOD factorisation
//   far_noise      Lanczos M_inf^{-1/2} psi (lanczos_iterations far-field products)
//   near_noise     the pairwise near-field noise
//   solve          the solve at x0 with F + xi (what Euler-Maruyama would also need)
//   drift          prepare(x') + solve at the midpoint x' (the extra work of the drift), warm-started
//                  from the iterate of the solve at x0 as the Fixman step does
// plus, beside the step:
//   start_solve    the deterministic solve at x0 that Simulation::run evaluates on frame steps;
//                  the Fixman step does not use its velocities
//   engine_step    wall time of sim.evaluate(x0) + sim.advance() through the Simulation, same
//                  configuration; sim.evaluate always solves at x0 (engine_start_solve), which
//                  Simulation::run skips between frames: a run's step is engine_step - engine_start_solve
// Far-field products per Brownian step = lanczos_iterations + products of both solves.
// Usage: bench_brownian [--quick] [--out DIR]; BENCH_MAX_N caps the sizes (default 10000 full,
// 1000 quick), BENCH_MIN_N skips smaller sizes, BENCH_STEPS the steps per size (default 2, quick 1)
// after BENCH_WARMUP untimed ones (default 1, quick 0; see measure()),
// BENCH_TOL the tolerance (1e-3), BENCH_THREADS one thread count, BENCH_NAME the results name,
// BENCH_NO_ENGINE skips the engine step (large N: one step, parts only).
// Rows: N, phi, threads, tolerance; phases: seconds per step (means over the steps), products.
#include "bench/harness.hpp"
#include "engine/core/flow.hpp"
#include "engine/core/random.hpp"
#include "engine/hydrodynamics.hpp"
#include "engine/sd_accelerated.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"
#include "lubrication/near_field.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <time.h>

using namespace stokesian;
using bench::Results;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
// CPU seconds of the process (all threads): on one thread the quiet-machine wall time even when
// other work shares the cores (then wall time is inflated by the share).
double cpu_now() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

std::string scene_text(long n, double phi, double tol) {
  const double L = std::cbrt(double(n) * 4.0 / 3.0 * kPi / phi);
  std::ostringstream t;
  t.precision(17);
  t << "[fluid]\nkT = 1.0\n[domain]\nkind = \"periodic\"\nbox = [" << L << ", " << L << ", " << L << "]\n"
    << "[particles]\ngenerate = \"random\"\ncount = " << n << "\nequilibration_sweeps = 20\nseed = 3\n"
    << "[flow]\nkind = \"simple_shear\"\nrate = 1.0\n"
    << "[hydrodynamics]\nmodel = \"stokesian\"\nsolver = \"accelerated\"\nmoments = \"FTS\"\ntolerance = " << tol << "\n"
    << "[brownian]\nseed = 17\n[time]\ndt = 0.001\nsteps = 1000\n";
  return t.str();
}

struct StepCost {
  double setup_far = 0, setup_near = 0, setup_factor = 0, setup = 0;
  double far_noise = 0, near_noise = 0, noise = 0;
  double solve = 0, drift_setup = 0, drift_solve = 0, drift = 0, start_solve = 0;
  double drift_far = 0, drift_near = 0, drift_factor = 0;  // the midpoint prepare's parts
  double lanczos = 0, products_solve = 0, products_drift = 0, products_start = 0;
  double engine_step = 0, engine_evaluate = 0;  // engine_evaluate: sim.evaluate(x0) of the engine step
  double engine_start_solve = 0;                // that evaluation's solve (skipped by run between frames)
  double cpu_step = 0, cpu_engine_step = 0;  // CPU seconds of the Fixman step parts / engine step
  void add(const StepCost& o, double w) {
    double* a = &setup_far;
    const double* b = &o.setup_far;
    for (std::size_t k = 0; k < sizeof(StepCost) / sizeof(double); ++k) a[k] += w * b[k];
  }
};

double radius_ratio(const std::vector<double>& a) {
  const auto [lo, hi] = std::minmax_element(a.begin(), a.end());
  return *hi / *lo;
}

// Mean cost of `steps` Fixman steps after `warmup` untimed ones from the scene's initial state, parts
// timed separately. The first step of a sheared scene builds the sheared PME (its box starts at
// strain 0 with unsheared parameters): a one-off of a run, not a step's cost.
StepCost measure(const Scene& scene, int steps, int warmup) {
  Simulation sim(scene);
  const ResolvedModel& model = sim.model();
  Hydrodynamics hyd(model, scene.fluid.viscosity, ambient_flow(scene.flow), scene.hydro.tolerance,
                    lubrication::near_field_params(scene.hydro, model.moments), radius_ratio(scene.radii));
  auto& sd = dynamic_cast<AcceleratedStokesianDynamics&>(hyd.solver());
  const double rate = lattice_strain_rate(scene.flow, scene.domain), kT = scene.fluid.kT;
  State s = sim.initial_state();
  const std::size_t n = s.position.size();
  const std::vector<Vec3> zero(n, Vec3::Zero());
  StepCost mean;
  for (int k = 0; k < warmup + steps; ++k) {
    const bool timed = k >= warmup;
    StepCost c;
    const double dt = s.dt;
    const Configuration c0{s.position, s.radius, s.domain};
    double cpu = cpu_now(), cpu_start = 0;
    double t = now();
    hyd.prepare(c0);
    c.setup = now() - t;
    c.setup_far = sd.stats().seconds_far_field_setup;
    c.setup_near = sd.stats().seconds_near_field_assembly;
    c.setup_factor = sd.stats().seconds_factorisation;
    Rng rng = RandomStream::for_purpose(scene.seed, Purpose::brownian, std::uint64_t(s.step));
    t = now();
    const VecX xi = hyd.brownian_force(c0, s.fixed, kT, dt, rng);
    c.noise = now() - t;
    c.far_noise = sd.stats().seconds_far_noise;
    c.near_noise = sd.stats().seconds_near_noise;
    c.lanczos = sd.stats().lanczos_iterations;
    double cpu_s = cpu_now();
    t = now();
    hyd.solve(c0, s.fixed, zero, zero, nullptr);
    c.start_solve = now() - t;
    cpu_start = cpu_now() - cpu_s;
    c.products_start = sd.stats().far_field_products;
    t = now();
    WarmStart warm;  // the midpoint solve starts from this one's iterate, as in FixmanIntegrator::step
    const HydroResult r0 = hyd.solve(c0, s.fixed, zero, zero, &xi, &warm);
    c.solve = now() - t;
    c.products_solve = sd.stats().far_field_products;
    std::vector<Vec3> xm(n);
    for (std::size_t i = 0; i < n; ++i) xm[i] = s.position[i] + 0.5 * dt * r0.U[i];
    const Domain dm = rate == 0.0 ? s.domain : s.domain.strained_by(0.5 * rate * dt);
    const Configuration cm{xm, s.radius, dm};
    t = now();
    hyd.prepare(cm);
    c.drift_setup = now() - t;
    c.drift_far = sd.stats().seconds_far_field_setup;
    c.drift_near = sd.stats().seconds_near_field_assembly;
    c.drift_factor = sd.stats().seconds_factorisation;
    t = now();
    hyd.solve(cm, s.fixed, zero, zero, &xi, &warm);
    c.drift_solve = now() - t;
    c.drift = c.drift_setup + c.drift_solve;
    c.products_drift = sd.stats().far_field_products;
    c.cpu_step = cpu_now() - cpu - cpu_start;
    // The same step through the engine (also moves s on); BENCH_NO_ENGINE: skipped (0 recorded).
    if (std::getenv("BENCH_NO_ENGINE")) {
      if (!timed) continue;  // warm-up: s does not move on
      mean.add(c, 1.0 / steps);
      break;  // one step only: s does not move on
    }
    cpu = cpu_now();
    t = now();
    const Evaluation ev = sim.evaluate(s, s.position);
    c.engine_evaluate = now() - t;
    // Its solve phase: Simulation::run solves at x0 only on frame steps (the Fixman step solves with
    // F + xi itself), so a run's step costs engine_step - engine_start_solve between frames.
    for (std::size_t q = 0; q < sim.phase_times().names.size(); ++q)
      if (sim.phase_times().names[q] == "solve") c.engine_start_solve = sim.phase_times().seconds[q];
    sim.advance(s, ev);
    c.engine_step = now() - t;
    c.cpu_engine_step = cpu_now() - cpu;
    std::printf("  %s %d: setup %.3f (far %.3f near %.3f factor %.3f) noise far %.3f near %.3f (lanczos %.0f) "
                "solve %.3f (%.0f products) drift %.3f (prepare %.3f [far %.3f near %.3f factor %.3f], solve %.3f, %.0f products) start solve %.3f "
                "(%.0f) | engine step %.3f s (evaluate %.3f, its solve %.3f) | CPU: step %.3f s, engine step %.3f s\n",
                timed ? "step" : "warm-up step", k, c.setup, c.setup_far, c.setup_near, c.setup_factor, c.far_noise, c.near_noise, c.lanczos, c.solve,
                c.products_solve, c.drift, c.drift_setup, c.drift_far, c.drift_near, c.drift_factor, c.drift_solve,
                c.products_drift, c.start_solve,
                c.products_start, c.engine_step, c.engine_evaluate, c.engine_start_solve, c.cpu_step, c.cpu_engine_step);
    std::fflush(stdout);
    if (timed) mean.add(c, 1.0 / steps);
  }
  return mean;
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  long max_n = opt.quick ? 1000 : 10000;
  if (const char* e = std::getenv("BENCH_MAX_N")) max_n = std::atol(e);
  long min_n = 0;
  if (const char* e = std::getenv("BENCH_MIN_N")) min_n = std::atol(e);
  int steps = opt.quick ? 1 : 2;
  if (const char* e = std::getenv("BENCH_STEPS")) steps = std::max(1, std::atoi(e));
  int warmup = opt.quick ? 0 : 1;
  if (const char* e = std::getenv("BENCH_WARMUP")) warmup = std::max(0, std::atoi(e));
  double tol = 1e-3;
  if (const char* e = std::getenv("BENCH_TOL")) tol = std::atof(e);
  const double phi = 0.4;
  const int max_threads = omp_get_max_threads();
  // BENCH_THREADS: one thread count to measure (default: 1 and all).
  std::vector<int> thread_counts{1, max_threads};
  if (max_threads == 1) thread_counts = {1};
  if (const char* e = std::getenv("BENCH_THREADS")) thread_counts = {std::max(1, std::atoi(e))};
  Results res(opt.quick ? "brownian_quick" : std::getenv("BENCH_NAME") ? std::getenv("BENCH_NAME") : "brownian");
  const std::vector<long> sizes = opt.quick ? std::vector<long>{300, 1000} : std::vector<long>{1000, 10000, 100000};
  for (long n : sizes) {
    if (n > max_n || n < min_n) continue;
    double t = now();
    const Scene scene = io::parse_scene(scene_text(n, phi, tol), "bench_brownian.toml");
    std::printf("N %ld phi %.2f: placement %.1f s\n", n, phi, now() - t);
    for (int threads : thread_counts) {
      omp_set_num_threads(threads);
      const StepCost c = measure(scene, steps, warmup);
      double load = -1;  // one-minute load average after the measurement (noisy machine: see docs)
      if (FILE* f = std::fopen("/proc/loadavg", "r")) {
        if (std::fscanf(f, "%lf", &load) != 1) load = -1;
        std::fclose(f);
      }
      const double step = c.setup + c.noise + c.solve + c.drift;
      const double products = c.lanczos + c.products_solve + c.products_drift;
      std::printf("N %6ld threads %d tol %g: Brownian step %.3f s = setup %.3f + far noise %.3f + near noise %.3f + "
                  "solve %.3f + drift %.3f; products per step %.1f (lanczos %.1f + solve %.1f + drift %.1f); "
                  "run-loop start solve %.3f s (%.1f products); engine step %.3f s; CPU step %.3f s, engine %.3f s\n",
                  n, threads, tol, step, c.setup, c.far_noise, c.near_noise, c.solve, c.drift, products, c.lanczos,
                  c.products_solve, c.products_drift, c.start_solve, c.products_start, c.engine_step, c.cpu_step,
                  c.cpu_engine_step);
      std::fflush(stdout);
      res.add({{"N", double(n)}, {"phi", phi}, {"threads", double(threads)}, {"tolerance", tol}, {"steps", double(steps)}, {"warmup", double(warmup)}},
              {{"step", step},
               {"setup", c.setup},
               {"setup_far_field", c.setup_far},
               {"setup_near_field", c.setup_near},
               {"setup_factorisation", c.setup_factor},
               {"far_noise", c.far_noise},
               {"near_noise", c.near_noise},
               {"noise", c.noise},
               {"solve", c.solve},
               {"drift", c.drift},
               {"engine_evaluate", c.engine_evaluate},
               {"engine_start_solve", c.engine_start_solve},
               {"drift_setup", c.drift_setup},
               {"drift_setup_far_field", c.drift_far},
               {"drift_setup_near_field", c.drift_near},
               {"drift_setup_factorisation", c.drift_factor},
               {"drift_solve", c.drift_solve},
               {"start_solve", c.start_solve},
               {"engine_step", c.engine_step},
               {"cpu_step", c.cpu_step},
               {"cpu_engine_step", c.cpu_engine_step},
               {"load_average", load},
               {"lanczos_iterations", c.lanczos},
               {"products_solve", c.products_solve},
               {"products_drift", c.products_drift},
               {"products_start_solve", c.products_start},
               {"products_step", products}});
    }
    omp_set_num_threads(max_threads);
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
