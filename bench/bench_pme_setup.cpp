// Benchmark of the PME set-up against the product (ewald/pme.hpp, ewald/pme_parameters.hpp): what a
// new configuration costs (PmeFarField::update_positions: windows, slab order, real-space pair search,
// pair data and scalar cache) beside one product, and what pricing it in the cost model
// (PmeOptions::products_per_update) gains. Far-field-only dynamics makes one product per
// configuration (each Runge-Kutta stage moves the particles), the iterative solvers about 20.
// Charted by bench/plot_pme_setup.py, which also fits the set-up constants of the cost model.
//
// Cases: n spheres of radius 1 (lognormal radii of s.d. 0.065 for the destabilisation case, the
// scene of configs/destabilisation.toml), centres uniform in a cubic periodic box at volume fraction
// phi (overlaps allowed), std::mt19937_64(seed 7); input uniform in [-1, 1]. One thread. Each case:
//   kind 0, neighbour sweep: the parameters for a fixed number of neighbours (PmeOptions::neighbours,
//     the rest by the model), the set-up (median of update_positions after a small displacement of
//     every particle) and the product (median of apply), the model's set-up estimate (est_setup) and
//     product estimate (est_cost at products_per_update 0). Params: case, N, phi, dof, tol,
//     neighbours, entries_per_particle (ordered real-space entries / N), grid, support; phases
//     setup, product, est_setup, est_product.
//   kind 1, the model's choice for products_per_update = 0 (the product alone), 1 and 20: parameters,
//     measured set-up and product, and the achieved error against a PME product at tolerance 1e-12.
//     Params: case, N, phi, dof, tol, ppu, grid, support, entries_per_particle, error; phases setup,
//     product, est_cost.
//   bench_pme_setup [--quick] [--out DIR]   (--quick: the two smallest cases, ~20 s)
#include "bench/harness.hpp"
#include "ewald/pme.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace stokesian;

namespace {

struct Case {
  std::string name;
  long n;
  double phi;
  Moments m;
  double tol;
  bool lognormal;
};

struct Config {
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain domain;
};

Config make_config(const Case& c) {
  std::mt19937_64 rng(7);
  Config k;
  k.a.assign(c.n, 1.0);
  if (c.lognormal) {
    // configs/destabilisation.toml: ln a ~ N(-0.0021076, 0.0042153) (mean 1, s.d. 0.065).
    std::normal_distribution<double> g(-0.0021076, std::sqrt(0.0042153));
    for (double& r : k.a) r = std::exp(g(rng));
  }
  double v = 0.0;
  for (double r : k.a) v += 4.0 / 3.0 * kPi * r * r * r;
  const double L = std::cbrt(v / c.phi);
  k.domain = Domain::periodic_box(Vec3(L, L, L));
  std::uniform_real_distribution<double> u(0.0, L);
  k.x.resize(c.n);
  for (Vec3& p : k.x) p = Vec3(u(rng), u(rng), u(rng));
  return k;
}

int dof_of(Moments m) { return dof_per_particle(m); }

// Median set-up (update_positions after a displacement of 1e-3 a) and product over `reps`.
std::pair<double, double> time_setup_product(ewald::PmeFarField& f, std::vector<Vec3> x, const VecX& in, int reps) {
  VecX out;
  double step = 1e-3;
  const double setup = bench::median_time(
      [&] {
        for (Vec3& p : x) p.x() += step;
        step = -step;
        f.update_positions(x);
      },
      reps);
  const double product = bench::median_time([&] { f.apply(in, out); }, reps);
  return {setup, product};
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  omp_set_num_threads(1);
  std::vector<Case> cases = {
      {"destabilisation N=500", 500, 0.05, Moments::FT, 1e-3, true},
      {"destabilisation N=2000", 2000, 0.05, Moments::FT, 1e-3, true},
      {"F phi=0.1 N=1e4", 10000, 0.1, Moments::F, 1e-4, false},
      {"FT phi=0.25 N=1e4", 10000, 0.25, Moments::FT, 1e-3, false},
      {"FTS phi=0.4 N=1e4", 10000, 0.4, Moments::FTS, 1e-4, false},
  };
  if (opt.quick) cases.resize(2);
  bench::Results res(opt.quick ? "pme_setup_quick" : "pme_setup");
  for (std::size_t ci = 0; ci < cases.size(); ++ci) {
    const Case& c = cases[ci];
    const Config k = make_config(c);
    const int d = dof_of(c.m);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    VecX in(c.n * d);
    for (Eigen::Index i = 0; i < in.size(); ++i) in[i] = u(rng);
    const int reps = opt.quick ? 5 : (c.n <= 2000 ? 41 : 7);
    std::printf("%s (%s, tol %g)\n", c.name.c_str(), c.m == Moments::F ? "F" : c.m == Moments::FT ? "FT" : "FTS", c.tol);
    // kind 0: neighbour sweep.
    for (double nb = 4.0; nb <= 250.0; nb *= 1.4) {
      ewald::PmeOptions o;
      o.neighbours = nb;
      std::unique_ptr<ewald::PmeFarField> f;
      try {
        f = std::make_unique<ewald::PmeFarField>(k.x, k.a, 1.0, c.m, k.domain, c.tol, o);
      } catch (const std::invalid_argument&) {
        continue;  // cutoff beyond half the box
      }
      const ewald::PmeParameters& p = f->parameters();
      const auto [setup, product] = time_setup_product(*f, k.x, in, reps);
      const double entries = 2.0 * double(f->real_pairs()) / double(c.n);
      std::printf("  neighbours %6.1f  grid %3d P %2d entries/N %6.1f  set-up %.3e s (model %.3e)  product %.3e s (model %.3e)\n",
                  nb, p.grid[0], p.support, entries, setup, p.est_setup, product, p.est_cost);
      res.add({{"kind", 0}, {"case", double(ci)}, {"N", double(c.n)}, {"phi", c.phi}, {"dof", double(d)}, {"tol", c.tol},
               {"neighbours", nb}, {"entries_per_particle", entries}, {"grid", double(p.grid[0])},
               {"support", double(p.support)}},
              {{"setup", setup}, {"product", product}, {"est_setup", p.est_setup}, {"est_product", p.est_cost}});
    }
    // kind 1: the model's choices.
    VecX ref;
    {
      ewald::PmeFarField r(k.x, k.a, 1.0, c.m, k.domain, 1e-12);
      r.apply(in, ref);
    }
    for (double ppu : {0.0, 1.0, 20.0}) {
      ewald::PmeOptions o;
      o.products_per_update = ppu;
      ewald::PmeFarField f(k.x, k.a, 1.0, c.m, k.domain, c.tol, o);
      const ewald::PmeParameters& p = f.parameters();
      VecX out;
      f.apply(in, out);
      const double err = (out - ref).norm() / ref.norm();
      const auto [setup, product] = time_setup_product(f, k.x, in, reps);
      const double entries = 2.0 * double(f.real_pairs()) / double(c.n);
      std::printf("  choice for %2.0f products per configuration: grid %3d P %2d entries/N %6.1f  set-up %.3e  product %.3e  "
                  "error/tol %.2f\n",
                  ppu, p.grid[0], p.support, entries, setup, product, err / c.tol);
      res.add({{"kind", 1}, {"case", double(ci)}, {"N", double(c.n)}, {"phi", c.phi}, {"dof", double(d)}, {"tol", c.tol},
               {"ppu", ppu}, {"grid", double(p.grid[0])}, {"support", double(p.support)},
               {"entries_per_particle", entries}, {"error", err}},
              {{"setup", setup}, {"product", product}, {"est_cost", p.est_cost}});
    }
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
}
