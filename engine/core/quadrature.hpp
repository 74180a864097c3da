#pragma once
// Gauss-Legendre quadrature on [-1, 1]: the n nodes are the roots of the Legendre polynomial P_n
// (Newton's method on the three-term recurrence (k+1) P_{k+1} = (2k+1) z P_k - k P_{k-1}, started
// from the asymptotic estimate cos(pi (i + 3/4) / (n + 1/2))), the weights 2 / ((1 - z^2) P_n'(z)^2);
// exact for polynomials of degree <= 2n - 1 [Abramowitz & Stegun 1964, 25.4.29].
#include "engine/core/types.hpp"

#include <cmath>
#include <vector>

namespace stokesian {

struct GaussLegendre {
  std::vector<double> x, w;  // nodes (descending) and weights
};

inline GaussLegendre gauss_legendre(int n) {
  GaussLegendre q;
  q.x.resize(std::size_t(n));
  q.w.resize(std::size_t(n));
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    q.x[std::size_t(i)] = z;
    q.w[std::size_t(i)] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
  return q;
}

}  // namespace stokesian
