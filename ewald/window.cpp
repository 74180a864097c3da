// PME windows; definitions in window.hpp.
#include "ewald/window.hpp"

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <stdexcept>
#include <string>

namespace stokesian::ewald {

const char* to_string(WindowKind k) { return k == WindowKind::kaiser_bessel ? "kaiser_bessel" : "gaussian"; }

Window1D::Window1D(WindowKind kind, int support, double shape) : kind_(kind), P_(support), shape_(shape) {
  if (support < 2 || !(shape > 0.0)) throw std::invalid_argument("Window1D: support < 2 or shape <= 0");
  if (kind != WindowKind::kaiser_bessel) return;
  // Power series of I0(beta sqrt(v)) in v; all terms positive, so the sum is accurate to rounding.
  const double q = shape * shape / 4.0;
  std::vector<double> c{1.0};
  double sum = 1.0;
  for (int k = 1;; ++k) {
    c.push_back(c.back() * q / (double(k) * k));
    sum += c.back();
    if (k > shape && c.back() < 1e-18 * sum) break;
  }
  const int K = int(c.size());
  for (int j = 0; j < 4; ++j) {
    coef_[j].assign(std::max(1, K - j), 0.0);
    for (int k = 0; k + j < K; ++k) {
      double f = c[k + j] / sum;  // c_{k+j} (k+j)! / k!
      for (int t = k + 1; t <= k + j; ++t) f *= t;
      coef_[j][k] = f;
    }
  }
}

void Window1D::derivatives(double delta, double out[4]) const {
  const double half = 0.5 * P_;
  if (std::abs(delta) > half) {
    out[0] = out[1] = out[2] = out[3] = 0.0;
    return;
  }
  if (kind_ == WindowKind::gaussian) {
    const double s2 = shape_ * shape_, u = delta / s2;
    const double w = std::exp(-0.5 * delta * u);
    out[0] = w;
    out[1] = -u * w;
    out[2] = (u * u - 1.0 / s2) * w;
    out[3] = (3.0 * u / s2 - u * u * u) * w;
    return;
  }
  // phi(z) = F(v), v = 1 - z^2, z = delta / half; derivatives in z, then d/d delta = (1/half) d/dz.
  const double z = delta / half, v = 1.0 - z * z;
  double F[4];
  for (int j = 0; j < 4; ++j) {
    const auto& c = coef_[j];
    double acc = 0.0;
    for (int k = int(c.size()) - 1; k >= 0; --k) acc = acc * v + c[k];
    F[j] = acc;
  }
  const double h = 1.0 / half;
  out[0] = F[0];
  out[1] = h * (-2.0 * z * F[1]);
  out[2] = h * h * (4.0 * z * z * F[2] - 2.0 * F[1]);
  out[3] = h * h * h * (12.0 * z * F[2] - 8.0 * z * z * z * F[3]);
}

double Window1D::value(double delta) const {
  double d[4];
  derivatives(delta, d);
  return d[0];
}

double Window1D::transform(double nu) const {
  if (kind_ == WindowKind::gaussian)
    return std::sqrt(2.0 * kPi) * shape_ * std::exp(-2.0 * kPi * kPi * shape_ * shape_ * nu * nu);
  // int_{-1}^{1} I0(beta sqrt(1 - z^2)) e^{-i w z} dz = 2 sinh(r) / r, r = sqrt(beta^2 - w^2); scaled
  // by half = P/2 (dz = d delta / half) and 1 / I0(beta) (the normalisation of phi).
  const double w = kPi * P_ * nu, d = shape_ * shape_ - w * w;
  double ratio;
  if (std::abs(d) < 1e-6) ratio = 1.0 + d / 6.0;
  else if (d > 0.0) ratio = std::sinh(std::sqrt(d)) / std::sqrt(d);
  else ratio = std::sin(std::sqrt(-d)) / std::sqrt(-d);
  return P_ * ratio * coef_[0][0];  // coef_[0][0] = 1 / I0(beta)
}

WindowTable::WindowTable(const Window1D& w) : P_(w.support()) {
  const int P = P_;
  // Largest |phi^(d)| on the support, from a fine sampling.
  std::array<double, 4> scale{};
  for (int i = 0; i <= 64 * P; ++i) {
    double v[4];
    w.derivatives(-0.5 * P + double(i) / 64.0, v);
    for (int d = 0; d < 4; ++d) scale[d] = std::max(scale[d], std::abs(v[d]));
  }
  for (int D = 8;; D += 2) {
    const int n = D + 1;
    c_.assign(std::size_t(4) * n * P, 0.0);
    std::vector<double> node(n), val(std::size_t(4) * n), cheb(n), mono(n), Tprev(n), Tcur(n), Tnext(n);
    for (int i = 0; i < n; ++i) node[i] = std::cos(kPi * (i + 0.5) / n);
    for (int j = 0; j < P; ++j) {
      for (int i = 0; i < n; ++i) {
        double v[4];
        w.derivatives(-0.5 * P + j + 0.5 * (node[i] + 1.0), v);
        for (int d = 0; d < 4; ++d) val[std::size_t(d) * n + i] = v[d];
      }
      for (int d = 0; d < 4; ++d) {
        // Chebyshev coefficients a_m = (2/n) sum_i f_i T_m(t_i) (a_0 halved), then monomials by the
        // recurrence T_{m+1} = 2 t T_m - T_{m-1} on coefficient vectors.
        for (int m = 0; m < n; ++m) {
          double sum = 0.0;
          for (int i = 0; i < n; ++i) sum += val[std::size_t(d) * n + i] * std::cos(m * kPi * (i + 0.5) / n);
          cheb[m] = (m == 0 ? 1.0 : 2.0) * sum / n;
        }
        std::fill(mono.begin(), mono.end(), 0.0);
        std::fill(Tprev.begin(), Tprev.end(), 0.0);
        std::fill(Tcur.begin(), Tcur.end(), 0.0);
        Tprev[0] = 1.0;  // T_0
        Tcur[1] = 1.0;   // T_1
        mono[0] += cheb[0];
        if (n > 1) mono[1] += cheb[1];
        for (int m = 2; m < n; ++m) {
          for (int k = 0; k < n; ++k) Tnext[k] = (k > 0 ? 2.0 * Tcur[k - 1] : 0.0) - Tprev[k];
          for (int k = 0; k < n; ++k) mono[k] += cheb[m] * Tnext[k];
          std::swap(Tprev, Tcur);
          std::swap(Tcur, Tnext);
        }
        for (int k = 0; k < n; ++k) c_[(std::size_t(d) * n + (D - k)) * P + j] = mono[k];
      }
    }
    D_ = D;
    // Error against the series at 4n points per interval (offsets in [0, 1], both ends included).
    err_ = 0.0;
    std::vector<double> out(std::size_t(4) * P);
    for (int i = 0; i <= 4 * n; ++i) {
      const double tau = double(i) / (4 * n);
      evaluate(tau, out.data());
      for (int j = 0; j < P; ++j) {
        double v[4];
        w.derivatives(-0.5 * P + j + tau, v);
        for (int d = 0; d < 4; ++d)
          if (scale[d] > 0.0) err_ = std::max(err_, std::abs(out[std::size_t(d) * P + j] - v[d]) / scale[d]);
      }
    }
    if (err_ <= kFitError) return;
    if (D >= 24)
    {
      char msg[160];
      std::snprintf(msg, sizeof msg, "WindowTable: the degree-24 fit of the window (support %d, shape %g) has relative error %.3g > %.3g",
                    P, w.shape(), err_, kFitError);
      throw std::runtime_error(msg);
    }
  }
}

void WindowTable::evaluate(double tau, double* out) const {
  const int P = P_, n = D_ + 1;
  const double t = 2.0 * tau - 1.0;
  for (int d = 0; d < 4; ++d) {
    const double* c = c_.data() + std::size_t(d) * n * P;
    double* o = out + d * P;
    for (int j = 0; j < P; ++j) o[j] = c[j];
    for (int k = 1; k < n; ++k)
      for (int j = 0; j < P; ++j) o[j] = o[j] * t + c[k * P + j];
  }
}

ParticleWindows make_windows(const GridGeometry& g, const std::vector<Vec3>& s_frac, const std::vector<double>& a) {
  const long n = long(s_frac.size());
  const int P = g.P;
  if (g.table.support() != P) throw std::invalid_argument("make_windows: the grid's window table is not set (GridGeometry::set_window)");
  ParticleWindows win;
  win.P = P;
  win.start.resize(n);
  win.w.resize(std::size_t(n) * 12 * P);
  win.cF.resize(n);
  win.cT.resize(n);
#pragma omp parallel for schedule(static)
  for (long p = 0; p < n; ++p) {
    win.cF[p] = a[p] * a[p] / 6.0;
    win.cT[p] = a[p] * a[p] / 10.0;
    for (int d = 0; d < 3; ++d) {
      const double u = s_frac[p][d] - std::floor(s_frac[p][d]);
      const double pos = u * g.M[d];  // particle position in grid units, [0, M)
      const int i0 = int(std::ceil(pos - 0.5 * P));
      win.start[p][d] = ((i0 % g.M[d]) + g.M[d]) % g.M[d];
      // Offsets (i0 + j) - pos = -P/2 + j + tau (WindowTable).
      g.table.evaluate((i0 - pos) + 0.5 * P, win.w.data() + (p * 3 + d) * 4 * P);
    }
  }
  return win;
}

}  // namespace stokesian::ewald
