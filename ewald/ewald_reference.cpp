// Dense Ewald sum of the periodic grand mobility; mathematics in ewald_reference.hpp and
// ewald_split.hpp.
#include "ewald/ewald_reference.hpp"

#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/lattice.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace stokesian::ewald {
namespace {


// M(i*d.., j*d..) += B, B (d x d) column-major.
void add_block(MatX& M, long i, long j, const double* B, int d) {
  for (int c = 0; c < d; ++c)
    for (int q = 0; q < d; ++q) M(i * d + q, j * d + c) += B[q + c * d];
}

// Bounds |n_i| for lattice points A n (or reciprocal B n) inside a ball of radius R:
// |n_i| <= R |row i of A^{-1}| = R |b_i| / (2 pi).
std::array<int, 3> index_bounds(const Mat3& inverse_basis, double R) {
  std::array<int, 3> b{};
  for (int i = 0; i < 3; ++i) b[i] = int(std::ceil(R * inverse_basis.row(i).norm())) + 1;
  return b;
}

}  // namespace

MatX ewald_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                    const Domain& domain, const EwaldReferenceOptions& opt) {
  std::vector<long> all(x.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = long(i);
  return ewald_mobility_rows(x, a, mu, m, domain, all, opt);
}

MatX ewald_mobility_rows(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                         const Domain& domain, const std::vector<long>& rows, const EwaldReferenceOptions& opt) {
  if (x.size() != a.size()) throw std::invalid_argument("ewald_mobility: size mismatch");
  const Lattice lat = Lattice::from_domain(domain);
  const double xi = opt.xi > 0.0 ? opt.xi : std::sqrt(kPi) / std::cbrt(lat.volume);
  const double rmax = opt.tail / xi, kmax = 2.0 * xi * opt.tail;
  const int d = dof_per_particle(m);
  const long n = long(x.size()), nr = long(rows.size());
  MatX M = MatX::Zero(nr * d, n * d);

  // Real space: every pair (both orders, so symmetry is a test, not an assumption) and images.
  const auto nb = index_bounds(lat.Ainv, rmax + lat.A.norm());
#pragma omp parallel for schedule(dynamic)
  for (long k = 0; k < (opt.real ? nr : 0); ++k) {
    const long i = rows[std::size_t(k)];
    double block[121], sum[121];  // one image's block and the image sum, d x d column-major
    for (long j = 0; j < n; ++j) {
      std::fill(sum, sum + d * d, 0.0);
      const Vec3 r0 = lat.nearest_image(x[i] - x[j]);
      for (int p = -nb[0]; p <= nb[0]; ++p)
        for (int q = -nb[1]; q <= nb[1]; ++q)
          for (int t = -nb[2]; t <= nb[2]; ++t) {
            const Vec3 r = r0 + lat.A * Vec3(p, q, t);
            const double dist = r.norm();
            if (dist >= rmax || (i == j && dist == 0.0)) continue;
            // Coincident distinct centres give an isotropic block: any axis will do.
            mobility::fill_pair_block(real_scalars(a[i], a[j], dist, xi, mu, m),
                                      dist > 0.0 ? Vec3(r / dist) : Vec3::UnitZ(), m, block, d);
            for (int e = 0; e < d * d; ++e) sum[e] += block[e];
          }
      add_block(M, k, j, sum, d);
    }
    mobility::fill_pair_block(self_correction(a[i], xi, mu), Vec3::UnitZ(), m, block, d);
    add_block(M, k, i, block, d);
  }

  // Wave space: half of the k-vectors (k and -k give complex-conjugate terms).
  // The lattice-point bound uses the inverse of B, i.e. A^T / (2 pi).
  const auto kb = index_bounds(lat.A.transpose() / (2.0 * kPi), kmax);
  std::vector<Vec3> ks;
  if (!opt.wave) return M;
  for (int p = 0; p <= kb[0]; ++p)
    for (int q = -kb[1]; q <= kb[1]; ++q)
      for (int t = -kb[2]; t <= kb[2]; ++t) {
        if (p == 0 && (q < 0 || (q == 0 && t <= 0))) continue;
        const Vec3 k = lat.B * Vec3(p, q, t);
        if (k.norm() < kmax) ks.push_back(k);
      }
  // Each wave vector adds Re(Z G Z^+) with Z the stacked responses R_i(k) e^{i k.x_i} (n d x 3)
  // and G = c (I - k k^T / k^2), c = H(k) / (mu k^2) >= 0. With t1, t2 an orthonormal basis of the
  // plane normal to k, G = Q Q^T for Q = sqrt(c) [t1 t2], so Re(Z G Z^+) = (Re Z Q)(Re Z Q)^T +
  // (Im Z Q)(Im Z Q)^T: four real columns per wave vector, and the whole wave sum is the single
  // product Y Y^T (one matrix product instead of one complex n d x n d update per wave vector).
  const long K = long(ks.size());
  MatX Y(n * d, 4 * K);
#pragma omp parallel for schedule(static)
  for (long w = 0; w < K; ++w) {
    const Vec3& k = ks[std::size_t(w)];
    const double k2 = k.squaredNorm();
    const double c = hasimoto(k2, xi) / (mu * k2);
    const Vec3 kh = k / std::sqrt(k2);
    const Vec3 t1 = kh.unitOrthogonal(), t2 = kh.cross(t1);
    Eigen::Matrix<double, 3, 2> Q;
    Q.col(0) = std::sqrt(c) * t1;
    Q.col(1) = std::sqrt(c) * t2;
    for (long i = 0; i < n; ++i) {
      const MatXc Z = fourier_response(k, a[i], m) * std::polar(1.0, k.dot(x[i]));
      Y.block(i * d, 4 * w, d, 2).noalias() = Z.real() * Q;
      Y.block(i * d, 4 * w + 2, d, 2).noalias() = Z.imag() * Q;
    }
  }
  if (nr == n) {
    M.noalias() += (2.0 / lat.volume) * Y * Y.transpose();
  } else {
    MatX Yr(nr * d, 4 * K);
    for (long k = 0; k < nr; ++k) Yr.middleRows(k * d, d) = Y.middleRows(rows[std::size_t(k)] * d, d);
    M.noalias() += (2.0 / lat.volume) * Yr * Y.transpose();
  }
  return M;
}

void EwaldFarField::set_configuration(const Configuration& c) {
  if (config_.same_as(c)) return;
  config_.store(c);
  built_ = false;
}

const MatX& EwaldFarField::matrix() const {
  if (!built_) {
    if (!config_.valid) throw std::logic_error("ewald far field: no configuration set");
    M_ = ewald_mobility(config_.x, config_.a, mu_, m_, config_.domain, opt_);
    built_ = true;
  }
  return M_;
}

bool EwaldFarField::dense_rows(const std::vector<long>& particles, MatX& rows) const {
  if (!config_.valid) throw std::logic_error("ewald far field: no configuration set");
  // Always summed afresh (not copied from a built M_), so that the rows do not depend on what
  // was asked before.
  rows = ewald_mobility_rows(config_.x, config_.a, mu_, m_, config_.domain, particles, opt_);
  return true;
}

}  // namespace stokesian::ewald
