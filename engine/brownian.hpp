#pragma once
// Brownian forces of the hydrodynamic solvers (docs/brownian.md).
//
// With R the solver's resistance in the generalised layout (engine/core/layout.hpp) and v the
// entries whose force is given (the mobile particles' F and T; stresslets and fixed particles'
// entries have their motion given), the Brownian velocity V_v must have covariance
// (2 kT / dt) (R_vv)^{-1} (fluctuation-dissipation; for fixed particles and rigid stresslets the
// mobility of the mobile block, seed 1 s. 2.1.3). A force xi with covariance (2 kT / dt) R_vv,
// solved for like any given force, R_vv V_v = xi_v, gives exactly that. With R = M_inf^{-1} + R_nf
// (Stokesian dynamics, Durlofsky, Brady & Bossis 1987) xi is the sum of two independent parts
// (method notes s. 5; seed 1 eqs. 2.50-2.51):
//   near field  xi_nf = sum over pairs of L_p w_p, L_p L_p^T the pair's lubrication block on the
//               v entries (NearField::brownian_force): covariance R_nf,vv exactly, O(pairs);
//   far field   xi_ff = (M_inf^{-1/2} psi)_v, psi standard normal on all entries, by the Lanczos
//               approximation of f(M) = M^{-1/2} (Chow & Saad 2014) with far-field products
//               only: covariance (M_inf^{-1})_vv.
// Both are scaled by sqrt(2 kT / dt). The same xi is reused by both stages of the Fixman midpoint
// step (engine/integrators.hpp), which then produces the drift kT div(R_vv^{-1}).
//
// Why these samplers (measured, bench/bench_brownian.cpp and docs/brownian.md):
//  - near field, pairwise rather than P^T L w with L the CHOLMOD factor of R_nf: the accelerated
//    solver factorises only the strong pairs plus a shift (engine/sd_accelerated.hpp) because the
//    factor of the whole R_nf fills like N^1.5 at phi >= 0.3 (bench_asd "fill": 2.3e6 against
//    5.1e4 nonzeros at N = 500, phi = 0.45); a factor of R_nf itself would be a second, much larger
//    factorisation per step, and R_nf is singular for particles with no pair. The pairwise sum is
//    exact, linear in the pairs, and parallel.
//  - far field, Lanczos rather than a positively split Ewald sampler (Fiore et al. 2017): it works
//    with every far-field method (direct, Ewald, PME, sheared) through the operator alone.
//    Plain Lanczos took 26 / 44 / 65 iterations at N = 1e3 / 1e4 / 1e5 (bench_brownian, phi = 0.4,
//    sheared, FTS, tolerance 1e-3), against 22 / 23 / 30 GMRES products per solve.
//  - in periodic boxes the Lanczos run is preconditioned (Chow & Saad 2014, SIAM J. Sci. Comput.
//    36, A588): for any invertible symmetric G, x = G (G M G)^{-1/2} psi has covariance
//    G (G M G)^{-1} G = M^{-1} exactly, and G = LongWaveDeflation (below) removes the long-wave
//    collective modes that set the top of M's spectrum.
// Streams: psi from the caller's stream, then the pair vectors from a fork of it (RandomStream::fork).
#include "engine/core/krylov.hpp"
#include "engine/core/layout.hpp"
#include "engine/core/operators.hpp"

#include <array>
#include <complex>
#include <vector>

namespace stokesian {

// One flag per generalised entry (length n d): 1 where the force is given (mobile particles' F, T).
std::vector<char> force_given_flags(Moments m, long n, const std::vector<char>& fixed);

// Self resistance per generalised entry: 6 pi mu a (F), 8 pi mu a^3 (T), 20/3 pi mu a^3 (S, in the
// orthonormal symmetric-traceless coordinates of engine/core/sym_traceless.hpp).
VecX self_resistance(const std::vector<double>& a, double mu, Moments m);

struct LanczosReport {
  int iterations = 0;
  long wave_vectors = 0;  // of the long-wave deflation (0: none)
};

// Long-wave deflation G of the far-field mobility of a periodic box (brownian.cpp has the
// mathematics). G is symmetric, fixed by the configuration, and the identity in open domains or when
// no collective mode stands above the rest of the spectrum.
class LongWaveDeflation {
 public:
  LongWaveDeflation(const Configuration& c, Moments m, double min_ratio = kMinRatio,
                    long max_wave_vectors = kMaxWaveVectors);
  bool empty() const { return n_.empty(); }
  std::size_t wave_vectors() const { return n_.size(); }
  // out = G in (out is resized; in and out may not alias).
  void apply(const VecX& in, VecX& out) const;

  // Deflate modes whose estimated eigenvalue is at least kMinRatio times the self mobility, at most
  // kMaxWaveVectors wave vectors (4 modes each; applying G costs ~24 flops per particle and wave
  // vector, so 128 is 10-30 % of an FTS PME product at N = 1e3-1e4, docs/brownian.md).
  static constexpr double kMinRatio = 2.0;
  static constexpr long kMaxWaveVectors = 128;

 private:
  int d_ = 3;
  long np_ = 0;
  int nmax_[3] = {0, 0, 0};
  std::vector<std::array<int, 3>> n_;  // integer wave vectors, k = 2 pi A^{-T} n
  std::vector<Mat3> w_;                // (c_k - 1) (2 / N) (I - k k^T / k^2) per wave vector
  std::vector<std::complex<double>> u_;  // e^{2 pi i s_d}, s the fractional coordinates, 3 per particle
};

// y = G (G M G)^{-1/2} psi, G = LongWaveDeflation(c) (the identity outside periodic boxes), by
// Lanczos to relative change `tol` on G M G: for standard normal psi, covariance M^{-1}.
KrylovResult far_field_inverse_sqrt(const MobilityOperator& M, const Configuration& c, const VecX& psi, VecX& y,
                                    double tol, LanczosReport* report = nullptr);

// scale * (M^{-1/2} psi) with psi standard normal from rng (M.size() draws), zero outside the
// flagged entries. Lanczos to relative change `tol` on G M G with G = LongWaveDeflation(c) (the
// identity outside periodic boxes); PhysicsError when it fails. c is M's configuration.
VecX far_field_brownian_force(const MobilityOperator& M, const Configuration& c, const std::vector<char>& given,
                              double scale, double tol, Rng& rng, LanczosReport* report = nullptr);

}  // namespace stokesian
