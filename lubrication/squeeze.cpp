// The thesis's squeeze lubrication (mathematics in squeeze.hpp).
#include "lubrication/squeeze.hpp"

#include <algorithm>
#include <cmath>

namespace stokesian::lubrication {

double squeeze_no_slip(double h, double a_red, double mu) {
  const double L = std::log(h / (2.0 * a_red));
  const double k1 = std::max(0.0, 1.041 - 0.281 * L - 0.0351 * L * L);
  return k1 * 6.0 * kPi * mu * a_red * a_red * (1.0 / h - 1.0 / (h + 2.0 * a_red));
}

double squeeze_slip(double h, double a_red, double mu, double d) {
  const double L = std::log(h / (2.0 * a_red));
  const double k2 = std::max(0.0, 1.309 - 0.082 * L - 0.009 * L * L);
  const double b = h + 2.0 * a_red;
  // (x + 6d) ln(1 + 6d/x) with log1p: the difference of the two terms is O(d^2) for d << h.
  const double bracket = (h + 6.0 * d) * std::log1p(6.0 * d / h) - (b + 6.0 * d) * std::log1p(6.0 * d / b);
  return k2 * kPi * mu * a_red * a_red / (3.0 * d * d) * bracket;
}

double squeeze_coefficient(double h_in, double ai, double aj, double mu, const SqueezeParams& p) {
  const double h = std::max(h_in, p.contact_gap);
  const double a_red = ai * aj / (ai + aj);
  if (h >= p.transition_gap) return squeeze_no_slip(h, a_red, mu);
  if (h < p.slip_gap) return squeeze_slip(h, a_red, mu, p.slip_gap);
  const double l = 0.5 * (std::erf(12.0 * (h - p.slip_gap) / (p.transition_gap - p.slip_gap) - 6.0) + 1.0);
  return l * squeeze_no_slip(h, a_red, mu) + (1.0 - l) * squeeze_slip(h, a_red, mu, p.slip_gap);
}

}  // namespace stokesian::lubrication
