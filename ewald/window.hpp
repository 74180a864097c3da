#pragma once
// Window of the PME far field: a separable, compactly supported function on the grid of fractional
// coordinates, evaluated per particle with its first three derivatives.
//
// The grid has M_d points along lattice direction d (fractional s_d = i_d / M_d). A particle at
// fractional position s_p touches the P points i = i0 .. i0 + P - 1 per direction with
// i0 = ceil(M s_p - P/2) (indices taken modulo M), at offsets delta = i - M s_p in grid units, and
//     W(x_g - x_p) = prod_d phi(delta_d),   |delta_d| <= P/2.
// Its continuous transform is What(n) = prod_d phihat(n_d / M_d), phihat(nu) = int phi(t) e^{-2 pi i nu t} dt;
// the DFT over the grid of W(x_g - x_p) is What(n) e^{-i k.x_p} plus aliases (Poisson summation), so
// dividing by What^2 in Fourier space undoes spreading and interpolation [docs/ewald.md (E7)].
// Windows (docs/pme_windows.md compares them):
//   Kaiser-Bessel   phi = I0(beta sqrt(1 - z^2)) / I0(beta),  z = 2 delta / P;
//                   phihat = (P / I0(beta)) sinh(sqrt(beta^2 - w^2)) / sqrt(beta^2 - w^2),  w = pi P nu
//                   (sin form for w > beta) [Kaiser 1966; Jackson et al. 1991, IEEE TMI 10, 473].
//                   I0(beta sqrt(v)) is an entire function of v = 1 - z^2, so every derivative is
//                   smooth up to the support edge (unlike the exponential of semicircle, whose first
//                   derivative is infinite there): the Faxen Laplacian and the gradient windows below
//                   stay accurate.
//   Gaussian        phi = exp(-delta^2 / (2 s^2)),  phihat = sqrt(2 pi) s exp(-2 pi^2 s^2 nu^2)
//                   (the truncation at P/2 is not in phihat; it is part of the window error).
// Physical derivatives: with J = diag(M) A^{-1} (grid units per unit length along x),
//     grad_x W = J^T grad_delta W,   lap W = sum_ij Gt_ij d_i d_j W,   Gt = J J^T.
// Faxen factors: a particle of radius a spreads/interpolates with W + c lap W, c = a^2/6 (force,
// velocity) or a^2/10 (torque, stresslet / rotation, strain), whose transform is (1 - c k^2) What:
// the truncated Faxen factors of ewald_split.hpp, exact for every radius.
#include "engine/core/types.hpp"

#include <array>
#include <vector>

namespace stokesian::ewald {

enum class WindowKind { kaiser_bessel, gaussian };
const char* to_string(WindowKind k);

// One-dimensional window: support P points, shape beta (Kaiser-Bessel) or width s = beta (Gaussian,
// grid spacings).
class Window1D {
 public:
  Window1D() = default;
  Window1D(WindowKind kind, int support, double shape);
  WindowKind kind() const { return kind_; }
  int support() const { return P_; }
  double shape() const { return shape_; }
  // phi^(0..3) at offset delta (grid units); zero outside |delta| <= P/2.
  void derivatives(double delta, double out[4]) const;
  double value(double delta) const;
  // Continuous transform phihat(nu), nu in cycles per grid spacing.
  double transform(double nu) const;

 private:
  WindowKind kind_ = WindowKind::kaiser_bessel;
  int P_ = 0;
  double shape_ = 0.0;
  // Kaiser-Bessel: phi(z) = f(1 - z^2) / I0(beta), f(v) = sum_k c_k v^k, c_k = (beta^2/4)^k / (k!)^2;
  // coef_[j] holds the coefficients of f^(j) divided by I0(beta).
  std::array<std::vector<double>, 4> coef_;
};

// The window as one polynomial per grid interval, for evaluating all P offsets of a particle at
// once. A particle's offsets are delta_j = -P/2 + j + tau (j = 0 .. P-1) with one tau in [0, 1)
// (window.hpp header: i0 = ceil(M s - P/2)), so interval j holds phi^(d)(-P/2 + j + tau) as a
// polynomial of degree D in t = 2 tau - 1: Chebyshev interpolation of Window1D::derivatives at D + 1
// Chebyshev points, stored as monomial coefficients and evaluated by Horner's rule across the P
// intervals at once (contiguous, vectorisable). D is the smallest of 8, 10, ..., 24 whose error,
// measured against Window1D::derivatives at 4 (D + 1) points per interval, is at most kFitError
// times the largest |phi^(d)| on the support, per derivative d; the constructor throws
// std::runtime_error if D = 24 does not reach it (tests/test_ewald.cpp sweeps the windows the
// parameter search can choose: P = 3..32, Kaiser-Bessel beta = 0.9..1.5 pi P (1 - 1/(2 sigma)),
// sigma = 1..2, and Gaussians).
class WindowTable {
 public:
  static constexpr double kFitError = 3e-14;
  WindowTable() = default;
  explicit WindowTable(const Window1D& w);
  int support() const { return P_; }
  int degree() const { return D_; }
  double fit_error() const { return err_; }  // measured, relative (see above)
  // out[d * P + j] = phi^(d)(-P/2 + j + tau), d = 0..3, j = 0..P-1, tau in [0, 1].
  void evaluate(double tau, double* out) const;

 private:
  int P_ = 0, D_ = 0;
  double err_ = 0.0;
  std::vector<double> c_;  // [d][power D..0][j]
};

// Support rounded up to whole 4-double vectors (the fast spreading and interpolation loops,
// spread_fast.cpp), and the stored length of a direction-2 row of M2 points: room for the
// padded_support - 1 ghost points a window starting at M2 - 1 reaches, rounded to a multiple of 4
// doubles so that every row starts 32-byte aligned when the field does.
inline int padded_support(int P) { return (P + 3) / 4 * 4; }
inline int row_length(int M2, int P) { return (M2 + padded_support(P) + 3) / 4 * 4; }

struct GridGeometry {
  std::array<int, 3> M{};      // grid points per lattice direction
  int P = 4;                   // support (points per direction)
  Window1D window;
  WindowTable table;           // window's polynomial form (make_windows); set with set_window
  void set_window(const Window1D& w) {
    window = w;
    table = WindowTable(w);
  }
  Mat3 J = Mat3::Identity();   // diag(M) A^{-1}
  Mat3 lap = Mat3::Zero();     // Gt = J J^T
  int row = 0;                 // stored length of a direction-2 row (ghost points, spread.hpp): row_length

  long points() const { return long(M[0]) * M[1] * M[2]; }
  long stored() const { return long(M[0]) * M[1] * row; }
};

// Window data of all particles: first index i0 per direction and phi^(0..3) at the P offsets per
// direction; cF = a^2/6 and cT = a^2/10 per particle.
struct ParticleWindows {
  int P = 0;
  std::vector<std::array<int, 3>> start;  // i0 in [0, M_d)
  std::vector<double> w;                  // [particle][dir 0..2][deriv 0..3][P]
  std::vector<double> cF, cT;
  const double* at(long p, int dir, int deriv) const { return w.data() + ((p * 3 + dir) * 4 + deriv) * P; }
};

// s_frac: fractional coordinates (any real values; wrapped here); a: radii.
ParticleWindows make_windows(const GridGeometry& g, const std::vector<Vec3>& s_frac, const std::vector<double>& a);

}  // namespace stokesian::ewald
