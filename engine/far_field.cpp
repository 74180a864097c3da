#include "engine/far_field.hpp"

#include "engine/mobility_pair.hpp"

#include <cassert>

namespace stokesian {

MatX dense_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m) {
  const int d = dof_per_particle(m);
  const Eigen::Index n = Eigen::Index(x.size());
  MatX M = MatX::Zero(n * d, n * d);
  for (Eigen::Index i = 0; i < n; ++i) {
    const mobility::PairScalars self = mobility::self_scalars(a[i], mu);
    M.block(i * d, i * d, d, d) = mobility::pair_block(self, Vec3::UnitZ(), m);
    for (Eigen::Index j = 0; j < n; ++j) {
      if (j == i) continue;
      const Vec3 rij = x[i] - x[j];
      const double r = rij.norm();
      const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
      M.block(i * d, j * d, d, d) = mobility::pair_block(mobility::pair_scalars(a[i], a[j], r, mu, m), e, m);
    }
  }
  return M;
}

void mobility_product(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                      const VecX& in, VecX& out) {
  const int d = dof_per_particle(m);
  const long n = long(x.size());
  assert(in.size() == n * d);
  out.setZero(n * d);
#pragma omp parallel for schedule(dynamic, 16) if (n >= 256)  // below this, thread start-up costs more than it saves
  for (long i = 0; i < n; ++i) {
    double* yi = out.data() + i * d;
    mobility::apply_self(a[i], mu, m, in.data() + i * d, yi);
    for (long j = 0; j < n; ++j) {
      if (j == i) continue;
      const Vec3 rij = x[i] - x[j];
      const double r = rij.norm();
      const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
      mobility::apply_pair(mobility::pair_scalars(a[i], a[j], r, mu, m), e, m, in.data() + j * d, yi);
    }
  }
}

}  // namespace stokesian
