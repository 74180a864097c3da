// Interpolation from the grid; contract in interpolate.hpp.
#include "ewald/interpolate.hpp"

#include "ewald/spread.hpp"

namespace stokesian::ewald {

void interpolate(const GridGeometry& g, const ParticleWindows& win, Moments m, const std::vector<double*>& grids,
                 VecX& out) {
  const int d = dof_per_particle(m);
  const long n = long(win.start.size());
  const long P3 = long(g.P) * g.P * g.P;
  out.setZero(n * d);
#pragma omp parallel
  {
    std::vector<double> wF(P3), wT(P3);
    std::vector<long> idx(P3);
#pragma omp for schedule(static)
    for (long p = 0; p < n; ++p) {
      window_weights(g, win, p, wF.data(), wT.data());
      window_indices(g, win, p, idx.data());
      for (int c = 0; c < d; ++c) {
        const double* w = c < 3 ? wF.data() : wT.data();
        const double* grid = grids[c];
        double sum = 0.0;
        for (long t = 0; t < P3; ++t) sum += grid[idx[t]] * w[t];
        out[p * d + c] = sum;
      }
    }
  }
}

}  // namespace stokesian::ewald
