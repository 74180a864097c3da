// Spreading to the grid; contract, weights and write-conflict strategy in spread.hpp.
#include "ewald/spread.hpp"

#include "engine/core/sym_traceless.hpp"

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
  for (auto& m : c.members)
    std::stable_sort(m.begin(), m.end(), [&](long p, long q) {
      const auto &sp = win.start[p], &sq = win.start[q];
      return sp[1] != sq[1] ? sp[1] < sq[1] : sp[2] < sq[2];
    });
  return c;
}

void row_weights(const GridGeometry& g, const ParticleWindows& win, long p, int j0, int j1, bool with_gradient,
                 double* wF, double (*gd)[64]) {
  const int P = g.P;
  const Mat3& G = g.lap;
  const double cF = win.cF[p], cT = win.cT[p];
  const double A0 = win.at(p, 0, 0)[j0], A1 = win.at(p, 0, 1)[j0], A2 = win.at(p, 0, 2)[j0], A3 = win.at(p, 0, 3)[j0];
  const double B0 = win.at(p, 1, 0)[j1], B1 = win.at(p, 1, 1)[j1], B2 = win.at(p, 1, 2)[j1], B3 = win.at(p, 1, 3)[j1];
  const double *c0 = win.at(p, 2, 0), *c1 = win.at(p, 2, 1), *c2 = win.at(p, 2, 2), *c3 = win.at(p, 2, 3);
  const double g00 = G(0, 0), g11 = G(1, 1), g22 = G(2, 2), g01 = 2.0 * G(0, 1), g02 = 2.0 * G(0, 2),
               g12 = 2.0 * G(1, 2);
  // lap W = g00 W_00 + g11 W_11 + g22 W_22 + g01 W_01 + g02 W_02 + g12 W_12, grouped by the order of
  // the direction-2 derivative.
  const double lap0 = g00 * A2 * B0 + g11 * A0 * B2 + g01 * A1 * B1, lap1 = g02 * A1 * B0 + g12 * A0 * B1;
  const double f0 = A0 * B0 + cF * lap0, f1 = cF * lap1, f2 = cF * g22 * A0 * B0;
  for (int l = 0; l < P; ++l) wF[l] = f0 * c0[l] + f1 * c1[l] + f2 * c2[l];
  if (!with_gradient) return;
  // d/d delta_0, d/d delta_1 and d/d delta_2 of W + cT lap W.
  const double t00 = A1 * B0 + cT * (g00 * A3 * B0 + g11 * A1 * B2 + g01 * A2 * B1),
               t01 = cT * (g02 * A2 * B0 + g12 * A1 * B1), t02 = cT * g22 * A1 * B0;
  const double t10 = A0 * B1 + cT * (g00 * A2 * B1 + g11 * A0 * B3 + g01 * A1 * B2),
               t11 = cT * (g02 * A1 * B1 + g12 * A0 * B2), t12 = cT * g22 * A0 * B1;
  const double t21 = A0 * B0 + cT * lap0, t22 = cT * lap1, t23 = cT * g22 * A0 * B0;
  double *d0 = gd[0], *d1 = gd[1], *d2 = gd[2];
  for (int l = 0; l < P; ++l) {
    d0[l] = t00 * c0[l] + t01 * c1[l] + t02 * c2[l];
    d1[l] = t10 * c0[l] + t11 * c1[l] + t12 * c2[l];
    d2[l] = t21 * c1[l] + t22 * c2[l] + t23 * c3[l];
  }
}

Mat3 source_matrix(const GridGeometry& g, Moments m, const double* q) {
  Mat3 Q = Mat3::Zero();
  if (m == Moments::F) return Q;
  const Vec3 T(q[3], q[4], q[5]);
  Q << 0.0, 0.5 * T.z(), -0.5 * T.y(), -0.5 * T.z(), 0.0, 0.5 * T.x(), 0.5 * T.y(), -0.5 * T.x(), 0.0;
  if (m == Moments::FTS) {
    const auto& basis = sym_traceless_basis();
    for (int b = 0; b < 5; ++b) Q -= q[6 + b] * basis[std::size_t(b)];
  }
  return Q * g.J.transpose();
}

namespace {
void spread_particle(const GridGeometry& g, const ParticleWindows& win, long p, Moments m, const double* q,
                     double* grid) {
  const int P = g.P;
  const long stored = g.stored();
  const bool grad = m != Moments::F;
  const Mat3 Q = source_matrix(g, m, q);
  for_each_window_row(g, win, p, grad, [&](long base, const double* wF, const double(*gd)[64]) {
    for (int c = 0; c < 3; ++c) {
      double* r = grid + c * stored + base;
      const double f = q[c];
      if (!grad) {
        for (int l = 0; l < P; ++l) r[l] += f * wF[l];
      } else {
        const double q0 = Q(c, 0), q1 = Q(c, 1), q2 = Q(c, 2);
        for (int l = 0; l < P; ++l) r[l] += f * wF[l] + q0 * gd[0][l] + q1 * gd[1][l] + q2 * gd[2][l];
      }
    }
  });
}
}  // namespace

void spread(const GridGeometry& g, const ParticleWindows& win, const SlabColouring& colouring, Moments m,
            const VecX& in, double* grid) {
  const int d = dof_per_particle(m);
  const long stored = g.stored();
  std::memset(grid, 0, sizeof(double) * stored * 3);
  const int phases = colouring.slabs >= 2 ? 2 : 1;
  const GridKernelFn fast = spread_kernel_for(g, m);
  for (int phase = 0; phase < phases; ++phase) {
#pragma omp parallel for schedule(dynamic, 1)
    for (int slab = phase; slab < colouring.slabs; slab += phases) {
      if (fast) {
        fast(g, win, colouring.members[slab], m, in.data(), grid);
        continue;
      }
      for (long p : colouring.members[slab]) spread_particle(g, win, p, m, in.data() + p * d, grid);
    }
  }
  // Fold the ghost points of every direction-2 row back onto its start (in order, so a row shorter
  // than its ghost region folds twice onto the same points deterministically).
  const long rows = long(g.M[0]) * g.M[1];
  const int M2 = g.M[2], ghosts = g.row - M2;
#pragma omp parallel for schedule(static)
  for (long r = 0; r < 3 * rows; ++r) {
    double* v = grid + r * g.row;
    for (int l = 0; l < ghosts; ++l) {
      v[l % M2] += v[M2 + l];
      v[M2 + l] = 0.0;
    }
  }
}

}  // namespace stokesian::ewald
