// Ewald splitting of Psi; the mathematics is stated in ewald_split.hpp (and docs/ewald.md s.2).
#include "ewald/ewald_split.hpp"

#include "engine/core/sym_traceless.hpp"

#include <array>
#include <cmath>

namespace stokesian::ewald {
namespace {

constexpr double kSqrtPi = 1.77245385090551602730;
// Below xi r = kSeries the wave part is summed from its Taylor series (terms (xi r)^(2n) / n!,
// n <= kTerms: truncation < 1e-19 at xi r = 0.5).
constexpr double kSeries = 0.5;
constexpr int kTerms = 16;

using mobility::PsiDerivatives;
using mobility::scalars_from_derivatives;

// Kind pair polynomial coefficients (0 = force kind, 1 = torque/stresslet kind).
struct Faxen {
  double c1, c2;
};
Faxen faxen(int ka, int kb, double a, double b) {
  const double wa = (ka ? 0.1 : 1.0 / 6.0) * a * a, wb = (kb ? 0.1 : 1.0 / 6.0) * b * b;
  return {wa + wb, wa * wb};
}

PsiDerivatives add(PsiDerivatives p, double c, const PsiDerivatives& q) {
  p.d1 += c * q.d1;
  p.d2 += c * q.d2;
  p.d3 += c * q.d3;
  p.d4 += c * q.d4;
  return p;
}

// Radial derivatives of R0, R1, R2 (real part of 8 pi mu Psi, separated form) at r > 0.
struct RealBasis {
  PsiDerivatives r0, r1, r2;
};
RealBasis real_basis(double r, double xi) {
  const double x = xi * r, x2 = x * x, e = std::exp(-x2) / kSqrtPi, ec = std::erfc(x);
  const double xi2 = xi * xi, xi3 = xi2 * xi, xi4 = xi2 * xi2;
  const double r2 = r * r, r3 = r2 * r, r4 = r3 * r, r5 = r4 * r;
  RealBasis b;
  b.r0 = {ec, -2.0 * xi * e, 4.0 * r * xi3 * e, xi3 * (4.0 - 8.0 * x2) * e};
  const double x3 = x2 * x, x5 = x3 * x2, x7 = x5 * x2, x9 = x7 * x2;
  b.r1 = {4.0 * r * xi3 * e - 4.0 * xi * e / r - 2.0 * ec / r2,
          4.0 * e * (x3 * (3.0 - 2.0 * x2) + 2.0 * x) / r3 + 4.0 * ec / r3,
          4.0 * e * (4.0 * x7 - 10.0 * x5 - 4.0 * x3 - 6.0 * x) / r4 - 12.0 * ec / r4,
          8.0 * e * (-4.0 * x9 + 16.0 * x7 - x5 + 8.0 * x3 + 12.0 * x) / r5 + 48.0 * ec / r5};
  b.r2 = {xi4 * (16.0 * x3 - 56.0 * x) * e, xi4 * xi * (-32.0 * x2 * x2 + 160.0 * x2 - 56.0) * e,
          xi4 * xi2 * (64.0 * x5 - 448.0 * x3 + 432.0 * x) * e,
          xi4 * xi3 * (-128.0 * x3 * x3 + 1216.0 * x2 * x2 - 2208.0 * x2 + 432.0) * e};
  return b;
}

PsiDerivatives real_derivs(const RealBasis& b, const Faxen& f) { return add(add(b.r0, f.c1, b.r1), f.c2, b.r2); }

// Free truncated kernel r + 2 c1 / r minus the real part: the wave part in closed form.
PsiDerivatives wave_derivs(const RealBasis& b, const Faxen& f, double r) {
  const double r2 = r * r;
  PsiDerivatives t{1.0 - 2.0 * f.c1 / r2, 4.0 * f.c1 / (r2 * r), -12.0 * f.c1 / (r2 * r2), 48.0 * f.c1 / (r2 * r2 * r)};
  return add(t, -1.0, real_derivs(b, f));
}

// Taylor coefficients (in r^(2n)) of W0, W1, W2.
struct Series {
  std::array<double, kTerms + 1> w0{}, w1{}, w2{};
};
Series wave_series(double xi) {
  Series s;
  double fact = 1.0, xin = 1.0, sign = 1.0;  // n!, xi^(2n), (-1)^n
  double fact_prev = 1.0;                    // (n-1)!
  for (int n = 0; n <= kTerms; ++n) {
    if (n > 0) {
      fact_prev = fact;
      fact *= n;
      xin *= xi * xi;
      sign = -sign;
    }
    double c0 = sign / fact;
    if (n > 0) c0 += 2.0 * (-sign) / (fact_prev * (2.0 * n - 1.0));
    s.w0[n] = c0 / (kSqrtPi * xi) * xin;
    s.w1[n] = 2.0 * xi / kSqrtPi * sign / fact * (2.0 / (2.0 * n + 1.0) + 1.0) * xin;
    double c2 = 20.0 * sign / fact;
    if (n > 0) c2 -= 8.0 * (-sign) / fact_prev;
    s.w2[n] = -xi * xi * xi / kSqrtPi * c2 * xin;
  }
  return s;
}

// res += c * (scalars of r^p at r = 1, scaled to r) for the kind pair selected by `kind`
// (0 ff, 1 tf, 2 ft, 3 tt); c per kind.
void add_power(PairScalars& res, int p, double r, const double c[4], double mu, Moments m) {
  const double fp = p, d1 = fp, d2 = fp * (fp - 1), d3 = d2 * (fp - 2), d4 = d3 * (fp - 3);
  const PsiDerivatives d{d1, d2, d3, d4};
  const PairScalars u = scalars_from_derivatives(d, d, d, d, 1.0, mu, m);
  auto pw = [&](double coef, int k) { return coef == 0.0 ? 0.0 : coef * std::pow(r, p - k); };
  res.xa += c[0] * pw(u.xa, 2);
  res.ya += c[0] * pw(u.ya, 2);
  if (m == Moments::F) return;
  res.yb += c[1] * pw(u.yb, 3);
  res.ybt += c[2] * pw(u.ybt, 3);
  res.xc += c[3] * pw(u.xc, 4);
  res.yc += c[3] * pw(u.yc, 4);
  if (m == Moments::FT) return;
  res.xg += c[1] * pw(u.xg, 3);
  res.yg += c[1] * pw(u.yg, 3);
  res.xgt += c[2] * pw(u.xgt, 3);
  res.ygt += c[2] * pw(u.ygt, 3);
  res.yh += c[3] * pw(u.yh, 4);
  res.yht += c[3] * pw(u.yht, 4);
  res.xm += c[3] * pw(u.xm, 4);
  res.ym += c[3] * pw(u.ym, 4);
  res.zm += c[3] * pw(u.zm, 4);
}

void axpy(PairScalars& y, double c, const PairScalars& x) {
  y.xa += c * x.xa;
  y.ya += c * x.ya;
  y.yb += c * x.yb;
  y.ybt += c * x.ybt;
  y.xc += c * x.xc;
  y.yc += c * x.yc;
  y.xg += c * x.xg;
  y.yg += c * x.yg;
  y.xgt += c * x.xgt;
  y.ygt += c * x.ygt;
  y.yh += c * x.yh;
  y.yht += c * x.yht;
  y.xm += c * x.xm;
  y.ym += c * x.ym;
  y.zm += c * x.zm;
}

}  // namespace

double hasimoto(double k2, double xi) {
  const double q = k2 / (4.0 * xi * xi);
  return (1.0 + q) * std::exp(-q);
}

PairScalars wave_scalars(double a, double b, double r, double xi, double mu, Moments m) {
  const Faxen f[4] = {faxen(0, 0, a, b), faxen(1, 0, a, b), faxen(0, 1, a, b), faxen(1, 1, a, b)};
  if (xi * r >= kSeries) {
    const RealBasis basis = real_basis(r, xi);
    return scalars_from_derivatives(wave_derivs(basis, f[0], r), wave_derivs(basis, f[1], r),
                                    wave_derivs(basis, f[2], r), wave_derivs(basis, f[3], r), r, mu, m);
  }
  const Series s = wave_series(xi);
  PairScalars res;
  for (int n = kTerms; n >= 1; --n) {  // smallest terms first; n = 0 (constant) has no scalars
    double c[4];
    for (int k = 0; k < 4; ++k) c[k] = s.w0[n] + f[k].c1 * s.w1[n] + f[k].c2 * s.w2[n];
    add_power(res, 2 * n, r, c, mu, m);
  }
  return res;
}

PairScalars real_scalars(double a, double b, double r, double xi, double mu, Moments m) {
  if (r >= a + b) {
    const RealBasis basis = real_basis(r, xi);
    return scalars_from_derivatives(real_derivs(basis, faxen(0, 0, a, b)), real_derivs(basis, faxen(1, 0, a, b)),
                                    real_derivs(basis, faxen(0, 1, a, b)), real_derivs(basis, faxen(1, 1, a, b)), r,
                                    mu, m);
  }
  PairScalars s = mobility::pair_scalars(a, b, r, mu, m);
  axpy(s, -1.0, wave_scalars(a, b, r, xi, mu, m));
  return s;
}

PairScalars self_correction(double a, double xi, double mu) {
  PairScalars s = mobility::self_scalars(a, mu);
  axpy(s, -1.0, wave_scalars(a, a, 0.0, xi, mu, Moments::FTS));
  return s;
}

MatXc fourier_response(const Vec3& k, double a, Moments m) {
  using C = std::complex<double>;
  const int d = dof_per_particle(m);
  const double k2 = k.squaredNorm();
  const double pf = 1.0 - a * a * k2 / 6.0, pt = 1.0 - a * a * k2 / 10.0;
  MatXc R = MatXc::Zero(d, 3);
  for (int i = 0; i < 3; ++i) R(i, i) = pf;
  if (d == 3) return R;
  const C h(0.0, 0.5 * pt);  // (i/2) P_T [k x]
  R(3, 1) = -h * k.z();
  R(3, 2) = h * k.y();
  R(4, 0) = h * k.z();
  R(4, 2) = -h * k.x();
  R(5, 0) = -h * k.y();
  R(5, 1) = h * k.x();
  if (d == 6) return R;
  for (int p = 0; p < 5; ++p) {
    const Vec3 bk = sym_traceless_basis()[std::size_t(p)] * k;
    for (int j = 0; j < 3; ++j) R(6 + p, j) = C(0.0, pt * bk[j]);
  }
  return R;
}

}  // namespace stokesian::ewald
