// Study (issue 17): why the held particles' rows converge slowly, and what a coarse space buys.
// Dense model of the held block alone (docs/accelerated_sd.md, "Coarse part"): the held spheres of
// the bench_channel scene ([L24] fig. 6: random hard spheres at phi = 0.2 in a periodic box, the
// first 90 % held, FT), M = the Ewald-summed grand mobility of the held spheres
// (ewald::ewald_mobility), and GMRES on M P y = b (b standard normal, relative residual 2e-6, the
// depth the solver's error-estimated passes reach at tolerance 1e-3) with
//   - P = B: the block-Jacobi inverse over clusters of at most 32 (the solver's bisect_clusters);
//   - P = G B G: with the long-wave deflation G of the held spheres (engine/brownian.hpp);
//   - two-level: coarse space Z of force fields uniform, or uniform and linear in position, over
//     coarse clusters of at most 32 / 64 / 128 spheres, E = Z^T M Z, added to G B G additively
//     (G B G + Z E^-1 Z^T) or multiplicatively (Z E^-1 Z^T + G B G (I - M Z E^-1 Z^T));
//   - the k slowest eigenvectors of G B G M deflated exactly (the best any recycled space can do).
// Also the spectrum of G B G M (similar to a symmetric matrix: real, positive).
// Rows: kind 0: smoother (1 blocks, 2 G B G), coarse (0 none, 1 uniform, 2 uniform + linear),
// cluster, form (0 additive, 1 multiplicative); iterations, columns. kind 1: k; iterations.
// kind 2: eigenvalue statistics. Usage: study_held_coarse [--quick] [--out DIR]; N = 300 (quick:
// 150); STUDY_N=n (up to 1000: a dense 6 N_H matrix and its eigenvectors, ~3 min at 1000); writes
// held_coarse_<N>.json.
#include "bench/harness.hpp"
#include "engine/brownian.hpp"
#include "engine/core/krylov.hpp"
#include "engine/sd_accelerated.hpp"
#include "engine/simulation.hpp"
#include "ewald/ewald_reference.hpp"
#include "io/scene_toml.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

using namespace stokesian;

using Clusters = std::vector<std::vector<std::size_t>>;

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  const long n = long(bench::env_number("STUDY_N", opt.quick ? 150 : 300, 50, 1000, true));
  bench::Results res(opt.quick ? "held_coarse_quick" : "held_coarse_" + std::to_string(n));
  const double L = std::cbrt(double(n) * 4.0 / 3.0 * kPi / 0.2);
  std::ostringstream o;
  o.precision(10);
  o << "[domain]\nkind = \"periodic\"\nbox = [" << L << ", " << L << ", " << L << "]\n"
    << "[particles]\ngenerate = \"random\"\ncount = " << n << "\nseed = 5\n"
    << "[hydrodynamics]\nmodel = \"stokesian\"\nsolver = \"accelerated\"\nmoments = \"FT\"\n[time]\ndt = 1e-4\nsteps = 1\n";
  const Scene scene = io::parse_scene(o.str(), "study_held_coarse.toml");
  const State st = Simulation(scene).initial_state();
  const long nh = std::lround(0.9 * double(n));
  const std::vector<Vec3> x(st.position.begin(), st.position.begin() + nh);
  const std::vector<double> a(std::size_t(nh), 1.0);
  const int d = 6;
  const long D = nh * d;
  MatX M = ewald::ewald_mobility(x, a, 1.0, Moments::FT, st.domain);
  M = (0.5 * (M + M.transpose())).eval();

  const Clusters blocks = bisect_clusters(x, 32);  // as the solver (engine/sd_accelerated.hpp)
  std::vector<std::vector<long>> entries;
  std::vector<Eigen::LLT<MatX>> factors;
  for (const auto& c : blocks) {
    std::vector<long> e;
    for (long i : c)
      for (int q = 0; q < d; ++q) e.push_back(i * d + q);
    MatX B(long(e.size()), long(e.size()));
    for (std::size_t r = 0; r < e.size(); ++r)
      for (std::size_t s = 0; s < e.size(); ++s) B(long(r), long(s)) = M(e[r], e[s]);
    entries.push_back(e);
    factors.emplace_back(B);
  }
  const LongWaveDeflation G(Configuration{x, a, st.domain}, Moments::FT, LongWaveDeflation::kMinRatio, 64);
  auto apply_blocks = [&](VecX& z) {
    for (std::size_t c = 0; c < entries.size(); ++c) {
      VecX r(long(entries[c].size()));
      for (std::size_t k = 0; k < entries[c].size(); ++k) r[long(k)] = z[entries[c][k]];
      r = factors[c].solve(r);
      for (std::size_t k = 0; k < entries[c].size(); ++k) z[entries[c][k]] = r[long(k)];
    }
  };
  auto apply_gbg = [&](VecX& z) {
    VecX t;
    G.apply(z, t);
    apply_blocks(t);
    G.apply(t, z);
  };
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  VecX b(D);
  for (long i = 0; i < D; ++i) b[i] = normal(rng);
  const double tol = 2e-6;
  auto iterations = [&](const std::function<VecX(const VecX&)>& P) {
    const LinearOperator A = [&](const VecX& y, VecX& out) { out = M * P(y); };
    VecX y = VecX::Zero(D);
    return gmres(A, b, y, tol, 3000, 300).iterations;
  };
  std::printf("N = %ld, held %ld (FT, %ld unknowns), %zu blocks, %zu long-wave vectors\n", n, nh, D, blocks.size(),
              G.wave_vectors());

  // Coarse spaces: per coarse cluster, uniform (3 columns) or uniform and linear (12).
  auto coarse_space = [&](std::size_t cap, bool linear) {
    const Clusters cl = bisect_clusters(x, cap);
    MatX Z = MatX::Zero(D, long(cl.size()) * (linear ? 12 : 3));
    long col = 0;
    for (const auto& c : cl) {
      Vec3 centre = Vec3::Zero();
      for (long i : c) centre += x[std::size_t(i)];
      centre /= double(c.size());
      for (long i : c)
        for (int q = 0; q < 3; ++q) {
          Z(i * d + q, col + q) = 1.0;
          if (linear)
            for (int p = 0; p < 3; ++p) Z(i * d + q, col + 3 + 3 * q + p) = x[std::size_t(i)][p] - centre[p];
        }
      col += linear ? 12 : 3;
    }
    return Z;
  };
  for (int smoother : {1, 2})
    for (int coarse : {0, 1, 2})
      for (std::size_t cap : {std::size_t(32), std::size_t(64), std::size_t(128)})
        for (int form : {0, 1}) {
          if (coarse == 0 && (cap != 32 || form == 1)) continue;
          MatX Z = coarse ? coarse_space(cap, coarse == 2) : MatX(D, 0);
          const MatX MZ = M * Z;
          const Eigen::LDLT<MatX> E(Z.transpose() * MZ);
          auto smooth = [&](VecX& z) { smoother == 1 ? apply_blocks(z) : apply_gbg(z); };
          auto P = [&](const VecX& r) -> VecX {
            if (!Z.cols()) {
              VecX t = r;
              smooth(t);
              return t;
            }
            const VecX c = E.solve(Z.transpose() * r);
            VecX t = form == 1 ? VecX(r - MZ * c) : r;
            smooth(t);
            return t + Z * c;
          };
          const int it = iterations(P);
          std::printf("%-8s coarse %-16s clusters <= %3zu, %-14s %4ld columns: %3d iterations\n",
                      smoother == 1 ? "blocks" : "G B G", coarse == 0 ? "none" : coarse == 1 ? "uniform" : "uniform+linear",
                      cap, form ? "multiplicative" : "additive", long(Z.cols()), it);
          res.add({{"kind", 0}, {"smoother", smoother}, {"coarse", coarse}, {"cluster", double(cap)}, {"form", form}},
                  {{"iterations", it}, {"columns", double(Z.cols())}});
        }

  // Spectrum of G B G M and exact deflation of its slowest eigenvectors.
  MatX Pm(D, D);
  for (long j = 0; j < D; ++j) {
    VecX e = VecX::Zero(D);
    e[j] = 1.0;
    apply_gbg(e);
    Pm.col(j) = e;
  }
  const MatX Lp = Eigen::LLT<MatX>((0.5 * (Pm + Pm.transpose())).eval()).matrixL();
  const Eigen::SelfAdjointEigenSolver<MatX> es((Lp.transpose() * M * Lp).eval());
  const VecX ev = es.eigenvalues();
  auto below = [&](double v) { return double((ev.array() < v).count()); };
  std::printf("spectrum of G B G M: %.3g ... %.3g (ratio %.1f); below 0.2: %.0f, below 0.3: %.0f, below 0.5: %.0f of %ld\n",
              ev[0], ev[D - 1], ev[D - 1] / ev[0], below(0.2), below(0.3), below(0.5), D);
  res.add({{"kind", 2}}, {{"min", ev[0]}, {"max", ev[D - 1]}, {"below_0.2", below(0.2)}, {"below_0.3", below(0.3)},
                          {"below_0.5", below(0.5)}, {"unknowns", double(D)}});
  for (long k : {10L, 30L, 100L}) {
    if (k >= D / 4) continue;
    MatX Z(D, k);
    for (long i = 0; i < k; ++i) Z.col(i) = Lp * es.eigenvectors().col(i);
    const MatX MZ = M * Z;
    const Eigen::LDLT<MatX> E(Z.transpose() * MZ);
    const int it = iterations([&](const VecX& r) -> VecX {
      const VecX c = E.solve(Z.transpose() * r);
      VecX t = r - MZ * c;
      apply_gbg(t);
      return t + Z * c;
    });
    std::printf("G B G with its %ld slowest eigenvectors deflated: %d iterations\n", k, it);
    res.add({{"kind", 1}, {"k", double(k)}}, {{"iterations", it}});
  }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
