// Validation (issue 13), long form: Brownian Stokesian dynamics with full hydrodynamic interactions
// samples the Boltzmann distribution with the thermal drift kT div(R^{-1}) (Fixman midpoint
// integrator) and does not without it (Euler-Maruyama with the noise dt R^{-1} xi only). Two
// scenes, the mathematics and the statistics are described in tests/support/equilibrium.hpp:
//   dimer: spheres of radii 1 and 2, harmonic spring on the gap (k = 1000 kT/a^2, rest gap 0.1 a)
//          and a Hertz contact, open domain; observable the centre distance r, reference
//          p(r) ~ r^2 exp(-U(r)).
//   wall:  a sphere of radius 1 under gravity g = 3 kT/a above a 3 x 3 layer of fixed spheres
//          (periodic box 6.3 x 6.3 x 8, hydrodynamic tolerance 1e-3); observable the height z,
//          reference the whole law p(z) ~ exp(-g z) A(z) with the lateral Boltzmann factor A(z)
//          of the hollows and soft contacts by quadrature (WallHeightLaw), so every sample counts.
// For each scene and scheme: trajectories, the integrated autocorrelation time tau_int of the
// observable (recorded every `rec` steps), samples every stride = ceil(3 tau_int) steps after a
// burn-in, the Kolmogorov-Smirnov test against the Boltzmann CDF, and a histogram for the chart.
//
// Usage: validate_equilibrium [--quick] [--out DIR] [--dimer-steps N] [--wall-steps N]
//   [--trajectories T] [--wall-trajectories T] [--only dimer|wall]
//   default: dimer T = 2 concurrent trajectories of 1e7 steps with the drift (>= 1e5 decorrelated
//   samples at tau_int ~ 60 steps), one of 2.5e6 without; wall: both schemes concurrently, T = 2
//   trajectories of 1e6 steps with the drift, one without; --quick: dimer 1e5, wall 4e4 steps. Results DIR/equilibrium.json
//   (quick: equilibrium_quick.json), chart by bench/plot_equilibrium.py.
#include "bench/harness.hpp"
#include "tests/support/equilibrium.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <thread>

using namespace stokesian;
namespace eq = stokesian::equilibrium;

namespace {

struct Run {
  std::string scene;
  bool drift = false;
  long steps = 0, burn = 0, rec = 0, stride = 0, below = 0, trajectories = 1;
  double dt = 0, tau_steps = 0, seconds = 0, min_obs = 0;
  eq::KsResult ks;
  std::vector<double> edges, density, reference;
};

// A JSON number, or null when not finite (a run with no samples above z_full has no p-value).
std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string json_list(const std::vector<double>& v) {
  std::string s = "[";
  char buf[64];
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%s", i ? ", " : "", num(v[i]).c_str());
    s += buf;
  }
  return s + "]";
}

// Trajectory of the observable, recorded every `rec` steps; then tau_int, stride, KS, histogram.
template <class Obs, class Cdf, class Pdf>
Run measure(const std::string& scene, const std::string& toml, bool drift, int trajectories, long steps, long burn,
            long rec, Obs obs,
            Cdf cdf, Pdf pdf, double lo, double hi, bool condition_above_lo, double split = -1e300) {
  Run run;
  run.scene = scene;
  run.drift = drift;
  run.steps = steps * trajectories;
  run.trajectories = trajectories;
  run.burn = burn;
  run.rec = rec;
  // `trajectories` independent trajectories (seeds seed, seed + 1, ...) in concurrent threads,
  // each `steps` long; their decorrelated samples are pooled.
  std::vector<std::vector<double>> series(static_cast<std::size_t>(trajectories));
  std::vector<double> mins(series.size(), 1e300);
  const auto t0 = std::chrono::steady_clock::now();
  auto one = [&](std::size_t t) {
    Scene sc = io::parse_scene(toml, scene + ".toml");
    sc.seed += t;
    Simulation sim(sc);
    State s = sim.initial_state();
    std::unique_ptr<Integrator> integ;
    if (drift) integ = std::make_unique<FixmanIntegrator>();
    else integ = std::make_unique<EulerIntegrator>();
    series[t].reserve(std::size_t(steps / rec + 1));
    eq::run(sim, s, *integ, steps, [&](const State& st) {
      if (st.step <= burn || st.step % rec != 0) return;
      const double v = obs(st);
      mins[t] = std::min(mins[t], v);
      series[t].push_back(v);
    });
  };
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < series.size(); ++t) pool.emplace_back(one, t);
  one(0);
  for (auto& th : pool) th.join();
  run.dt = io::parse_scene(toml, scene + ".toml").time.dt;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.min_obs = *std::min_element(mins.begin(), mins.end());
  const double mn = run.min_obs;
  // tau_int of the whole recorded series (the wall's heights below z_full included: the slow
  // exchange with the hollows is part of the decorrelation), the largest over the trajectories.
  run.tau_steps = 0.0;
  for (const auto& sr : series) run.tau_steps = std::max(run.tau_steps, eq::tau_int(sr) * double(rec));
  const long stride_rec = std::max(1L, long(std::ceil(3.0 * run.tau_steps / double(rec))));
  run.stride = stride_rec * rec;
  std::vector<double> x;
  for (const auto& sr : series) {
    const std::vector<double> y = eq::subsample(sr, 0, std::size_t(stride_rec));
    x.insert(x.end(), y.begin(), y.end());
  }
  if (condition_above_lo) {
    std::vector<double> y;
    for (double v : x)
      if (v >= lo) y.push_back(v);
    run.below = long(x.size() - y.size());
    x.swap(y);
  } else {
    run.below = long(std::count_if(x.begin(), x.end(), [&](double v) { return v < split; }));
  }
  run.ks = eq::ks_test(x, cdf);
  const int bins = 60;
  run.edges.resize(bins + 1);
  for (int b = 0; b <= bins; ++b) run.edges[b] = lo + (hi - lo) * b / bins;
  run.density.assign(bins, 0.0);
  run.reference.assign(bins, 0.0);
  for (double v : x) {
    const int b = int(std::floor((v - lo) / (hi - lo) * bins));
    if (b >= 0 && b < bins) run.density[b] += 1.0;
  }
  for (int b = 0; b < bins; ++b) {
    const double w = run.edges[b + 1] - run.edges[b];
    run.density[b] /= double(x.size()) * w;
    run.reference[b] = (cdf(run.edges[b + 1]) - cdf(run.edges[b])) / w;
  }
  (void)pdf;
  std::printf("%-5s %-8s steps %ld dt %g: tau_int %.1f steps, stride %ld, n %ld, KS D %.4g p %.3g (%.0f s; min %.4g)\n",
              scene.c_str(), drift ? "drift" : "no drift", steps, run.dt, run.tau_steps, run.stride, run.ks.n, run.ks.D,
              run.ks.p, run.seconds, mn);
  std::fflush(stdout);
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "bench/results";
  bool quick = false;
  long dimer_steps = 10000000, wall_steps = 1000000;
  bool do_dimer = true, do_wall = true;
  int trajectories = 2, wall_trajectories = 2;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") quick = true;
    else if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--dimer-steps" && i + 1 < argc) dimer_steps = std::atol(argv[++i]);
    else if (a == "--wall-steps" && i + 1 < argc) wall_steps = std::atol(argv[++i]);
    else if (a == "--trajectories" && i + 1 < argc) trajectories = std::atoi(argv[++i]);
    else if (a == "--wall-trajectories" && i + 1 < argc) wall_trajectories = std::atoi(argv[++i]);
    else if (a == "--only" && i + 1 < argc) {
      const std::string w = argv[++i];
      do_dimer = w == "dimer";
      do_wall = w == "wall";
    } else {
      std::fprintf(stderr, "usage: %s [--quick] [--out DIR] [--dimer-steps N] [--wall-steps N] [--trajectories T] [--wall-trajectories T] [--only dimer|wall]\n", argv[0]);
      return 1;
    }
  }
  if (quick) {
    dimer_steps = 100000;
    wall_steps = 40000;
  }
  std::vector<Run> runs;
  const eq::DimerParams dp;
  const eq::DimerBoltzmann dref(dp);
  const eq::WallParams wp;
  const eq::WallHeightLaw wlaw(wp);
  if (do_dimer)
    for (bool drift : {true, false})
      runs.push_back(measure(
          "dimer", eq::dimer_toml(dp), drift, drift ? trajectories : 1, drift ? dimer_steps : dimer_steps / 4, 2000, 5,
          [](const State& s) { return (s.position[1] - s.position[0]).norm(); },
          [&](double r) { return dref.cdf(r); }, [&](double r) { return dref.pdf(r); }, dp.a1 + dp.a2 - 0.05,
          dp.a1 + dp.a2 + dp.h0 + 0.15, false));
  if (do_wall) {
    // Both schemes at once (`wall_trajectories` threads with the drift, one without); the
    // whole height law, hollows and soft contacts included (WallHeightLaw), so every sample counts.
    const std::size_t m = std::size_t(wp.n * wp.n);  // the mobile sphere
    auto wall = [&](bool drift) {
      return measure(
          "wall", eq::wall_toml(wp), drift, drift ? wall_trajectories : 1, wall_steps, 2000, 5,
          [m](const State& s) { return s.position[m].z(); }, [&](double z) { return wlaw.cdf(z); },
          [&](double z) { return (wlaw.cdf(z + 1e-5) - wlaw.cdf(z - 1e-5)) / 2e-5; }, wlaw.lo() + 0.3,
          wp.z_full() + 6.0 / wp.g, false, wp.z_full());
    };
    Run no_drift;
    std::thread other([&] { no_drift = wall(false); });
    runs.push_back(wall(true));
    other.join();
    runs.push_back(no_drift);
    // The reference law itself, checked where no drift is needed: free draining (constant
    // mobility), Euler-Maruyama, 50 times the steps (a step costs ~0.2 % of a full-SD one).
    eq::WallParams fp = wp;
    fp.model = "free_draining";
    Run fd = measure(
        "wall", eq::wall_toml(fp), false, 1, 50 * wall_steps, 2000, 5, [m](const State& s) { return s.position[m].z(); },
        [&](double z) { return wlaw.cdf(z); }, [&](double z) { return (wlaw.cdf(z + 1e-5) - wlaw.cdf(z - 1e-5)) / 2e-5; },
        wlaw.lo() + 0.3, wp.z_full() + 6.0 / wp.g, false, wp.z_full());
    fd.scene = "wall_free_draining";
    runs.push_back(fd);
  }

  const auto meta = bench::machine_metadata();
  const std::string path = out + (quick ? "/equilibrium_quick.json" : "/equilibrium.json");
  std::ofstream f(path);
  f << "{\n  \"benchmark\": \"equilibrium\",\n  \"machine\": {\n";
  std::size_t k = 0;
  for (const auto& [key, v] : meta) f << "    \"" << key << "\": \"" << v << "\"" << (++k < meta.size() ? ",\n" : "\n");
  f << "  },\n  \"dimer\": {\"a1\": " << dp.a1 << ", \"a2\": " << dp.a2 << ", \"k\": " << dp.k << ", \"h0\": " << dp.h0
    << ", \"hertz\": " << dp.hertz << "},\n";
  f << "  \"wall\": {\"n\": " << wp.n << ", \"spacing\": " << wp.spacing << ", \"Lz\": " << wp.Lz << ", \"zw\": " << wp.zw
    << ", \"g\": " << wp.g << ", \"z_full\": " << wp.z_full() << ", \"z_max\": " << wp.z_max()
    << ", \"tolerance\": " << wp.tolerance << ", \"boltzmann_below_z_full\": " << wlaw.below_z_full() << "},\n";
  f << "  \"runs\": [\n";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    f << "    {\"scene\": \"" << r.scene << "\", \"drift\": " << (r.drift ? "true" : "false") << ", \"steps\": " << r.steps << ", \"trajectories\": " << r.trajectories
      << ", \"dt\": " << r.dt << ", \"burn_in\": " << r.burn << ", \"record_every\": " << r.rec
      << ", \"tau_int_steps\": " << num(r.tau_steps) << ", \"stride_steps\": " << r.stride << ", \"samples\": " << r.ks.n
      << ", \"samples_below_z_full\": " << r.below << ", \"ks_D\": " << num(r.ks.D) << ", \"ks_p\": " << num(r.ks.p)
      << ", \"seconds\": " << r.seconds << ", \"min_observable\": " << r.min_obs << ",\n     \"edges\": " << json_list(r.edges)
      << ",\n     \"density\": " << json_list(r.density) << ",\n     \"boltzmann\": " << json_list(r.reference) << "}"
      << (i + 1 < runs.size() ? ",\n" : "\n");
  }
  f << "  ]\n}\n";
  std::printf("wrote %s\n", path.c_str());
  return 0;
}
