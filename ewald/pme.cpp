// PME far field: set-up and the three parts of the product; mathematics in pme.hpp.
#include "ewald/pme.hpp"

#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/interpolate.hpp"
#include "ewald/kernel.hpp"

#include <fftw3.h>

#include <algorithm>
#include <complex>
#include <stdexcept>

namespace stokesian::ewald {

// FFTW plans (made once per grid, FFTW_ESTIMATE so the plan -- hence the result -- does not depend
// on timing) and the work arrays: 3 real fields of g.stored() doubles (rows padded to `row`, a
// multiple of 4 so that every plane and field starts 32-byte aligned, as the new-array execute
// functions require) and 3 complex half-spectra of M0 planes. The direction-0 column transforms step
// by one spectral plane; a plane of a multiple of 512 bytes maps a column onto few cache sets, so
// such planes are padded by 16 complex values (to 256 mod 512 bytes). Measured on the reference
// machine (one thread, these plans, scratch microbenchmark 2026-11-29): the columns of a
// 120 x 128 x 120 grid took 9.8 ms unpadded against 1.6 ms for 120^3; for cubes M = 64 / 96 / 128 /
// 160 / 192 / 256 the padding takes 0.76 / 0.91 / 0.32 / 0.72 / 0.46 / 0.07 of the unpadded
// column time and 1.02 at 288. Other planes are left alone: a pad of 4 or 8 values made
// M = 240 / 270 / 288 1.3-1.6x slower.
struct PmeFarField::Fft {
  fftw_plan plane_r2c = nullptr, plane_c2r = nullptr;      // one direction-0 plane (2D)
  fftw_plan cols_fwd = nullptr, cols_bwd = nullptr;        // kChunk direction-0 columns (1D)
  fftw_plan rest_fwd = nullptr, rest_bwd = nullptr;        // the remaining columns of a field
  static constexpr int kChunk = 8;
  double* real = nullptr;
  std::complex<double>* spectral = nullptr;
  long nspec = 0, plane = 0, columns = 0, chunks = 0, rest = 0;
  ~Fft() {
    for (fftw_plan q : {plane_r2c, plane_c2r, cols_fwd, cols_bwd, rest_fwd, rest_bwd})
      if (q) fftw_destroy_plan(q);
    fftw_free(real);
    fftw_free(spectral);
  }
};

PmeFarField::PmeFarField(const MobilitySpec& spec, const PmeOptions& opt)
    : n_(0), mu_(spec.viscosity), m_(spec.moments), tolerance_(spec.tolerance), options_(opt) {
  if (options_.products_per_update <= 0.0) options_.products_per_update = spec.products_per_configuration;
}

PmeFarField::PmeFarField(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                         const Domain& domain, double tolerance, const PmeOptions& opt)
    : n_(0), mu_(mu), m_(m), tolerance_(tolerance), options_(opt) {
  build(x, a, domain);
}

void PmeFarField::set_configuration(const Configuration& c) {
  // Same particles, radii, box and strain: keep parameters, grid and FFTW plans.
  if (fft_ && radius_ == c.a && domain_ == c.domain) {
    update_positions(c.x);
    return;
  }
  // Only the strain moved and the parameters hold for every strain (zero included): new lattice, same
  // grid and plans. An operator built unsheared is rebuilt once when the box first shears.
  if (fft_ && radius_ == c.a && p_.sheared && c.domain.periodic() && c.domain.box == domain_.box &&
      long(c.x.size()) == n_) {
    domain_ = c.domain;
    set_lattice();
    set_windows(c.x);
    real_.update_positions(c.x, domain_);
    return;
  }
  build(c.x, c.a, c.domain);
}

void PmeFarField::set_lattice() {
  lattice_ = Lattice::from_domain(domain_);
  for (int d = 0; d < 3; ++d) grid_.J.row(d) = grid_.M[d] * lattice_.Ainv.row(d);
  grid_.lap = grid_.J * grid_.J.transpose();
  kernel_.build(grid_, lattice_, p_.xi, mu_);
}

void PmeFarField::build(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain) {
  if (x.size() != a.size() || x.empty()) throw std::invalid_argument("PmeFarField: bad particle arrays");
  n_ = long(x.size());
  domain_ = domain;
  lattice_ = Lattice::from_domain(domain);
  const double mu = mu_;
  const Moments m = m_;
  const auto [amin, amax] = std::minmax_element(a.begin(), a.end());
  PmeOptions opt = options_;
  if (opt.self_scale2 <= 0.0) {
    double s2 = 0.0;
    for (double r : a) s2 += pme_self_scale2(r, m);
    opt.self_scale2 = s2 / double(n_);
  }
  p_ = opt.fixed ? *opt.fixed : pme_parameters(tolerance_, lattice_, int(n_), *amin, *amax, m, opt);
  if (p_.support > 64) throw std::invalid_argument("PmeFarField: window support above 64 points");

  // Grid and windows in fractional coordinates.
  grid_.M = p_.grid;
  grid_.P = p_.support;
  grid_.set_window(Window1D(p_.window, p_.support, p_.shape));
  grid_.row = row_length(grid_.M[2], grid_.P);
  set_lattice();
  radius_ = a;
  set_windows(x);
  real_ = RealSpaceSum(x, a, domain, p_.cutoff_gap, p_.xi, mu, m, tolerance_, std::size_t(p_.cache_bytes));

  // FFTW arrays and plans.
  fft_ = std::make_unique<Fft>();
  Fft& f = *fft_;
  const int M0 = grid_.M[0], M1 = grid_.M[1], M2 = grid_.M[2], H2 = M2 / 2 + 1;
  f.columns = long(M1) * H2;
  f.plane = f.columns % 32 == 0 ? f.columns + 16 : f.columns;  // see Fft
  f.nspec = long(M0) * f.plane;
  f.chunks = f.columns / Fft::kChunk;
  f.rest = f.columns % Fft::kChunk;
  f.real = static_cast<double*>(fftw_malloc(sizeof(double) * grid_.stored() * 3));
  f.spectral = static_cast<std::complex<double>*>(fftw_malloc(sizeof(fftw_complex) * f.nspec * 3));
  if (!f.real || !f.spectral) throw std::bad_alloc();
  std::fill_n(f.spectral, f.nspec * 3, std::complex<double>(0.0));  // the padding stays zero
  auto* spec = reinterpret_cast<fftw_complex*>(f.spectral);
  const int plane[2] = {M1, M2}, rembed[2] = {M1, grid_.row}, cembed[2] = {M1, H2};
  const unsigned flags = FFTW_ESTIMATE;
  f.plane_r2c = fftw_plan_many_dft_r2c(2, plane, 1, f.real, rembed, 1, 0, spec, cembed, 1, 0, flags);
  f.plane_c2r = fftw_plan_many_dft_c2r(2, plane, 1, spec, cembed, 1, 0, f.real, rembed, 1, 0, flags);
  const int col[1] = {M0};
  const int stride = int(f.plane);
  f.cols_fwd = fftw_plan_many_dft(1, col, Fft::kChunk, spec, nullptr, stride, 1, spec, nullptr, stride, 1,
                                  FFTW_FORWARD, flags);
  f.cols_bwd = fftw_plan_many_dft(1, col, Fft::kChunk, spec, nullptr, stride, 1, spec, nullptr, stride, 1,
                                  FFTW_BACKWARD, flags);
  if (f.rest > 0) {
    f.rest_fwd = fftw_plan_many_dft(1, col, int(f.rest), spec, nullptr, stride, 1, spec, nullptr, stride, 1,
                                    FFTW_FORWARD, flags);
    f.rest_bwd = fftw_plan_many_dft(1, col, int(f.rest), spec, nullptr, stride, 1, spec, nullptr, stride, 1,
                                    FFTW_BACKWARD, flags);
  }
  if (!f.plane_r2c || !f.plane_c2r || !f.cols_fwd || !f.cols_bwd || (f.rest > 0 && (!f.rest_fwd || !f.rest_bwd)))
    throw std::runtime_error("PmeFarField: FFTW planning failed");
}

void PmeFarField::set_windows(const std::vector<Vec3>& x) {
  std::vector<Vec3> s(n_);
  for (long p = 0; p < n_; ++p) s[p] = lattice_.Ainv * x[p];
  windows_ = make_windows(grid_, s, radius_);
  colouring_ = colour_slabs(grid_, windows_);
}

void PmeFarField::update_positions(const std::vector<Vec3>& x) {
  if (long(x.size()) != n_) throw std::invalid_argument("PmeFarField::update_positions: particle count changed");
  set_windows(x);
  real_.update_positions(x);
}

PmeFarField::~PmeFarField() = default;

void PmeFarField::apply_wave(const VecX& in, VecX& out) const {
  Fft& f = *fft_;
  const int M0 = grid_.M[0], M1 = grid_.M[1], M2 = grid_.M[2];
  const long stored = grid_.stored(), plane_real = long(M1) * grid_.row, plane_spec = f.plane;
  auto* spec = reinterpret_cast<fftw_complex*>(f.spectral);
  const long units = f.chunks + (f.rest > 0 ? 1 : 0);  // column blocks per field
  // Column blocks of one field: kChunk columns each, the last one `rest`.
  auto columns = [&](long item, bool forward) {
    const long c = item / units, b = item % units;
    fftw_complex* at = spec + c * f.nspec + b * Fft::kChunk;
    if (b < f.chunks) fftw_execute_dft(forward ? f.cols_fwd : f.cols_bwd, at, at);
    else fftw_execute_dft(forward ? f.rest_fwd : f.rest_bwd, at, at);
  };

  spread(grid_, windows_, colouring_, m_, in, f.real);
#pragma omp parallel for schedule(static)
  for (long item = 0; item < 3L * M0; ++item) {
    const long c = item / M0, i0 = item % M0;
    fftw_execute_dft_r2c(f.plane_r2c, f.real + c * stored + i0 * plane_real, spec + c * f.nspec + i0 * plane_spec);
  }
#pragma omp parallel for schedule(static)
  for (long item = 0; item < 3 * units; ++item) columns(item, true);
  kernel_.apply(f.spectral, f.nspec, f.plane);
#pragma omp parallel for schedule(static)
  for (long item = 0; item < 3 * units; ++item) columns(item, false);
#pragma omp parallel for schedule(static)
  for (long item = 0; item < 3L * M0; ++item) {
    const long c = item / M0, i0 = item % M0;
    fftw_execute_dft_c2r(f.plane_c2r, spec + c * f.nspec + i0 * plane_spec, f.real + c * stored + i0 * plane_real);
  }
  // Ghost points of every direction-2 row: the periodic copies of its start.
  const int ghosts = grid_.row - M2;
#pragma omp parallel for schedule(static)
  for (long r = 0; r < 3L * M0 * M1; ++r) {
    double* v = f.real + r * grid_.row;
    for (int l = 0; l < ghosts; ++l) v[M2 + l] = v[l % M2];
  }
  interpolate(grid_, windows_, colouring_, m_, f.real, out);
}

void PmeFarField::apply_real(const VecX& in, VecX& out) const { real_.apply(in, out); }

void PmeFarField::apply(const VecX& in, VecX& out) const {
  if (in.size() != size()) throw std::invalid_argument("PmeFarField::apply: wrong input size");
  VecX real;
  apply_wave(in, out);
  apply_real(in, real);
  out += real;
}

}  // namespace stokesian::ewald
