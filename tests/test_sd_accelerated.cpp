// Accelerated Stokesian dynamics (engine/sd_accelerated.hpp) against the dense SD reference
// (engine/sd_dense.hpp: M_inf formed and inverted, Ewald sum in periodic boxes), over a sweep of
// tolerances 1e-3 ... 1e-8; F, FT, FTS; open, periodic and sheared boxes; monodisperse and
// bidisperse spheres (radius ratio 10 in the open domain, 4 in the periodic boxes, whose size the
// pair search's minimum image limits); fixed particles; phi = 0.1 ... 0.5 with pairs at gaps of
// 1e-4 a. The solver is built as a run builds it (knobs from engine/accuracy.hpp), and the
// achieved relative error of every solved quantity must be at or below the requested tolerance:
//     |U - U_ref| <= tol |U_ref|,  |Omega - Omega_ref| <= tol |Omega_ref|,
//     |S - S_ref| <= tol |S_ref|,  |F_fixed - F_fixed,ref| <= tol |F_fixed,ref|   (2-norms over particles).
// Also: the answer depends neither on the shift B (seed 1 eq. 2.46) nor on which pairs are dropped
// from the factorised matrix, and GMRES and BiCGStab agree.
#include <doctest/doctest.h>

#include <algorithm>

#include "engine/accuracy.hpp"
#include "engine/core/flow.hpp"
#include "engine/methods.hpp"
#include "engine/sd_accelerated.hpp"
#include "support/sanitizer.hpp"
#include "engine/sd_dense.hpp"
#include "trees/placement.hpp"

#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

using namespace stokesian;

namespace {

struct Case {
  std::string name;
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain domain;
  std::vector<char> fixed;
};

// N spheres at volume fraction phi in a periodic box (or the same positions in an open domain),
// radii from the placement generator; `close` pairs pushed to a surface gap of 1e-4 a.
Case make_case(std::string name, long n, double phi, bool periodic, double strain, double ratio, int close,
               bool with_fixed, std::uint64_t seed) {
  PlacementParams pp;
  pp.count = n;
  pp.seed = seed;
  pp.min_gap = 1e-3;
  pp.equilibration_sweeps = 20;
  double vol = 0.0;
  const bool poly = ratio > 1.0;
  if (poly) {
    pp.sizes = PlacementParams::Sizes::bidisperse;
    pp.radius = 0.5;
    pp.radius_ratio = ratio;  // radii 0.5 and 0.5 ratio
    pp.large_fraction = 0.05;
  }
  // Expected particle volume for the box size.
  const double a3 = poly ? (1 - pp.large_fraction) * 0.125 + pp.large_fraction * std::pow(0.5 * ratio, 3) : 1.0;
  vol = double(n) * 4.0 / 3.0 * kPi * a3 / phi;
  const double L = std::cbrt(vol);
  const Placement pl = place_particles(pp, Vec3(L, L, L));
  Case c;
  c.name = name;
  c.x = pl.position;
  c.a = pl.radius;
  if (periodic) {
    c.domain.kind = Domain::Kind::periodic;
    c.domain.box = pl.box;
    c.domain.shear_strain = strain;
  }
  // Close pairs: particle 2k+1 moved next to its nearest neighbour at gap 1e-4 a, if it stays clear
  // of the others.
  int made = 0;
  for (long i = 1; i < n && made < close; i += 2) {
    long j = -1;
    double best = 1e300;
    for (long k = 0; k < n; ++k) {
      if (k == i) continue;
      const double r = c.domain.minimum_image(c.x[std::size_t(i)] - c.x[std::size_t(k)]).norm() -
                       c.a[std::size_t(i)] - c.a[std::size_t(k)];
      if (r < best) best = r, j = k;
    }
    const Vec3 d = c.domain.minimum_image(c.x[std::size_t(i)] - c.x[std::size_t(j)]);
    const Vec3 xi = c.x[std::size_t(j)] + d.normalized() * (c.a[std::size_t(i)] + c.a[std::size_t(j)] + 1e-4);
    bool clear = true;
    for (long k = 0; k < n && clear; ++k)
      if (k != i && k != j)
        clear = c.domain.minimum_image(xi - c.x[std::size_t(k)]).norm() > c.a[std::size_t(i)] + c.a[std::size_t(k)] + 1e-3;
    if (clear) {
      c.x[std::size_t(i)] = xi;
      ++made;
    }
  }
  CHECK(made == close);
  c.fixed.assign(std::size_t(n), 0);
  if (with_fixed)
    for (long i = 0; i < n; i += 5) c.fixed[std::size_t(i)] = 1;
  return c;
}

double rel(const std::vector<Vec3>& u, const std::vector<Vec3>& ref, const std::vector<char>* only_fixed = nullptr) {
  double e = 0, s = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (only_fixed && !(*only_fixed)[i]) continue;
    e += (u[i] - ref[i]).squaredNorm();
    s += ref[i].squaredNorm();
  }
  return s > 0 ? std::sqrt(e / s) : std::sqrt(e);
}
double rel5(const std::vector<Vec5>& u, const std::vector<Vec5>& ref) {
  double e = 0, s = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    e += (u[i] - ref[i]).squaredNorm();
    s += ref[i].squaredNorm();
  }
  return s > 0 ? std::sqrt(e / s) : std::sqrt(e);
}

struct Errors {
  double U = 0, Omega = 0, S = 0, Ffixed = 0;
  double worst() const { return std::max({U, Omega, S, Ffixed}); }
};

Errors compare(const HydroResult& r, const HydroResult& ref, Moments m, const std::vector<char>& fixed) {
  Errors e;
  e.U = rel(r.U, ref.U);
  if (m != Moments::F) e.Omega = rel(r.Omega, ref.Omega);
  if (m == Moments::FTS) e.S = rel5(r.S, ref.S);
  bool anyfixed = false;
  for (char f : fixed) anyfixed |= f != 0;
  if (anyfixed) e.Ffixed = rel(r.F, ref.F, &fixed);
  return e;
}

// Loads: random forces and torques of unit scale on mobile particles.
void loads(long n, std::uint64_t seed, std::vector<Vec3>& F, std::vector<Vec3>& T) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  F.clear();
  T.clear();
  for (long i = 0; i < n; ++i) {
    F.emplace_back(g(rng), g(rng), g(rng));
    T.emplace_back(g(rng), g(rng), g(rng));
  }
}

std::unique_ptr<AcceleratedStokesianDynamics> accelerated(const Case& c, Moments m, double mu, double tol,
                                                          double shift = AcceleratedStokesianDynamics::kShift,
                                                          double factor_gap = AcceleratedStokesianDynamics::kFactorGap,
                                                          AcceleratedStokesianDynamics::Method method =
                                                              AcceleratedStokesianDynamics::Method::gmres,
                                                          const lubrication::NearFieldParams& near = {}) {
  const auto [amin, amax] = std::minmax_element(c.a.begin(), c.a.end());
  const AccuracyKnobs k = derive_knobs(tol, HydroModel::stokesian, *amax / *amin, any_fixed(c.fixed));
  const MobilitySpec spec{m, mu, k.far_field};
  const FarFieldMethodEntry* ff = far_field_methods().find(c.domain.periodic() ? "pme" : "direct");
  auto s = std::make_unique<AcceleratedStokesianDynamics>(ff->make(spec), mu, near, k.krylov, shift, method, factor_gap);
  s->set_far_field_factory([ff, spec] { return ff->make(spec); });  // as engine/methods.cpp
  return s;
}

// Every particle held but each k-th (k = 10: 90 % held; k = 2: half).
Case holding_all_but_every(Case c, long k) {
  for (std::size_t i = 0; i < c.fixed.size(); ++i) c.fixed[i] = long(i) % k != 0;
  return c;
}

// A random suspension at phi = 0.2 with 90 % held (every particle but each tenth): open, or periodic
// at the given Lees-Edwards strain ("sheared" when it is not zero).
Case ninety_percent_held(long n, bool periodic, double strain, int close, std::uint64_t seed) {
  const std::string box = !periodic ? "open" : strain != 0.0 ? "sheared" : "periodic";
  return holding_all_but_every(make_case(box + " phi 0.2, 90 % held", n, 0.2, periodic, strain, 0.0, close, false, seed), 10);
}

// A case's problem: its configuration, the ambient flow at its centres, random unit loads.
struct Loaded {
  Configuration conf;
  FlowSample sample;
  std::vector<Vec3> F, T;
};
Loaded loaded(const Case& c, const AmbientFlow& flow, std::uint64_t seed) {
  Loaded l{{c.x, c.a, c.domain}, {}, {}, {}};
  flow.sample(c.x, l.sample);
  loads(long(c.x.size()), seed, l.F, l.T);
  return l;
}

// A 10 x 10 wall of held spheres (gap 0.05) under 20 mobile ones: in an open domain, or in a
// periodic box 20.5 x 11 x 20.5 (a slit between the wall and its image).
Case wall_case(bool periodic) {
  Case w;
  w.name = periodic ? "wall of 100 held in a periodic slit" : "wall of 100 held under 20 mobile";
  for (int i = 0; i < 10; ++i)
    for (int k = 0; k < 10; ++k) w.x.emplace_back(2.05 * i, 0.0, 2.05 * k);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (w.x.size() < 120) {
    const Vec3 p(18.45 * u(rng), 2.2 + 6.0 * u(rng), 18.45 * u(rng));
    bool clear = true;
    for (const Vec3& q : w.x) clear &= (p - q).norm() > 2.1;
    if (clear) w.x.push_back(p);
  }
  w.a.assign(w.x.size(), 1.0);
  w.fixed.assign(w.x.size(), 0);
  for (std::size_t i = 0; i < 100; ++i) w.fixed[i] = 1;
  if (periodic) {
    w.domain.kind = Domain::Kind::periodic;
    w.domain.box = Vec3(20.5, 11.0, 20.5);
    bool clear = true;
    for (std::size_t i = 0; i < w.x.size(); ++i)
      for (std::size_t j = 0; j < i; ++j) clear &= w.domain.minimum_image(w.x[i] - w.x[j]).norm() > 2.04;
    REQUIRE(clear);
  }
  return w;
}

AmbientFlow simple_shear(double rate) {
  FlowParams fp;
  fp.kind = FlowParams::Kind::simple_shear;
  fp.rate = rate;
  return ambient_flow(fp);
}

}  // namespace

TEST_CASE("accelerated SD: achieved error against dense SD at or below the requested tolerance") {
  const double mu = 1.0;
  const AmbientFlow flow = simple_shear(1.0);
  struct Spec {
    const char* name;
    long n;
    double phi;
    bool periodic;
    double strain;
    double ratio;  // bidisperse radius ratio (0: monodisperse)
    int close;
    bool fixed;
  };
  const Spec specs[] = {
      {"open phi 0.1", 60, 0.1, false, 0.0, 0.0, 4, false},
      {"open phi 0.3 fixed", 60, 0.3, false, 0.0, 0.0, 4, true},
      {"open phi 0.5", 60, 0.5, false, 0.0, 0.0, 6, false},
      {"open poly ratio 10", 60, 0.2, false, 0.0, 10.0, 3, true},
      {"periodic phi 0.1", 40, 0.1, true, 0.0, 0.0, 3, false},
      {"periodic phi 0.45 fixed", 80, 0.45, true, 0.0, 0.0, 4, true},
      {"sheared phi 0.3", 60, 0.3, true, 0.31, 0.0, 4, false},
      {"sheared poly ratio 4 fixed", 60, 0.02, true, 0.17, 4.0, 3, true},
  };
  int seed = 1;
  const char* only = std::getenv("ASD_CASE");  // run one case by name (diagnostics)
  for (const Spec& sp : specs) {
    if (only && std::string(only) != sp.name) {
      ++seed;
      continue;
    }
    const Case c = make_case(sp.name, sp.n, sp.phi, sp.periodic, sp.strain, sp.ratio, sp.close, sp.fixed, 100 + seed++);
    const Configuration conf{c.x, c.a, c.domain};
    FlowSample sample;
    flow.sample(c.x, sample);
    std::vector<Vec3> F, T;
    loads(sp.n, 7 + seed, F, T);
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      DenseStokesianDynamics dense(m, mu, flow);
      dense.prepare(conf);
      const HydroResult ref = dense.solve(HydroProblem{conf, c.fixed, sample, F, T});
      for (double tol : {1e-3, 1e-4, 1e-6, 1e-8}) {
        CAPTURE(c.name);
        const std::string moments = to_string(m);
        CAPTURE(moments);
        CAPTURE(tol);
        auto s = accelerated(c, m, mu, tol);
        s->prepare(conf);
        const HydroResult r = s->solve(HydroProblem{conf, c.fixed, sample, F, T});
        const Errors e = compare(r, ref, m, c.fixed);
        CAPTURE(e.U);
        CAPTURE(e.Omega);
        CAPTURE(e.S);
        CAPTURE(e.Ffixed);
        CAPTURE(s->stats().iterations);
        MESSAGE(c.name << " " << std::string(to_string(m)) << " tol " << tol << ": error " << e.worst() << ", iterations "
                       << s->stats().iterations << ", products " << s->stats().far_field_products);
        CHECK(e.worst() <= tol);
      }
    }
  }
}

TEST_CASE("accelerated SD with the squeeze near field (lubrication = \"squeeze\") agrees with dense SD") {
  // The thesis's squeeze blocks act on force rows only: the factor's torque and stresslet rows hold
  // the shift alone, and the pairs below the factor gap still reach the answer through the Krylov
  // operator. Reference: dense SD with the same near field.
  const double mu = 1.0;
  const AmbientFlow flow = simple_shear(1.0);
  lubrication::NearFieldParams np;
  np.model = Lubrication::squeeze;
  int seed = 40;
  for (const bool periodic : {false, true}) {
    const Case c = make_case(periodic ? "periodic phi 0.3" : "open phi 0.3", 50, 0.3, periodic, 0.0, 0.0, 5, !periodic,
                             seed++);
    const Configuration conf{c.x, c.a, c.domain};
    FlowSample sample;
    flow.sample(c.x, sample);
    std::vector<Vec3> F, T;
    loads(50, seed, F, T);
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      DenseStokesianDynamics dense(m, mu, flow, np);
      dense.prepare(conf);
      const HydroResult ref = dense.solve(HydroProblem{conf, c.fixed, sample, F, T});
      for (double tol : {1e-3, 1e-6}) {
        CAPTURE(c.name);
        const std::string moments = to_string(m);
        CAPTURE(moments);
        CAPTURE(tol);
        auto s = accelerated(c, m, mu, tol, AcceleratedStokesianDynamics::kShift, AcceleratedStokesianDynamics::kFactorGap,
                             AcceleratedStokesianDynamics::Method::gmres, np);
        s->prepare(conf);
        const Errors e = compare(s->solve(HydroProblem{conf, c.fixed, sample, F, T}), ref, m, c.fixed);
        MESSAGE(c.name << " squeeze " << moments << " tol " << tol << ": error " << e.worst() << ", iterations "
                       << s->stats().iterations);
        CHECK(e.worst() <= tol);
      }
    }
  }
}

TEST_CASE("accelerated SD: the answer depends neither on the shift nor on the pairs dropped from the factor; "
          "GMRES and BiCGStab agree") {
  const double mu = 1.3;
  const AmbientFlow flow = simple_shear(0.7);
  const Case c = make_case("open phi 0.4", 50, 0.4, false, 0.0, 0.0, 4, true, 77);
  const Configuration conf{c.x, c.a, c.domain};
  FlowSample sample;
  flow.sample(c.x, sample);
  std::vector<Vec3> F, T;
  loads(50, 3, F, T);
  const double tol = 1e-10;
  for (Moments m : {Moments::FT, Moments::FTS}) {
    auto base = accelerated(c, m, mu, tol);
    base->prepare(conf);
    const HydroResult r0 = base->solve(HydroProblem{conf, c.fixed, sample, F, T});
    for (double shift : {0.05, 0.3, 1.0, 20.0})
      for (double gap : {1e300, 0.5, 0.01}) {
      CAPTURE(shift);
      CAPTURE(gap);
      auto s = accelerated(c, m, mu, tol, shift, gap);
      s->prepare(conf);
      const HydroResult r = s->solve(HydroProblem{conf, c.fixed, sample, F, T});
      CHECK(compare(r, r0, m, c.fixed).worst() <= 1e-8);
    }
    auto b = accelerated(c, m, mu, tol, AcceleratedStokesianDynamics::kShift, AcceleratedStokesianDynamics::kFactorGap,
                         AcceleratedStokesianDynamics::Method::bicgstab);
    b->prepare(conf);
    const HydroResult rb = b->solve(HydroProblem{conf, c.fixed, sample, F, T});
    CHECK(compare(rb, r0, m, c.fixed).worst() <= 1e-8);
  }
}

TEST_CASE("accelerated SD: the held-row preconditioner and the plain solve agree to the tolerance") {
  // The fast path (block-Jacobi on the held particles' rows, open domains) against its plain twin
  // over tolerances 1e-3 ... 1e-8, F / FT / FTS, 20 % and 90 % held spheres, and a wall of touching
  // held spheres under mobile ones. Each is within the tolerance of the exact answer (the GMRES
  // residual is the true one for both; the test above checks the fast path against dense SD), so
  // they differ by at most 2 tol; the preconditioner takes no more iterations in the first pass (to
  // the GMRES tolerance; one more allowed in periodic boxes, whose random held particles it barely
  // helps), and on the walls fewer: a fifth fewer on the open wall. Periodic boxes (a slit between a
  // wall and its image, a sheared suspension) use Ewald-summed blocks.
  const double mu = 1.0;
  const AmbientFlow flow = simple_shear(1.0);
  std::vector<Case> cases;
  cases.push_back(make_case("open phi 0.3, 20 % held", 60, 0.3, false, 0.0, 0.0, 4, true, 201));
  cases.push_back(ninety_percent_held(60, false, 0.0, 3, 202));
  cases.push_back(make_case("sheared phi 0.3, 20 % held", 60, 0.3, true, 0.23, 0.0, 3, true, 203));
  cases.push_back(ninety_percent_held(60, true, 0.23, 3, 204));
  cases.push_back(wall_case(false));
  cases.push_back(wall_case(true));
  for (const Case& c : cases) {
    const Loaded l = loaded(c, flow, 11);
    const Configuration& conf = l.conf;
    const HydroProblem problem{conf, c.fixed, l.sample, l.F, l.T};
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS})
      for (double tol : {1e-3, 1e-5, 1e-8}) {
        auto fast = accelerated(c, m, mu, tol), plain = accelerated(c, m, mu, tol);
        plain->set_held_preconditioner(false);
        fast->prepare(conf);
        plain->prepare(conf);
        const HydroResult rf = fast->solve(problem);
        const HydroResult rp = plain->solve(problem);
        const double e = compare(rf, rp, m, c.fixed).worst();
        MESSAGE(c.name << " " << std::string(to_string(m)) << " tol " << tol << ": difference " << e << ", iterations "
                       << fast->stats().first_pass_iterations << " + " << fast->stats().iterations - fast->stats().first_pass_iterations
                       << " (" << fast->stats().held_clusters << " blocks) against "
                       << plain->stats().first_pass_iterations << " + " << plain->stats().iterations - plain->stats().first_pass_iterations << ", estimated error " << fast->stats().held_error_estimate / tol << " / "
                       << plain->stats().held_error_estimate / tol << " tol");
        CAPTURE(c.name);
        CAPTURE(tol);
        CHECK(plain->stats().held_clusters == 0);
        CHECK(fast->stats().held_clusters > 0);
        CHECK(e <= 2 * tol);
        // The preconditioner's effect: the first pass, to the GMRES tolerance (the further passes
        // depend on each solve's error estimate).
        const int spare = c.domain.periodic() ? 1 : 0;
        const int it_fast = fast->stats().first_pass_iterations, it_plain = plain->stats().first_pass_iterations;
        CHECK(it_fast <= it_plain + spare);
        if (c.name.rfind("wall", 0) == 0) {  // open: a fifth fewer; periodic: fewer (measured 5-25 %)
          if (c.domain.periodic()) CHECK(it_fast < it_plain);
          else CHECK(it_fast <= 0.8 * it_plain);
        }
        // Next configurations: the mobile particles moved (the held blocks are kept), then every
        // particle moved (the blocks are redone); the same solver objects. At the middle tolerance
        // (the kept and redone blocks do not depend on it).
        if (tol != 1e-5) continue;
        for (bool move_held : {false, true}) {
          std::vector<Vec3> x2 = c.x;
          for (std::size_t i = 0; i < x2.size(); ++i)
            if (move_held || !c.fixed[i]) x2[i] += Vec3(0.003, -0.002, 0.001);
          const Configuration conf2{x2, c.a, c.domain};
          FlowSample sample2;
          flow.sample(x2, sample2);
          fast->prepare(conf2);
          plain->prepare(conf2);
          const HydroResult rf2 = fast->solve(HydroProblem{conf2, c.fixed, sample2, l.F, l.T});
          const HydroResult rp2 = plain->solve(HydroProblem{conf2, c.fixed, sample2, l.F, l.T});
          CAPTURE(move_held);
          CHECK(compare(rf2, rp2, m, c.fixed).worst() <= 2 * tol);
          CHECK(fast->stats().first_pass_iterations <= plain->stats().first_pass_iterations + spare);
        }
      }
  }
}

// A fast path of the held-row preconditioner against its twin on one problem: the two solvers as
// accelerated() makes them, each adjusted by its setter, prepared and solved once.
struct TwinSolves {
  double difference;  // worst relative difference of the solutions (compare().worst())
  AcceleratedSdStats fast, twin;
};
TwinSolves solve_twins(const Case& c, const Loaded& l, Moments m, double tol,
                       const std::function<void(AcceleratedStokesianDynamics&)>& set_fast,
                       const std::function<void(AcceleratedStokesianDynamics&)>& set_twin) {
  const HydroProblem problem{l.conf, c.fixed, l.sample, l.F, l.T};
  auto fast = accelerated(c, m, 1.0, tol), twin = accelerated(c, m, 1.0, tol);
  set_fast(*fast);
  set_twin(*twin);
  fast->prepare(l.conf);
  twin->prepare(l.conf);
  const HydroResult rf = fast->solve(problem), rt = twin->solve(problem);
  return {compare(rf, rt, m, c.fixed).worst(), fast->stats(), twin->stats()};
}

TEST_CASE("accelerated SD: the long-wave part of the held-row preconditioner agrees with block-Jacobi alone and "
          "cuts the iterations") {
  // Fast path: P^-1 = G B G (G the long-wave deflation of the held particles, engine/brownian.hpp);
  // twin: B alone (set_held_long_wave(false)). 300 spheres at phi = 0.2 in a sheared box (strain
  // 0.23), 90 % held as in [L24] fig. 6, F / FT / FTS, tolerances 1e-3 and 1e-6: the two within 2 tol
  // of each other (each within tol of the exact answer), and the first pass (to the GMRES tolerance)
  // at least a sixth shorter with the long-wave part (measured: FT 1e-3 about a third). Against dense
  // SD: "accelerated SD with held particles", periodic case.
  const AmbientFlow flow = simple_shear(1.0);
  const Case c = ninety_percent_held(300, true, 0.23, 0, 205);
  const Loaded l = loaded(c, flow, 13);
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS})
    for (double tol : {1e-3, 1e-6}) {
      if (test::kSanitized && (m == Moments::FTS || tol < 1e-3)) continue;
      const TwinSolves t = solve_twins(c, l, m, tol, [](AcceleratedStokesianDynamics&) {},
                                       [](AcceleratedStokesianDynamics& s) { s.set_held_long_wave(false); });
      const double e = t.difference;
      const int it_fast = t.fast.first_pass_iterations, it_twin = t.twin.first_pass_iterations;
      MESSAGE(std::string(to_string(m)) << " tol " << tol << ": difference " << e / tol << " tol, first pass "
                                        << it_fast << " against " << it_twin << ", all passes " << t.fast.iterations
                                        << " against " << t.twin.iterations << ", wave vectors "
                                        << t.fast.held_wave_vectors);
      CAPTURE(to_string(m));
      CAPTURE(tol);
      CHECK(t.fast.held_wave_vectors > 0);
      CHECK(t.twin.held_wave_vectors == 0);
      CHECK(e <= 2 * tol);
      CHECK(it_fast <= 5 * it_twin / 6);
    }
}

TEST_CASE("accelerated SD: the coarse part of the held-row preconditioner agrees with blocks and long waves "
          "alone and cuts the iterations") {
  // Fast path: P^-1 = G B G + Z E^-1 Z^T (engine/sd_accelerated.hpp), built at once here; twin:
  // G B G alone (set_held_coarse(false)). The default builds it once it has paid: checked below. 300 spheres at phi = 0.2,
  // 90 % held, open and sheared periodic (strain 0.23), F / FT / FTS, tolerances 1e-3 and 1e-6:
  // within 2 tol of each other (each within tol of the exact answer), and all passes at least a
  // tenth shorter with the coarse part (measured 0.40-0.73 of the twin's; per step at N = 1000-3000
  // in bench_channel 0.5-0.6). Against dense SD: "accelerated SD with held particles".
  const double mu = 1.0;
  const AmbientFlow flow = simple_shear(1.0);
  for (bool periodic : {false, true}) {
    const Case c = ninety_percent_held(300, periodic, periodic ? 0.23 : 0.0, 0, 205);
    const Loaded l = loaded(c, flow, 13);
    const HydroProblem problem{l.conf, c.fixed, l.sample, l.F, l.T};
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS})
      for (double tol : {1e-3, 1e-6}) {
        if (test::kSanitized && (m == Moments::FTS || tol < 1e-3)) continue;
        const TwinSolves t = solve_twins(c, l, m, tol, [](AcceleratedStokesianDynamics& s) { s.set_held_coarse(true, true); },
                                         [](AcceleratedStokesianDynamics& s) { s.set_held_coarse(false); });
        const double e = t.difference;
        const int it_fast = t.fast.first_pass_iterations, it_twin = t.twin.first_pass_iterations;
        MESSAGE(c.name << " " << std::string(to_string(m)) << " tol " << tol << ": difference " << e / tol
                       << " tol, first pass " << it_fast << " against " << it_twin << ", all passes "
                       << t.fast.iterations << " against " << t.twin.iterations << ", coarse columns "
                       << t.fast.held_coarse_columns << " (" << t.fast.held_clusters << " blocks)");
        CAPTURE(c.name);
        CAPTURE(to_string(m));
        CAPTURE(tol);
        CHECK(t.fast.held_coarse_columns > 0);
        CHECK(t.twin.held_coarse_columns == 0);
        CHECK(e <= 2 * tol);
        CHECK(t.fast.iterations <= 9 * t.twin.iterations / 10);
        CHECK(it_fast <= it_twin);
      }
    // Default: at the first solve in a box at zero strain (open here); in a sheared box once a third
    // of the iterations of the solves with the same held blocks reaches its columns. Then kept.
    auto s = accelerated(c, Moments::FT, mu, 1e-3);
    s->prepare(l.conf);
    long spent = 0, last = 0;
    int solves = 0;
    while (s->stats().held_coarse_columns == 0 && solves < 100) {
      s->solve(problem);
      ++solves;
      if (s->stats().held_coarse_columns == 0) spent += last = s->stats().iterations;
    }
    const long columns = s->stats().held_coarse_columns;
    MESSAGE(c.name << ": coarse part built at solve " << solves << " (" << spent << " iterations before, "
                   << columns << " columns)");
    CHECK(columns > 0);
    if (!periodic) {
      CHECK(solves == 1);
    } else {
      CHECK(spent >= 3 * columns);        // not before
      CHECK(spent - last < 3 * columns);  // nor later
    }
    s->solve(problem);
    CHECK(s->stats().held_coarse_columns == columns);
  }
}

TEST_CASE("accelerated SD: the held-row preconditioner depends on the held particles alone (a resumed run "
          "solves as the uninterrupted one)") {
  // A run resumed from a checkpoint builds the held blocks and the coarse part at the configuration
  // it resumes from; the uninterrupted run built them at its first one. In a box at zero strain both
  // must give the same preconditioner, hence bitwise the same solves: here a solver that built them
  // at configuration 1 and then solves configuration 2 against a fresh one that builds them at
  // configuration 2 (the mobile spheres moved by up to 0.005 a). Open and periodic (PME), FT, with
  // and without the coarse part (whose products use an operator of the held particles alone: with
  // the solver's own PME they differed by 3e-17 in U).
  const double mu = 1.0;
  const AmbientFlow flow = simple_shear(0.0);
  for (bool periodic : {false, true}) {
    const Case c1 = ninety_percent_held(300, periodic, 0.0, 0, 307);
    Case c2 = c1;
    Rng rng(11, 0);
    for (std::size_t i = 0; i < c2.x.size(); ++i)
      if (!c2.fixed[i]) c2.x[i] += 0.01 * Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
    const Loaded l1 = loaded(c1, flow, 3), l2 = loaded(c2, flow, 4);
    for (int coarse : {0, 1}) {
    auto first = accelerated(c1, Moments::FT, mu, 1e-3), fresh = accelerated(c2, Moments::FT, mu, 1e-3);
    first->set_held_coarse(coarse == 1);
    fresh->set_held_coarse(coarse == 1);
    first->prepare(l1.conf);
    first->solve(HydroProblem{l1.conf, c1.fixed, l1.sample, l1.F, l1.T});
    REQUIRE((first->stats().held_coarse_columns > 0) == (coarse == 1));
    first->prepare(l2.conf);
    fresh->prepare(l2.conf);
    const HydroProblem p2{l2.conf, c2.fixed, l2.sample, l2.F, l2.T};
    const HydroResult r1 = first->solve(p2), r2 = fresh->solve(p2);
    CAPTURE(c1.name);
    CHECK(first->stats().iterations == fresh->stats().iterations);
    bool same = true;
    for (std::size_t i = 0; i < c2.x.size(); ++i)
      same = same && r1.U[i] == r2.U[i] && r1.Omega[i] == r2.Omega[i] && r1.F[i] == r2.F[i];
    CAPTURE(coarse);
    double worst = 0;
    for (std::size_t i = 0; i < c2.x.size(); ++i) worst = std::max(worst, (r1.U[i] - r2.U[i]).norm());
    MESSAGE(c1.name << (coarse ? ", coarse part" : "") << ": largest |dU| " << worst);
    CHECK(same);
    }
  }
}

TEST_CASE("accelerated SD: a warm start meets the tolerance against dense SD and saves iterations; a bad one "
          "costs one product") {
  // The Fixman step's midpoint solve starts from the iterate of its solve at x0 (HydroProblem::warm).
  // Here: solve at x0, move every sphere along its velocity by at most 0.4 of the smallest gap, and
  // solve there cold and warm; both against dense SD at the moved positions. With held particles
  // too: their error-estimated passes run from the warm iterate like any other start.
  const double mu = 1.0;
  const AmbientFlow flow = simple_shear(1.0);
  struct Spec {
    const char* name;
    long n;
    double phi;
    bool periodic;
    double strain;
    Moments m;
    int hold_every;  // 0: every sphere mobile; k: all but every k-th held (their rows first-kind)
  };
  const Spec specs[] = {{"sheared phi 0.45", 80, 0.45, true, 0.2, Moments::FTS, 0},
                        {"open phi 0.3", 60, 0.3, false, 0.0, Moments::FT, 0},
                        {"open phi 0.2, half held", 60, 0.2, false, 0.0, Moments::FT, 2},
                        {"periodic phi 0.2, 90 % held", 100, 0.2, true, 0.0, Moments::FT, 10}};
  int seed = 40;
  for (const Spec& sp : specs) {
    Case c = make_case(sp.name, sp.n, sp.phi, sp.periodic, sp.strain, 0.0, 0, false, std::uint64_t(seed++));
    if (sp.hold_every) c = holding_all_but_every(c, sp.hold_every);
    const Loaded l0 = loaded(c, flow, std::uint64_t(seed++));
    for (double tol : {1e-3, 1e-6}) {
      CAPTURE(sp.name);
      CAPTURE(tol);
      auto s = accelerated(c, sp.m, mu, tol);
      s->prepare(l0.conf);
      WarmStart warm;
      const HydroResult r0 = s->solve(HydroProblem{l0.conf, c.fixed, l0.sample, l0.F, l0.T, nullptr, nullptr, &warm});
      REQUIRE(warm.iterate.size() > 0);
      // Smallest surface gap (placement keeps >= 1e-3 a) and the largest speed set the move.
      double gap = 1e300, umax = 0.0;
      for (std::size_t i = 0; i < c.x.size(); ++i) {
        umax = std::max(umax, r0.U[i].norm());
        for (std::size_t j = 0; j < i; ++j)
          gap = std::min(gap, c.domain.minimum_image(c.x[i] - c.x[j]).norm() - c.a[i] - c.a[j]);
      }
      Case moved = c;
      for (std::size_t i = 0; i < c.x.size(); ++i) moved.x[i] += (0.4 * gap / umax) * r0.U[i];
      const Loaded l1 = loaded(moved, flow, std::uint64_t(seed - 1));  // the same loads
      DenseStokesianDynamics dense(sp.m, mu, flow);
      dense.prepare(l1.conf);
      const HydroResult ref = dense.solve(HydroProblem{l1.conf, c.fixed, l1.sample, l1.F, l1.T});
      s->prepare(l1.conf);
      const AcceleratedSdStats::Totals before = s->stats().totals;
      const HydroResult cold = s->solve(HydroProblem{l1.conf, c.fixed, l1.sample, l1.F, l1.T});
      const int cold_products = s->stats().far_field_products;
      const HydroResult hot = s->solve(HydroProblem{l1.conf, c.fixed, l1.sample, l1.F, l1.T, nullptr, nullptr, &warm});
      const int warm_products = s->stats().far_field_products;
      // The running sums (bench_channel's phases) add up the two solves.
      CHECK(s->stats().totals.solves == before.solves + 2);
      CHECK(s->stats().totals.products == before.products + cold_products + warm_products);
      MESSAGE(std::string(sp.name) << " tol " << tol << ": far-field products cold " << cold_products << ", warm " << warm_products
                      << "; errors " << compare(cold, ref, sp.m, c.fixed).worst() << " / "
                      << compare(hot, ref, sp.m, c.fixed).worst());
      CHECK(compare(cold, ref, sp.m, c.fixed).worst() <= tol);
      CHECK(compare(hot, ref, sp.m, c.fixed).worst() <= tol);
      CHECK(warm_products < cold_products);
      // An iterate far worse than zero is dropped: one product more than the cold solve, same answer.
      std::mt19937_64 rng(3);
      std::normal_distribution<double> g;
      for (Eigen::Index k = 0; k < warm.iterate.size(); ++k) warm.iterate[k] = 1e3 * g(rng);
      const HydroResult bad = s->solve(HydroProblem{l1.conf, c.fixed, l1.sample, l1.F, l1.T, nullptr, nullptr, &warm});
      CHECK(s->stats().far_field_products == cold_products + 1);
      CHECK(compare(bad, cold, sp.m, c.fixed).worst() == 0.0);
      // An iterate of another size (another solver or moment level) is ignored.
      warm.iterate = VecX::Ones(3);
      const HydroResult other = s->solve(HydroProblem{l1.conf, c.fixed, l1.sample, l1.F, l1.T, nullptr, nullptr, &warm});
      CHECK(s->stats().far_field_products == cold_products);
      CHECK(compare(other, cold, sp.m, c.fixed).worst() == 0.0);
    }
  }
}

TEST_CASE("accelerated SD: set-up as task-graph phases equals prepare()") {
  const double mu = 1.0;
  FlowParams fp;
  fp.kind = FlowParams::Kind::simple_shear;
  fp.rate = 0.5;
  const AmbientFlow flow = ambient_flow(fp);
  const Case c = make_case("sheared phi 0.3", 60, 0.3, true, 0.2, 0.0, 3, false, 5);
  const Configuration conf{c.x, c.a, c.domain};
  FlowSample sample;
  flow.sample(c.x, sample);
  std::vector<Vec3> F, T;
  loads(60, 9, F, T);
  auto a = accelerated(c, Moments::FTS, mu, 1e-6), b = accelerated(c, Moments::FTS, mu, 1e-6);
  a->prepare(conf);
  const std::vector<PreparePhase> phases = b->prepare_phases(conf);
  CHECK(phases.size() == 3);
  for (const PreparePhase& p : phases) p.body();  // insertion order respects `after`
  const HydroResult ra = a->solve(HydroProblem{conf, c.fixed, sample, F, T});
  const HydroResult rb = b->solve(HydroProblem{conf, c.fixed, sample, F, T});
  CHECK(compare(rb, ra, Moments::FTS, c.fixed).worst() == 0.0);
}

TEST_CASE("accelerated SD: a sphere pushed along a periodic slit's midplane, its rotation zero by symmetry") {
  // The held-particle error estimate compares two iterates block by block; a block that vanishes
  // by symmetry holds only round-off and is measured against 1e-3 of the largest block
  // (AcceleratedStokesianDynamics::kNegligibleBlock). Before, this solve reported an estimated error
  // of 1e-4 ... 2e-3 above t = 1e-5 with the residual at 1e-13.
  const double mu = 1.0;
  const AmbientFlow still = ambient_flow(FlowParams{});
  Case c = wall_case(true);
  c.x.resize(100);
  c.x.emplace_back(2.05 * 4.5, 5.5, 2.05 * 4.5);  // above a cell centre, on the midplane y = 5.5
  c.a.assign(c.x.size(), 1.0);
  c.fixed.assign(c.x.size(), 1);
  c.fixed.back() = 0;
  const Configuration conf{c.x, c.a, c.domain};
  FlowSample sample;
  still.sample(c.x, sample);
  for (int dir : {0, 1}) {
    std::vector<Vec3> F(c.x.size(), Vec3::Zero()), T(c.x.size(), Vec3::Zero());
    F.back()[dir] = 1.0;
    for (Moments m : {Moments::FT, Moments::FTS}) {
      DenseStokesianDynamics dense(m, mu, still);
      dense.prepare(conf);
      const HydroResult ref = dense.solve(HydroProblem{conf, c.fixed, sample, F, T});
      for (double tol : {1e-3, 1e-5, 1e-8}) {
        CAPTURE(dir);
        CAPTURE(tol);
        auto s = accelerated(c, m, mu, tol);
        s->prepare(conf);
        HydroResult r;
        REQUIRE_NOTHROW(r = s->solve(HydroProblem{conf, c.fixed, sample, F, T}));
        const Vec3 U = r.U.back(), Uref = ref.U.back();
        MESSAGE("slit midplane, force along " << dir << ", " << std::string(to_string(m)) << ", tol " << tol << ": U "
                                              << U.transpose() << " (dense " << Uref.transpose() << "), |Omega| "
                                              << r.Omega.back().norm() << ", estimate " << s->stats().held_error_estimate);
        CHECK((U - Uref).norm() <= tol * Uref.norm());
        CHECK(r.Omega.back().norm() <= tol * Uref.norm());  // zero by symmetry, in units of U / a
        CHECK(rel(r.F, ref.F, &c.fixed) <= tol);
      }
    }
  }
  // No load and no flow: the right-hand side is zero, and so is the answer.
  const std::vector<Vec3> none(c.x.size(), Vec3::Zero());
  auto s = accelerated(c, Moments::FTS, mu, 1e-4);
  s->prepare(conf);
  HydroResult r;
  REQUIRE_NOTHROW(r = s->solve(HydroProblem{conf, c.fixed, sample, none, none}));
  CHECK(r.U.back().norm() == 0.0);
  CHECK(s->stats().iterations == 0);
}

TEST_CASE("accelerated SD with held particles: achieved error against dense SD at or below the tolerance") {
  // Held particles can make the right-hand side far larger than some solved quantities (random held
  // spheres in shear: forces ~ 6 pi mu a |u_inf| against rotations ~ rate; small holding forces on
  // a wall where the flow vanishes). Before the solver's error-estimated passes and the tighter far
  // field (engine/accuracy.cpp) these cases reached 0.95 t (random, half held) and 1.4-3.2 t (the
  // periodic slit's holding forces); at N = 1000 half held, 2.5 t (docs/accelerated_sd.md).
  const double mu = 1.0;
  const AmbientFlow flow = simple_shear(1.0);
  std::vector<Case> cases;
  // HELD_N=1000 (diagnostics): the random cases at that N, open 90 % held added (FT only above 500).
  const long n = std::getenv("HELD_N") ? std::atol(std::getenv("HELD_N")) : 300;
  const std::string of = " of " + std::to_string(n) + " held";
  cases.push_back(holding_all_but_every(make_case("open phi 0.2, half" + of, n, 0.2, false, 0.0, 0.0, 3, false, 911), 2));
  if (n > 300)
    cases.push_back(holding_all_but_every(make_case("open phi 0.2, 90 %" + of, n, 0.2, false, 0.0, 0.0, 3, false, 911), 10));
  cases.push_back(holding_all_but_every(make_case("periodic phi 0.2, 90 %" + of, n, 0.2, true, 0.0, 0.0, 3, false, 911), 10));
  cases.push_back(wall_case(true));
  for (const Case& c : cases) {
    const Loaded l = loaded(c, flow, 5);
    const Configuration& conf = l.conf;
    const HydroProblem problem{conf, c.fixed, l.sample, l.F, l.T};
    for (Moments m : {Moments::FT, Moments::FTS}) {
      if (m == Moments::FTS && c.x.size() > (c.domain.periodic() ? 200u : 500u)) continue;  // time (dense FTS)
      DenseStokesianDynamics dense(m, mu, flow);
      dense.prepare(conf);
      const HydroResult ref = dense.solve(problem);
      for (double tol : {1e-3, 1e-5}) {
        // Without and with the coarse part of the held-row preconditioner (built at once here;
        // engine/sd_accelerated.hpp), so both meet dense SD.
        for (int pass = 0; pass < 2; ++pass) {
          auto s = accelerated(c, m, mu, tol);
          s->set_held_coarse(pass == 1, true);
          s->prepare(conf);
          const Errors e = compare(s->solve(problem), ref, m, c.fixed);
          MESSAGE(c.name << " " << std::string(to_string(m)) << " tol " << tol << std::string(pass ? " (coarse part)" : "")
                         << ": error / tol U " << e.U / tol << ", Omega " << e.Omega / tol << ", S " << e.S / tol
                         << ", holding forces " << e.Ffixed / tol << "; iterations "
                         << s->stats().first_pass_iterations << " + "
                         << s->stats().iterations - s->stats().first_pass_iterations << ", estimated error "
                         << s->stats().held_error_estimate / tol << " tol");
          CAPTURE(c.name);
          CAPTURE(tol);
          CAPTURE(pass);
          CHECK(e.worst() <= tol);
          // The random held spheres of the periodic box use the long-wave part of the preconditioner,
          // so this also checks it against dense SD.
          if (c.domain.periodic() && c.name.rfind("periodic", 0) == 0) CHECK(s->stats().held_wave_vectors > 0);
          CHECK((s->stats().held_coarse_columns > 0) == (pass == 1 && s->stats().held_clusters > 1));
        }
      }
    }
  }
}
