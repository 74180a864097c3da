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

#include <map>
#include <memory>
#include <mutex>
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

/// Thread-safe cache of tables, one per distinct lambda (exact match of the double).
class ResistanceTableCache {
 public:
  const ResistanceTable& get(double lambda);
  /// Scalars 11/12 and 22/21 of the pair with radii a1, a2 at centre distance r.
  void pair_scalars(double r, double a1, double a2, ResistanceScalars& s11_12,
                    ResistanceScalars& s22_21);

 private:
  std::mutex mutex_;
  std::map<double, std::unique_ptr<ResistanceTable>> tables_;
};

}  // namespace stokesian::lubrication
