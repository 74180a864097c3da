// The lubrication cutoff band from a tolerance, and the switch (mathematics in cutoff.hpp).
#include "lubrication/cutoff.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stokesian::lubrication {

namespace {
// e(s) <= A s^-p for s >= 4 (measured, cutoff.hpp and docs/lubrication.md section 7).
struct Fit {
  double A, p;
};
Fit fit(Moments m) { return m == Moments::FTS ? Fit{32.0, 6.0} : Fit{6.8, 4.0}; }
}  // namespace

double far_field_pair_error(double s, Moments m) {
  const Fit f = fit(m);
  return f.A * std::pow(s, -f.p);
}

CutoffBand cutoff_for_tolerance(double tol, Moments m, double max_cutoff) {
  if (!(tol > 0.0) || !std::isfinite(tol)) throw std::invalid_argument("cutoff_for_tolerance: tolerance must be > 0");
  if (!(max_cutoff >= kStandardCutoff + kAutoTaper))
    throw std::invalid_argument("cutoff_for_tolerance: the cap must be >= 4.5");
  const Fit f = fit(m);
  const double s_tol = std::pow(f.A / tol, 1.0 / f.p);  // far-field error <= tol for s >= s_tol
  const double s_in = std::clamp(s_tol, kStandardCutoff, max_cutoff - kAutoTaper);
  return {s_in, s_in + kAutoTaper};
}

double tolerance_floor(Moments m, double max_cutoff) {
  return far_field_pair_error(std::max(max_cutoff - kAutoTaper, kStandardCutoff), m);
}

double cutoff_weight(double s, const CutoffBand& band) {
  if (s >= band.s_cut) return 0.0;
  if (s <= band.s_in) return 1.0;
  const double t = (s - band.s_in) / (band.s_cut - band.s_in);
  return 1.0 - t * t * t * (10.0 + t * (-15.0 + 6.0 * t));
}

}  // namespace stokesian::lubrication
