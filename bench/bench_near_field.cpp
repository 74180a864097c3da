// Benchmark: near-field (lubrication) assembly and CHOLMOD factorisation against N and volume
// fraction, random bidisperse configurations (radii 1 and 1.4, equal numbers) in periodic boxes
// (phi = 0.1-0.5). NearField registers the scene's size ratios (<= 4 distinct radii: exact tables
// for lambda = 1, 1.4, 1/1.4), built during the untimed first assembly (phase "tables").
// Continuous radii use tables interpolated in ln(lambda) (lubrication/resistance_table.hpp).
// Phases: "neighbors" (cell-list search), "assembly" (R_nf over pairs with s < 4), "analyze_factor"
// (first factorisation: ordering + symbolic + numeric), "refactor" (numeric only, pattern reused),
// "solve". The factorised matrix is R_nf + R_self, R_self the block-diagonal single-sphere
// resistance (the near-field part of the preconditioner of [L24] eq. 2.46). Fill = nnz(L).
//   bench_near_field [--quick] [--out DIR]
#include "bench/harness.hpp"
#include "trees/placement.hpp"
#include "lubrication/cholmod_factor.hpp"
#include "lubrication/near_field.hpp"
#include "trees/neighbor_list.hpp"

#include <omp.h>

#include <cmath>
#include <cstdio>
#include <cstring>

using namespace stokesian;

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  const bool quick = opt.quick;
  const std::string out = opt.out;
  const std::vector<long> sizes = quick ? std::vector<long>{200, 400} : std::vector<long>{500, 1000, 2000, 4000};
  const std::vector<double> phis = quick ? std::vector<double>{0.1, 0.5} : std::vector<double>{0.1, 0.2, 0.3, 0.4, 0.5};
  bench::Results res(quick ? "near_field_quick" : "near_field");
  for (Moments m : {Moments::FT, Moments::FTS}) {
    const int d = dof_per_particle(m);
    for (double phi : phis) {
      for (long n : sizes) {
        if (m == Moments::FTS && n > 2000) continue;
        PlacementParams p;
        p.count = n;
        p.volume_fraction = phi;
        p.sizes = PlacementParams::Sizes::bidisperse;
        p.radius_ratio = 1.4;
        p.large_fraction = 0.5;
        p.seed = std::uint64_t(n);
        const double L = std::cbrt(double(n) * 4.0 / 3.0 * M_PI * 0.5 * (1 + 1.4 * 1.4 * 1.4) / phi);
        const Placement pl = place_particles(p, Vec3::Constant(L));
        Domain dom;
        dom.kind = Domain::Kind::periodic;
        dom.box = Vec3::Constant(L);
        lubrication::NearField nf(m, 1.0);
        std::map<std::string, double> ph;
        ph["neighbors"] = bench::median_time([&] { trees::neighbor_pairs(pl.position, pl.radius, dom, 2.0 * 1.4); }, 3);
        lubrication::SparseMatrix R;
        lubrication::NearFieldStats st;
        ph["tables"] = bench::time_once([&] { nf.assemble(pl.position, pl.radius, dom); });  // once per lambda
        lubrication::SymmetricBlockMatrix blocks;  // the assembly the accelerated solver uses
        ph["assembly"] = bench::median_time([&] { nf.assemble(pl.position, pl.radius, dom, blocks, &st); }, 1);
        R = blocks.to_sparse();
        for (long i = 0; i < n; ++i) {
          const double a = pl.radius[std::size_t(i)];
          for (int k = 0; k < d; ++k)
            R.coeffRef(i * d + k, i * d + k) += k < 3 ? 6 * M_PI * a : k < 6 ? 8 * M_PI * a * a * a : 20.0 / 3.0 * M_PI * a * a * a;
        }
        R.makeCompressed();
        double nnzL = 0;
        ph["analyze_factor"] = bench::time_once([&] {
          lubrication::CholmodFactor f;
          f.factorize(R);
          nnzL = double(f.factor_nonzeros());
        });
        lubrication::CholmodFactor f;
        f.factorize(R);
        ph["refactor"] = bench::median_time([&] { f.factorize(R); }, 3);
        const VecX b = VecX::Ones(R.rows());
        ph["solve"] = bench::median_time([&] { f.solve(b); }, 3);
        res.add({{"N", double(n)}, {"phi", phi}, {"dof", double(d)}, {"pairs", double(st.pairs)}, {"nnz_R", double(R.nonZeros())},
                 {"nnz_L", nnzL}, {"threads", double(omp_get_max_threads())}},
                ph);
        std::printf("%-3s phi=%.1f N=%5ld pairs=%7ld assembly %.3e s factor %.3e s refactor %.3e s fill %.2f\n", to_string(m),
                    phi, n, st.pairs, ph["assembly"], ph["analyze_factor"], ph["refactor"], nnzL / double(R.nonZeros()));
        std::fflush(stdout);
      }
    }
  }
  std::printf("wrote %s\n", res.write(out).c_str());
  return 0;
}
