#include "engine/kernels/far_field.hpp"

#include "engine/core/parallel.hpp"

#include "engine/kernels/mobility_pair.hpp"

#include <cassert>
#include <stdexcept>

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

MatX assemble_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m) {
  MatX M;
  assemble_mobility(x, a, mu, m, M);
  return M;
}

void assemble_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m, MatX& M) {
  const int d = dof_per_particle(m);
  const long n = long(x.size()), ld = n * d;
  M.resize(ld, ld);
  // Block (i, j) for i >= j from the formulas; block (j, i) is its transpose (M is symmetric:
  // the pair scalars are symmetric under exchanging the particles with e -> -e; the explicit
  // reference dense_mobility computes both orders independently, tests/test_sd_dense_fast.cpp).
#pragma omp parallel for schedule(dynamic, 8)
  for (long j = 0; j < n; ++j) {  // block column j: contiguous storage
    double* col = M.data() + j * d * ld;
    mobility::fill_pair_block(mobility::self_scalars(a[j], mu), Vec3::UnitZ(), m, col + j * d, ld);
    for (long i = j + 1; i < n; ++i) {
      const Vec3 rij = x[i] - x[j];
      const double r = rij.norm();
      const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
      double* B = col + i * d;
      mobility::fill_pair_block(mobility::pair_scalars(a[i], a[j], r, mu, m), e, m, B, ld);
      double* T = M.data() + i * d * ld + j * d;  // block (j, i)
      for (int q = 0; q < d; ++q)
        for (int p = 0; p < d; ++p) T[p + q * ld] = B[q + p * ld];
    }
  }
}

void assemble_mobility_rows(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                            const std::vector<long>& particles, MatX& rows) {
  const int d = dof_per_particle(m);
  const long n = long(x.size()), np = long(particles.size());
  rows.resize(np * d, n * d);
  // Block (i, j) with e = (x_i - x_j) / r, as assemble_mobility writes block (i, j) for i > j.
#pragma omp parallel for schedule(dynamic, 4)
  for (long k = 0; k < np; ++k) {
    const long i = particles[std::size_t(k)];
    for (long j = 0; j < n; ++j) {
      double* B = rows.data() + j * d * (np * d) + k * d;
      if (j == i) {
        mobility::fill_pair_block(mobility::self_scalars(a[i], mu), Vec3::UnitZ(), m, B, np * d);
        continue;
      }
      const Vec3 rij = x[i] - x[j];
      const double r = rij.norm();
      const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
      mobility::fill_pair_block(mobility::pair_scalars(a[i], a[j], r, mu, m), e, m, B, np * d);
    }
  }
}

void mobility_product_reference(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                                const VecX& in, VecX& out) {
  const int d = dof_per_particle(m);
  const long n = long(x.size());
  assert(in.size() == n * d);
  out.setZero(n * d);
#pragma omp parallel for schedule(dynamic, 16) if (n >= parallel::kDirectProductParticles)
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

namespace stokesian {

void DirectFarField::set_configuration(const Configuration& c) {
  if (c.domain.periodic()) throw std::invalid_argument("direct far field: the domain is periodic (use ewald or pme)");
  x_ = c.x;
  a_ = c.a;
  have_dense_ = false;
}

const MatX* DirectFarField::dense() const {
  if (!have_dense_) {
    assemble_mobility(x_, a_, mu_, m_, dense_);
    have_dense_ = true;
  }
  return &dense_;
}

void SelfMobility::apply(const VecX& in, VecX& out) const {
  const int d = dof_per_particle(m_);
  const long n = long(a_.size());
  out.setZero(in.size());
  for (long i = 0; i < n; ++i) mobility::apply_self(a_[std::size_t(i)], mu_, m_, in.data() + i * d, out.data() + i * d);
}

}  // namespace stokesian
