// Brownian equilibrium with full hydrodynamic interactions (issue 13, short CI form; the long form
// is bench/validate_equilibrium.cpp, results in docs/benchmarks.md "Brownian equilibrium").
// Scene, mathematics and statistics: tests/support/equilibrium.hpp. A dimer of spheres of radii 1
// and 2 joined by a harmonic spring on the gap (k = 1000 kT/a^2, rest gap 0.1 a, so the gap
// fluctuates by 0.03 a around 0.1 a and lubrication dominates its mobility), Hertz contact,
// model = "stokesian" (dense SD, open domain), dt = 2e-3, seeded.
//  - With the thermal drift (FixmanIntegrator): 1.5e5 steps; the centre distance r sampled every
//    stride >= 3 tau_int steps (tau_int measured from the run, ~60 steps) gives ~800 samples whose
//    Kolmogorov-Smirnov p-value against p(r) ~ r^2 exp(-U(r)) must exceed 0.01.
//  - Without it (EulerIntegrator, noise dt R^{-1} xi only): 3e5 steps, ~1300 samples, the same test
//    must reject at p < 1e-4 (the sampled law is ~ exp(-U)/M(r), shifted towards contact).
// Both runs are deterministic for the seed (RandomStream (seed, brownian, step)), so the outcome is
// not "rerun until green"; the significance levels are those of single tests.
#include <doctest/doctest.h>

#include "tests/support/equilibrium.hpp"

#include <cstdio>
#include <random>

using namespace stokesian;
namespace eq = stokesian::equilibrium;

namespace {

struct Outcome {
  double tau = 0;
  long stride = 0;
  eq::KsResult ks;
};

Outcome dimer_run(bool drift, long steps) {
  const eq::DimerParams p;
  Simulation sim(io::parse_scene(eq::dimer_toml(p), "dimer.toml"));
  State s = sim.initial_state();
  FixmanIntegrator fixman;
  EulerIntegrator euler;
  Integrator& integ = drift ? static_cast<Integrator&>(fixman) : static_cast<Integrator&>(euler);
  std::vector<double> r;
  const long burn = 2000;
  eq::run(sim, s, integ, steps, [&](const State& st) {
    if (st.step > burn) r.push_back((st.position[1] - st.position[0]).norm());
  });
  Outcome o;
  o.tau = eq::tau_int(r);
  o.stride = std::max(1L, long(std::ceil(3.0 * o.tau)));
  const eq::DimerBoltzmann ref(p);
  o.ks = eq::ks_test(eq::subsample(r, 0, std::size_t(o.stride)), [&](double x) { return ref.cdf(x); });
  std::printf("dimer %s: tau_int %.1f steps, stride %ld, %ld samples, KS D = %.4f, p = %.3g\n",
              drift ? "with drift" : "without drift", o.tau, o.stride, o.ks.n, o.ks.D, o.ks.p);
  return o;
}

}  // namespace

TEST_CASE("Boltzmann reference and KS machinery: exact samples pass, shifted samples fail") {
  // The test's own tools against an independent sampler: rejection sampling of r^2 exp(-U(r)).
  const eq::DimerParams p;
  const eq::DimerBoltzmann ref(p);
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double s = p.a1 + p.a2, lo = s - 0.05, hi = s + 0.35;
  const double wmax = hi * hi;  // exp(-U) <= 1
  std::vector<double> x;
  while (x.size() < 4000) {
    const double r = lo + (hi - lo) * u(gen);
    const double h = r - s;
    double U = 0.5 * p.k * (h - p.h0) * (h - p.h0);
    if (h < 0) U += 0.4 * p.hertz * std::pow(-h, 2.5);
    if (u(gen) * wmax < r * r * std::exp(-U)) x.push_back(r);
  }
  const eq::KsResult good = eq::ks_test(x, [&](double r) { return ref.cdf(r); });
  CHECK(good.p > 0.01);
  for (double& r : x) r -= 0.005;  // a sixth of the spread
  const eq::KsResult bad = eq::ks_test(x, [&](double r) { return ref.cdf(r); });
  CHECK(bad.p < 1e-4);
  // Kolmogorov's Q: Q(1.358) = 0.05, Q(1.628) = 0.01 (standard tables).
  CHECK(eq::q_ks(1.3581) == doctest::Approx(0.05).epsilon(2e-3));
  CHECK(eq::q_ks(1.6276) == doctest::Approx(0.01).epsilon(2e-3));
}

TEST_CASE("Dimer with full HI near contact: Boltzmann with the drift, not without") {
  const Outcome with = dimer_run(true, 150000);
  CHECK(with.ks.n >= 500);
  CHECK(with.ks.p > 0.01);
  const Outcome without = dimer_run(false, 300000);
  CHECK(without.ks.n >= 500);
  CHECK(without.ks.p < 1e-4);
}
