#pragma once
// Tabulated two-sphere resistance functions for one size ratio.
//
// Mathematics: the 22 scalars of resistance_functions.hpp (JO84/J92 normalisation) are
// sampled once per lambda on a uniform grid in u = ln(xi), xi = s - 2, and evaluated between
// nodes by 6-point (quintic) Lagrange interpolation in u.  In u the singular near-contact
// terms become e^-u, -u and u e^u, all smooth, and the far field is smooth as well, so the
// interpolation error is O(h^6); with the default h = 0.025 the measured relative error is
// below 3e-8 (tests/test_resistance_functions.cpp, docs/lubrication.md).  Outside
// [xi_min, xi_max] the direct series evaluation is used.

#include "lubrication/resistance_functions.hpp"

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <utility>
#include <vector>

namespace stokesian::lubrication {

class ResistanceTable {
 public:
  /// order = 0 selects ResistanceSeries::default_order(lambda).
  explicit ResistanceTable(double lambda, double xi_min = 1e-8, double xi_max = 1e3,
                           double step = 0.025, int order = 0);

  double lambda() const { return series_.lambda(); }
  double xi_min() const { return xi_min_; }
  double xi_max() const { return xi_max_; }

  /// Scalars of the pair (1,2) at gap xi = s - 2 > 0.
  ResistanceScalars at_gap(double xi) const;
  ResistanceScalars at_s(double s) const { return at_gap(s - 2.0); }

  /// The exact evaluator behind the table.
  const ResistanceSeries& series() const { return series_; }

 private:
  ResistanceSeries series_;
  double xi_min_, xi_max_, u0_, h_;
  int n_;
  std::vector<double> values_;  // n_ nodes x kNumScalars
};

/// Thread-safe cache of resistance tables for any number of size ratios.
///
/// Rule (fixed, independent of the order and history of the calls; docs/lubrication.md 2.5):
///  * lambda uses an EXACT table (a ResistanceTable at that lambda, error ~1e-8) if lambda is
///    in the registered set (set_exact_ratios / prepare_radii) or lambda is exactly a grid
///    node exp(k h), k integer (so lambda = 1 is always exact);
///  * otherwise lambda is INTERPOLATED: 8-point Lagrange interpolation (degree 7) in
///    ln(lambda) between the node tables exp(k h), k = floor(ln(lambda)/h) - 3 .. +4, each
///    evaluated at the same gap xi.  Node tables are built lazily (only the nodes some lambda
///    needs; concurrently by the threads that need different nodes) with the series order of
///    the REQUESTED lambda, ResistanceSeries::default_order(lambda), so the interpolant
///    approximates exactly the function ResistanceSeries(lambda) evaluates (the order jumps
///    at max(lambda, 1/lambda) = 4 and 16 are reproduced, not smeared).
///  Measured with h = 0.1 (docs/lubrication.md 2.5): error <= 2.5e-7 for lambda in
///  [0.01, 100], xi in [1e-8, 1e3], in the metric |dF| / max(|F|, phi), phi = 1 for "11"
///  and (2 sqrt(lambda)/(1+lambda))^m for "12" functions (m = 1 A; 2 B, G; 3 C, H, M).
///  8 points at h = 0.1 are as accurate as 6 points at h = 0.05 with half the node tables;
///  6 points at h = 0.1 reach 2.7e-6 (lambda = 0.013, where F ~ lambda^3 = e^(3 ln lambda)).
/// The result for (lambda, xi) depends only on lambda, xi, the grid and the registered set,
/// never on which tables happen to exist, so it does not depend on the order of the calls or
/// the threads.  The registered set is the only state that changes results; change it before
/// (not during) an assembly.  All tables ever used stay in the cache (~0.25-0.5 MB each);
/// built tables are also kept in a process-wide store (the last 128, shared between caches),
/// so a new cache (e.g. a new NearField) reuses them instead of rebuilding.
class ResistanceTableCache {
 public:
  /// Spacing of the interpolation nodes in ln(lambda) (chosen by measurement, see docs; a
  /// value not 0.1 changes which ratios are nodes, hence exact).
  static constexpr double kDefaultLogLambdaStep = 0.1;
  /// prepare_radii(): at most this many distinct ratios a_j/a_i (i != j) use exact tables.
  static constexpr std::size_t kMaxExactRatios = 16;

  /// Points of the Lagrange stencil in ln(lambda) (even, <= kMaxStencil).
  static constexpr int kDefaultStencil = 8;
  static constexpr int kMaxStencil = 10;

  /// order > 0 fixes the series order of every table (tests); 0 = default_order(lambda).
  explicit ResistanceTableCache(double log_lambda_step = kDefaultLogLambdaStep,
                                int stencil = kDefaultStencil, int order = 0);

  /// The exact table at lambda (built on first use), whatever the rule says.
  const ResistanceTable& get(double lambda);

  /// Replace the registered set of exactly tabulated ratios (pass both a2/a1 and a1/a2 as
  /// computed by division from the radii; pair_scalars looks up a2/a1 and a1/a2).  Builds the
  /// missing tables now (in parallel with OpenMP).
  void set_exact_ratios(const std::vector<double>& lambdas);
  /// Scene rule: with the distinct radii of the scene, the distinct ratios a_j/a_i
  /// (a_i != a_j) are registered exact if there are at most kMaxExactRatios of them (always
  /// for up to 4 distinct radii), otherwise the registered set is cleared (all non-node
  /// ratios interpolated).  Returns true if the exact mode was chosen.
  bool prepare_radii(const std::vector<double>& radii);

  /// Build now (in parallel with OpenMP) every table that scalars(lambda, .) will use for
  /// these lambda (pass a2/a1 and a1/a2 of the pairs); optional, tables are otherwise built
  /// on first use by the thread that needs them.
  void prefetch(const std::vector<double>& lambdas);

  /// True if the rule above selects the exact table for lambda.
  bool is_exact(double lambda) const;
  /// Scalars of the pair (1,2) at (xi, lambda) by the rule above.
  ResistanceScalars scalars(double lambda, double xi);
  /// Scalars 11/12 and 22/21 of the pair with radii a1, a2 at centre distance r:
  /// scalars(a2/a1, xi) and relabel_spheres(scalars(a1/a2, xi)).
  void pair_scalars(double r, double a1, double a2, ResistanceScalars& s11_12,
                    ResistanceScalars& s22_21);

  double log_lambda_step() const { return h_; }
  /// Node k of the ln(lambda) grid: exp(k h).
  double node(int k) const;
  /// Number of tables built so far (exact and node tables).
  std::size_t num_tables() const;

 private:
  struct Entry {  // one table, built once (std::call_once) outside mutex_
    std::once_flag once;
    std::shared_ptr<const ResistanceTable> table;  // shared with the process-wide store
    std::atomic<bool> ready{false};
  };
  using Key = std::pair<double, int>;  // (lambda, series order)
  Entry& entry_locked(const Key& key);  // mutex_ held
  static const ResistanceTable& built(Entry& e, const Key& key);
  bool is_exact_locked(double lambda, long& k) const;
  int order_of(double lambda) const;
  // Keys, entries and weights of the tables scalars(lambda, .) combines; returns their number.
  int stencil_locked(double lambda, Key* keys, Entry** entries, double* w);
  void build_all(const std::vector<std::pair<Key, Entry*>>& todo);

  double h_;
  int stencil_;
  int order_;
  mutable std::mutex mutex_;
  std::map<Key, std::unique_ptr<Entry>> tables_;
  std::set<double> exact_;
};

}  // namespace stokesian::lubrication
