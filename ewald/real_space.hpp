#pragma once
// Real-space part of the Ewald-split periodic grand mobility, fast form (docs/ewald.md s.2):
//     y_a = S_a x_a + sum_{b : |r_ab| < cutoff_gap + a_a + a_b} M^real_ab(r_ab) x_b,
// r_ab = x_a - x_b the minimum image, S_a = self_correction(a_a) (ewald_split.hpp), M^real the
// blocks of real_scalars. This is the product PmeFarField::apply_real computes; the pair set is
// that of trees::neighbor_pairs (same contract: boxes with cutoff_gap + 2 a_max > min(L) / 2 are
// rejected).
//
// Tabulation. For a separated pair (r >= a_a + a_b) the real part of 8 pi mu Psi is
//     R = (r + 2 c1 / r) - (W0 + c1 W1 + c2 W2)
// for each kind pair (ff, tf, ft, tt), c1 = w_a a_a^2 + w_b a_b^2, c2 = w_a a_a^2 w_b a_b^2
// (w = 1/6 force kind, 1/10 torque/stresslet kind; ewald_split.hpp). Every scalar is a fixed
// linear form in the radial derivatives d1..d4 of Psi divided by powers of r
// (mobility::scalars_from_derivatives), so the whole pair follows from the twelve functions
// d_k W_j(r) (k = 1..4, j = 0..2; F needs only k = 1, 2), whatever the radii. The W_j are even entire
// functions of r (no singularity, scale 1/xi), so they are tabulated on [r_lo, r_hi] =
// [2 a_min, cutoff_gap + 2 a_max] as piecewise polynomials of degree 7 (Chebyshev interpolation in
// each interval, stored as monomials in the local variable t in [-1, 1]); the free part r + 2 c1/r is
// evaluated exactly. At most four distinct radii (mono- to tetradisperse suspensions): one table
// per ordered pair of radii holds the 2 / 6 / 14 pair scalars themselves instead, on
// [a_p + a_q, cutoff_gap + a_p + a_q] (same degree, nodes and accuracy rule, compared with their
// long-double values from the same closed forms), so an entry costs one polynomial vector per four
// scalars and no combination; the general tables are its reference twin (force_general_tables). Polynomials are
// evaluated by Estrin's scheme. Overlapping and nested pairs (r < a_a + a_b) keep the exact
// real_scalars, computed once per position update.
//
// Table accuracy. The intervals are halved until, on 9 sample points per interval (against the
// closed forms in long double; Taylor series below xi r = 0.5), the error of every pair scalar is
// bounded by
//     eps_table = max(1e-4 tol, 2e-14) x (self mobility of a sphere of radius rho = min(a_max, r/2))
// (the U <- F scalars against the translational self mobility, all others against the smallest
// self mobility of the moments). The bound adds the errors of d_k W_j times c1_max, c2_max (a
// separated pair at distance r has a_a + a_b <= r, so c1 <= min(r^2, 2 a_max^2)/6,
// c2 <= rho^4/36, and its smaller sphere has radius <= rho) times the largest multiplier of d_k in
// the scalars (mobility::scalars_from_derivatives). table_error() returns the measured bound in
// units of that self mobility (per-class tables: every scalar's error is measured directly against
// that bound). Summed over the neighbours of a particle these errors stay orders of magnitude below tol
// (tests/test_ewald_real.cpp: relative 2-norm error <= 1e-3 tol required, at most 5.2e-5 tol
// measured; the per-class and general tables agree to 1e-3 tol from 1e-2 to 1e-10).
//
// Speed. Particles are binned in cells over fractional coordinates (Lees-Edwards aware, as
// trees/neighbor_list.hpp; cells of width >= range / 2 with a 5-cell stencil when the box allows)
// and renumbered cell by cell; inputs are gathered into that order, each sorted particle gathers
// its own row from contiguous structure-of-arrays pair data (neighbour, unit vector, distance), and
// the result is scattered back. Each row is summed by one thread in a fixed order, so the result is
// bitwise independent of the number of OpenMP threads. The pair set is exactly that of
// neighbor_pairs (same cutoff test on its minimum image near the cutoff); inside it the separation
// comes from the cell image, equal to the minimum image within rounding. The scalars of the
// separated entries are kept per entry (one record per entry) when they fit in cache_bytes
// (default 256 MB: 16, 48 or 112 bytes per ordered pair for F, FT, FTS); repeated products then
// only read them, four entries at a time (the cache holds groups of four consecutive entries, each
// scalar four-wide, and a row's whole groups go through one vector evaluation of the block formula).
// Measured on one core (bench/bench_pme_real.cpp, bench/results/pme_real.json): about 3 / 8 / 20 ns
// per pair (F / FT / FTS) with the cache (4 / 10 / 32 one entry at a time), 18 / 44 / 75 without; without the
// cache, equal radii (per-class tables) take 0.65 / 0.59 / 0.77 of that (12.4 / 24 / 56 against 19 / 41 / 72 ns on a
// slower day, N = 10648, phi 0.1, tol 1e-4; not priced by the cost model, pme_parameters.cpp).
// The per-class tables cost more to build (FTS, one thread: one radius 0.008 / 0.056 s at tol
// 1e-4 / 1e-12, two radii 0.07 / 0.30 s, four radii 0.12 / 0.59 s, against 0.003-0.044 s for the
// general tables); they are built by the constructor only (PmeFarField::build: new particles, radii
// or box), never by update_positions.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"
#include "engine/kernels/mobility_pair.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace stokesian::ewald {

class RealSpaceSum {
 public:
  RealSpaceSum() = default;
  // x, a: N positions and radii [a]; domain periodic (any strain); cutoff_gap > 0 [a]; xi > 0 [1/a];
  // mu > 0; tolerance in [1e-14, 0.1] (the PME tolerance, sets the table accuracy). Throws
  // std::invalid_argument on bad input or a box smaller than twice the interaction range.
  // cache_bytes: memory allowed for the per-entry scalar cache (below).
  RealSpaceSum(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain, double cutoff_gap,
               double xi, double mu, Moments m, double tolerance,
               std::size_t cache_bytes = kDefaultCacheBytes);
  static constexpr std::size_t kDefaultCacheBytes = std::size_t(256) << 20;
  // Memory of `entries` separated ordered pairs [bytes]: the scalar cache (16 / 48 / 112 bytes per
  // entry for F / FT / FTS; kept when it fits in cache_bytes), and the pair data (neighbour index,
  // unit vector and distance, 36 bytes per entry) held twice: the arrays the product reads and the
  // pair search's per-thread copy, kept between updates with 10 % spare capacity (measured in
  // docs/reliability.md). The cost model (pme_parameters.cpp) and the resource estimate use them.
  static double cache_bytes_for(double entries, Moments m);
  static double pair_bytes_for(double entries) { return 2.1 * 36.0 * entries; }

  // New positions of the same particles (same radii, box, strain): rebuilds the cell order and
  // the pair data, keeps the tables and self terms. The result equals a new object's.
  void update_positions(const std::vector<Vec3>& x);
  // The same with a new Lees-Edwards strain (same box edges, still periodic): the tables and self
  // terms do not depend on the strain, so shearing boxes keep them too.
  void update_positions(const std::vector<Vec3>& x, const Domain& domain);

  // out = real-space sum + self term (overwritten), size N * dof_per_particle(m).
  void apply(const VecX& in, VecX& out) const;

  Eigen::Index size() const { return Eigen::Index(n_) * dof_per_particle(m_); }
  Moments moments() const { return m_; }
  std::size_t pairs() const { return pairs_; }              // unordered pairs within the cutoff
  std::size_t overlapping_pairs() const { return overlap_j_.size() / 2; }
  int table_intervals() const { return intervals_; }
  double table_error() const { return table_error_; }     // measured, relative (see header)
  double table_target() const { return table_target_; }   // max(1e-4 tol, 2e-14)
  bool cached() const { return !cache_.empty(); }
  // The row kernels exist for the baseline x86-64 target and for AVX2 + FMA (chosen at run time
  // when the CPU has them); true forces the baseline ones in every object (for tests).
  static void force_baseline_kernels(bool on);
  // true: objects built afterwards use the general tables even for a few distinct radii (the
  // reference twin of the per-class tables, for tests and benchmarks).
  static void force_general_tables(bool on);
  bool direct_tables() const { return direct_; }
  // Cell order: order()[k] = original index of the k-th particle in the sorted (cell by cell) order.
  const std::vector<int>& order() const { return order_; }

 private:
  void build_table(double tolerance);
  void build_direct_table();
  struct ClassTable {  // pair scalars of one (row radius, neighbour radius) class pair
    double r_lo = 0.0, inv_h = 0.0;
    int intervals = 0;
    std::size_t offset = 0;  // in table_
  };
  template <Moments M>
  mobility::PairScalars direct_scalars(const ClassTable& ct, double r) const;
  void set_positions(const std::vector<Vec3>& x);
  template <Moments M>
  void apply_rows(const double* xs, double* ys) const;
  template <Moments M>
  mobility::PairScalars table_scalars(double A, double B, double r) const;
  template <Moments M>
  void fill_cache();
  template <Moments M>
  void row(long k, const double* xs, double* ys) const;
  template <Moments M>
  void fill_row(long k);
  template <Moments M>
  void rows_avx2(long k0, long k1, const double* xs, double* ys) const;
  template <Moments M>
  void rows_base(long k0, long k1, const double* xs, double* ys) const;
  template <Moments M>
  void fill_avx2(long k0, long k1);
  template <Moments M>
  void fill_base(long k0, long k1);

  long n_ = 0;
  Moments m_ = Moments::F;
  Domain domain_;
  double cutoff_gap_ = 0.0, xi_ = 1.0, mu_ = 1.0;
  std::vector<double> radius_;  // original order
  std::vector<double> self0_;   // self-term coefficients F, T, S per particle, original order

  // Tables: intervals_ intervals of width h on [r_lo, r_hi]; per interval, kCoef levels (highest
  // power first) of nf_ functions (k-major: d1 W0, d1 W1, d1 W2, d2 W0, ...; stored with stride_,
  // zero padded), already times 1/(8 pi mu).
  static constexpr int kCoef = 8;
  // At most kMaxClasses distinct radii (direct_): one table of the pair scalars themselves (record
  // order of the cache, stride 4 / 8 / 16) per ordered pair of radius classes, class_tables_[p K + q]
  // for a row sphere of radius classes_[p] and a neighbour of radius classes_[q]; cls_ = class of
  // each sorted particle. intervals_ is then the largest interval count of the tables.
  static constexpr int kMaxClasses = 4;
  int intervals_ = 0, nf_ = 0, stride_ = 0;  // functions used, functions stored per level
  bool direct_ = false;
  std::vector<double> classes_;
  std::vector<ClassTable> class_tables_;
  std::vector<std::uint8_t> cls_;
  double r_lo_ = 0.0, inv_h_ = 0.0;
  std::vector<double> table_;
  double table_error_ = 0.0, table_target_ = 0.0;

  // Sorted order (cell by cell): order_[k] = original index of sorted particle k.
  std::vector<int> order_;
  std::vector<double> a2s_;                  // sorted radii squared
  std::vector<double> self_f_, self_t_, self_s_;  // sorted self-term coefficients
  // Separated entries of sorted row k: [row_[k], row_[k+1]), structure of arrays.
  std::vector<long> row_;
  std::vector<int> nbr_;
  std::vector<double> ex_, ey_, ez_, dist_;
  // Overlapping/nested entries: [orow_[k], orow_[k+1]), exact scalars.
  std::vector<long> orow_;
  std::vector<int> overlap_j_;
  std::vector<Vec3> overlap_e_;
  std::vector<mobility::PairScalars> overlap_s_;
  std::size_t pairs_ = 0;
  // Scalars of the separated entries from the tables (records of 2, 6 or 14 values per entry: xa ya |
  // yb ybt xc yc | xg yg xgt ygt yh xm ym zm), kept when they fit in cache_bytes_; otherwise each
  // product evaluates the tables again. The two agree to rounding (the compiler may fuse the
  // multiply-adds differently when the scalars are not stored).
  std::size_t cache_bytes_ = kDefaultCacheBytes;
  std::vector<double> cache_;
  // Per-thread scratch of the pair search (kept so that updates reuse the storage).
  struct Block {
    std::vector<long> count, ocount;
    std::vector<int> nbr, onbr;
    std::vector<double> ex, ey, ez, dist, odist;
    std::vector<Vec3> oe;
    std::vector<int> candidates;  // pair search: the cell range's particles within the bound
  };
  std::vector<Block> blocks_;
};

}  // namespace stokesian::ewald
