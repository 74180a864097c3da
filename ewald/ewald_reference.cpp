// Dense Ewald sum of the periodic grand mobility; mathematics in ewald_reference.hpp and
// ewald_split.hpp.
#include "ewald/ewald_reference.hpp"

#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/lattice.hpp"

#include <array>
#include <cmath>
#include <stdexcept>

namespace stokesian::ewald {
namespace {


// M(i*d.., j*d..) += block of scalars s along e, built column by column with apply_pair.
void add_block(MatX& M, long i, long j, const PairScalars& s, const Vec3& e, Moments m) {
  const int d = dof_per_particle(m);
  double x[11], y[11];
  for (int c = 0; c < d; ++c) {
    for (int q = 0; q < d; ++q) x[q] = y[q] = 0.0;
    x[c] = 1.0;
    mobility::apply_pair(s, e, m, x, y);
    for (int q = 0; q < d; ++q) M(i * d + q, j * d + c) += y[q];
  }
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
  if (x.size() != a.size()) throw std::invalid_argument("ewald_mobility: size mismatch");
  const Lattice lat = Lattice::from_domain(domain);
  const double xi = opt.xi > 0.0 ? opt.xi : std::sqrt(kPi) / std::cbrt(lat.volume);
  const double rmax = opt.tail / xi, kmax = 2.0 * xi * opt.tail;
  const int d = dof_per_particle(m);
  const long n = long(x.size());
  MatX M = MatX::Zero(n * d, n * d);

  // Real space: every pair (both orders, so symmetry is a test, not an assumption) and images.
  const auto nb = index_bounds(lat.Ainv, rmax + lat.A.norm());
#pragma omp parallel for schedule(dynamic)
  for (long i = 0; i < (opt.real ? n : 0); ++i) {
    for (long j = 0; j < n; ++j) {
      const Vec3 r0 = lat.nearest_image(x[i] - x[j]);
      for (int p = -nb[0]; p <= nb[0]; ++p)
        for (int q = -nb[1]; q <= nb[1]; ++q)
          for (int t = -nb[2]; t <= nb[2]; ++t) {
            const Vec3 r = r0 + lat.A * Vec3(p, q, t);
            const double dist = r.norm();
            if (dist >= rmax || (i == j && dist == 0.0)) continue;
            // Coincident distinct centres give an isotropic block: any axis will do.
            add_block(M, i, j, real_scalars(a[i], a[j], dist, xi, mu, m), dist > 0.0 ? Vec3(r / dist) : Vec3::UnitZ(), m);
          }
    }
    add_block(M, i, i, self_correction(a[i], xi, mu), Vec3::UnitZ(), m);
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
  MatX W = MatX::Zero(n * d, n * d);
  MatXc Z(n * d, 3);
  for (const Vec3& k : ks) {
    for (long i = 0; i < n; ++i)
      Z.block(i * d, 0, d, 3) = fourier_response(k, a[i], m) * std::polar(1.0, k.dot(x[i]));
    const double k2 = k.squaredNorm();
    const Mat3 G = hasimoto(k2, xi) / (mu * k2) * (Mat3::Identity() - k * k.transpose() / k2);
    const MatXc ZG = Z * G.cast<std::complex<double>>();
    W.noalias() += (ZG * Z.adjoint()).real();
  }
  M += (2.0 / lat.volume) * W;
  return M;
}

void EwaldFarField::set_configuration(const Configuration& c) {
  if (built_.same_as(c)) return;
  M_ = ewald_mobility(c.x, c.a, mu_, m_, c.domain, opt_);
  built_.store(c);
}

}  // namespace stokesian::ewald
