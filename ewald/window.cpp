// Gaussian window with Faxen Laplacian; definitions in window.hpp.
#include "ewald/window.hpp"

#include <cmath>

namespace stokesian::ewald {

ParticleWindows make_windows(const GridGeometry& g, const std::vector<Vec3>& s_frac, const std::vector<double>& a) {
  const long n = long(s_frac.size());
  const int P = g.P;
  ParticleWindows win;
  win.P = P;
  win.start.resize(n);
  win.w.resize(std::size_t(n) * 9 * P);
  win.cF.resize(n);
  win.cT.resize(n);
  const double s2 = g.s * g.s, norm = 1.0 / (std::sqrt(2.0 * kPi) * g.s);
  for (long p = 0; p < n; ++p) {
    win.cF[p] = a[p] * a[p] / 6.0;
    win.cT[p] = a[p] * a[p] / 10.0;
    for (int d = 0; d < 3; ++d) {
      const double u = s_frac[p][d] - std::floor(s_frac[p][d]);
      const double pos = u * g.M[d];  // particle position in grid units, [0, M)
      const int i0 = int(std::ceil(pos - 0.5 * P));
      win.start[p][d] = ((i0 % g.M[d]) + g.M[d]) % g.M[d];
      double* w0 = win.w.data() + ((p * 3 + d) * 3 + 0) * P;
      double* w1 = w0 + P;
      double* w2 = w1 + P;
      for (int j = 0; j < P; ++j) {
        const double delta = (i0 + j) - pos;
        const double w = norm * std::exp(-0.5 * delta * delta / s2);
        w0[j] = w;
        w1[j] = -delta / s2 * w;
        w2[j] = (delta * delta / s2 - 1.0) / s2 * w;
      }
    }
  }
  return win;
}

void window_weights(const GridGeometry& g, const ParticleWindows& win, long p, double* wF, double* wT) {
  const int P = g.P;
  const double *x0 = win.at(p, 0, 0), *x1 = win.at(p, 0, 1), *x2 = win.at(p, 0, 2);
  const double *y0 = win.at(p, 1, 0), *y1 = win.at(p, 1, 1), *y2 = win.at(p, 1, 2);
  const double *z0 = win.at(p, 2, 0), *z1 = win.at(p, 2, 1), *z2 = win.at(p, 2, 2);
  const Mat3& G = g.lap;
  const double cF = win.cF[p], cT = win.cT[p];
  long q = 0;
  for (int i = 0; i < P; ++i)
    for (int j = 0; j < P; ++j) {
      // Terms of lap W grouped by their z factor: z0 (xx, yy, xy), z1 (xz, yz), z2 (zz).
      const double base = x0[i] * y0[j];
      const double l0 = G(0, 0) * x2[i] * y0[j] + G(1, 1) * x0[i] * y2[j] + 2.0 * G(0, 1) * x1[i] * y1[j];
      const double l1 = 2.0 * (G(0, 2) * x1[i] * y0[j] + G(1, 2) * x0[i] * y1[j]);
      const double l2 = G(2, 2) * base;
      for (int k = 0; k < P; ++k, ++q) {
        const double w = base * z0[k];
        const double lap = l0 * z0[k] + l1 * z1[k] + l2 * z2[k];
        wF[q] = w + cF * lap;
        wT[q] = w + cT * lap;
      }
    }
}

}  // namespace stokesian::ewald
