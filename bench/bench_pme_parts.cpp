// The PME error model part by part (issue 12): each part's achieved error against its estimate
// (ewald/pme_parameters.hpp: est_real, est_wave, est_alias; est_alias includes the window's edge
// jumps), which shows which estimate sets the achieved/requested ratio of the whole product
// (docs/ewald.md s.5). For the engine's parameters at tolerance tol, the product's relative error against a
// 1e-10 PME reference, and three variants with one or two parts made negligible (PmeOptions::fixed):
//   real_only   the same xi and cutoff, grid doubled per direction, support +6 (window shape scaled
//               with it): wave truncation and aliasing vanish, the real-space truncation remains;
//   wave_alias  the same grid and window, the cutoff gap extended by 4 / xi: real-space truncation
//               vanishes, wave truncation and aliasing remain;
//   wave_trunc  as wave_alias with the support +6: aliasing (and the window's truncation) vanish as
//               well, the wave truncation at the grid's resolution remains.
// alias = sqrt(wave_alias^2 - wave_trunc^2). Variants whose range exceeds half the box are skipped
// (-1). Configurations as bench_pme (unit spheres at uniform random centres, overlaps allowed, cubic
// box; input uniform in [-1, 1] from seed N + 17). Rows: moments (3 = F, 11 = FTS), phi, tol, N,
// xi, cutoff_gap, grid, support; est_real, est_wave, est_alias; error, real_only, wave_alias,
// wave_trunc, alias (all relative to |M x|). No timing.
//   bench_pme_parts [--quick] [--out DIR]   (--quick: N = 2000, tolerances 1e-2 and 1e-4)
#include "bench/harness.hpp"
#include "ewald/pme.hpp"
#include "ewald/pme_parameters.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

using namespace stokesian;

namespace {

// Relative error of the PME product with parameters q (or the engine's when q is null); -1 when
// the variant cannot be built in this box.
double variant_error(const std::vector<Vec3>& x, const std::vector<double>& a, Moments m, const Domain& dom, double tol,
                     const ewald::PmeParameters* q, const VecX& v, const VecX& yref) {
  ewald::PmeOptions o;
  if (q) o.fixed = *q;
  try {
    ewald::PmeFarField f(x, a, 1.0, m, dom, tol, o);
    VecX y;
    f.apply(v, y);
    return (y - yref).norm() / yref.norm();
  } catch (const std::invalid_argument&) {
    return -1.0;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "pme_parts_quick" : "pme_parts");
  const long n = opt.quick ? 2000 : 10000;
  const std::vector<double> tols = opt.quick ? std::vector<double>{1e-2, 1e-4} : std::vector<double>{1e-2, 1e-4, 1e-6};
  std::printf("%-3s %4s %6s: %6s %6s %6s | %6s %6s %6s %6s %6s  (x tol; measured / estimate: real, wave, alias)\n", "m",
              "phi", "tol", "est_r", "est_w", "est_a", "error", "real", "w+a", "wave", "alias");
  for (Moments m : {Moments::F, Moments::FTS})
    for (double phi : {0.1, 0.4}) {
      const double L = std::cbrt(double(n) * 4.0 * kPi / 3.0 / phi);
      std::mt19937_64 rng(static_cast<unsigned long>(n));
      std::uniform_real_distribution<double> u(0, 1);
      std::vector<Vec3> x;
      for (long i = 0; i < n; ++i) {
        const double p = L * u(rng), q = L * u(rng), r = L * u(rng);
        x.emplace_back(p, q, r);
      }
      const std::vector<double> a(static_cast<std::size_t>(n), 1.0);
      const Domain dom = Domain::periodic_box(Vec3(L, L, L));
      std::mt19937_64 r2(static_cast<unsigned long>(n) + 17);
      std::uniform_real_distribution<double> u2(-1, 1);
      VecX v(n * dof_per_particle(m));
      for (auto& e : v) e = u2(r2);
      VecX yref;
      ewald::PmeFarField(x, a, 1.0, m, dom, 1e-10).apply(v, yref);
      for (double tol : tols) {
        const ewald::PmeFarField engine(x, a, 1.0, m, dom, tol);
        const ewald::PmeParameters p = engine.parameters();
        const double error = variant_error(x, a, m, dom, tol, &p, v, yref);
        ewald::PmeParameters fine = p, longer = p, wide = p;
        for (auto& g : fine.grid) g = ewald::fft_size(2 * g);
        fine.support = std::min(16, p.support + 6);
        fine.shape = p.shape * double(fine.support) / double(p.support);
        fine.k_max = 2.0 * p.k_max;
        longer.cutoff_gap = p.cutoff_gap + 4.0 / p.xi;
        wide = longer;
        wide.support = fine.support;
        wide.shape = fine.shape;
        const double real_only = variant_error(x, a, m, dom, tol, &fine, v, yref);
        const double wave_alias = variant_error(x, a, m, dom, tol, &longer, v, yref);
        const double wave_trunc = variant_error(x, a, m, dom, tol, &wide, v, yref);
        const double alias = wave_alias >= 0 && wave_trunc >= 0 && wave_alias > wave_trunc
                                 ? std::sqrt(wave_alias * wave_alias - wave_trunc * wave_trunc)
                                 : -1.0;
        auto cell = [](double meas, double scale) {
          char b[16];
          if (meas < 0) return std::string("     -");
          std::snprintf(b, sizeof b, "%6.3f", meas / scale);
          return std::string(b);
        };
        std::printf("%-3s %4.1f %6.0e: %6.3f %6.3f %6.3f | %s %s %s %s %s  (%s, %s, %s)\n", to_string(m), phi, tol,
                    p.est_real / tol, p.est_wave / tol, p.est_alias / tol, cell(error, tol).c_str(),
                    cell(real_only, tol).c_str(), cell(wave_alias, tol).c_str(), cell(wave_trunc, tol).c_str(),
                    cell(alias, tol).c_str(), cell(real_only, p.est_real).c_str(), cell(wave_trunc, p.est_wave).c_str(),
                    cell(alias, p.est_alias).c_str());
        std::fflush(stdout);
        res.add({{"moments", double(dof_per_particle(m))},
                 {"phi", phi},
                 {"tol", tol},
                 {"N", double(n)},
                 {"xi", p.xi},
                 {"cutoff_gap", p.cutoff_gap},
                 {"grid", double(p.grid[0])},
                 {"support", double(p.support)},
                 {"est_real", p.est_real},
                 {"est_wave", p.est_wave},
                 {"est_alias", p.est_alias}},
                {{"error", error},
                 {"real_only", real_only},
                 {"wave_alias", wave_alias},
                 {"wave_trunc", wave_trunc},
                 {"alias", alias}});
      }
    }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
