#include "engine/kernels/mobility_pair.hpp"

#include <array>
#include <cmath>

namespace stokesian::mobility {
namespace {


// 8 pi mu Psi(r) = sum_{m=-1}^{7} q[m+1] r^m for one pair of kinds (0 = force, 1 = torque/stresslet).
using PsiPoly = std::array<double, 9>;

PsiPoly psi_poly(int ka, int kb, double a, double b, double r) {
  PsiPoly q{};
  const PairRegime regime = pair_regime(a, b, r);
  if (regime == PairRegime::separate) {
    const double wa = ka ? 0.1 : 1.0 / 6.0, wb = kb ? 0.1 : 1.0 / 6.0;
    q[0] = 2.0 * (wa * a * a + wb * b * b);
    q[2] = 1.0;
    return q;
  }
  if (regime == PairRegime::nested) {
    // Derived for a >= b; the kernel is symmetric under (kind, radius) exchange.
    if (a < b) return psi_poly(kb, ka, b, a, r);
    const double a2 = a * a, b2 = b * b, a3 = a2 * a;
    if (!ka && !kb) {
      q[1] = (3 * a2 + b2) / (3 * a);
      q[3] = 1.0 / (3 * a);
    } else if (ka && !kb) {
      q[1] = (15 * a2 * a2 + 10 * a2 * b2 - b2 * b2) / (20 * a3);
      q[3] = (3 * a2 - b2) / (6 * a3);
      q[5] = -1.0 / (20 * a3);
    } else if (!ka && kb) {
      q[1] = (5 * a2 + b2) / (5 * a);
      q[3] = 1.0 / (3 * a);
    } else {
      q[1] = 3.0 * (35 * a2 * a2 + 14 * a2 * b2 - b2 * b2) / (140 * a3);
      q[3] = (5 * a2 - b2) / (10 * a3);
      q[5] = -1.0 / (20 * a3);
    }
    return q;
  }
  // Overlapping: |a - b| < r < a + b. Factored forms keep (a - b)^n accurate.
  const double d = a - b, s = a + b, ab = a * b, a3 = a * a * a, b3 = b * b * b;
  if (!ka && !kb) {
    q[0] = -std::pow(d, 4) / (24 * ab);
    q[1] = std::pow(s, 3) / (6 * ab);
    q[2] = -d * d / (4 * ab);
    q[3] = s / (6 * ab);
    q[4] = -1.0 / (24 * ab);
  } else if (ka && !kb) {
    q[0] = -std::pow(d, 5) * (5 * a + b) / (240 * a3 * b);
    q[1] = std::pow(s, 4) * (4 * a - b) / (40 * a3 * b);
    q[2] = -std::pow(d, 3) * (3 * a + b) / (16 * a3 * b);
    q[3] = s * s * (2 * a - b) / (12 * a3 * b);
    q[4] = -d * s / (16 * a3 * b);
    q[5] = -1.0 / (40 * a3);
    q[6] = 1.0 / (240 * a3 * b);
  } else if (!ka && kb) {
    q[0] = std::pow(d, 5) * (a + 5 * b) / (240 * a * b3);
    q[1] = -(a - 4 * b) * std::pow(s, 4) / (40 * a * b3);
    q[2] = std::pow(d, 3) * (a + 3 * b) / (16 * a * b3);
    q[3] = -(a - 2 * b) * s * s / (12 * a * b3);
    q[4] = d * s / (16 * a * b3);
    q[5] = -1.0 / (40 * b3);
    q[6] = 1.0 / (240 * a * b3);
  } else {
    const double a3b3 = a3 * b3, aa = a * a, bb = b * b;
    q[0] = std::pow(d, 6) * (aa + 6 * ab + bb) / (640 * a3b3);
    q[1] = -3.0 * std::pow(s, 5) * (aa - 5 * ab + bb) / (280 * a3b3);
    q[2] = std::pow(d, 4) * (aa + 4 * ab + bb) / (32 * a3b3);
    q[3] = -std::pow(s, 3) * (aa - 3 * ab + bb) / (20 * a3b3);
    q[4] = 3.0 * d * d * s * s / (64 * a3b3);
    q[5] = -s * (aa - ab + bb) / (40 * a3b3);
    q[6] = (aa + bb) / (160 * a3b3);
    q[8] = -1.0 / (4480 * a3b3);
  }
  return q;
}

// Each scalar s is linear in Psi; for Psi = r^m it equals C[s][m+1] r^(m - k_s), with k_s = 2 for
// xa, ya; 3 for yb, xg, yg; 4 for xc, yc, yh, xm, ym, zm (tools/derive_scalars_table.py).
enum Scalar { XA, YA, YB, XC, YC, XG, YG, YH, XM, YM, ZM, NSCALAR };
constexpr int kPower[NSCALAR] = {2, 2, 3, 4, 4, 3, 3, 4, 4, 4, 4};
constexpr double kC[NSCALAR][9] = {
    {-2, 0, 2, 4, 6, 8, 10, 12, 14},            // xa = 2 Psi'/r
    {1, 0, 1, 4, 9, 16, 25, 36, 49},            // ya = Psi'' + Psi'/r
    {0, 0, 1, 0, -6, -20, -45, -84, -140},      // yb = -Psi'''/2 - Psi''/r + Psi'/r^2
    {0, 0, 1, 0, -6, -20, -45, -84, -140},      // xc = yb / r
    {0, 0, -0.5, 0, -3, -20, -67.5, -168, -350},  // yc
    {9, 0, -3, 0, 9, 24, 45, 72, 105},          // xg = 3 (r Psi'' - Psi') / r^2
    {-3, 0, 0, 0, 3, 12, 30, 60, 105},          // yg = Psi''' / 2
    {0, 0, -1.5, 0, 3, 0, -22.5, -84, -210},    // yh
    {36, 0, -6, 0, 0, -24, -90, -216, -420},    // xm
    {-24, 0, 3, 0, -6, -24, -75, -192, -420},   // ym
    {6, 0, 0, 0, -6, -24, -60, -120, -210},     // zm = -Psi''' / r
};

double scalar(Scalar s, const PsiPoly& q, double r) {
  double sum = 0.0;
  for (int i = 0; i < 9; ++i) {
    if (q[i] == 0.0 || kC[s][i] == 0.0) continue;
    sum += q[i] * kC[s][i] * std::pow(r, i - 1 - kPower[s]);
  }
  return sum;
}

}  // namespace

PairRegime pair_regime(double a, double b, double r) {
  if (r >= a + b) return PairRegime::separate;
  if (r <= std::abs(a - b)) return PairRegime::nested;
  return PairRegime::overlapping;
}

namespace {
// Separated pairs (the hot path): 8 pi mu Psi = r + c/r, so with u = 1/r the scalars are
// (tools/derive_scalars_table.py, columns m = -1 and m = 1 of kC):
//   xa = 2u - 2cu^3, ya = u + cu^3, yb = u^2, xc = u^3, yc = -u^3/2, xg = -3u^2 + 9cu^4,
//   yg = -3cu^4, yh = -3u^3/2, xm = -6u^3 + 36cu^5, ym = 3u^3 - 24cu^5, zm = 6cu^5.
PairScalars separated_scalars(double a, double b, double r, double mu, Moments m) {
  const double k = 1.0 / (8.0 * kPi * mu), u = 1.0 / r, u2 = u * u, u3 = u2 * u, u4 = u2 * u2, u5 = u4 * u;
  const double a2 = a * a, b2 = b * b;
  PairScalars s;
  const double cff = (a2 + b2) / 3.0;
  s.xa = k * (2.0 * u - 2.0 * cff * u3);
  s.ya = k * (u + cff * u3);
  if (m == Moments::F) return s;
  s.yb = s.ybt = k * u2;
  s.xc = k * u3;
  s.yc = -0.5 * k * u3;
  if (m == Moments::FT) return s;
  const double ctf = a2 / 5.0 + b2 / 3.0, cft = a2 / 3.0 + b2 / 5.0, ctt = (a2 + b2) / 5.0;
  s.xg = k * (-3.0 * u2 + 9.0 * ctf * u4);
  s.yg = -3.0 * k * ctf * u4;
  s.xgt = -k * (-3.0 * u2 + 9.0 * cft * u4);
  s.ygt = 3.0 * k * cft * u4;
  s.yh = s.yht = -1.5 * k * u3;
  s.xm = k * (-6.0 * u3 + 36.0 * ctt * u5);
  s.ym = k * (3.0 * u3 - 24.0 * ctt * u5);
  s.zm = 6.0 * k * ctt * u5;
  return s;
}
}  // namespace

PairScalars pair_scalars(double a, double b, double r, double mu, Moments m) {
  if (r >= a + b) return separated_scalars(a, b, r, mu, m);
  const double k = 1.0 / (8.0 * kPi * mu);
  PairScalars s;
  const PsiPoly ff = psi_poly(0, 0, a, b, r);
  s.xa = k * scalar(XA, ff, r);
  s.ya = k * scalar(YA, ff, r);
  if (m == Moments::F) return s;
  const PsiPoly tf = psi_poly(1, 0, a, b, r), ft = psi_poly(0, 1, a, b, r), tt = psi_poly(1, 1, a, b, r);
  s.yb = k * scalar(YB, tf, r);
  s.ybt = k * scalar(YB, ft, r);
  s.xc = k * scalar(XC, tt, r);
  s.yc = k * scalar(YC, tt, r);
  if (m == Moments::FT) return s;
  s.xg = k * scalar(XG, tf, r);
  s.yg = k * scalar(YG, tf, r);
  s.xgt = -k * scalar(XG, ft, r);
  s.ygt = -k * scalar(YG, ft, r);
  s.yh = k * scalar(YH, tt, r);
  s.yht = s.yh;
  s.xm = k * scalar(XM, tt, r);
  s.ym = k * scalar(YM, tt, r);
  s.zm = k * scalar(ZM, tt, r);
  return s;
}

PairScalars scalars_from_derivatives(const PsiDerivatives& ff, const PsiDerivatives& tf, const PsiDerivatives& ft,
                                     const PsiDerivatives& tt, double r, double mu, Moments m) {
  const double k = 1.0 / (8.0 * kPi * mu), r2 = r * r, r3 = r2 * r;
  PairScalars s;
  s.xa = k * 2.0 * ff.d1 / r;
  s.ya = k * (ff.d2 + ff.d1 / r);
  if (m == Moments::F) return s;
  auto yb = [&](const PsiDerivatives& d) { return -0.5 * d.d3 - d.d2 / r + d.d1 / r2; };
  s.yb = k * yb(tf);
  s.ybt = k * yb(ft);
  s.xc = k * yb(tt) / r;
  s.yc = k * (-0.25 * tt.d4 - 0.75 * tt.d3 / r + 0.5 * tt.d2 / r2 - 0.5 * tt.d1 / r3);
  if (m == Moments::FT) return s;
  s.xg = k * 3.0 * (r * tf.d2 - tf.d1) / r2;
  s.yg = k * 0.5 * tf.d3;
  s.xgt = -k * 3.0 * (r * ft.d2 - ft.d1) / r2;
  s.ygt = -k * 0.5 * ft.d3;
  s.yh = s.yht = k * (-r3 * tt.d4 - r2 * tt.d3 + 6.0 * r * tt.d2 - 6.0 * tt.d1) / (4.0 * r3);
  s.xm = k * 3.0 * (-r2 * tt.d3 + 2.0 * r * tt.d2 - 2.0 * tt.d1) / r3;
  s.ym = k * (-0.5 * tt.d4 + 0.5 * tt.d3 / r - 3.0 * tt.d2 / r2 + 3.0 * tt.d1 / r3);
  s.zm = k * (-tt.d3 / r);
  return s;
}

PairScalars self_scalars(double a, double mu) {
  PairScalars s;
  s.xa = s.ya = 1.0 / (6.0 * kPi * mu * a);
  s.xc = s.yc = 1.0 / (8.0 * kPi * mu * a * a * a);
  s.xm = s.ym = s.zm = 3.0 / (20.0 * kPi * mu * a * a * a);
  return s;
}

void apply_pair(const PairScalars& s, const Vec3& e, Moments m, const double* x, double* y) {
  const Eigen::Map<const Vec3> F(x);
  Eigen::Map<Vec3> U(y);
  const double eF = e.dot(F);
  U += s.xa * eF * e + s.ya * (F - eF * e);
  if (m == Moments::F) return;
  const Eigen::Map<const Vec3> T(x + 3);
  Eigen::Map<Vec3> W(y + 3);
  const double eT = e.dot(T);
  W += s.yb * F.cross(e) + s.xc * eT * e + s.yc * (T - eT * e);
  U += s.ybt * T.cross(e);
  if (m == Moments::FT) return;
  const Mat3 S = from_vec5(Eigen::Map<const Vec5>(x + 6));
  const Vec3 Se = S * e;
  const double eSe = e.dot(Se);
  U += s.xgt * eSe * e + s.ygt * (2.0 * Se - 2.0 * eSe * e);
  W += 2.0 * s.yht * e.cross(Se);
  const Vec3 Txe = T.cross(e);
  const Mat3 ee = e * e.transpose();
  Mat3 E = s.xg * (ee - Mat3::Identity() / 3.0) * eF +
           s.yg * (e * F.transpose() + F * e.transpose() - 2.0 * eF * ee) +
           s.yh * (e * Txe.transpose() + Txe * e.transpose());
  // m_ijkl S_kl with the projectors d0, d1, d2 of Kim & Karrila (1991) eq. 11.9, S traceless.
  const Mat3 eSeT = e * Se.transpose() + Se * e.transpose();
  E += s.xm * 1.5 * (ee - Mat3::Identity() / 3.0) * eSe;
  E += s.ym * (eSeT - 2.0 * eSe * ee);
  E += s.zm * 0.5 * (2.0 * S + Mat3::Identity() * eSe - 2.0 * eSeT + ee * eSe);
  Eigen::Map<Vec5>(y + 6) += to_vec5(E);
}

void apply_self(double a, double mu, Moments m, const double* x, double* y) {
  const PairScalars s = self_scalars(a, mu);
  const int d = dof_per_particle(m);
  for (int i = 0; i < 3; ++i) y[i] += s.xa * x[i];
  if (d > 3)
    for (int i = 3; i < 6; ++i) y[i] += s.xc * x[i];
  if (d > 6)
    for (int i = 6; i < 11; ++i) y[i] += s.xm * x[i];
}

void fill_pair_block(const PairScalars& s, const Vec3& e, Moments m, double* B, long ld) {
  const int d = dof_per_particle(m);
  auto at = [&](int r, int c) -> double& { return B[r + long(c) * ld]; };
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) at(i, j) = (s.xa - s.ya) * e[i] * e[j] + (i == j ? s.ya : 0.0);
  if (d == 3) return;
  // eps_ijk e_k: the matrix of F -> F x e.
  const double cx[3][3] = {{0.0, e[2], -e[1]}, {-e[2], 0.0, e[0]}, {e[1], -e[0], 0.0}};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      at(3 + i, j) = s.yb * cx[i][j];
      at(i, 3 + j) = s.ybt * cx[i][j];
      at(3 + i, 3 + j) = (s.xc - s.yc) * e[i] * e[j] + (i == j ? s.yc : 0.0);
    }
  if (d == 6) return;
  const auto& basis = sym_traceless_basis();
  Vec3 Pe[5];
  double c[5];
  for (int p = 0; p < 5; ++p) {
    Pe[p] = basis[std::size_t(p)] * e;
    c[p] = e.dot(Pe[p]);
  }
  for (int p = 0; p < 5; ++p) {
    const Vec3 exPe = e.cross(Pe[p]);
    for (int k = 0; k < 3; ++k) {
      const double rad = 2.0 * Pe[p][k] - 2.0 * c[p] * e[k];
      at(6 + p, k) = s.xg * c[p] * e[k] + s.yg * rad;
      at(k, 6 + p) = s.xgt * c[p] * e[k] + s.ygt * rad;
      at(6 + p, 3 + k) = 2.0 * s.yh * exPe[k];
      at(3 + k, 6 + p) = 2.0 * s.yht * exPe[k];
    }
  }
  for (int q = 0; q < 5; ++q)
    for (int p = 0; p < 5; ++p) {
      const double cc = c[p] * c[q], pq = Pe[p].dot(Pe[q]);
      at(6 + p, 6 + q) = 1.5 * s.xm * cc + s.ym * (2.0 * pq - 2.0 * cc) + s.zm * ((p == q ? 1.0 : 0.0) - 2.0 * pq + 0.5 * cc);
    }
}

MatX pair_block(const PairScalars& s, const Vec3& e, Moments m) {
  auto dl = [](int i, int j) { return i == j ? 1.0 : 0.0; };
  auto eps = [](int i, int j, int k) { return 0.5 * double((i - j) * (j - k) * (k - i)); };
  const int d = dof_per_particle(m);
  MatX B = MatX::Zero(d, d);
  double a[3][3], b[3][3], bt[3][3], c[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      a[i][j] = s.xa * e[i] * e[j] + s.ya * (dl(i, j) - e[i] * e[j]);
      c[i][j] = s.xc * e[i] * e[j] + s.yc * (dl(i, j) - e[i] * e[j]);
      b[i][j] = bt[i][j] = 0.0;
      for (int k = 0; k < 3; ++k) {
        b[i][j] += s.yb * eps(i, j, k) * e[k];    // Omega_i = b_ij F_j = yb (F x e)_i
        bt[i][j] += s.ybt * eps(i, j, k) * e[k];  // U_i = bt_ij T_j
      }
    }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      B(i, j) = a[i][j];
      if (d > 3) {
        B(3 + i, j) = b[i][j];
        B(i, 3 + j) = bt[i][j];
        B(3 + i, 3 + j) = c[i][j];
      }
    }
  if (d < 11) return B;
  // Basis tensors of the symmetric traceless space (engine/sym_traceless.hpp).
  const auto& basis = sym_traceless_basis();
  for (int p = 0; p < 5; ++p) {
    const Mat3& P = basis[p];
    for (int k = 0; k < 3; ++k) {
      double gF = 0, gtS = 0, hT = 0, htS = 0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          // g_ijk: E_ij <- F_k ; gt_ijk: U_k <- S_ij (same structure with xgt, ygt).
          const double sg = (e[i] * e[j] - dl(i, j) / 3.0) * e[k];
          const double sy = e[i] * dl(j, k) + e[j] * dl(i, k) - 2.0 * e[i] * e[j] * e[k];
          gF += P(i, j) * (s.xg * sg + s.yg * sy);
          gtS += P(i, j) * (s.xgt * sg + s.ygt * sy);
          // h_ijk: E_ij <- T_k = yh (e_i eps_jkl e_l + e_j eps_ikl e_l); ht likewise.
          double hs = 0;
          for (int l = 0; l < 3; ++l) hs += e[i] * eps(j, k, l) * e[l] + e[j] * eps(i, k, l) * e[l];
          hT += P(i, j) * s.yh * hs;
          htS += P(i, j) * s.yht * hs;
        }
      B(6 + p, k) = gF;
      B(k, 6 + p) = gtS;
      B(6 + p, 3 + k) = hT;
      B(3 + k, 6 + p) = htS;
    }
    for (int q = 0; q < 5; ++q) {
      const Mat3& Q = basis[q];
      double sum = 0;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l) {
              const double ei = e[i], ej = e[j], ek = e[k], el = e[l];
              const double d0 = 1.5 * (ei * ej - dl(i, j) / 3.0) * (ek * el - dl(k, l) / 3.0);
              const double d1 = 0.5 * (ei * dl(j, l) * ek + ej * dl(i, l) * ek + ei * dl(j, k) * el +
                                       ej * dl(i, k) * el - 4.0 * ei * ej * ek * el);
              const double d2 = 0.5 * (dl(i, k) * dl(j, l) + dl(j, k) * dl(i, l) - dl(i, j) * dl(k, l) +
                                       ei * ej * dl(k, l) + dl(i, j) * ek * el - ei * dl(j, l) * ek -
                                       ej * dl(i, l) * ek - ei * dl(j, k) * el - ej * dl(i, k) * el +
                                       ei * ej * ek * el);
              sum += P(i, j) * (s.xm * d0 + s.ym * d1 + s.zm * d2) * Q(k, l);
            }
      B(6 + p, 6 + q) = sum;
    }
  }
  return B;
}

}  // namespace stokesian::mobility
