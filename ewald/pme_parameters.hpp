#pragma once
// PME parameters from one tolerance: the only place where accuracy is turned into numbers
// (docs/ewald.md s.4 derives each line; s.5 has the measured errors).
//
// With L = ln(10 / tol) (one factor 10 of safety for sums over particles):
//  1. Real-space cutoff r_c (gap): about `neighbours` particles inside at the mean density, bounded
//     by the minimum-image contract of trees::neighbor_pairs (r_c + 2 a_max <= L_min / 2).
//  2. Splitting xi: the smallest value for which every real-space scalar of a neglected pair, at the
//     closest distance r_c + a_i + a_j, is below e^{-L} times the smallest self mobility (E9). The
//     scalars themselves are evaluated because their polynomial prefactors (up to (xi a)^3 x^4 e^{-x^2})
//     depend on the radii and the moments.
//  3. Wave-space truncation: the Hasimoto factor (1 + q) e^{-q}, q = k^2 / (4 xi^2), is below e^{-L}
//     for k > k_max; the grid holds |n_d| <= k_max |a_d| / (2 pi) per lattice direction, oversampled
//     by beta: M_d >= 2 beta n_max,d (FFT-friendly sizes 2^a 3^b 5^c).
//  4. Window width s (grid units), from aliasing: the alias of mode nu = n / M relative to nu is
//     exp(-2 pi^2 s^2 (1 - 2 nu)), weighted by the kernel exp(-La (2 beta nu)^2); the worst nu gives
//     2 t - t^2 / (beta^2 La) >= La with t = pi^2 s^2, smallest for t = beta^2 La (1 - sqrt(1 - 1/beta^2))
//     (E10; cf. the same trade-off in the parameters m, P of Lindbo & Tornberg 2010).
//     La = L + ln 10 + ln sqrt(M0 M1 M2) (aliasing errors of all modes add with random phases)
//     + ln(1 + a_max^2 k_max^2 / 6) (Faxen factor of the modes near k_max) + ln max(1, 2 (xi a_max)^3)
//     (share of the wave part in the torque/stresslet self terms).
//  5. Support P from truncation: exp(-(P/2)^2 / (2 s^2)) (1 + edge Laplacian term) <= e^{-Lt},
//     Lt = L + ln 10 + ln max(1, 2 (xi a_max)^3) (one window per particle: no sum over modes).
// Why Gaussians: their transform is analytic, so the deconvolution is exact on sheared grids
// (the window is separable in fractional coordinates, transform exp(-2 pi^2 sum (s n_d / M_d)^2)),
// and the Faxen Laplacian of the window is analytic too (window.hpp). The exponential of
// semicircle would need roughly half the points per direction at equal accuracy (8x fewer in 3D)
// but a numerical transform and a numerical Laplacian; B-splines alias more and need larger grids.
#include "ewald/lattice.hpp"

#include <array>

namespace stokesian::ewald {

struct PmeParameters {
  double tolerance = 1e-6;      // requested relative error of M x
  double xi = 1.0;              // splitting parameter [1/a]
  double cutoff_gap = 1.0;      // real-space cutoff: pairs with |r| < cutoff_gap + a_i + a_j [a]
  std::array<int, 3> grid{};    // FFT grid M_d along the lattice directions
  int support = 4;              // window points per direction P
  double width = 1.0;           // Gaussian standard deviation s [grid spacings]
  double k_max = 1.0;           // largest |k| kept by the Hasimoto factor [1/a]
};

struct PmeOptions {
  // Target particles inside the real-space cutoff sphere; 0 = automatic, P^3 / 8 (measured cost
  // balance: one real-space pair costs about as much as 8 window points of the wave part; at
  // most 400 to bound the memory of the pair list).
  double neighbours = 0.0;
  double beta = 1.4;         // k-space oversampling (3 above)
};

// Parameters for tolerance tol in [1e-14, 0.1] for n particles with radii in [a_min, a_max].
// Throws std::invalid_argument if the box is too small for the minimum-image real-space sum.
PmeParameters pme_parameters(double tol, const Lattice& lattice, int n, double a_min, double a_max, Moments m,
                             const PmeOptions& opt = {});

// Smallest integer >= n of the form 2^a 3^b 5^c with a >= 1 (even, FFT-friendly).
int fft_size(int n);

}  // namespace stokesian::ewald
