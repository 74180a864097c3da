#pragma once
// Spreading: particle moments -> grid fields (step 1 of the PME product).
//
// Field c (c = 0..d-1 in the particle layout [F(3) T(3) S(5)]) receives
//     rho_c(i) = sum_p x_{p,c} (W + c_p lap W)(i - M s_p),
// with c_p = a_p^2/6 for force components and a_p^2/10 for torque and stresslet components
// (window.hpp). Its DFT is then sum_p x_{p,c} (1 - c_p k^2) W^(n) e^{-i k . x_p} up to aliasing,
// with no volume or grid-size factors.
// Write conflicts (OpenMP): the grid is cut along direction 0 into an even number of slabs at least P
// points wide; a particle belongs to the slab of its first window index, so its window touches only
// its slab and the next. Slabs of one parity never touch each other's targets: all even slabs are
// spread in parallel, then all odd slabs. Within a slab particles are taken in index order, so every
// grid value is summed in an order fixed by the configuration: results are bitwise independent of
// the thread count. Fewer than two slabs (tiny grids): serial.
#include "ewald/window.hpp"

#include <vector>

namespace stokesian::ewald {

struct SlabColouring {
  int slabs = 1;
  std::vector<std::vector<long>> members;  // particles per slab, ascending
};
SlabColouring colour_slabs(const GridGeometry& g, const ParticleWindows& win);

// grid: g.points() * d doubles, interleaved (value of field c at point i is grid[i * d + c],
// d = dof_per_particle(m)), so one window point updates d adjacent values; overwritten.
void spread(const GridGeometry& g, const ParticleWindows& win, const SlabColouring& colouring, Moments m,
            const VecX& in, double* grid);

// The P^3 grid indices of particle p's window (row-major over j0, j1, j2), wrapped.
void window_indices(const GridGeometry& g, const ParticleWindows& win, long p, long* idx);

}  // namespace stokesian::ewald
