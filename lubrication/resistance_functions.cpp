// Two-sphere resistance functions: twin-multipole series plus near-contact resummation.
//
// Mathematics implemented (details and accuracy: docs/lubrication.md).  Equation numbers:
// JO84 = Jeffrey & Onishi 1984, J92 = Jeffrey 1992, T23 = Townsend arXiv:1802.08226 v4,
// I13 = Ichiki et al. 2013 (as cited in T23).
//
// 1. Twin-multipole recurrences for lambda-independent numbers P_npq, Q_npq, V_npq:
//    X^A type: T23 eqs. 5-8 (corrected JO84 section 3); Y^A type: JO84 eqs. 4.6-4.11 with
//    T23 eq. 18; Y^C: JO84 eqs. 7.3-7.5; X^M: I13 eq. 104; Y^M: J92 eq. 58; Z^M: J92
//    eqs. 73-76.  Three families ("X", "Y", "Z" type: azimuthal mode m = 0, 1, 2); the
//    initial conditions select the problem:
//       XA: P=V=delta_1n   YA: P=V=delta_1n, Q=0   YC: Q=delta_1n, P=V=0
//       XM: P=V=delta_2n   YM: P=V=delta_2n, Q=0   ZM: P=V=delta_2n, Q=0.
// 2. Series (JO84 eq. 3.15 and its analogues; I13 eqs. 94, 105, 115, 120, 125, 131):
//       F_nat(s) = sum_k c_k t^k,   t = 2/s,   c_k = f_k(lambda) / (2 (1+lambda))^k,
//    with f_k = 2^k sum_q P_{n, k-q, q} lambda^q (times lambda^(k mod 2) for C, H, M type).
//    Self functions ("11") use one parity of k, cross functions ("12") the other.  The
//    cross functions are converted from the natural scale of sphere 1 (6 pi mu a1,
//    4 pi mu a1^2, 8 pi mu a1^3, ...) to the JO normalisation by the factor (2/(1+lambda))^m.
// 3. Near contact: c_k -> a_k = g1 + 2 g2/k - 4 g3/(k(k+2)) as k -> infinity, with g1, g2,
//    g3 the published lubrication coefficients (JO84 eqs. 3.17, 4.15-4.16, 5.6, 7.10; J92
//    eqs. 19b, 27b, 35b, 48b, 64b, 79b; T23 corrections).  We write
//       F_nat = sum_k (c_k - a_k) t^k + g1 S1(t) + g2 S2(t) - g3 S3(t),
//    where S1..S3 are the exact sums of t^k, 2t^k/k, 4t^k/(k(k+2)) over the parity (closed
//    forms below).  This is an identity for every t < 1; as t -> 1 (xi -> 0) it reduces to
//    the JO form g1/xi + g2 ln(1/xi) + A + g3 xi ln(1/xi) + ..., and the O(1) constant A is
//    the JO "series minus singular terms" limit (JO84 eqs. 3.22-3.23, 4.17-4.18; J92 eqs.
//    21, 29, 37, 50, 66, 81).  The remainder is small (k^-3 decay), so the evaluation is
//    uniform in xi; the plain series is used for s >= 3.
// 4. X^C: exact bispherical-coordinate solution for rotation about the line of centres
//    (Jeffery 1915, Proc. Lond. Math. Soc. 14, 327):
//       T_1 = 8 pi mu c^3 Omega_1 sum_{n>=0} csch^3((n+1) alpha + n beta),
//       T_2 = -8 pi mu c^3 Omega_1 sum_{n>=1} csch^3(n (alpha + beta)),
//    c = a1 sinh(alpha) = a2 sinh(beta); tails summed by Euler-Maclaurin.  Its contact limit
//    is the Hurwitz-zeta form of T23 eqs. 26-27.
// 5. Pair matrix: tensor forms of the A, B, C (JO84) and G, H, M (J92) blocks, with the M
//    basis d0 = 3/2 (dd - I/3)(dd - I/3), d1, d2 of J92 (also Kim & Karrila 1991, ch. 11),
//    projected on the orthonormal symmetric-traceless basis of engine/core/sym_traceless.hpp.

#include "lubrication/resistance_functions.hpp"

#include "engine/core/sym_traceless.hpp"

#include <cmath>
#include <algorithm>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

namespace stokesian::lubrication {
namespace {

constexpr double kLn2 = 0.69314718055994530942;

// ---------------------------------------------------------------------------------------------
// Twin-multipole recurrences.  Values T(n, p, q) for n >= 1, p, q >= 0, n + p + q <= L are
// stored at [q][n + p][n] (packed), so that the sums over s in the recurrences, which read
// T(s, m - s, c) for fixed m and c, walk contiguous memory.
enum class Kind { X, Y, Z };

class Recurrence {
 public:
  Recurrence(Kind kind, int n0, bool init_pv, bool init_q, int L)
      : L_(L), off_(static_cast<std::size_t>(L) + 2, 0) {
    std::size_t total = 0;
    for (int c = 0; c <= L; ++c) {
      off_[c] = total;
      const std::size_t mm = static_cast<std::size_t>(L - c) + 1;  // m = 0..L-c
      total += mm * (mm + 1) / 2;
    }
    P_.assign(total, 0.0);
    V_.assign(total, 0.0);
    if (kind != Kind::X) Q_.assign(total, 0.0);
    run(kind, n0, init_pv, init_q);
  }

  // T(n, p, q) with zero outside the stored range.
  double P(int n, int p, int q) const { return get(P_, n, p, q); }
  double Q(int n, int p, int q) const { return Q_.empty() ? 0.0 : get(Q_, n, p, q); }

 private:
  std::size_t idx(int n, int a, int c) const {  // element T(n, a, c)
    const std::size_t m = static_cast<std::size_t>(n + a);
    return off_[c] + m * (m + 1) / 2 + static_cast<std::size_t>(n);
  }
  double get(const std::vector<double>& T, int n, int a, int c) const {
    if (n < 1 || a < 0 || c < 0 || n + a + c > L_) return 0.0;
    return T[idx(n, a, c)];
  }
  // Pointer to T(s, m - s, c) for s = 0..m (s = 0 slot unused), or nullptr if empty.
  const double* row(const std::vector<double>& T, int m, int c) const {
    if (m < 0 || c < 0 || m + c > L_) return nullptr;
    return &T[off_[c] + static_cast<std::size_t>(m) * (m + 1) / 2];
  }

  void run(Kind kind, int n0, bool init_pv, bool init_q) {
    const int L = L_;
    const int smin = (kind == Kind::Z) ? 2 : 1;
    // binom[a][b] = C(a, b) for a <= 2L + 2.
    const int B = 2 * L + 3;
    std::vector<double> binom(static_cast<std::size_t>(B) * B, 0.0);
    auto C = [&](int a, int b) -> double& { return binom[static_cast<std::size_t>(a) * B + b]; };
    for (int a = 0; a < B; ++a) {
      C(a, 0) = 1.0;
      for (int b = 1; b <= a; ++b) C(a, b) = C(a - 1, b - 1) + (b < a ? C(a - 1, b) : 0.0);
    }
    std::vector<double> w1(L + 2), w2(L + 2), w3(L + 2), w4(L + 2), wq1(L + 2), wq2(L + 2),
        wv(L + 2);
    for (int lev = 1; lev <= L; ++lev) {
      for (int n = smin; n <= lev; ++n) {
        const double nn = n;
        // s-dependent weights (binomial included) for this n.
        for (int s = smin; s <= lev; ++s) {
          const double ss = s;
          if (kind == Kind::X) {
            const double b = C(n + s, n);
            w1[s] = b * nn * (2 * nn + 1) * (2 * nn * ss - nn - ss + 2) /
                    (2 * (nn + 1) * (2 * ss - 1) * (nn + ss));
            w2[s] = -b * nn * (2 * nn - 1) / (2 * (nn + 1));
            w3[s] = -b * nn * (4 * nn * nn - 1) / (2 * (nn + 1) * (2 * ss + 1));
            wv[s] = b;
          } else if (kind == Kind::Y) {
            const double b = C(n + s, n + 1);
            w1[s] = b * (2 * nn + 1) / (2 * (nn + 1)) *
                    (3 * (nn + ss) - (nn * ss + 1) * (2 * nn * ss - ss - nn + 2)) /
                    (ss * (nn + ss) * (2 * ss - 1));
            w2[s] = b * nn * (2 * nn - 1) / (2 * (nn + 1));
            w3[s] = b * nn * (4 * nn * nn - 1) / (2 * (nn + 1) * (2 * ss + 1));
            w4[s] = -b * 2 * (4 * nn * nn - 1) / (3 * (nn + 1));
            wq1[s] = b * ss / (nn + 1);
            wq2[s] = -b * 3 / (2 * nn * ss * (nn + 1));
            wv[s] = b;
          } else {
            const double b = C(n + s, n + 2);
            w1[s] = b * (2 * nn + 1) / (nn + 1) *
                    (nn * ss * (nn + ss - 2 * nn * ss - 2) - 4 * (2 * nn * ss - 4 * ss - 4 * nn + 2)) /
                    (2 * ss * (nn + ss) * (2 * ss - 1));
            w2[s] = b * nn * (2 * nn - 1) / (2 * (nn + 1));
            w3[s] = b * nn * (2 * nn + 1) * (2 * nn - 1) / (2 * (nn + 1) * (2 * ss + 1));
            w4[s] = -b * 2 * (2 * nn + 1) * (2 * nn - 1) / (nn + 1);
            wq1[s] = b * ss / (nn + 1);
            wq2[s] = -b * 2 / (nn * ss * (nn + 1));
            wv[s] = b;
          }
        }
        for (int p = 0; p <= lev - n; ++p) {
          const int q = lev - n - p;
          const std::size_t i = idx(n, p, q);
          if (p == 0 && q == 0) {
            if (n == n0) {
              if (init_pv) P_[i] = V_[i] = 1.0;
              if (init_q) Q_[i] = 1.0;
            }
            continue;
          }
          if (p < n - 1) continue;  // every term needs p - n + 1 >= 0
          // Sums over s = smin..q of weight(s) * T(s, q - s [- 1, - 2], c).
          auto dot = [&](const std::vector<double>& T, const std::vector<double>& w, int m,
                         int c, int smax) {
            const double* rp = row(T, m, c);
            if (!rp) return 0.0;
            double acc = 0.0;
            const int top = std::min(smax, m);
            for (int s = smin; s <= top; ++s) acc += w[s] * rp[s];
            return acc;
          };
          const int c1 = p - n + 1, c2 = p - n - 1, c0 = p - n;
          double sP = dot(P_, w1, q, c1, q) + dot(P_, w2, q, c2, q) + dot(V_, w3, q - 2, c1, q);
          double sV = dot(P_, wv, q, c2, q);
          if (kind == Kind::X) {
            P_[i] = sP;
            V_[i] = sP - 2 * nn / ((nn + 1) * (2 * nn + 3)) * sV;
          } else {
            sP += dot(Q_, w4, q - 1, c1, q);
            const double sQ = dot(Q_, wq1, q - 1, c0, q) + dot(P_, wq2, q, c0, q);
            P_[i] = sP;
            Q_[i] = sQ;
            V_[i] = sP + 2 * nn / ((nn + 1) * (2 * nn + 3)) * sV;
          }
        }
      }
    }
  }

  int L_;
  std::vector<std::size_t> off_;
  std::vector<double> P_, Q_, V_;
};

// Lambda-weighted form of the same recurrences (used by ResistanceSeries).  With
// x = lambda/(1+lambda), y = 1/(1+lambda) define for each array T in {P, Q, V}
//    Aw[T](n, k) = sum_{p+q=k} x^q y^p T(n, p, q),    Bw[T](n, k) = sum_{p+q=k} x^p y^q T(n, p, q).
// A term T(s, q-s-i, p-n+j) of the recurrence for (n, p, q) contributes to Aw(n, k)
//    x^(s+i) y^(n-j) Bw[T](s, k-s-n-i+j)
// (and symmetrically to Bw with x <-> y, Aw <-> Bw): the two spheres alternate.  The series
// coefficients are c_k ~ Aw[P](1 or 2, k) and Aw[Q](1, k).  The combined weights binomial *
// x^(s+i) y^(n-j) are <= 1 + lambda (terms of (x+y)^m up to one factor 1/y), so they are
// formed in log space and nothing overflows even at order 1000; the cost is O(K^3) per lambda instead of O(K^4).
class WeightedRecurrence {
  // A row of weights w[s], stored only on [lo, lo + w.size()).
  struct Row {
    int lo = 0;
    std::vector<double> w;
    void assign(const std::vector<double>& full) {
      int a = 0, b = static_cast<int>(full.size()) - 1;
      while (a <= b && full[a] == 0.0) ++a;
      while (b >= a && full[b] == 0.0) --b;
      lo = a;
      w.assign(full.begin() + a, full.begin() + b + 1);
    }
    // sum_{s = max(smin, lo)}^{min(smax, hi)} w[s] v[s]
    double dot(const std::vector<double>& v, int smin, int smax) const {
      const int a = std::max(smin, lo);
      const int b = std::min(smax, lo + static_cast<int>(w.size()) - 1);
      double acc = 0.0;
      for (int s = a; s <= b; ++s) acc += w[s - lo] * v[s];
      return acc;
    }
  };

 public:
  WeightedRecurrence(Kind kind, int n0, bool init_pv, bool init_q, int L, double x, double y)
      : L_(L) {
    const bool has_q = kind != Kind::X;
    for (auto* a : {&AP_, &BP_, &AV_, &BV_}) alloc(*a);
    if (has_q) {
      alloc(AQ_);
      alloc(BQ_);
    }
    const int smin = kind == Kind::Z ? 2 : 1;
    const int bshift = kind == Kind::X ? 0 : (kind == Kind::Y ? 1 : 2);  // C(n+s, n+bshift)
    std::vector<double> lf(2 * L + 3, 0.0);
    for (std::size_t m = 1; m < lf.size(); ++m) lf[m] = lf[m - 1] + std::log(double(m));
    const double lx = std::log(x), ly = std::log(y);

    // A term: rational weight r(n, s), source array, shifts i, j.
    struct Term {
      int src;  // 0: P, 1: Q, 2: V
      int i, j;
      int dst;  // 0: P, 1: Q, 2: V-correction
    };
    // X type: P <- P(s,q-s,p-n+1), P(s,q-s,p-n-1), V(s,q-s-2,p-n+1); V <- P(s,q-s,p-n-1).
    static const Term kTermsX[] = {{0, 0, 1, 0}, {0, 0, -1, 0}, {2, 2, 1, 0}, {0, 0, -1, 2}};
    // Y, Z type: the same plus Q(s,q-s-1,p-n+1) in P; Q <- Q(s,q-s-1,p-n), P(s,q-s,p-n).
    static const Term kTermsY[] = {{0, 0, 1, 0}, {0, 0, -1, 0}, {2, 2, 1, 0}, {1, 1, 1, 0},
                                   {1, 1, 0, 1}, {0, 0, 0, 1}, {0, 0, -1, 2}};
    const Term* terms = kind == Kind::X ? kTermsX : kTermsY;
    const int nt = kind == Kind::X ? 4 : 7;
    auto rational = [kind](int t, int n, int s) -> double {
      const double nn = n, ss = s;
      if (kind == Kind::X) {
        switch (t) {
          case 0: return nn * (2 * nn + 1) * (2 * nn * ss - nn - ss + 2) / (2 * (nn + 1) * (2 * ss - 1) * (nn + ss));
          case 1: return -nn * (2 * nn - 1) / (2 * (nn + 1));
          case 2: return -nn * (4 * nn * nn - 1) / (2 * (nn + 1) * (2 * ss + 1));
          default: return -2 * nn / ((nn + 1) * (2 * nn + 3));
        }
      }
      if (kind == Kind::Y) {
        switch (t) {
          case 0: return (2 * nn + 1) / (2 * (nn + 1)) * (3 * (nn + ss) - (nn * ss + 1) * (2 * nn * ss - ss - nn + 2)) / (ss * (nn + ss) * (2 * ss - 1));
          case 1: return nn * (2 * nn - 1) / (2 * (nn + 1));
          case 2: return nn * (4 * nn * nn - 1) / (2 * (nn + 1) * (2 * ss + 1));
          case 3: return -2 * (4 * nn * nn - 1) / (3 * (nn + 1));
          case 4: return ss / (nn + 1);
          case 5: return -3 / (2 * nn * ss * (nn + 1));
          default: return 2 * nn / ((nn + 1) * (2 * nn + 3));
        }
      }
      switch (t) {
        case 0: return (2 * nn + 1) / (nn + 1) * (nn * ss * (nn + ss - 2 * nn * ss - 2) - 4 * (2 * nn * ss - 4 * ss - 4 * nn + 2)) / (2 * ss * (nn + ss) * (2 * ss - 1));
        case 1: return nn * (2 * nn - 1) / (2 * (nn + 1));
        case 2: return nn * (2 * nn + 1) * (2 * nn - 1) / (2 * (nn + 1) * (2 * ss + 1));
        case 3: return -2 * (2 * nn + 1) * (2 * nn - 1) / (nn + 1);
        case 4: return ss / (nn + 1);
        case 5: return -2 / (nn * ss * (nn + 1));
        default: return 2 * nn / ((nn + 1) * (2 * nn + 3));
      }
    };
    // Weight rows wa[t][n] (for Aw) and wb[t][n] (for Bw) over s <= L - n + 1, trimmed to the
    // range where |w| >= 1e-30: all weighted arrays are bounded by 1 in magnitude (checked
    // numerically for 0.01 <= lambda <= 100), so dropped terms are below rounding.  For
    // unequal spheres the binomial weights are concentrated (n ~ s/lambda or s ~ n/lambda),
    // which makes high orders cheap there.
    const int nt_rows = L + 1;
    std::vector<std::vector<Row>> wa(nt, std::vector<Row>(nt_rows)), wb(nt, std::vector<Row>(nt_rows));
    std::vector<double> bufa, bufb;
    for (int t = 0; t < nt; ++t) {
      for (int n = smin; n <= L; ++n) {
        const int smax = L - n + 1;
        bufa.assign(smax + 1, 0.0);
        bufb.assign(smax + 1, 0.0);
        for (int s = smin; s <= smax; ++s) {
          const double r = rational(t, n, s);
          if (r == 0.0) continue;
          const double lc = lf[n + s] - lf[n + bshift] - lf[s - bshift];
          const int i = terms[t].i, j = terms[t].j;
          const double sg = r < 0 ? -1.0 : 1.0, lr = std::log(std::abs(r));
          const double ea = lr + lc + (s + i) * lx + (n - j) * ly;
          const double eb = lr + lc + (s + i) * ly + (n - j) * lx;
          bufa[s] = ea > -69.0 ? sg * std::exp(ea) : 0.0;  // e^-69 = 1e-30
          bufb[s] = eb > -69.0 ? sg * std::exp(eb) : 0.0;
        }
        wa[t][n].assign(bufa);
        wb[t][n].assign(bufb);
      }
    }
    for (int lev = 0; lev <= L; ++lev) {
      for (int n = smin; n <= lev; ++n) {
        const int k = lev - n;
        if (k == 0) {
          if (n == n0) {
            if (init_pv) AP_[lev][n] = BP_[lev][n] = AV_[lev][n] = BV_[lev][n] = 1.0;
            if (init_q) AQ_[lev][n] = BQ_[lev][n] = 1.0;
          }
          continue;
        }
        double acc[3][2] = {{0, 0}, {0, 0}, {0, 0}};  // [P, Q, Vcorr][A, B]
        for (int t = 0; t < nt; ++t) {
          const Term& tm = terms[t];
          const int lin = k - n - tm.i + tm.j;  // level of the source entries
          if (lin < smin) continue;
          const auto& srcB = tm.src == 0 ? BP_ : (tm.src == 1 ? BQ_ : BV_);
          const auto& srcA = tm.src == 0 ? AP_ : (tm.src == 1 ? AQ_ : AV_);
          acc[tm.dst][0] += wa[t][n].dot(srcB[lin], smin, lin);
          acc[tm.dst][1] += wb[t][n].dot(srcA[lin], smin, lin);
        }
        AP_[lev][n] = acc[0][0];
        BP_[lev][n] = acc[0][1];
        if (has_q) {
          AQ_[lev][n] = acc[1][0];
          BQ_[lev][n] = acc[1][1];
        }
        AV_[lev][n] = acc[0][0] + acc[2][0];
        BV_[lev][n] = acc[0][1] + acc[2][1];
      }
    }
  }
  double AP(int n, int k) const { return n + k <= L_ ? AP_[n + k][n] : 0.0; }
  double AQ(int n, int k) const { return (!AQ_.empty() && n + k <= L_) ? AQ_[n + k][n] : 0.0; }

 private:
  void alloc(std::vector<std::vector<double>>& a) {
    a.resize(L_ + 1);
    for (int lev = 0; lev <= L_; ++lev) a[lev].assign(lev + 1, 0.0);
  }
  int L_;
  std::vector<std::vector<double>> AP_, BP_, AQ_, BQ_, AV_, BV_;
};

// Identifiers of the coefficient arrays: (P or Q)_{n, k-q, q} of a problem.
struct Coefficients {
  enum Id { XA_P1, YA_P1, YA_Q1, YC_Q1, XA_P2, YA_P2, YC_P2, XM_P2, YM_P2, ZM_P2, kCount };
};

// Sums sum_q T_{n,k-q,q} x^q y^(k-q), k = 0..K, for every coefficient array, from the
// lambda-weighted recurrences.
using LambdaSums = std::array<std::vector<double>, Coefficients::kCount>;
LambdaSums compute_lambda_sums(double lambda, int K) {
  const double x = lambda / (1.0 + lambda), y = 1.0 / (1.0 + lambda);
  const int L = K + 2;
  std::array<std::vector<double>, Coefficients::kCount> out;
  for (auto& v : out) v.assign(K + 1, 0.0);
  auto take = [&](const WeightedRecurrence& w, Coefficients::Id id, int n, bool q) {
    for (int k = 0; k <= K; ++k) out[id][k] = q ? w.AQ(n, k) : w.AP(n, k);
  };
#pragma omp parallel sections
  {
#pragma omp section
    {
      const WeightedRecurrence xa(Kind::X, 1, true, false, L, x, y);
      take(xa, Coefficients::XA_P1, 1, false);
      take(xa, Coefficients::XA_P2, 2, false);
    }
#pragma omp section
    {
      const WeightedRecurrence ya(Kind::Y, 1, true, false, L, x, y);
      take(ya, Coefficients::YA_P1, 1, false);
      take(ya, Coefficients::YA_Q1, 1, true);
      take(ya, Coefficients::YA_P2, 2, false);
    }
#pragma omp section
    {
      const WeightedRecurrence yc(Kind::Y, 1, false, true, L, x, y);
      take(yc, Coefficients::YC_Q1, 1, true);
      take(yc, Coefficients::YC_P2, 2, false);
    }
#pragma omp section
    {
      const WeightedRecurrence xm(Kind::X, 2, true, false, L, x, y);
      take(xm, Coefficients::XM_P2, 2, false);
    }
#pragma omp section
    {
      const WeightedRecurrence ym(Kind::Y, 2, true, false, L, x, y);
      take(ym, Coefficients::YM_P2, 2, false);
    }
#pragma omp section
    {
      const WeightedRecurrence zm(Kind::Z, 2, true, false, L, x, y);
      take(zm, Coefficients::ZM_P2, 2, false);
    }
  }
  return out;
}

// Process-wide cache of the sums (a few lambdas are typically used over and over).
std::shared_ptr<const LambdaSums> lambda_sums(double lambda, int K) {
  static std::mutex mutex;
  static std::map<std::pair<double, int>, std::shared_ptr<const LambdaSums>> cache;
  const auto key = std::make_pair(lambda, K);
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
  }
  auto sums = std::make_shared<const LambdaSums>(compute_lambda_sums(lambda, K));
  std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() >= 64) cache.erase(cache.begin());
  cache.emplace(key, sums);
  return sums;
}

// ---------------------------------------------------------------------------------------------
// Sums over k >= 1 of the given parity of t^k, 2 t^k / k and 4 t^k / (k (k+2)).
// one_minus_t2 = 1 - t^2 = xi (4 + xi) / s^2 and xi are passed to avoid cancellation.
struct SingularSums {
  double S1, S2, S3;
};

SingularSums singular_sums(int parity, double t, double one_minus_t2, double xi) {
  SingularSums r{};
  if (t < 0.5) {  // direct power series (closed forms cancel for small t)
    double tk = parity ? t : t * t;
    for (int k = parity ? 1 : 2; k < 200; k += 2) {
      r.S1 += tk;
      r.S2 += 2.0 * tk / k;
      r.S3 += 4.0 * tk / (k * (k + 2.0));
      tk *= t * t;
      if (tk < 1e-18) break;
    }
    return r;
  }
  const double t2 = t * t;
  if (parity == 0) {
    const double L = -std::log(one_minus_t2);  // sum 2 t^k / k (k even)
    r.S1 = t2 / one_minus_t2;
    r.S2 = L;
    r.S3 = 1.0 - one_minus_t2 * L / t2;
  } else {
    // 2 atanh(t) = ln((1+t)/(1-t)) = ln((4+xi)/xi) = sum 2 t^k / k (k odd)
    const double L = std::log1p(4.0 / xi);
    r.S1 = t / one_minus_t2;
    r.S2 = L;
    r.S3 = 2.0 / t - one_minus_t2 * L / t2;
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// X^C from the exact bispherical solution.  csch^3 and the sum over n >= 0 of csch^3(y0 + n x).
double csch3(double y) {
  if (y > 20.0) {
    const double e = std::exp(-y);
    const double c = 2.0 * e / (1.0 - e * e);
    return c * c * c;
  }
  const double c = 1.0 / std::sinh(y);
  return c * c * c;
}

double sum_csch3(double y0, double x) {
  double sum = 0.0;
  const int N = 40;
  for (int n = 0;; ++n) {
    const double y = y0 + n * x;
    if (n >= N && y < 2.0) {
      // Euler-Maclaurin tail: int_n^inf F + F(n)/2 - F'(n)/12 + F'''(n)/720, F(n) = csch^3(y0+nx).
      // The F''' term is below 1e-11 relative for n >= 40 and is dropped.
      const double cs = 1.0 / std::sinh(y), ct = 1.0 / std::tanh(y);
      const double integral = (0.5 * cs * ct + 0.5 * std::log(std::tanh(0.5 * y))) / x;
      const double F = cs * cs * cs;
      const double dF = -3.0 * x * F * ct;
      sum += integral + 0.5 * F - dF / 12.0;
      break;
    }
    const double term = csch3(y);
    sum += term;
    if (term < 1e-18 * sum) break;
  }
  return sum;
}

double acosh1p(double x) { return std::log1p(x + std::sqrt(x * (x + 2.0))); }

// Near-contact coefficient functions (JO84, J92, as corrected by Townsend 2023).
struct G3 {
  double g1, g2, g3;
};

}  // namespace

namespace detail {
std::vector<double> series_sums(double lambda, int order, int id, bool reference) {
  if (id < 0 || id >= Coefficients::kCount) throw std::out_of_range("series_sums");
  if (!reference) return compute_lambda_sums(lambda, order)[id];
  // Lambda-independent O(K^4) recurrences, evaluated afresh at this order.
  const Kind kinds[] = {Kind::X, Kind::Y, Kind::Y, Kind::Y, Kind::X,
                        Kind::Y, Kind::Y, Kind::X, Kind::Y, Kind::Z};
  const int n0s[] = {1, 1, 1, 1, 1, 1, 1, 2, 2, 2};
  const bool pvs[] = {true, true, true, false, true, true, false, true, true, true};
  const int ns[] = {1, 1, 1, 1, 2, 2, 2, 2, 2, 2};
  const bool qs[] = {false, false, true, true, false, false, false, false, false, false};
  const Recurrence rec(kinds[id], n0s[id], pvs[id], !pvs[id], order + 2);
  const double x = lambda / (1.0 + lambda), y = 1.0 / (1.0 + lambda);
  std::vector<double> out(order + 1, 0.0);
  for (int k = 0; k <= order; ++k)
    for (int q = 0; q <= k; ++q)
      out[k] += (qs[id] ? rec.Q(ns[id], k - q, q) : rec.P(ns[id], k - q, q)) * std::pow(x, q) *
                std::pow(y, k - q);
  return out;
}
}  // namespace detail

double hurwitz_zeta3(double a) {
  // sum_{n>=0} (n+a)^-3: direct terms, then Euler-Maclaurin tail from n = N.
  double sum = 0.0;
  const int N = 20;
  for (int n = 0; n < N; ++n) sum += 1.0 / std::pow(n + a, 3);
  const double y = N + a;
  sum += 0.5 / (y * y) + 0.5 / (y * y * y) + 0.25 / std::pow(y, 4) - 1.0 / (12.0 * std::pow(y, 6)) +
         1.0 / (12.0 * std::pow(y, 8));
  return sum;
}

double NearContactForm::operator()(double xi) const {
  const double l = std::log(1.0 / xi);
  return g1 / xi + g2 * l + constant + g3 * xi * l;
}

// ---------------------------------------------------------------------------------------------
namespace {
const char* const kNames[kNumScalars] = {"XA11", "XA12", "YA11", "YA12", "YB11", "YB12",
                                         "XC11", "XC12", "YC11", "YC12", "XG11", "XG12",
                                         "YG11", "YG12", "YH11", "YH12", "XM11", "XM12",
                                         "YM11", "YM12", "ZM11", "ZM12"};
enum Slot {
  XA11, XA12, YA11, YA12, YB11, YB12, XC11, XC12, YC11, YC12, XG11, XG12,
  YG11, YG12, YH11, YH12, XM11, XM12, YM11, YM12, ZM11, ZM12
};
}  // namespace

namespace {
using Member = double ResistanceScalars::*;
constexpr Member kMembers[kNumScalars] = {
    &ResistanceScalars::XA11, &ResistanceScalars::XA12, &ResistanceScalars::YA11,
    &ResistanceScalars::YA12, &ResistanceScalars::YB11, &ResistanceScalars::YB12,
    &ResistanceScalars::XC11, &ResistanceScalars::XC12, &ResistanceScalars::YC11,
    &ResistanceScalars::YC12, &ResistanceScalars::XG11, &ResistanceScalars::XG12,
    &ResistanceScalars::YG11, &ResistanceScalars::YG12, &ResistanceScalars::YH11,
    &ResistanceScalars::YH12, &ResistanceScalars::XM11, &ResistanceScalars::XM12,
    &ResistanceScalars::YM11, &ResistanceScalars::YM12, &ResistanceScalars::ZM11,
    &ResistanceScalars::ZM12};
}  // namespace

double& scalar_at(ResistanceScalars& r, int i) {
  if (i < 0 || i >= kNumScalars) throw std::out_of_range("scalar_at");
  return r.*kMembers[i];
}
double scalar_at(const ResistanceScalars& r, int i) {
  if (i < 0 || i >= kNumScalars) throw std::out_of_range("scalar_at");
  return r.*kMembers[i];
}
const char* scalar_name(int i) { return kNames[i]; }

ResistanceScalars relabel_spheres(const ResistanceScalars& r) {
  ResistanceScalars o = r;
  o.YB11 = -r.YB11;
  o.YB12 = -r.YB12;
  o.XG11 = -r.XG11;
  o.XG12 = -r.XG12;
  o.YG11 = -r.YG11;
  o.YG12 = -r.YG12;
  return o;
}

int ResistanceSeries::default_order(double lambda) {
  const double ratio = std::max(lambda, 1.0 / lambda);
  if (ratio <= 4.0) return 200;
  if (ratio <= 16.0) return 400;
  return 800;
}

ResistanceSeries::ResistanceSeries(double lambda, int order)
    : lambda_(lambda), order_(order > 0 ? order : default_order(lambda)) {
  if (!(lambda > 0.0) || !std::isfinite(lambda))
    throw std::invalid_argument("ResistanceSeries: lambda must be positive");
  if (order_ < 20 || order_ > 1200) throw std::invalid_argument("ResistanceSeries: order must be in [20, 1200]");
  const std::shared_ptr<const LambdaSums> sums_ptr = lambda_sums(lambda, order_);
  const LambdaSums& sums = *sums_ptr;
  const double l = lambda, l2 = l * l, l3 = l2 * l, l4 = l3 * l, l5 = l4 * l;
  const double p1 = 1.0 + l, p2 = p1 * p1, p3 = p2 * p1;
  const int K = order_;

  // Lubrication coefficients of the natural-scale sums (JO84, J92, Townsend 2023).
  const G3 xa{2 * l2 / p3, l * (1 + 7 * l + l2) / (5 * p3),
              (1 + 18 * l - 29 * l2 + 18 * l3 + l4) / (42 * p3)};
  const G3 ya{0, 4 * l * (2 + l + 2 * l2) / (15 * p3),
              2 * (16 - 45 * l + 58 * l2 - 45 * l3 + 16 * l4) / (375 * p3)};
  const G3 yb{0, -l * (4 + l) / (5 * p2), -(32 - 33 * l + 83 * l2 + 43 * l3) / (250 * p2)};
  const G3 yc11{0, 2 * l / (5 * p1), (8 + 6 * l + 33 * l2) / (125 * p1)};
  const G3 yc12{0, l2 / (10 * p1), l * (43 - 24 * l + 43 * l2) / (500 * p1)};
  const G3 xg{3 * l2 / p3, 3 * (l + 12 * l2 - 4 * l3) / (10 * p3),
              (5 + 181 * l - 453 * l2 + 566 * l3 - 65 * l4) / (140 * p3)};
  const G3 yg{0, (4 * l - l2 + 7 * l3) / (10 * p3),
              (32 - 179 * l + 532 * l2 - 356 * l3 + 221 * l4) / (500 * p3)};
  const G3 yh11{0, (2 * l - l2) / (10 * p2), (16 - 61 * l + 180 * l2 + 2 * l3) / (500 * p2)};
  const G3 yh12{0, (l2 + 7 * l3) / (20 * p2), (43 * l + 147 * l2 - 185 * l3 + 221 * l4) / (1000 * p2)};
  const G3 xm11{6 * l2 / (5 * p3), 3 * (l + 17 * l2 - 9 * l3) / (25 * p3),
                (5 + 272 * l - 831 * l2 + 1322 * l3 - 415 * l4) / (350 * p3)};
  const G3 xm12{6 * l3 / (5 * p3), 3 * (-4 * l2 + 17 * l3 - 4 * l4) / (25 * p3),
                (-65 * l + 832 * l2 - 1041 * l3 + 832 * l4 - 65 * l5) / (350 * p3)};
  const G3 ym11{0, 6 * (l - l2 + 4 * l3) / (25 * p3),
                (24 - 201 * l + 882 * l2 - 1182 * l3 + 591 * l4) / (625 * p3)};
  const G3 ym12{0, 3 * (7 * l2 - 10 * l3 + 7 * l4) / (50 * p3),
                3 * l * (221 - 728 * l + 1902 * l2 - 728 * l3 + 221 * l4) / (2500 * p3)};
  const G3 zm{0, 0, -3 * (l2 + l4) / (10 * p3)};

  struct Spec {
    Coefficients::Id arr;
    double pref;        // multiplies the sum over q
    bool lam_parity;    // extra lambda^(k mod 2)
    int parity11;       // parity of the self series; the cross series has the other one
    G3 g11, g12;
    double sigma12;     // sign of the natural cross function
    int m;              // cross normalisation (2/(1+lambda))^m
    int slot11;
  };
  const Spec specs[] = {
      {Coefficients::XA_P1, 1.0, false, 0, xa, xa, -1.0, 1, XA11},
      {Coefficients::YA_P1, 1.0, false, 0, ya, ya, -1.0, 1, YA11},
      {Coefficients::YA_Q1, 2.0, false, 1, yb, yb, -1.0, 2, YB11},
      {Coefficients::YC_Q1, 1.0, true, 0, yc11, yc12, 1.0, 3, YC11},
      {Coefficients::XA_P2, 0.75, false, 1, xg, xg, -1.0, 2, XG11},
      {Coefficients::YA_P2, 0.75, false, 1, yg, yg, -1.0, 2, YG11},
      {Coefficients::YC_P2, -0.375, true, 0, yh11, yh12, 1.0, 3, YH11},
      {Coefficients::XM_P2, 1.0, true, 0, xm11, xm12, 1.0, 3, XM11},
      {Coefficients::YM_P2, 1.0, true, 0, ym11, ym12, 1.0, 3, YM11},
      {Coefficients::ZM_P2, 1.0, true, 0, zm, zm, -1.0, 3, ZM11},
  };

  const double x = l / p1;  // lambda/(1+lambda)

  for (const Spec& sp : specs) {
    // sums[id][k] = sum_q T_{n,k-q,q} lambda^q / (1+lambda)^k
    std::vector<double> c(K + 1, 0.0);
    for (int k = 0; k <= K; ++k)
      c[k] = sp.pref * sums[sp.arr][k] * ((sp.lam_parity && (k % 2)) ? l : 1.0);
    for (int which = 0; which < 2; ++which) {
      Function& f = fn_[sp.slot11 + which];
      f.parity = which == 0 ? sp.parity11 : 1 - sp.parity11;
      const G3 g = which == 0 ? sp.g11 : sp.g12;
      f.g1 = g.g1;
      f.g2 = g.g2;
      f.g3 = g.g3;
      f.factor = which == 0 ? 1.0 : sp.sigma12 * std::pow(2.0 / p1, sp.m);
      f.c.assign(K + 1, 0.0);
      f.r.assign(K + 1, 0.0);
      for (int k = 0; k <= K; ++k) {
        if (k % 2 != f.parity) continue;
        f.c[k] = c[k];
        f.r[k] = k == 0 ? c[k] : c[k] - (f.g1 + 2.0 * f.g2 / k - 4.0 * f.g3 / (k * (k + 2.0)));
      }
      // Near-contact constant: limit t -> 1 of the resummed form minus the singular terms.
      double rsum = 0.0;
      for (int k = K; k >= 0; --k) rsum += f.r[k];
      NearContactForm& nc = near_[sp.slot11 + which];
      const double A = f.parity == 0 ? rsum - f.g1 / 4.0 - f.g3
                                     : rsum + f.g1 / 4.0 + 2.0 * f.g2 * kLn2 - 2.0 * f.g3;
      nc.g1 = f.factor * f.g1;
      nc.g2 = f.factor * f.g2;
      nc.g3 = f.factor * f.g3;
      nc.constant = f.factor * A;
    }
  }

  // X^C near contact: exact contact values (Hurwitz zeta) and the xi ln(1/xi) slope.
  {
    const double z = hurwitz_zeta3(x);
    const double zeta3 = 1.2020569031595942854;
    NearContactForm& n11 = near_[XC11];
    n11.constant = x * x * x * z;
    n11.g3 = -l2 / (4 * p1);
    NearContactForm& n12 = near_[XC12];
    const double f12 = std::pow(2.0 / p1, 3);
    n12.constant = -f12 * x * x * x * zeta3;
    n12.g3 = f12 * l2 / (4 * p1);
  }
}

double ResistanceSeries::series_value(const Function& f, double xi, bool resum) const {
  const double s = 2.0 + xi;
  const double t = 2.0 / s;
  const int K = order_;
  // Horner in t^2 over the entries of the right parity.
  const double t2 = t * t;
  const std::vector<double>& a = resum ? f.r : f.c;
  double acc = 0.0;
  int top = K;
  if (top % 2 != f.parity) --top;
  for (int k = top; k >= 0; k -= 2) acc = acc * t2 + a[k];
  if (f.parity == 1) acc *= t;
  if (resum) {
    const double omt2 = xi * (4.0 + xi) / (s * s);
    const SingularSums S = singular_sums(f.parity, t, omt2, xi);
    acc += f.g1 * S.S1 + f.g2 * S.S2 - f.g3 * S.S3;
  }
  return f.factor * acc;
}

void ResistanceSeries::xc_values(double xi, double& xc11, double& xc12) const {
  const double a1 = 1.0, a2 = lambda_;
  const double r = (2.0 + xi) * (a1 + a2) / 2.0;
  const double h = xi * (a1 + a2) / 2.0;  // r - a1 - a2
  const double alpha = acosh1p(h * (r - a1 + a2) / (2.0 * r * a1));
  const double beta = acosh1p(h * (r + a1 - a2) / (2.0 * r * a2));
  const double sa = std::sinh(alpha);
  const double c = a1 * sa;
  xc11 = sa * sa * sa * sum_csch3(alpha, alpha + beta);
  xc12 = -8.0 * c * c * c * sum_csch3(alpha + beta, alpha + beta) / std::pow(a1 + a2, 3);
}

ResistanceScalars ResistanceSeries::at_gap(double xi) const {
  if (!(xi > 0.0)) throw std::invalid_argument("resistance functions need xi = s - 2 > 0");
  const bool resum = (2.0 + xi) < kSwitchS;
  ResistanceScalars out{};
  for (int i = 0; i < kNumScalars; ++i) {
    if (i == XC11 || i == XC12) continue;
    scalar_at(out, i) = series_value(fn_[i], xi, resum);
  }
  xc_values(xi, out.XC11, out.XC12);
  return out;
}

ResistanceScalars ResistanceSeries::far_field_series(double s) const {
  ResistanceScalars out{};
  for (int i = 0; i < kNumScalars; ++i) {
    if (i == XC11 || i == XC12) continue;
    scalar_at(out, i) = series_value(fn_[i], s - 2.0, false);
  }
  xc_values(s - 2.0, out.XC11, out.XC12);
  return out;
}

ResistanceScalars ResistanceSeries::near_contact_at_gap(double xi) const {
  ResistanceScalars out{};
  for (int i = 0; i < kNumScalars; ++i) scalar_at(out, i) = near_[i](xi);
  return out;
}

// ---------------------------------------------------------------------------------------------
namespace {

double levi(int i, int j, int k) { return 0.5 * (i - j) * (j - k) * (k - i); }

// Scalars of the ordered pair (a, b) with a, b in {0, 1}.
struct PairScalars {
  double XA, YA, YB, XC, YC, XG, YG, YH, XM, YM, ZM;
};
PairScalars pick(const ResistanceScalars& r, bool cross) {
  if (!cross)
    return {r.XA11, r.YA11, r.YB11, r.XC11, r.YC11, r.XG11, r.YG11, r.YH11, r.XM11, r.YM11, r.ZM11};
  return {r.XA12, r.YA12, r.YB12, r.XC12, r.YC12, r.XG12, r.YG12, r.YH12, r.XM12, r.YM12, r.ZM12};
}

}  // namespace

PairMatrix two_sphere_resistance_reference(const Eigen::Vector3d& r_vec, double a1, double a2, double mu,
                                           const ResistanceScalars& s11_12, const ResistanceScalars& s22_21) {
  const double r = r_vec.norm();
  const Eigen::Vector3d d = r_vec / r;
  const double pi = kPi;
  const double rad[2] = {a1, a2};
  auto dl = [](int i, int j) { return i == j ? 1.0 : 0.0; };
  // Basis of symmetric traceless tensors.
  const auto& basis = sym_traceless_basis();

  // Tensors of the ordered pair (a, b) acting as in the class comment.
  struct Blocks {
    Mat3 A, B, C;
    double G[3][3][3], H[3][3][3], M[3][3][3][3];
  };
  auto blocks = [&](int a, int b) {
    const PairScalars p = a == 0 ? pick(s11_12, b == 1) : pick(s22_21, b == 0);
    const double L = rad[a] + rad[b];
    const double nA = 3 * pi * mu * L, nB = pi * mu * L * L, nC = pi * mu * L * L * L;
    const double nG = nB, nH = nC, nM = 5.0 / 6.0 * pi * mu * L * L * L;
    Blocks k{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const double dd = d[i] * d[j];
        k.A(i, j) = nA * (p.XA * dd + p.YA * (dl(i, j) - dd));
        k.C(i, j) = nC * (p.XC * dd + p.YC * (dl(i, j) - dd));
        double e = 0.0;
        for (int l = 0; l < 3; ++l) e += levi(i, j, l) * d[l];
        k.B(i, j) = nB * p.YB * e;
        for (int l = 0; l < 3; ++l) {
          k.G[i][j][l] = nG * (p.XG * (dd - dl(i, j) / 3.0) * d[l] +
                               p.YG * (d[i] * dl(j, l) + d[j] * dl(i, l) - 2 * dd * d[l]));
          double h = 0.0;
          for (int q = 0; q < 3; ++q) h += levi(i, l, q) * d[q] * d[j] + levi(j, l, q) * d[q] * d[i];
          k.H[i][j][l] = nH * p.YH * h;
          for (int m = 0; m < 3; ++m) {
            const double d0 = 1.5 * (dd - dl(i, j) / 3.0) * (d[l] * d[m] - dl(l, m) / 3.0);
            const double d1 = 0.5 * (d[i] * dl(j, m) * d[l] + d[j] * dl(i, m) * d[l] +
                                     d[i] * dl(j, l) * d[m] + d[j] * dl(i, l) * d[m] -
                                     4 * dd * d[l] * d[m]);
            const double d2 =
                0.5 * (dl(i, l) * dl(j, m) + dl(j, l) * dl(i, m) - dl(i, j) * dl(l, m) +
                       dd * dl(l, m) + dl(i, j) * d[l] * d[m] - d[i] * dl(j, m) * d[l] -
                       d[j] * dl(i, m) * d[l] - d[i] * dl(j, l) * d[m] - d[j] * dl(i, l) * d[m] +
                       dd * d[l] * d[m]);
            k.M[i][j][l][m] = nM * (p.XM * d0 + p.YM * d1 + p.ZM * d2);
          }
        }
      }
    return k;
  };

  PairMatrix R = PairMatrix::Zero();
  const Blocks all[2][2] = {{blocks(0, 0), blocks(0, 1)}, {blocks(1, 0), blocks(1, 1)}};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      const Blocks& k = all[a][b];   // (a, b)
      const Blocks& kt = all[b][a];  // (b, a), for the transposed couplings
      const int ro = 11 * a, co = 11 * b;
      R.block<3, 3>(ro, co) = k.A;
      R.block<3, 3>(ro, co + 3) = kt.B.transpose();  // Bt_ab = B_ba^T
      R.block<3, 3>(ro + 3, co) = k.B;
      R.block<3, 3>(ro + 3, co + 3) = k.C;
      for (int m = 0; m < 5; ++m) {
        const Mat3& Bm = basis[m];
        for (int l = 0; l < 3; ++l) {
          double g = 0.0, h = 0.0, gt = 0.0, ht = 0.0;
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
              g += Bm(i, j) * k.G[i][j][l];
              h += Bm(i, j) * k.H[i][j][l];
              gt += Bm(i, j) * kt.G[i][j][l];
              ht += Bm(i, j) * kt.H[i][j][l];
            }
          R(ro + 6 + m, co + l) = g;       // S_a from U_b
          R(ro + 6 + m, co + 3 + l) = h;   // S_a from Omega_b
          R(ro + l, co + 6 + m) = gt;      // F_a from E_b: Gt_ab = G_ba^T
          R(ro + 3 + l, co + 6 + m) = ht;  // T_a from E_b: Ht_ab = H_ba^T
        }
        for (int n = 0; n < 5; ++n) {
          const Mat3& Bn = basis[n];
          double acc = 0.0;
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
              for (int l = 0; l < 3; ++l)
                for (int q = 0; q < 3; ++q) acc += Bm(i, j) * k.M[i][j][l][q] * Bn(l, q);
          R(ro + 6 + m, co + 6 + n) = acc;
        }
      }
    }
  return R;
}

// The same matrix with the basis contractions done in closed form. With d the unit vector along
// r_vec, B_m the orthonormal basis of symmetric traceless tensors (B_m:B_n = delta_mn), q_m = d.B_m.d,
// b_m = B_m d and c_m = d x b_m, the tensors of the reference contract to
//     B_m:G_.l  = n_G [XG q_m d_l + 2 YG (b_m,l - q_m d_l)]
//     B_m:H_.l  = 2 n_H YH c_m,l
//     B_m:M:B_n = n_M [3/2 XM q_m q_n + 2 YM (b_m.b_n - q_m q_n) + ZM (delta_mn - 2 b_m.b_n + q_m q_n / 2)]
// (traceless B_m removes every delta_ij term), and B_ab = n_B YB eps_ijl d_l. About 20 times fewer
// operations per pair; tests/test_resistance_functions.cpp holds it to the reference.
PairMatrix two_sphere_resistance(const Eigen::Vector3d& r_vec, double a1, double a2, double mu,
                                 const ResistanceScalars& s11_12, const ResistanceScalars& s22_21) {
  const Eigen::Vector3d d = r_vec / r_vec.norm();
  const double rad[2] = {a1, a2};
  const auto& basis = sym_traceless_basis();
  const Mat3 dd = d * d.transpose(), cross_d = (Mat3() << 0.0, d[2], -d[1], -d[2], 0.0, d[0], d[1], -d[0], 0.0).finished();
  double q[5];
  Eigen::Vector3d b[5], c[5];
  for (int m = 0; m < 5; ++m) {
    b[m] = basis[std::size_t(m)] * d;
    q[m] = d.dot(b[m]);
    c[m] = d.cross(b[m]);
  }
  double bb[5][5];
  for (int m = 0; m < 5; ++m)
    for (int n = 0; n <= m; ++n) bb[m][n] = bb[n][m] = b[m].dot(b[n]);
  // Per ordered pair (a, b): the blocks A, B, C and the projected G (5 x 3), H (5 x 3), M (5 x 5).
  struct Projected {
    Mat3 A, B, C;
    Eigen::Matrix<double, 5, 3> G, H;
    Eigen::Matrix<double, 5, 5> M;
  };
  auto projected = [&](int a, int bi) {
    const PairScalars p = a == 0 ? pick(s11_12, bi == 1) : pick(s22_21, bi == 0);
    const double L = rad[a] + rad[bi];
    const double nA = 3 * kPi * mu * L, nB = kPi * mu * L * L, nC = kPi * mu * L * L * L;
    const double nG = nB, nH = nC, nM = 5.0 / 6.0 * kPi * mu * L * L * L;
    Projected k;
    k.A = nA * (p.XA * dd + p.YA * (Mat3::Identity() - dd));
    k.C = nC * (p.XC * dd + p.YC * (Mat3::Identity() - dd));
    k.B = nB * p.YB * cross_d;
    for (int m = 0; m < 5; ++m) {
      k.G.row(m) = (nG * (p.XG * q[m] * d + 2.0 * p.YG * (b[m] - q[m] * d))).transpose();
      k.H.row(m) = (2.0 * nH * p.YH * c[m]).transpose();
      for (int n = 0; n < 5; ++n)
        k.M(m, n) = nM * (1.5 * p.XM * q[m] * q[n] + 2.0 * p.YM * (bb[m][n] - q[m] * q[n]) +
                          p.ZM * ((m == n ? 1.0 : 0.0) - 2.0 * bb[m][n] + 0.5 * q[m] * q[n]));
    }
    return k;
  };
  const Projected all[2][2] = {{projected(0, 0), projected(0, 1)}, {projected(1, 0), projected(1, 1)}};
  PairMatrix R;
  for (int a = 0; a < 2; ++a)
    for (int bi = 0; bi < 2; ++bi) {
      const Projected& k = all[a][bi];   // (a, b)
      const Projected& kt = all[bi][a];  // (b, a), for the transposed couplings
      const int ro = 11 * a, co = 11 * bi;
      R.block<3, 3>(ro, co) = k.A;
      R.block<3, 3>(ro, co + 3) = kt.B.transpose();
      R.block<3, 3>(ro + 3, co) = k.B;
      R.block<3, 3>(ro + 3, co + 3) = k.C;
      R.block<5, 3>(ro + 6, co) = k.G;
      R.block<5, 3>(ro + 6, co + 3) = k.H;
      R.block<3, 5>(ro, co + 6) = kt.G.transpose();
      R.block<3, 5>(ro + 3, co + 6) = kt.H.transpose();
      R.block<5, 5>(ro + 6, co + 6) = k.M;
    }
  return R;
}

PairMatrix two_sphere_resistance(const Eigen::Vector3d& r_vec, double a1, double a2, double mu) {
  const double s = 2.0 * r_vec.norm() / (a1 + a2);
  const ResistanceSeries first(a2 / a1), second(a1 / a2);
  return two_sphere_resistance(r_vec, a1, a2, mu, first.at_s(s),
                               relabel_spheres(second.at_s(s)));
}

ResistanceScalars resistance_scalars(double s, double lambda) {
  thread_local std::unique_ptr<ResistanceSeries> cache;
  if (!cache || cache->lambda() != lambda) cache = std::make_unique<ResistanceSeries>(lambda);
  return cache->at_s(s);
}

ResistanceScalars resistance_scalars_22_21(double s, double lambda) {
  return relabel_spheres(resistance_scalars(s, 1.0 / lambda));
}

}  // namespace stokesian::lubrication
