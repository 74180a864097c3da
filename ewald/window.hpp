#pragma once
// Gaussian window of the PME far field, evaluated per particle on the grid of fractional coordinates.
//
// The grid has M_d points along lattice direction d (fractional s_d = i_d / M_d). A particle at
// fractional position s_p touches the P points i = i0 .. i0 + P - 1 per direction with
// i0 = ceil(M s_p - P/2) (indices taken modulo M), at offsets delta = i - M s_p in grid units. The
// window is separable in fractional coordinates,
//     W(x) = prod_d omega(delta_d),   omega(delta) = exp(-delta^2 / (2 s^2)) / (sqrt(2 pi) s),
// (unit sum over the grid), with transform W^(n) = prod_d exp(-2 pi^2 s^2 n_d^2 / M_d^2)
// [docs/ewald.md (E7)]. On a sheared lattice it is an anisotropic Gaussian
// in x, which the deconvolution by W^(n)^2 handles exactly.
// Faxen factors: the spreading/interpolation kernel of a particle of radius a is W + c lap W with
// c = a^2/6 (force/velocity) or a^2/10 (torque, stresslet / rotation, strain), whose transform is
// (1 - c k^2) W^ -- the truncated Faxen factor of ewald_split.hpp. In grid units
//     lap = sum_ij Gt_ij d/d delta_i d/d delta_j,   Gt_ij = (A^{-1} A^{-T})_ij M_i M_j.
#include "engine/core/types.hpp"

#include <array>
#include <vector>

namespace stokesian::ewald {

struct GridGeometry {
  std::array<int, 3> M{};  // grid points per lattice direction
  int P = 4;               // support (points per direction)
  double s = 1.0;          // Gaussian standard deviation [grid spacings]
  Mat3 lap = Mat3::Zero(); // Gt: the physical Laplacian in grid-unit derivatives
  long points() const { return long(M[0]) * M[1] * M[2]; }
  long index(int i, int j, int k) const { return (long(i) * M[1] + j) * M[2] + k; }
};

// Window data of all particles: first index i0 per direction and omega, omega', omega'' at the
// P offsets, per direction; cF = a^2/6 and cT = a^2/10 per particle.
struct ParticleWindows {
  int P = 0;
  std::vector<std::array<int, 3>> start;  // i0 in [0, M_d)
  std::vector<double> w;                  // [particle][dir 0..2][omega, omega', omega''][P]
  std::vector<double> cF, cT;
  const double* at(long p, int dir, int deriv) const { return w.data() + ((p * 3 + dir) * 3 + deriv) * P; }
};

// s_frac: fractional coordinates (any real values; wrapped here); a: radii.
ParticleWindows make_windows(const GridGeometry& g, const std::vector<Vec3>& s_frac, const std::vector<double>& a);

// Window weights of particle p at the P^3 points (row-major over j0, j1, j2), force kind and
// torque kind: wF = W + cF lap W, wT = W + cT lap W. Buffers of size P^3.
void window_weights(const GridGeometry& g, const ParticleWindows& win, long p, double* wF, double* wT);

}  // namespace stokesian::ewald
