#pragma once
// Interpolation: grid velocity field -> particle responses (last step of the PME product).
//
// With u the velocity on the grid (3 fields, after the inverse transforms) and the windows of
// window.hpp, per particle
//     U = sum_g W^F u,     D_{bc} = sum_g (grad W^T)_b u_c,
// whose main Fourier terms are (1 - a^2 k^2/6) u^ and -i k_b u^_c (1 - a^2 k^2/10) (the sign from the
// adjoint of the spreading, spread.hpp), so
//     Omega_a = -(1/2) eps_abc D_bc,   E_m = -B_m : D
// (B_m the basis of engine/core/sym_traceless.hpp): rotation and strain come from the velocity alone.
// Each particle reads the grid only (its ghost points must hold the periodic copies): parallel
// over slabs, no conflicts, deterministic. Particles are visited in the spreading order of
// spread.hpp (slab by slab, sorted by window start within a slab), so consecutive windows overlap
// and the grid is read from cache; in index order the reads miss (measured: 87 % of the
// interpolation time at N = 3e4 stalled on grid loads).
#include "ewald/spread.hpp"
#include "ewald/window.hpp"

#include <vector>

namespace stokesian::ewald {

// out (size N d) is overwritten; grid as in spread.hpp (3 fields, ghost points filled). Runs the fast
// kernels of spread_fast.cpp or the generic loops (spread.hpp: GridKernels).
void interpolate(const GridGeometry& g, const ParticleWindows& win, const SlabColouring& colouring, Moments m,
                 const double* grid, VecX& out);

// A particle's responses y (U, then Omega and E as m has them) from o[c][0] = U_c and
// o[c][1 + e] = Dd_ec, the delta-gradient sums (D = J^T Dd).
void responses_from_gradient(const GridGeometry& g, Moments m, const double (*o)[4], double* y);

}  // namespace stokesian::ewald
