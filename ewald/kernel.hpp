#pragma once
// Fourier-space kernel of the PME product (between the forward and inverse FFTs).
//
// Input: the DFTs rho_c(n) of the spread fields (spread.hpp), c in [F(3) T(3) S(5)], on the r2c
// half grid. At each k = B n (n != 0, no Nyquist index) the point-force density is
//     f = F + (i/2) k x T - i S k                       (sources of ewald_split.hpp)
// and the velocity u = H(k) / (mu V k^2 W^(n)^2) (I - k k / k^2) f, with H the Hasimoto factor and
// W^ the window transform (window.hpp; dividing by W^2 undoes spreading and interpolation)
// [docs/ewald.md (E8); the deconvolution is that of the spectral Ewald method, Lindbo & Tornberg
// 2010]. Output, in place:
//     U = u,  Omega = (i/2) k x u,  E_m = i (B_m k) . u    (B_m: symmetric-traceless basis).
// The k = 0 term is zero (mean pressure gradient balances the net force). Nyquist planes are zeroed:
// the grid is oversampled (pme_parameters.hpp), so H is below the tolerance there.
#include "ewald/lattice.hpp"
#include "ewald/window.hpp"

#include <complex>
#include <vector>

namespace stokesian::ewald {

// fields: M0 * M1 * (M2/2 + 1) points (FFTW r2c layout) times d = dof_per_particle(m) values,
// interleaved (field c at point i: fields[i * d + c]).
void apply_fourier_kernel(const GridGeometry& g, const Lattice& lattice, double xi, double mu, Moments m,
                          std::complex<double>* fields);

}  // namespace stokesian::ewald
