#pragma once
// Interpolation: grid fields -> particle responses (last step of the PME product).
//
//     y_{p,c} = sum_i u_c(i) (W + c_p lap W)(i - M s_p),
// c_p = a_p^2/6 for velocity components, a_p^2/10 for rotation and strain components, which
// applies the truncated Faxen factor (1 - c_p k^2) of the response (window.hpp). Each particle
// reads the grid only: parallel over particles, no conflicts, deterministic.
#include "ewald/window.hpp"

#include <vector>

namespace stokesian::ewald {

// out (size N d) is overwritten; grid interleaved as in spread.hpp.
void interpolate(const GridGeometry& g, const ParticleWindows& win, Moments m, const double* grid, VecX& out);

}  // namespace stokesian::ewald
