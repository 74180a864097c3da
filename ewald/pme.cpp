// PME far field: set-up and the three parts of the product; mathematics in pme.hpp.
#include "ewald/pme.hpp"

#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/interpolate.hpp"
#include "ewald/kernel.hpp"
#include "trees/neighbor_list.hpp"

#include <fftw3.h>

#include <algorithm>
#include <complex>
#include <stdexcept>

namespace stokesian::ewald {

// FFTW plans (made once per grid, FFTW_ESTIMATE so the plan -- hence the result -- does not depend
// on timing) and the work arrays. The d fields are interleaved (spread.hpp); one strided plan
// transforms one field and is executed for each field offset c (FFTW_UNALIGNED permits the offset
// arrays), the d transforms running on different threads.
struct PmeFarField::Fft {
  fftw_plan forward = nullptr, backward = nullptr;
  double* real = nullptr;
  std::complex<double>* spectral = nullptr;
  ~Fft() {
    if (forward) fftw_destroy_plan(forward);
    if (backward) fftw_destroy_plan(backward);
    fftw_free(real);
    fftw_free(spectral);
  }
};

PmeFarField::PmeFarField(const MobilitySpec& spec, const PmeOptions& opt)
    : n_(0), mu_(spec.viscosity), m_(spec.moments), tolerance_(spec.tolerance), options_(opt) {}

PmeFarField::PmeFarField(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                         const Domain& domain, double tolerance, const PmeOptions& opt)
    : n_(0), mu_(mu), m_(m), tolerance_(tolerance), options_(opt) {
  build(x, a, domain);
}

void PmeFarField::set_configuration(const Configuration& c) {
  // Same particles, radii, box and strain: keep parameters, grid and FFTW plans.
  if (fft_ && radius_ == c.a && domain_ == c.domain)
    update_positions(c.x);
  else
    build(c.x, c.a, c.domain);
}

void PmeFarField::build(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain) {
  if (x.size() != a.size() || x.empty()) throw std::invalid_argument("PmeFarField: bad particle arrays");
  n_ = long(x.size());
  domain_ = domain;
  lattice_ = Lattice::from_domain(domain);
  const double mu = mu_;
  const Moments m = m_;
  const auto [amin, amax] = std::minmax_element(a.begin(), a.end());
  p_ = pme_parameters(tolerance_, lattice_, int(n_), *amin, *amax, m, options_);
  if (p_.support > 64) throw std::invalid_argument("PmeFarField: window support above 64 points");

  // Grid and windows in fractional coordinates.
  grid_.M = p_.grid;
  grid_.P = p_.support;
  grid_.s = p_.width;
  const Mat3 metric = lattice_.Ainv * lattice_.Ainv.transpose();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) grid_.lap(i, j) = metric(i, j) * grid_.M[i] * grid_.M[j];
  radius_ = a;
  set_positions(x);
  self_F_.resize(n_);
  self_T_.resize(n_);
  self_S_.resize(n_);
  for (long i = 0; i < n_; ++i) {
    const PairScalars sc = self_correction(a[i], p_.xi, mu);
    self_F_[i] = sc.xa;
    self_T_[i] = sc.xc;
    self_S_[i] = sc.xm;
  }

  // FFTW arrays and plans.
  fft_ = std::make_unique<Fft>();
  const int d = dof_per_particle(m);
  const long npts = grid_.points(), nspec = long(grid_.M[0]) * grid_.M[1] * (grid_.M[2] / 2 + 1);
  fft_->real = static_cast<double*>(fftw_malloc(sizeof(double) * npts * d));
  fft_->spectral = static_cast<std::complex<double>*>(fftw_malloc(sizeof(fftw_complex) * nspec * d));
  if (!fft_->real || !fft_->spectral) throw std::bad_alloc();
  auto* spec = reinterpret_cast<fftw_complex*>(fft_->spectral);
  const int dims[3] = {grid_.M[0], grid_.M[1], grid_.M[2]};
  const unsigned flags = FFTW_ESTIMATE | FFTW_UNALIGNED;
  fft_->forward = fftw_plan_many_dft_r2c(3, dims, 1, fft_->real, nullptr, d, 1, spec, nullptr, d, 1, flags);
  fft_->backward = fftw_plan_many_dft_c2r(3, dims, 1, spec, nullptr, d, 1, fft_->real, nullptr, d, 1, flags);
  if (!fft_->forward || !fft_->backward) throw std::runtime_error("PmeFarField: FFTW planning failed");
}

void PmeFarField::set_positions(const std::vector<Vec3>& x) {
  std::vector<Vec3> s(n_);
  for (long p = 0; p < n_; ++p) s[p] = lattice_.Ainv * x[p];
  windows_ = make_windows(grid_, s, radius_);
  colouring_ = colour_slabs(grid_, windows_);

  // Real-space pairs (minimum image, Lees-Edwards aware).
  const auto pairs = trees::neighbor_pairs(x, radius_, domain_, p_.cutoff_gap);
  pairs_.resize(pairs.size());
  for (std::size_t q = 0; q < pairs.size(); ++q)
    pairs_[q] = Pair{pairs[q].i, pairs[q].j, pairs[q].dist > 0.0 ? Vec3(pairs[q].r / pairs[q].dist) : Vec3::UnitZ(),
                     pairs[q].dist};  // coincident centres: isotropic block, any axis
  pair_start_.assign(n_ + 1, 0);
  for (const Pair& pr : pairs_) {
    ++pair_start_[pr.i + 1];
    ++pair_start_[pr.j + 1];
  }
  for (long i = 0; i < n_; ++i) pair_start_[i + 1] += pair_start_[i];
  pair_list_.resize(2 * pairs_.size());
  std::vector<int> fill(pair_start_.begin(), pair_start_.end() - 1);
  for (int q = 0; q < int(pairs_.size()); ++q) {
    pair_list_[fill[pairs_[q].i]++] = 2 * q;
    pair_list_[fill[pairs_[q].j]++] = 2 * q + 1;
  }
  cache_.clear();
  if (pair_list_.size() * sizeof(PairScalars) <= kCacheBytes) {
    std::vector<PairScalars> cache(pair_list_.size());
#pragma omp parallel for schedule(dynamic, 64)
    for (long i = 0; i < n_; ++i)
      for (int t = pair_start_[i]; t < pair_start_[i + 1]; ++t) cache[t] = entry_scalars(i, t);
    cache_ = std::move(cache);
  }
}

void PmeFarField::update_positions(const std::vector<Vec3>& x) {
  if (long(x.size()) != n_) throw std::invalid_argument("PmeFarField::update_positions: particle count changed");
  set_positions(x);
}

PmeFarField::~PmeFarField() = default;

void PmeFarField::apply_wave(const VecX& in, VecX& out) const {
  const int d = dof_per_particle(m_);
  spread(grid_, windows_, colouring_, m_, in, fft_->real);
  auto* spec = reinterpret_cast<fftw_complex*>(fft_->spectral);
  // The d transforms are independent: one per thread (fftw_execute_* is thread-safe).
#pragma omp parallel for schedule(static)
  for (int c = 0; c < d; ++c) fftw_execute_dft_r2c(fft_->forward, fft_->real + c, spec + c);
  apply_fourier_kernel(grid_, lattice_, p_.xi, mu_, m_, fft_->spectral);
#pragma omp parallel for schedule(static)
  for (int c = 0; c < d; ++c) fftw_execute_dft_c2r(fft_->backward, spec + c, fft_->real + c);
  interpolate(grid_, windows_, m_, fft_->real, out);
}

PairScalars PmeFarField::entry_scalars(long i, int t) const {
  if (!cache_.empty()) return cache_[t];
  const Pair& pr = pairs_[pair_list_[t] / 2];
  const long j = pair_list_[t] % 2 == 0 ? pr.j : pr.i;
  return real_scalars(radius_[i], radius_[j], pr.dist, p_.xi, mu_, m_);
}

void PmeFarField::apply_real(const VecX& in, VecX& out) const {
  const int d = dof_per_particle(m_);
  out.setZero(n_ * d);
  // Each particle gathers its own row: no write conflicts, fixed summation order.
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < n_; ++i) {
    double* yi = out.data() + i * d;
    const double* xi = in.data() + i * d;
    for (int c = 0; c < 3; ++c) yi[c] += self_F_[i] * xi[c];
    if (d > 3)
      for (int c = 3; c < 6; ++c) yi[c] += self_T_[i] * xi[c];
    if (d > 6)
      for (int c = 6; c < 11; ++c) yi[c] += self_S_[i] * xi[c];
    for (int t = pair_start_[i]; t < pair_start_[i + 1]; ++t) {
      const Pair& pr = pairs_[pair_list_[t] / 2];
      const bool first = pair_list_[t] % 2 == 0;  // i is the pair's first particle
      const long j = first ? pr.j : pr.i;
      mobility::apply_pair(entry_scalars(i, t), first ? pr.e : Vec3(-pr.e), m_, in.data() + j * d, yi);
    }
  }
}

void PmeFarField::apply(const VecX& in, VecX& out) const {
  if (in.size() != size()) throw std::invalid_argument("PmeFarField::apply: wrong input size");
  VecX real;
  apply_wave(in, out);
  apply_real(in, real);
  out += real;
}

}  // namespace stokesian::ewald
