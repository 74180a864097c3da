// Spreading to the grid; contract and write-conflict strategy in spread.hpp.
#include "ewald/spread.hpp"

#include <algorithm>
#include <cstring>

namespace stokesian::ewald {
namespace {
// Window update for one particle with the field count D known at compile time.
template <int D>
void scatter(long P3, const long* idx, const double* wF, const double* wT, const double* q, double* grid) {
  for (long t = 0; t < P3; ++t) {
    double* v = grid + idx[t] * D;
    const double wf = wF[t], wt = wT[t];
    for (int c = 0; c < 3; ++c) v[c] += q[c] * wf;
    for (int c = 3; c < D; ++c) v[c] += q[c] * wt;
  }
}
}  // namespace

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
            const VecX& in, double* grid) {
  const int d = dof_per_particle(m);
  const long npts = g.points();
  const long P3 = long(g.P) * g.P * g.P;
  std::memset(grid, 0, sizeof(double) * npts * d);
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
          const double* q = in.data() + p * d;
          if (d == 3) scatter<3>(P3, idx.data(), wF.data(), wT.data(), q, grid);
          else if (d == 6) scatter<6>(P3, idx.data(), wF.data(), wT.data(), q, grid);
          else scatter<11>(P3, idx.data(), wF.data(), wT.data(), q, grid);
        }
      }
    }
  }
}

}  // namespace stokesian::ewald
