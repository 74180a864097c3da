#include "engine/brownian.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/krylov.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <sstream>

// Long-wave deflation of the periodic far-field mobility (LongWaveDeflation).
//
// In a periodic box of volume V (lattice A, reciprocal vectors k = 2 pi A^{-T} n, n integer) the
// flow of a unit point force has the Fourier coefficients (I - k k^T / k^2) / (mu V k^2), k != 0
// (Hasimoto 1959). A transverse force wave on the N spheres, F_j = p e^{i k.x_j} with p . k = 0,
// therefore drives U_i ~ [N / (mu V k^2) + 1 / (6 pi mu a_i)] p e^{i k.x_i}: M_inf has eigenvalues
// near lambda_k = n / (mu k^2), n = N / V, which grow as L^2 at fixed volume fraction and sit far
// above the rest of the spectrum (bench: at N = 1e4, phi = 0.4 the largest is ~100 times the self
// mobility; the smallest, from close pairs, ~0.1 of it). They set the Lanczos count.
//
// With lambda_s = mean of 1 / (6 pi mu a_i) and rho_k = lambda_k / lambda_s = n / (k^2 mean(1/(6 pi a)))
// (independent of mu),
// the wave vectors with rho_k >= min_ratio (the max_wave_vectors largest; one of each pair +-k) get
// c_k = rho_k^{-1/2} and, on the translational entries,
//
//     G_ij = delta_ij I + sum_k (c_k - 1) (2 / N) (I - k k^T / k^2) cos(k.(x_i - x_j)),
//
// symmetric by construction. For particles spread over the box the vectors p cos(k.x), p sin(k.x)
// (norm^2 ~ N / 2) are nearly orthonormal, so G scales each such mode by about c_k and G M G has it
// near lambda_s. Whatever the accuracy of the estimate, x = G (G M G)^{-1/2} psi has covariance
// M^{-1} exactly (Chow & Saad 2014, SIAM J. Sci. Comput. 36, A588: preconditioned sampling); only
// the Lanczos count depends on it. Applying G: A_k = sum_j F_j e^{-i k.x_j}, then
// out_i += Re(e^{i k.x_i} W_k A_k), W_k = (c_k - 1)(2/N)(I - k k^T / k^2). Phases are products of
// powers of e^{2 pi i s_d} (s = A^{-1} x, the fractional coordinates of Domain::fractional; the three
// bases are kept per particle), identical in both passes. The forward sums are formed over fixed
// blocks of particles and added in block order, so G does not depend on the thread count.

namespace stokesian {

namespace {
// Lanczos cap for M^{-1/2} psi: it converges like CG on the well-conditioned far-field mobility,
// in tens of iterations; the cap only marks a failure.
constexpr int kLanczosCap = 300;
// Particles per block of the forward sums of LongWaveDeflation.
constexpr long kDeflationBlock = 256;

using Cplx = std::complex<double>;

// u^m for m = -nmax ... nmax into e[0 ... 2 nmax], |u| = 1.
void phase_powers(Cplx u, int nmax, Cplx* e) {
  e[nmax] = 1.0;
  for (int m = 1; m <= nmax; ++m) {
    e[nmax + m] = e[nmax + m - 1] * u;
    e[nmax - m] = std::conj(e[nmax + m]);
  }
}
}  // namespace

LongWaveDeflation::LongWaveDeflation(const Configuration& c, Moments m, double min_ratio, long max_wave_vectors) {
  d_ = dof_per_particle(m);
  np_ = long(c.x.size());
  if (!c.domain.periodic() || np_ == 0) return;
  const Mat3 A = c.domain.lattice();
  const Mat3 B = 2.0 * kPi * A.inverse().transpose();  // k = B n
  double inv_a = 0.0;
  for (double r : c.a) inv_a += 1.0 / (6.0 * kPi * r);
  inv_a /= double(np_);
  const double density = double(np_) / std::abs(A.determinant());
  // rho(k) = density / (k^2 inv_a) >= kMinRatio  <=>  |k| <= kmax; |n_d| = |a_d . k| / (2 pi).
  const double kmax = std::sqrt(density / (inv_a * min_ratio));
  // At most 3N/16 wave vectors (4 modes each, against 3N translational entries).
  const long cap = std::min<long>(max_wave_vectors, 3 * np_ / 16);
  if (cap <= 0) return;
  int bound[3];
  for (int q = 0; q < 3; ++q) bound[q] = int(std::floor(kmax * A.col(q).norm() / (2.0 * kPi)));
  struct Cand {
    double rho;
    std::array<int, 3> n;
  };
  std::vector<Cand> cand;
  for (int n0 = -bound[0]; n0 <= bound[0]; ++n0)
    for (int n1 = -bound[1]; n1 <= bound[1]; ++n1)
      for (int n2 = 0; n2 <= bound[2]; ++n2) {
        // one of each pair +-n: first nonzero component positive
        if (n2 == 0 && (n1 < 0 || (n1 == 0 && n0 <= 0))) continue;
        const Vec3 k = B * Vec3(n0, n1, n2);
        const double rho = density / (k.squaredNorm() * inv_a);
        if (rho >= min_ratio) cand.push_back({rho, {n0, n1, n2}});
      }
  std::sort(cand.begin(), cand.end(), [](const Cand& p, const Cand& q) { return p.rho != q.rho ? p.rho > q.rho : p.n < q.n; });
  if (long(cand.size()) > cap) cand.resize(std::size_t(cap));
  if (cand.empty()) return;
  for (const Cand& q : cand) {
    const Vec3 k = B * Vec3(q.n[0], q.n[1], q.n[2]);
    const Vec3 kh = k.normalized();
    const double ck = 1.0 / std::sqrt(q.rho);
    n_.push_back(q.n);
    w_.push_back((ck - 1.0) * (2.0 / double(np_)) * (Mat3::Identity() - kh * kh.transpose()));
    for (int d = 0; d < 3; ++d) nmax_[d] = std::max(nmax_[d], std::abs(q.n[std::size_t(d)]));
  }
  u_.resize(std::size_t(3 * np_));
  for (long i = 0; i < np_; ++i) {
    const Vec3 s = c.domain.fractional(c.x[std::size_t(i)]);
    for (int d = 0; d < 3; ++d) u_[std::size_t(3 * i + d)] = std::polar(1.0, 2.0 * kPi * s[d]);
  }
}

void LongWaveDeflation::apply(const VecX& in, VecX& out) const {
  out = in;
  if (n_.empty()) return;
  const long K = long(n_.size()), nb = (np_ + kDeflationBlock - 1) / kDeflationBlock;
  const int w0 = 2 * nmax_[0] + 1, w1 = 2 * nmax_[1] + 1, w2 = 2 * nmax_[2] + 1;
  std::vector<Cplx> part(std::size_t(nb * K * 3), Cplx(0.0, 0.0));
#pragma omp parallel
  {
    std::vector<Cplx> e(std::size_t(w0 + w1 + w2));
#pragma omp for schedule(static)
    for (long b = 0; b < nb; ++b) {
      Cplx* Ab = part.data() + b * K * 3;
      for (long i = b * kDeflationBlock; i < std::min(np_, (b + 1) * kDeflationBlock); ++i) {
        phase_powers(u_[std::size_t(3 * i)], nmax_[0], e.data());
        phase_powers(u_[std::size_t(3 * i + 1)], nmax_[1], e.data() + w0);
        phase_powers(u_[std::size_t(3 * i + 2)], nmax_[2], e.data() + w0 + w1);
        const double f0 = in[i * d_], f1 = in[i * d_ + 1], f2 = in[i * d_ + 2];
        for (long k = 0; k < K; ++k) {
          const auto& n = n_[std::size_t(k)];
          const Cplx ph = std::conj(e[std::size_t(nmax_[0] + n[0])] * e[std::size_t(w0 + nmax_[1] + n[1])] *
                                    e[std::size_t(w0 + w1 + nmax_[2] + n[2])]);
          Ab[3 * k] += f0 * ph;
          Ab[3 * k + 1] += f1 * ph;
          Ab[3 * k + 2] += f2 * ph;
        }
      }
    }
  }
  std::vector<Cplx> W(std::size_t(K * 3), Cplx(0.0, 0.0));
  for (long b = 0; b < nb; ++b)
    for (long q = 0; q < K * 3; ++q) W[std::size_t(q)] += part[std::size_t(b * K * 3 + q)];
  for (long k = 0; k < K; ++k) {
    const Mat3& w = w_[std::size_t(k)];
    const Cplx a0 = W[std::size_t(3 * k)], a1 = W[std::size_t(3 * k + 1)], a2 = W[std::size_t(3 * k + 2)];
    for (int r = 0; r < 3; ++r) W[std::size_t(3 * k + r)] = w(r, 0) * a0 + w(r, 1) * a1 + w(r, 2) * a2;
  }
#pragma omp parallel
  {
    std::vector<Cplx> e(std::size_t(w0 + w1 + w2));
#pragma omp for schedule(static)
    for (long i = 0; i < np_; ++i) {
      phase_powers(u_[std::size_t(3 * i)], nmax_[0], e.data());
      phase_powers(u_[std::size_t(3 * i + 1)], nmax_[1], e.data() + w0);
      phase_powers(u_[std::size_t(3 * i + 2)], nmax_[2], e.data() + w0 + w1);
      double u0 = 0.0, u1 = 0.0, u2 = 0.0;
      for (long k = 0; k < K; ++k) {
        const auto& n = n_[std::size_t(k)];
        const Cplx ph = e[std::size_t(nmax_[0] + n[0])] * e[std::size_t(w0 + nmax_[1] + n[1])] *
                        e[std::size_t(w0 + w1 + nmax_[2] + n[2])];
        u0 += (ph * W[std::size_t(3 * k)]).real();
        u1 += (ph * W[std::size_t(3 * k + 1)]).real();
        u2 += (ph * W[std::size_t(3 * k + 2)]).real();
      }
      out[i * d_] += u0;
      out[i * d_ + 1] += u1;
      out[i * d_ + 2] += u2;
    }
  }
}

std::vector<char> force_given_flags(Moments m, long n, const std::vector<char>& fixed) {
  const int d = dof_per_particle(m), dv = d > 6 ? 6 : d;
  std::vector<char> g(std::size_t(n * d), 0);
  for (long i = 0; i < n; ++i) {
    if (!fixed.empty() && fixed[std::size_t(i)]) continue;
    for (int k = 0; k < dv; ++k) g[std::size_t(i * d + k)] = 1;
  }
  return g;
}

VecX self_resistance(const std::vector<double>& a, double mu, Moments m) {
  const int d = dof_per_particle(m);
  VecX D(long(a.size()) * d);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double r = a[i], r3 = r * r * r;
    for (int c = 0; c < d; ++c)
      D[long(i) * d + c] = c < 3 ? 6.0 * kPi * mu * r : c < 6 ? 8.0 * kPi * mu * r3 : 20.0 / 3.0 * kPi * mu * r3;
  }
  return D;
}

KrylovResult far_field_inverse_sqrt(const MobilityOperator& M, const Configuration& c, const VecX& psi, VecX& y,
                                    double tol, LanczosReport* report) {
  const LongWaveDeflation G(c, M.moments());
  KrylovResult kr;
  if (G.empty()) {
    const LinearOperator A = [&M](const VecX& in, VecX& out) { M.apply(in, out); };
    kr = lanczos_power(A, psi, y, -0.5, tol, kLanczosCap);
  } else {
    VecX t, u, z;
    const LinearOperator GMG = [&](const VecX& in, VecX& out) {
      G.apply(in, t);
      M.apply(t, u);
      G.apply(u, out);
    };
    kr = lanczos_power(GMG, psi, z, -0.5, tol, kLanczosCap);
    G.apply(z, y);
  }
  if (report) {
    report->iterations = kr.iterations;
    report->wave_vectors = long(G.wave_vectors());
  }
  return kr;
}

VecX far_field_brownian_force(const MobilityOperator& M, const Configuration& c, const std::vector<char>& given,
                              double scale, double tol, Rng& rng, LanczosReport* report) {
  const long size = long(M.size());
  VecX psi(size), y;
  for (auto& v : psi) v = rng.normal();
  const KrylovResult kr = far_field_inverse_sqrt(M, c, psi, y, tol, report);
  if (!kr.converged) {
    std::ostringstream o;
    o << "far-field Brownian force M^(-1/2) psi: the Lanczos iteration " << describe(kr) << " after "
      << kr.iterations << " iterations (last relative change " << kr.relative_residual << ", tolerance " << tol
      << ", cap " << kLanczosCap << ")";
    throw PhysicsError(o.str());
  }
  for (long q = 0; q < size; ++q) y[q] = given[std::size_t(q)] ? scale * y[q] : 0.0;
  return y;
}

}  // namespace stokesian
