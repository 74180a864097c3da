#pragma once
// Spreading: particle moments -> force density on the grid (step 1 of the PME product).
//
// The point-force density of the sources (docs/ewald.md (E2)), f(k) = F + (i/2) k x T - i S k, is in
// real space F delta + Q grad delta with Q = -(1/2)[T]x - S ([T]x v = T x v). With the window and the
// truncated Faxen factors (window.hpp) the three grid fields are
//     rho(x_g) = sum_p [ F_p W^F_p(x_g) + Q_p grad W^T_p(x_g) ],   W^F = W + (a^2/6) lap W,  W^T = W + (a^2/10) lap W,
// whose DFT is sum_p [F_p (1 - a^2 k^2/6) + Q_p (i k)(1 - a^2 k^2/10)] What(n) e^{-i k.x_p} up to aliasing.
// So torques and stresslets need no grid fields of their own: F, FT and FTS all spread 3 fields
// (and 3 inverse transforms come back, interpolate.hpp). grad_x = J^T grad_delta, so Q J^T is
// formed once per particle and the window's delta-gradient is used at the grid points.
// Weights per direction-2 row (j0, j1 fixed): W^F = f0 c0 + f1 c1 + f2 c2 and each delta-derivative
// of W^T = t0 c0 + .. + t3 c3 with c_k = phi^(k) along direction 2 and coefficients from the other
// two directions: separable evaluation, P^2 coefficient sets and P^3 multiply-adds per field.
// Layout: each field is M0 x M1 rows of `row` doubles (row_length, window.hpp); a window never wraps
// along direction 2 but runs into the ghost points after M2, which are folded back after spreading
// (and filled from the periodic values before interpolating), so the innermost loops are contiguous.
// Two implementations: the loops below (row weights formed per row, any support; the generic path)
// and the fast kernels of spread_fast.cpp (supports up to kMaxFastSupport, the default), which
// agree to rounding.
// Write conflicts (OpenMP): the grid is cut along direction 0 into an even number of slabs at least P
// points wide; a particle belongs to the slab of its first window index, so its window touches only
// its slab and the next. Slabs of one parity never touch each other's targets: all even slabs are
// spread in parallel, then all odd slabs. Within a slab particles are taken in a fixed order (sorted
// by their direction-1 and -2 window starts, for locality), so every grid value is summed in an
// order fixed by the configuration: results are bitwise independent of the thread count.
#include "ewald/window.hpp"

#include <vector>

namespace stokesian::ewald {

struct SlabColouring {
  int slabs = 1;
  std::vector<std::vector<long>> members;  // particles per slab, in spreading order
};
SlabColouring colour_slabs(const GridGeometry& g, const ParticleWindows& win);

// Weights of particle p on the row (j0, j1) of its window: wF[l] and the delta-gradient of W^T,
// gd[3][l] (only wF when with_gradient is false). l = 0..P-1 along direction 2.
void row_weights(const GridGeometry& g, const ParticleWindows& win, long p, int j0, int j1, bool with_gradient,
                 double* wF, double (*gd)[64]);

// Q J^T of a particle with moments q (F: zero): maps the delta-gradient of W^T to the force density.
Mat3 source_matrix(const GridGeometry& g, Moments m, const double* q);

// Which spreading and interpolation loops run (tests compare them): automatic = the fast kernels
// with AVX2 + FMA when the CPU has them, baseline = the fast kernels without AVX2, generic = the
// loops of spread.cpp and interpolate.cpp for every support. Supports above kMaxFastSupport always
// take the generic loops. Process-wide; not to be changed while a product runs.
enum class GridKernels { automatic, baseline, generic };
void force_grid_kernels(GridKernels k);
constexpr int kMaxFastSupport = 32;
// A fast kernel over a list of particles: spreading (in = moments, out = grid, accumulated) or
// interpolation (in = grid, out = responses, overwritten per listed particle); null when the
// generic loops must run.
using GridKernelFn = void (*)(const GridGeometry&, const ParticleWindows&, const std::vector<long>&, Moments,
                              const double* in, double* out);
GridKernelFn spread_kernel_for(const GridGeometry& g, Moments m);
GridKernelFn interpolate_kernel_for(const GridGeometry& g, Moments m);

// grid: 3 fields of g.stored() doubles each (field c at grid + c * g.stored()); overwritten,
// ghost points folded. `in` has dof_per_particle(m) values per particle, [F(3) T(3) S(5)].
void spread(const GridGeometry& g, const ParticleWindows& win, const SlabColouring& colouring, Moments m,
            const VecX& in, double* grid);

// Row-major offset of point (i0, i1, i2) in a field, i2 in [0, M2 + P - 1).
inline long grid_offset(const GridGeometry& g, int i0, int i1, int i2) {
  return (long(i0) * g.M[1] + i1) * g.row + i2;
}

// The walk shared by spreading and interpolation: for each of the P^2 direction-2 rows of particle
// p's window, f(base, wF, gd) with base the offset of the row's first point in a field and the
// row's weights from row_weights.
template <class F>
void for_each_window_row(const GridGeometry& g, const ParticleWindows& win, long p, bool with_gradient, F&& f) {
  double wF[64], gd[3][64];
  const auto& s = win.start[std::size_t(p)];
  for (int j0 = 0; j0 < g.P; ++j0) {
    const int i0 = (s[0] + j0) % g.M[0];
    for (int j1 = 0; j1 < g.P; ++j1) {
      const int i1 = (s[1] + j1) % g.M[1];
      row_weights(g, win, p, j0, j1, with_gradient, wF, gd);
      f(grid_offset(g, i0, i1, s[2]), static_cast<const double*>(wF), static_cast<const double(*)[64]>(gd));
    }
  }
}

}  // namespace stokesian::ewald
