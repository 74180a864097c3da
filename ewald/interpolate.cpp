// Interpolation from the grid; contract in interpolate.hpp.
#include "ewald/interpolate.hpp"

#include "ewald/spread.hpp"

namespace stokesian::ewald {

namespace {
// Window sum for one particle with the field count D known at compile time (unrolled inner loop).
template <int D>
void gather(long P3, const long* idx, const double* wF, const double* wT, const double* grid, double* acc) {
  for (int c = 0; c < D; ++c) acc[c] = 0.0;
  for (long t = 0; t < P3; ++t) {
    const double* v = grid + idx[t] * D;
    const double wf = wF[t], wt = wT[t];
    for (int c = 0; c < 3; ++c) acc[c] += v[c] * wf;
    for (int c = 3; c < D; ++c) acc[c] += v[c] * wt;
  }
}
}  // namespace

void interpolate(const GridGeometry& g, const ParticleWindows& win, Moments m, const double* grid, VecX& out) {
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
      double* acc = out.data() + p * d;
      if (d == 3) gather<3>(P3, idx.data(), wF.data(), wT.data(), grid, acc);
      else if (d == 6) gather<6>(P3, idx.data(), wF.data(), wT.data(), grid, acc);
      else gather<11>(P3, idx.data(), wF.data(), wT.data(), grid, acc);
    }
  }
}

}  // namespace stokesian::ewald
