#pragma once
// Fourier-space kernel of the PME product (between the forward and inverse FFTs).
//
// Input: the DFTs rho(n) of the three force-density fields (spread.hpp) on the r2c half grid. At each
// k = B n (n != 0, no Nyquist index) the velocity is
//     u(k) = H(k) / (mu V k^2 What(n)^2) (I - k k / k^2) rho(n),
// H the Hasimoto factor (ewald_split.hpp), What the window transform (window.hpp; dividing by What^2
// undoes spreading and interpolation; the deconvolution of the spectral Ewald method, Lindbo &
// Tornberg 2010) [docs/ewald.md (E8)]. The Faxen factors and the k-factors of torques and stresslets
// are applied by the windows themselves (spread.hpp, interpolate.hpp), so the kernel is the Oseen
// projection only. The k = 0 term is zero (a mean pressure gradient balances the net force); the
// Nyquist planes are zeroed (the grid resolves H to the tolerance below them, pme_parameters.hpp).
// The scalar factors depend only on the grid, lattice and xi: computed once per operator.
#include "ewald/lattice.hpp"
#include "ewald/window.hpp"

#include <complex>
#include <vector>

namespace stokesian::ewald {

class FourierKernel {
 public:
  void build(const GridGeometry& g, const Lattice& lattice, double xi, double mu);
  // fields: 3 arrays of M0 planes of M1 * (M2/2 + 1) complex values (FFTW r2c layout), plane i0 of
  // field c at fields + c * stride + i0 * plane (plane >= M1 * (M2/2 + 1): padded planes allowed).
  void apply(std::complex<double>* fields, long stride, long plane) const;

 private:
  std::array<int, 3> M_{};
  Mat3 B_ = Mat3::Identity();
  std::vector<double> s1_, s2_;  // H / (mu V k^2 What^2) and that / k^2 per half-grid point
};

}  // namespace stokesian::ewald
