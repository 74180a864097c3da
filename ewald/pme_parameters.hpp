#pragma once
// PME parameters from one tolerance: the only place where accuracy is turned into numbers.
//
// Error sources and the choice that bounds each by about tol (L_eps = ln(1 / tol) + margin):
//  1. Real-space truncation. The real part of Psi decays like erfc(xi r) and exp(-xi^2 r^2)
//     (ewald_split.hpp), so pairs farther than r_c contribute ~ exp(-xi^2 r_c^2): xi = sqrt(L_eps) / r_c,
//     with r_c the smallest centre distance a neglected pair can have.
//  2. Wave-space truncation. The Hasimoto factor (1 + q) exp(-q), q = k^2 / (4 xi^2), is below tol for
//     k > k_max; the grid must hold |n_d| <= n_max,d = k_max |a_d| / (2 pi) in every lattice
//     direction, times an oversampling factor beta: M_d >= 2 beta n_max,d.
//  3. Window aliasing. The Gaussian window w(delta) = exp(-delta^2 / (2 s^2)) (delta in grid units)
//     has transform exp(-2 pi^2 s^2 nu^2) (nu = n / M); the alias from n - M relative to n is
//     exp(-2 pi^2 s^2 (1 - 2 nu)), weighted by the kernel exp(-L_eps (2 beta nu)^2). The worst nu
//     gives the bound 2 t - t^2 / (beta^2 L_eps) >= L_eps with t = pi^2 s^2, smallest for
//     t = beta^2 L_eps (1 - sqrt(1 - 1 / beta^2)) (Lindbo & Tornberg 2010, s.4, give the same trade-off
//     in their notation m, P).
//  4. Window truncation at P points: exp(-(P/2)^2 / (2 s^2)) <= tol, P = 2 s sqrt(2 L_eps).
// Why Gaussians: their transform is analytic, so the deconvolution is exact on sheared grids
// (the window is separable in fractional coordinates and its transform is exp(-2 pi^2 sum (s n_d / M_d)^2)),
// and the Faxen Laplacian of the window is analytic too (spread.hpp). The exponential of
// semicircle needs about 30% fewer points per direction at equal accuracy but a numerical
// transform; B-splines alias more and need larger grids.
// Real-space cutoff: r_c gives about `neighbours` particles in the cutoff sphere at the mean
// density, bounded by the minimum-image contract of trees::neighbor_pairs (r_c + 2 a_max <= L_min / 2).
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
