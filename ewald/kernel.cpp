// Fourier-space PME kernel; mathematics in kernel.hpp.
#include "ewald/kernel.hpp"

#include "ewald/ewald_split.hpp"

#include <cmath>

namespace stokesian::ewald {

void FourierKernel::build(const GridGeometry& g, const Lattice& lattice, double xi, double mu) {
  M_ = g.M;
  B_ = lattice.B;
  const int M0 = g.M[0], M1 = g.M[1], M2 = g.M[2], H2 = M2 / 2 + 1;
  // 1 / phihat(n_d / M_d)^2 per direction.
  std::array<std::vector<double>, 3> inv;
  for (int d = 0; d < 3; ++d) {
    inv[d].resize(g.M[d]);
    for (int i = 0; i < g.M[d]; ++i) {
      const int n = i <= g.M[d] / 2 ? i : i - g.M[d];
      const double w = g.window.transform(double(n) / g.M[d]);
      inv[d][i] = 1.0 / (w * w);
    }
  }
  const long total = long(M0) * M1 * H2;
  s1_.assign(total, 0.0);
  s2_.assign(total, 0.0);
#pragma omp parallel for schedule(static)
  for (int i0 = 0; i0 < M0; ++i0) {
    const int n0 = i0 <= M0 / 2 ? i0 : i0 - M0;
    for (int i1 = 0; i1 < M1; ++i1) {
      const int n1 = i1 <= M1 / 2 ? i1 : i1 - M1;
      for (int i2 = 0; i2 < H2; ++i2) {
        const int n2 = i2;
        const bool drop = (n0 == 0 && n1 == 0 && n2 == 0) || 2 * std::abs(n0) == M0 || 2 * std::abs(n1) == M1 ||
                          2 * n2 == M2;
        if (drop) continue;
        const Vec3 k = lattice.B * Vec3(n0, n1, n2);
        const double k2 = k.squaredNorm();
        const double s = hasimoto(k2, xi) * inv[0][i0] * inv[1][i1] * inv[2][i2] / (mu * lattice.volume * k2);
        const long t = (long(i0) * M1 + i1) * H2 + i2;
        s1_[t] = s;
        s2_[t] = s / k2;
      }
    }
  }
}

void FourierKernel::apply(std::complex<double>* fields, long stride, long plane) const {
  using C = std::complex<double>;
  const int M0 = M_[0], M1 = M_[1], H2 = M_[2] / 2 + 1;
  C* f0 = fields;
  C* f1 = fields + stride;
  C* f2 = fields + 2 * stride;
#pragma omp parallel for schedule(static)
  for (int i0 = 0; i0 < M0; ++i0) {
    const int n0 = i0 <= M0 / 2 ? i0 : i0 - M0;
    for (int i1 = 0; i1 < M1; ++i1) {
      const int n1 = i1 <= M1 / 2 ? i1 : i1 - M1;
      const Vec3 k01 = B_.col(0) * n0 + B_.col(1) * n1;
      const long base = (long(i0) * M1 + i1) * H2, at = long(i0) * plane + long(i1) * H2;
      for (int i2 = 0; i2 < H2; ++i2) {
        const long t = base + i2, u = at + i2;
        const Vec3 k = k01 + B_.col(2) * double(i2);
        const C a = f0[u], b = f1[u], c = f2[u];
        const C kf = k.x() * a + k.y() * b + k.z() * c;
        const double s = s1_[t], q = s2_[t];
        f0[u] = s * a - q * k.x() * kf;
        f1[u] = s * b - q * k.y() * kf;
        f2[u] = s * c - q * k.z() * kf;
      }
    }
  }
}

}  // namespace stokesian::ewald
