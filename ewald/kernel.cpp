// Fourier-space PME kernel; mathematics in kernel.hpp.
#include "ewald/kernel.hpp"

#include "engine/core/sym_traceless.hpp"
#include "ewald/ewald_split.hpp"

#include <cmath>

namespace stokesian::ewald {
namespace {
using Vec3c = Eigen::Matrix<std::complex<double>, 3, 1>;
// k x v for complex v (Eigen's cross() conjugates complex results).
Vec3c cross(const Vec3& k, const Vec3c& v) {
  return Vec3c(k.y() * v.z() - k.z() * v.y(), k.z() * v.x() - k.x() * v.z(), k.x() * v.y() - k.y() * v.x());
}
}  // namespace

void apply_fourier_kernel(const GridGeometry& g, const Lattice& lattice, double xi, double mu, Moments m,
                          std::complex<double>* fields) {
  using C = std::complex<double>;
  const int d = dof_per_particle(m);
  const int M0 = g.M[0], M1 = g.M[1], M2 = g.M[2], H2 = M2 / 2 + 1;
  const double wexp = 4.0 * kPi * kPi * g.s * g.s;  // W^2 = exp(-wexp sum (n_d / M_d)^2)
  const auto& basis = sym_traceless_basis();
  const C I(0.0, 1.0);
#pragma omp parallel for schedule(static)
  for (int i0 = 0; i0 < M0; ++i0) {
    const int n0 = i0 <= M0 / 2 ? i0 : i0 - M0;
    for (int i1 = 0; i1 < M1; ++i1) {
      const int n1 = i1 <= M1 / 2 ? i1 : i1 - M1;
      for (int i2 = 0; i2 < H2; ++i2) {
        C* v = fields + ((long(i0) * M1 + i1) * H2 + i2) * d;
        const int n2 = i2;
        const bool drop = (n0 == 0 && n1 == 0 && n2 == 0) || 2 * std::abs(n0) == M0 || 2 * std::abs(n1) == M1 ||
                          2 * n2 == M2;
        if (drop) {
          for (int c = 0; c < d; ++c) v[c] = 0.0;
          continue;
        }
        const Vec3 k = lattice.B * Vec3(n0, n1, n2);
        const double k2 = k.squaredNorm();
        const double nu2 = double(n0) * n0 / (double(M0) * M0) + double(n1) * n1 / (double(M1) * M1) +
                           double(n2) * n2 / (double(M2) * M2);
        const double scale = hasimoto(k2, xi) * std::exp(wexp * nu2) / (mu * lattice.volume * k2);
        Eigen::Matrix<C, 3, 1> f(v[0], v[1], v[2]);
        Vec3 bk[5];
        if (d > 3) {
          const Eigen::Matrix<C, 3, 1> T(v[3], v[4], v[5]);
          f += 0.5 * I * cross(k, T);
        }
        if (d > 6)
          for (int q = 0; q < 5; ++q) {
            bk[q] = basis[q] * k;
            f -= I * v[6 + q] * bk[q].cast<C>();
          }
        const Vec3 kh = k / std::sqrt(k2);
        const Eigen::Matrix<C, 3, 1> u = scale * (f - kh.cast<C>() * kh.cast<C>().dot(f));  // dot conjugates arg 1 (real)
        for (int c = 0; c < 3; ++c) v[c] = u[c];
        if (d > 3) {
          const Vec3c w = 0.5 * I * cross(k, u);
          for (int c = 0; c < 3; ++c) v[3 + c] = w[c];
        }
        if (d > 6)
          for (int q = 0; q < 5; ++q) v[6 + q] = I * bk[q].cast<C>().dot(u);
      }
    }
  }
}

}  // namespace stokesian::ewald
