// Interpolation from the grid; contract in interpolate.hpp.
#include "ewald/interpolate.hpp"

#include "engine/core/sym_traceless.hpp"
#include "ewald/spread.hpp"

namespace stokesian::ewald {

void responses_from_gradient(const GridGeometry& g, Moments m, const double (*o)[4], double* y) {
  for (int c = 0; c < 3; ++c) y[c] = o[c][0];
  if (m == Moments::F) return;
  // Physical gradient: D = J^T Dd.
  Mat3 D = Mat3::Zero();
  for (int b = 0; b < 3; ++b)
    for (int c = 0; c < 3; ++c)
      for (int e = 0; e < 3; ++e) D(b, c) += g.J(e, b) * o[c][1 + e];
  y[3] = -0.5 * (D(1, 2) - D(2, 1));
  y[4] = -0.5 * (D(2, 0) - D(0, 2));
  y[5] = -0.5 * (D(0, 1) - D(1, 0));
  if (m == Moments::FTS) {
    const auto& basis = sym_traceless_basis();
    for (int b = 0; b < 5; ++b) y[6 + b] = -(basis[std::size_t(b)].cwiseProduct(D)).sum();
  }
}

void interpolate(const GridGeometry& g, const ParticleWindows& win, const SlabColouring& colouring, Moments m,
                 const double* grid, VecX& out) {
  const int d = dof_per_particle(m);
  const long n = long(win.start.size());
  const int P = g.P;
  const long stored = g.stored();
  const bool grad = m != Moments::F;
  out.resize(n * d);
  const GridKernelFn fast = interpolate_kernel_for(g, m);
#pragma omp parallel for schedule(dynamic, 1)
  for (int slab = 0; slab < colouring.slabs; ++slab) {
    if (fast) {
      fast(g, win, colouring.members[std::size_t(slab)], m, grid, out.data());
      continue;
    }
    for (long p : colouring.members[std::size_t(slab)]) {
      double o[3][4] = {};  // o[c][0] = U_c, o[c][1 + e] = Dd[e][c] (delta direction e)
      for_each_window_row(g, win, p, grad, [&](long base, const double* wF, const double(*gd)[64]) {
        for (int c = 0; c < 3; ++c) {
          const double* r = grid + c * stored + base;
          double u = 0.0;
          for (int l = 0; l < P; ++l) u += wF[l] * r[l];
          o[c][0] += u;
          if (grad) {
            double e0 = 0.0, e1 = 0.0, e2 = 0.0;
            for (int l = 0; l < P; ++l) {
              e0 += gd[0][l] * r[l];
              e1 += gd[1][l] * r[l];
              e2 += gd[2][l] * r[l];
            }
            o[c][1] += e0;
            o[c][2] += e1;
            o[c][3] += e2;
          }
        }
      });
      responses_from_gradient(g, m, o, out.data() + p * d);
    }
  }
}

}  // namespace stokesian::ewald
