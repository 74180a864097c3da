// Tabulation of the two-sphere resistance functions in u = ln(xi) with 6-point Lagrange
// interpolation (see resistance_table.hpp for the mathematics and error estimate).

#include "lubrication/resistance_table.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stokesian::lubrication {

ResistanceTable::ResistanceTable(double lambda, double xi_min, double xi_max, double step,
                                 int order)
    : series_(lambda, order), xi_min_(xi_min), xi_max_(xi_max) {
  if (!(xi_min > 0.0) || !(xi_max > xi_min) || !(step > 0.0))
    throw std::invalid_argument("ResistanceTable: bad range");
  u0_ = std::log(xi_min);
  const double u1 = std::log(xi_max);
  n_ = static_cast<int>(std::ceil((u1 - u0_) / step)) + 1;
  n_ = std::max(n_, 6);
  h_ = (u1 - u0_) / (n_ - 1);
  values_.resize(static_cast<std::size_t>(n_) * kNumScalars);
  for (int j = 0; j < n_; ++j) {
    const ResistanceScalars r = series_.at_gap(std::exp(u0_ + j * h_));
    for (int i = 0; i < kNumScalars; ++i)
      values_[static_cast<std::size_t>(j) * kNumScalars + i] = scalar_at(r, i);
  }
}

ResistanceScalars ResistanceTable::at_gap(double xi) const {
  if (!(xi > 0.0)) throw std::invalid_argument("ResistanceTable: xi must be > 0");
  if (xi < xi_min_ || xi > xi_max_) return series_.at_gap(xi);
  const double v = (std::log(xi) - u0_) / h_;
  int j0 = static_cast<int>(std::floor(v)) - 2;  // nodes j0 .. j0+5
  j0 = std::clamp(j0, 0, n_ - 6);
  const double x = v - j0;  // position in node units, nodes at 0..5
  double w[6];
  // Lagrange weights for nodes 0..5: w_m = prod_{l != m} (x - l) / (m - l).
  static const double denom[6] = {-120.0, 24.0, -12.0, 12.0, -24.0, 120.0};
  for (int m = 0; m < 6; ++m) {
    double p = 1.0;
    for (int l = 0; l < 6; ++l)
      if (l != m) p *= (x - l);
    w[m] = p / denom[m];
  }
  ResistanceScalars out{};
  const double* base = &values_[static_cast<std::size_t>(j0) * kNumScalars];
  for (int i = 0; i < kNumScalars; ++i) {
    double acc = 0.0;
    for (int m = 0; m < 6; ++m) acc += w[m] * base[m * kNumScalars + i];
    scalar_at(out, i) = acc;
  }
  return out;
}

const ResistanceTable& ResistanceTableCache::get(double lambda) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = tables_.find(lambda);
  if (it == tables_.end())
    it = tables_.emplace(lambda, std::make_unique<ResistanceTable>(lambda)).first;
  return *it->second;
}

void ResistanceTableCache::pair_scalars(double r, double a1, double a2, ResistanceScalars& s11_12,
                                        ResistanceScalars& s22_21) {
  const double lambda = a2 / a1;
  const double xi = 2.0 * r / (a1 + a2) - 2.0;
  s11_12 = get(lambda).at_gap(xi);
  s22_21 = relabel_spheres(get(a1 / a2).at_gap(xi));
}

}  // namespace stokesian::lubrication
