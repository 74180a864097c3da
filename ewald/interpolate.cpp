// Interpolation from the grid; contract in interpolate.hpp.
#include "ewald/interpolate.hpp"

#include "engine/core/sym_traceless.hpp"
#include "ewald/spread.hpp"

namespace stokesian::ewald {

void interpolate(const GridGeometry& g, const ParticleWindows& win, const SlabColouring& colouring, Moments m,
                 const double* grid, VecX& out) {
  const int d = dof_per_particle(m);
  const long n = long(win.start.size());
  const int P = g.P;
  const long stored = g.stored();
  const bool grad = m != Moments::F;
  const auto& basis = sym_traceless_basis();
  out.resize(n * d);
#pragma omp parallel for schedule(dynamic, 1)
  for (int slab = 0; slab < colouring.slabs; ++slab)
    for (long p : colouring.members[std::size_t(slab)]) {
      double U[3] = {0, 0, 0}, Dd[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};  // Dd[delta dir][velocity comp]
      for_each_window_row(g, win, p, grad, [&](long base, const double* wF, const double(*gd)[64]) {
        for (int c = 0; c < 3; ++c) {
          const double* r = grid + c * stored + base;
          double u = 0.0;
          for (int l = 0; l < P; ++l) u += wF[l] * r[l];
          U[c] += u;
          if (grad) {
            double e0 = 0.0, e1 = 0.0, e2 = 0.0;
            for (int l = 0; l < P; ++l) {
              e0 += gd[0][l] * r[l];
              e1 += gd[1][l] * r[l];
              e2 += gd[2][l] * r[l];
            }
            Dd[0][c] += e0;
            Dd[1][c] += e1;
            Dd[2][c] += e2;
          }
        }
      });
      double* y = out.data() + p * d;
      for (int c = 0; c < 3; ++c) y[c] = U[c];
      if (!grad) continue;
      // Physical gradient: D = J^T Dd.
      Mat3 D = Mat3::Zero();
      for (int b = 0; b < 3; ++b)
        for (int c = 0; c < 3; ++c)
          for (int e = 0; e < 3; ++e) D(b, c) += g.J(e, b) * Dd[e][c];
      y[3] = -0.5 * (D(1, 2) - D(2, 1));
      y[4] = -0.5 * (D(2, 0) - D(0, 2));
      y[5] = -0.5 * (D(0, 1) - D(1, 0));
      if (d > 6)
        for (int b = 0; b < 5; ++b) y[6 + b] = -(basis[std::size_t(b)].cwiseProduct(D)).sum();
    }
}

}  // namespace stokesian::ewald
