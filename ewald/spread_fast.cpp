// Fast spreading and interpolation (the paths spread() and interpolate() take for supports up to
// kMaxFastSupport); the mathematics is that of spread.hpp and interpolate.hpp, regrouped.
//
// Row coefficients. On the direction-2 row (j0, j1) of a particle's window, W^F and the three
// delta-derivatives of W^T are combinations of the direction-2 factors C_d = phi^(d) (d = 0..3):
//     w_e = sum_d T_ed C_d,   e = 0: W^F,  e = 1, 2, 3: d/d delta_{0,1,2} of W^T,
// with T_ed bilinear in the direction-0 factors A_alpha(j0) and direction-1 factors B_beta(j1)
// (row_coeffs below, the expansion of lap W = sum_ij Gt_ij d_i d_j W of window.hpp). The T_ed of all
// rows j1 of one j0 are computed together, vectorised over j1.
// Spreading: field c gets sum_e S_ce w_e with S = [F | Q J^T] (spread.hpp), i.e. the row update
//     u_c[l] += sum_d a_cd C_d[l],   a_cd = sum_e S_ce T_ed,
// four multiply-adds per point and field (F: three) instead of forming the four weight rows first.
// Interpolation: U_c = sum w_0 u_c and Dd_ec = sum w_e u_c, accumulated in 4-lane vectors and
// summed across lanes once per particle.
// Vector width. Rows are processed in V = 4 ceil(P / 4) doubles (padded_support, window.hpp) with
// the factors C_d zero beyond P, so every inner loop is a whole number of 4-double vectors and the
// support is a compile-time constant (one instantiation per V up to kMaxFastSupport; wider windows
// take the generic loops of spread.cpp / interpolate.cpp). The padding writes +0 to (and reads
// with weight 0 from) up to 3 more ghost points per row, which GridGeometry::row provides.
// Each kernel is compiled twice, for AVX2 + FMA (chosen at run time when the CPU has them) and for
// the baseline ISA. Sums run in an order fixed by the configuration (spread.hpp): the result does
// not depend on the thread count; the AVX2 and baseline paths differ by rounding only (FMA), and
// the paths agree with the generic loops and with a point-by-point sum to 1e-13 relative
// (tests/test_ewald.cpp).
#include "ewald/interpolate.hpp"
#include "ewald/spread.hpp"

#include "engine/core/cpu.hpp"
#include "engine/core/sym_traceless.hpp"

#include <atomic>
#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#define STOKESIAN_GK_INLINE inline __attribute__((always_inline))
#else
#define STOKESIAN_GK_INLINE inline
#endif

namespace stokesian::ewald {
namespace {

std::atomic<int> g_kernels{int(GridKernels::automatic)};

bool use_avx2() { return cpu_has_avx2_fma() && g_kernels.load() == int(GridKernels::automatic); }

typedef double v4u __attribute__((vector_size(32), aligned(8)));  // 4 doubles, unaligned access

// The metric entries of lap W as row_coeffs uses them: Gt_00, Gt_11, Gt_22, 2 Gt_01, 2 Gt_02, 2 Gt_12.
struct Metric {
  double g00, g11, g22, g01, g02, g12;
  explicit Metric(const Mat3& G)
      : g00(G(0, 0)), g11(G(1, 1)), g22(G(2, 2)), g01(2.0 * G(0, 1)), g02(2.0 * G(0, 2)), g12(2.0 * G(1, 2)) {}
};

// T[e][d][j1] for all rows j1 of one j0 (file header); A = phi^(0..3) along direction 0 at j0,
// B[beta][j1] along direction 1. W^F = W + cF lap W and W^T = W + cT lap W, grouped by the order of
// the direction-2 derivative.
template <int V, bool Grad>
STOKESIAN_GK_INLINE void row_coeffs(const double* A, const double (*B)[V], double cF, double cT, const Metric& g,
                                    double (*T)[4][V]) {
  for (int l = 0; l < V; ++l) {
    const double b0 = B[0][l], b1 = B[1][l], b2 = B[2][l], b3 = B[3][l];
    const double A0B0 = A[0] * b0;
    const double lap0 = g.g00 * A[2] * b0 + g.g11 * A[0] * b2 + g.g01 * A[1] * b1;
    const double lap1 = g.g02 * A[1] * b0 + g.g12 * A[0] * b1;
    T[0][0][l] = A0B0 + cF * lap0;
    T[0][1][l] = cF * lap1;
    T[0][2][l] = cF * g.g22 * A0B0;
    T[0][3][l] = 0.0;
    if constexpr (Grad) {
      T[1][0][l] = A[1] * b0 + cT * (g.g00 * A[3] * b0 + g.g11 * A[1] * b2 + g.g01 * A[2] * b1);
      T[1][1][l] = cT * (g.g02 * A[2] * b0 + g.g12 * A[1] * b1);
      T[1][2][l] = cT * g.g22 * A[1] * b0;
      T[1][3][l] = 0.0;
      T[2][0][l] = A[0] * b1 + cT * (g.g00 * A[2] * b1 + g.g11 * A[0] * b3 + g.g01 * A[1] * b2);
      T[2][1][l] = cT * (g.g02 * A[1] * b1 + g.g12 * A[0] * b2);
      T[2][2][l] = cT * g.g22 * A[0] * b1;
      T[2][3][l] = 0.0;
      T[3][0][l] = 0.0;
      T[3][1][l] = A0B0 + cT * lap0;
      T[3][2][l] = cT * lap1;
      T[3][3][l] = cT * g.g22 * A0B0;
    }
  }
}

// A particle's direction-1 factors (B, zero-padded to V) and direction-2 factors (C, as V / 4
// vectors, zero-padded).
template <int V>
STOKESIAN_GK_INLINE void load_factors(const ParticleWindows& win, long p, double (*B)[V], v4u (*C)[V / 4]) {
  const int P = win.P;
  for (int d = 0; d < 4; ++d) {
    const double* b = win.at(p, 1, d);
    const double* c = win.at(p, 2, d);
    double tmp[V];
    for (int l = 0; l < V; ++l) {
      B[d][l] = l < P ? b[l] : 0.0;
      tmp[l] = l < P ? c[l] : 0.0;
    }
    std::memcpy(C[d], tmp, sizeof tmp);
  }
}

// The walk shared by spreading and interpolation: loads the particle's factors (C, the direction-2
// ones, is returned for the row loops), then per direction-0 index j0 computes the coefficients T of
// all its rows, calls plane(T) once and row(j1, base) for each row, base the offset of the row's first
// point in a field.
template <int V, bool Grad, class Plane, class Row>
STOKESIAN_GK_INLINE void walk_window(const GridGeometry& g, const ParticleWindows& win, const Metric& gm, long p,
                                     v4u (*C)[V / 4], Plane&& plane, Row&& row) {
  const int P = g.P;
  double B[4][V];
  load_factors<V>(win, p, B, C);
  const auto& s = win.start[std::size_t(p)];
  double T[4][4][V];
  for (int j0 = 0; j0 < P; ++j0) {
    const int i0 = (s[0] + j0) % g.M[0];
    const double A[4] = {win.at(p, 0, 0)[j0], win.at(p, 0, 1)[j0], win.at(p, 0, 2)[j0], win.at(p, 0, 3)[j0]};
    row_coeffs<V, Grad>(A, B, win.cF[p], win.cT[p], gm, T);
    plane(static_cast<const double(*)[4][V]>(T));
    for (int j1 = 0; j1 < P; ++j1) row(j1, grid_offset(g, i0, (s[1] + j1) % g.M[1], s[2]));
  }
}

template <int V, bool Grad>
STOKESIAN_GK_INLINE void spread_one(const GridGeometry& g, const ParticleWindows& win, const Metric& gm, long p,
                                    const double (*S)[4], double* grid) {
  constexpr int K = V / 4, E = Grad ? 4 : 1;
  const long stored = g.stored();
  v4u C[4][K];
  double a[3][4][V];
  walk_window<V, Grad>(
      g, win, gm, p, C,
      [&](const double (*T)[4][V]) {
        for (int c = 0; c < 3; ++c)
          for (int d = 0; d < 4; ++d)
            for (int l = 0; l < V; ++l) {
              double v = S[c][0] * T[0][d][l];
              for (int e = 1; e < E; ++e) v += S[c][e] * T[e][d][l];
              a[c][d][l] = v;
            }
      },
      [&](int j1, long base) {
        for (int c = 0; c < 3; ++c) {
          v4u* r = reinterpret_cast<v4u*>(grid + c * stored + base);
          const double a0 = a[c][0][j1], a1 = a[c][1][j1], a2 = a[c][2][j1], a3 = a[c][3][j1];
          for (int k = 0; k < K; ++k) {
            v4u v = a0 * C[0][k] + a1 * C[1][k] + a2 * C[2][k];
            if constexpr (Grad) v += a3 * C[3][k];
            r[k] += v;
          }
        }
      });
}

template <int V, bool Grad>
STOKESIAN_GK_INLINE void interpolate_one(const GridGeometry& g, const ParticleWindows& win, const Metric& gm, long p,
                                         const double* grid, double (*out)[4]) {
  constexpr int K = V / 4, E = Grad ? 4 : 1;
  const long stored = g.stored();
  v4u C[4][K];
  v4u acc[3][E];
  for (int c = 0; c < 3; ++c)
    for (int e = 0; e < E; ++e) acc[c][e] = v4u{0.0, 0.0, 0.0, 0.0};
  const double (*T)[4][V] = nullptr;
  walk_window<V, Grad>(
      g, win, gm, p, C, [&](const double (*plane)[4][V]) { T = plane; },
      [&](int j1, long base) {
        const double* row = grid + base;
        for (int k = 0; k < K; ++k) {
          v4u w[E];
          for (int e = 0; e < E; ++e)
            w[e] = T[e][0][j1] * C[0][k] + T[e][1][j1] * C[1][k] + T[e][2][j1] * C[2][k] + T[e][3][j1] * C[3][k];
          for (int c = 0; c < 3; ++c) {
            const v4u r = *reinterpret_cast<const v4u*>(row + c * stored + 4 * k);
            for (int e = 0; e < E; ++e) acc[c][e] += w[e] * r;
          }
        }
      });
  for (int c = 0; c < 3; ++c)
    for (int e = 0; e < E; ++e) out[c][e] = (acc[c][e][0] + acc[c][e][1]) + (acc[c][e][2] + acc[c][e][3]);
}

// S = [F | Q J^T] of spread.hpp for the moments q of one particle.
void source_coeffs(const GridGeometry& g, Moments m, const double* q, double (*S)[4]) {
  for (int c = 0; c < 3; ++c) S[c][0] = q[c];
  if (m == Moments::F) return;
  const Mat3 Q = source_matrix(g, m, q);
  for (int c = 0; c < 3; ++c)
    for (int e = 0; e < 3; ++e) S[c][1 + e] = Q(c, e);
}

template <int V, bool Grad>
STOKESIAN_GK_INLINE void spread_list(const GridGeometry& g, const ParticleWindows& win, const std::vector<long>& list,
                                     Moments m, const double* in, double* grid) {
  const int d = dof_per_particle(m);
  const Metric gm(g.lap);
  for (long p : list) {
    double S[3][4];
    source_coeffs(g, m, in + p * d, S);
    spread_one<V, Grad>(g, win, gm, p, S, grid);
  }
}

template <int V, bool Grad>
STOKESIAN_GK_INLINE void interpolate_list(const GridGeometry& g, const ParticleWindows& win,
                                          const std::vector<long>& list, Moments m, const double* grid, double* out) {
  const int d = dof_per_particle(m);
  const Metric gm(g.lap);
  for (long p : list) {
    double o[3][4];
    interpolate_one<V, Grad>(g, win, gm, p, grid, o);
    responses_from_gradient(g, m, o, out + p * d);
  }
}

template <int V, bool Grad>
STOKESIAN_AVX2_FMA void spread_avx2(const GridGeometry& g, const ParticleWindows& win, const std::vector<long>& list,
                                   Moments m, const double* in, double* grid) {
  spread_list<V, Grad>(g, win, list, m, in, grid);
}
template <int V, bool Grad>
void spread_base(const GridGeometry& g, const ParticleWindows& win, const std::vector<long>& list, Moments m,
                 const double* in, double* grid) {
  spread_list<V, Grad>(g, win, list, m, in, grid);
}
template <int V, bool Grad>
STOKESIAN_AVX2_FMA void interpolate_avx2(const GridGeometry& g, const ParticleWindows& win,
                                        const std::vector<long>& list, Moments m, const double* grid, double* out) {
  interpolate_list<V, Grad>(g, win, list, m, grid, out);
}
template <int V, bool Grad>
void interpolate_base(const GridGeometry& g, const ParticleWindows& win, const std::vector<long>& list, Moments m,
                      const double* grid, double* out) {
  interpolate_list<V, Grad>(g, win, list, m, grid, out);
}

using SpreadFn = void (*)(const GridGeometry&, const ParticleWindows&, const std::vector<long>&, Moments, const double*,
                          double*);
template <int V>
SpreadFn spread_kernel(bool grad, bool avx) {
  if (avx) return grad ? spread_avx2<V, true> : spread_avx2<V, false>;
  return grad ? spread_base<V, true> : spread_base<V, false>;
}
template <int V>
SpreadFn interpolate_kernel(bool grad, bool avx) {
  if (avx) return grad ? interpolate_avx2<V, true> : interpolate_avx2<V, false>;
  return grad ? interpolate_base<V, true> : interpolate_base<V, false>;
}

// The kernel for padded support V (a multiple of 4 up to kMaxFastSupport), or null.
SpreadFn choose(int V, bool grad, bool interp) {
  const bool avx = use_avx2();
  switch (V) {
#define STOKESIAN_GK_CASE(W) \
  case W: return interp ? interpolate_kernel<W>(grad, avx) : spread_kernel<W>(grad, avx);
    STOKESIAN_GK_CASE(4) STOKESIAN_GK_CASE(8) STOKESIAN_GK_CASE(12) STOKESIAN_GK_CASE(16)
    STOKESIAN_GK_CASE(20) STOKESIAN_GK_CASE(24) STOKESIAN_GK_CASE(28) STOKESIAN_GK_CASE(32)
#undef STOKESIAN_GK_CASE
    default: return nullptr;
  }
}
static_assert(kMaxFastSupport == 32, "choose() instantiates the padded supports 4, 8, ..., 32");

}  // namespace

void force_grid_kernels(GridKernels k) { g_kernels = int(k); }

GridKernelFn spread_kernel_for(const GridGeometry& g, Moments m) {
  if (g_kernels.load() == int(GridKernels::generic) || g.P > kMaxFastSupport) return nullptr;
  return choose(padded_support(g.P), m != Moments::F, false);
}

GridKernelFn interpolate_kernel_for(const GridGeometry& g, Moments m) {
  if (g_kernels.load() == int(GridKernels::generic) || g.P > kMaxFastSupport) return nullptr;
  return choose(padded_support(g.P), m != Moments::F, true);
}

}  // namespace stokesian::ewald
