// Spreading to the grid; contract and write-conflict strategy in spread.hpp.
#include "ewald/spread.hpp"

#include <algorithm>
#include <cstring>

namespace stokesian::ewald {

SlabColouring colour_slabs(const GridGeometry& g, const ParticleWindows& win) {
  SlabColouring c;
  int n = g.M[0] / g.P;
  n -= n % 2;
  c.slabs = std::max(1, n);
  c.members.assign(c.slabs, {});
  for (long p = 0; p < long(win.start.size()); ++p) {
    const int slab = int((long(win.start[p][0]) * c.slabs) / g.M[0]);
    c.members[slab].push_back(p);
  }
  return c;
}

void window_indices(const GridGeometry& g, const ParticleWindows& win, long p, long* idx) {
  const int P = g.P;
  int ii[3][64];
  for (int d = 0; d < 3; ++d)
    for (int j = 0; j < P; ++j) ii[d][j] = (win.start[p][d] + j) % g.M[d];
  long q = 0;
  for (int i = 0; i < P; ++i)
    for (int j = 0; j < P; ++j) {
      const long row = (long(ii[0][i]) * g.M[1] + ii[1][j]) * g.M[2];
      for (int k = 0; k < P; ++k) idx[q++] = row + ii[2][k];
    }
}

void spread(const GridGeometry& g, const ParticleWindows& win, const SlabColouring& colouring, Moments m,
            const VecX& in, const std::vector<double*>& grids) {
  const int d = dof_per_particle(m);
  const long npts = g.points();
  const long P3 = long(g.P) * g.P * g.P;
  for (int c = 0; c < d; ++c) std::memset(grids[c], 0, sizeof(double) * npts);
  const int phases = colouring.slabs >= 2 ? 2 : 1;
  for (int phase = 0; phase < phases; ++phase) {
#pragma omp parallel
    {
      std::vector<double> wF(P3), wT(P3);
      std::vector<long> idx(P3);
#pragma omp for schedule(dynamic, 1)
      for (int slab = phase; slab < colouring.slabs; slab += phases) {
        for (long p : colouring.members[slab]) {
          window_weights(g, win, p, wF.data(), wT.data());
          window_indices(g, win, p, idx.data());
          const double* x = in.data() + p * d;
          for (int c = 0; c < d; ++c) {
            const double q = x[c];
            if (q == 0.0) continue;
            const double* w = c < 3 ? wF.data() : wT.data();
            double* grid = grids[c];
            for (long t = 0; t < P3; ++t) grid[idx[t]] += q * w[t];
          }
        }
      }
    }
  }
}

}  // namespace stokesian::ewald
