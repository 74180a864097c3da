// Pair-force evaluators and the shared pair loop; the mathematics is stated in pair_forces.hpp.
#include "engine/pair_forces.hpp"

#include "engine/core/parallel.hpp"

#include "trees/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace stokesian::forces {

// ---------------------------------------------------------------------------------------------
// Components
// ---------------------------------------------------------------------------------------------

EnergyDerivative vdw_hamaker(double r, double ai, double aj, double hamaker) {
  const double h = r - ai - aj;
  const double P = h * (r + ai + aj);                    // r^2 - (a_i+a_j)^2 without cancellation
  const double d = std::abs(ai - aj);
  const double M = (r - d) * (r + d);                    // r^2 - (a_i-a_j)^2
  const double t = 4.0 * ai * aj / M;                    // in (0, 1) for h > 0
  double bracket;
  if (t < 0.2) {
    // sum_{k>=3} (k-2)/(2k) t^k: the closed form loses ~1/t^2 digits here.
    bracket = 0.0;
    double tk = t * t;
    for (int k = 3; k < 200; ++k) {
      tk *= t;
      const double term = tk * (k - 2) / (2.0 * k);
      bracket += term;
      if (term < 1e-17 * bracket) break;
    }
  } else {
    bracket = 2.0 * ai * aj / P + 2.0 * ai * aj / M + std::log(P / M);
  }
  const double ab = ai * aj;
  return {-hamaker / 6.0 * bracket, 32.0 * hamaker * ab * ab * ab * r / (3.0 * P * P * M * M)};
}

EnergyDerivative born_feke(double r, double ai, double aj, double hamaker, double sigma) {
  if (sigma == 0.0) return {};
  const double R = r / ai, l = aj / ai, s = sigma / ai;
  const double s3 = s * s * s;
  const double pref = hamaker * s3 * s3 / 37800.0;
  // Gap-like denominators formed from r directly so that D4 = h/a_i keeps its digits.
  const double D[4] = {(r - ai + aj) / ai, (r + ai - aj) / ai, (r + ai + aj) / ai, (r - ai - aj) / ai};
  const double cm = 6.0 * (l * l - 7.0 * l + 1.0), cp = 6.0 * (l * l + 7.0 * l + 1.0);
  const double N[4] = {-R * R - 7.0 * (l - 1.0) * R - cm, -R * R + 7.0 * (l - 1.0) * R - cm,
                       R * R + 7.0 * (l + 1.0) * R + cp, R * R - 7.0 * (l + 1.0) * R + cp};
  const double dN[4] = {-2.0 * R - 7.0 * (l - 1.0), -2.0 * R + 7.0 * (l - 1.0), 2.0 * R + 7.0 * (l + 1.0),
                        2.0 * R - 7.0 * (l + 1.0)};
  double S = 0.0, dS = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double d2 = D[k] * D[k], d7 = d2 * d2 * d2 * D[k];
    S += N[k] / d7;
    dS += dN[k] / d7 - 7.0 * N[k] / (d7 * D[k]);
  }
  const double U = pref * S / R;
  const double dUdR = pref * (dS / R - S / (R * R));
  return {U, dUdR / ai};
}

EnergyDerivative double_layer_hhf(double r, double ai, double aj, double Z, double kappa) {
  const double h = r - ai - aj;
  const double aeff = ai * aj / (ai + aj);
  const double e = std::exp(-kappa * h);
  return {2.0 * Z * aeff * std::log1p(e), -2.0 * Z * aeff * kappa * e / (1.0 + e)};
}

EnergyDerivative double_layer_lsa(double r, double ai, double aj, double Z, double kappa, double psi_reduced) {
  double g = 1.0;  // [tanh(psi~/4)/(psi~/4)]^2 -> 1 in the linear (small-potential) limit
  if (psi_reduced != 0.0) {
    const double q = 0.25 * psi_reduced;
    g = std::tanh(q) / q;
    g *= g;
  }
  const double h = r - ai - aj;
  const double U = 2.0 * Z * g * ai * aj / r * std::exp(-kappa * h);
  return {U, -U * (1.0 / r + kappa)};
}

// ---------------------------------------------------------------------------------------------
// Evaluators
// ---------------------------------------------------------------------------------------------

EnergyDerivative MorseLaw::operator()(double r, double ai, double aj) const {
  const double e = std::exp(-kappa * (r - ai - aj));
  return {-depth * (2.0 * e - e * e), 2.0 * depth * kappa * (e - e * e)};
}

EnergyDerivative DlvoLaw::unregularised(double r, double ai, double aj) const {
  const EnergyDerivative v = vdw_hamaker(r, ai, aj, hamaker);
  const EnergyDerivative b = born_feke(r, ai, aj, hamaker, sigma);
  const EnergyDerivative d = double_layer == PairForceParams::DoubleLayer::hhf
                                 ? double_layer_hhf(r, ai, aj, Z, kappa)
                                 : double_layer_lsa(r, ai, aj, Z, kappa, psi_reduced);
  return {v.U + b.U + d.U, v.dUdr + b.dUdr + d.dUdr};
}

EnergyDerivative DlvoLaw::operator()(double r, double ai, double aj) const {
  const double rmin = ai + aj + min_gap;
  if (r >= rmin) return unregularised(r, ai, aj);
  const EnergyDerivative f = unregularised(rmin, ai, aj);  // linear continuation below the floor
  return {f.U + f.dUdr * (r - rmin), f.dUdr};
}

EnergyDerivative HertzLaw::operator()(double r, double ai, double aj) const {
  const double delta = ai + aj - r;
  if (!(delta > 0.0)) return {};
  const double s = std::sqrt(delta);
  return {0.4 * stiffness * delta * delta * s, -stiffness * delta * s};
}

EnergyDerivative HarmonicLaw::operator()(double r, double ai, double aj) const {
  const double stretch = (r - ai - aj) - rest_gap;
  return {0.5 * stiffness * stretch * stretch, stiffness * stretch};
}

double HarmonicLaw::default_cutoff(double, double) const {
  return rest_gap + std::sqrt(2.0 * kHarmonicCutoffEnergy / stiffness);
}

EnergyDerivative RepulsionLaw::operator()(double r, double ai, double aj) const {
  // U = -F0 a ln(1 - e^{-tau h}), -dU/dh = F0 (tau a) e^{-tau h} / (1 - e^{-tau h}), a = 1 (the
  // reference radius); log1p/expm1 keep the precision at small and large tau h.
  const double hmin = min_gap;
  const double h = std::max(r - ai - aj, hmin);
  const double e = std::exp(-decay * h);
  const double U = -strength * std::log1p(-e);
  const double dUdr = -strength * decay * e / -std::expm1(-decay * h);
  if (r - ai - aj >= hmin) return {U, dUdr};
  return {U + dUdr * (r - ai - aj - hmin), dUdr};  // linear continuation below the floor
}

double RepulsionLaw::default_cutoff(double, double tol) const { return std::log(1.0 / tol) / decay; }

MorseLaw morse_law(const PairForceParams& p) {
  if (!(p.morse_kappa > 0.0)) throw std::invalid_argument("morse: kappa must be positive");
  return {p.morse_depth, p.morse_kappa};
}

DlvoLaw dlvo_law(const PairForceParams& p) {
  if (!(p.min_gap > 0.0)) throw std::invalid_argument("dlvo: min_gap must be positive");
  if (!(p.debye_kappa > 0.0)) throw std::invalid_argument("dlvo: debye_kappa must be positive");
  return {p.hamaker, p.debye_kappa, p.surface_potential, p.surface_potential_reduced,
          p.born_sigma, p.min_gap, p.double_layer};
}

HertzLaw hertz_law(const PairForceParams& p) { return {p.hertz_stiffness}; }

RepulsionLaw repulsion_law(const PairForceParams& p) {
  if (!(p.repulsion_strength >= 0.0) || !std::isfinite(p.repulsion_strength))
    throw std::invalid_argument("repulsion: strength must be >= 0 and finite");
  if (!(p.repulsion_decay > 0.0) || !std::isfinite(p.repulsion_decay))
    throw std::invalid_argument("repulsion: decay must be positive and finite");
  if (!(p.min_gap > 0.0)) throw std::invalid_argument("repulsion: min_gap must be positive");
  return {p.repulsion_strength, p.repulsion_decay, p.min_gap};
}

HarmonicLaw harmonic_law(const PairForceParams& p) {
  if (!(p.harmonic_stiffness > 0.0) || !std::isfinite(p.harmonic_stiffness))
    throw std::invalid_argument("harmonic: stiffness must be positive and finite");
  if (!(p.harmonic_rest_gap >= 0.0) || !std::isfinite(p.harmonic_rest_gap))
    throw std::invalid_argument("harmonic: rest_gap must be >= 0 and finite");
  if (p.cutoff > 0.0 && !(p.cutoff > p.harmonic_rest_gap))
    throw std::invalid_argument("harmonic: cutoff must exceed rest_gap (the spring's minimum would be cut off)");
  return {p.harmonic_stiffness, p.harmonic_rest_gap};
}

// ---------------------------------------------------------------------------------------------
// Cut-offs
// ---------------------------------------------------------------------------------------------

namespace {

// Gap where |U_vdW| of two spheres of radius a falls to tol*A (|U_vdW| decreases monotonically).
double vdw_range(double a, double tol, double h_start) {
  auto small = [&](double h) { return std::abs(vdw_hamaker(2.0 * a + h, a, a, 1.0).U) <= tol; };
  double lo = h_start, hi = std::max(h_start, a);
  while (!small(hi)) {
    lo = hi;
    hi *= 2.0;
  }
  for (int it = 0; it < 100 && hi - lo > 1e-10 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (small(mid) ? hi : lo) = mid;
  }
  return hi;
}

}  // namespace

double MorseLaw::default_cutoff(double, double tol) const { return std::log(2.0 / tol) / kappa; }

double DlvoLaw::default_cutoff(double a_max, double tol) const {
  const double h_dl = std::log(1.0 / tol) / kappa;
  const double h_vdw = a_max > 0.0 ? vdw_range(a_max, tol, min_gap) : 0.0;
  return std::max({h_dl, h_vdw, 2.0 * min_gap});
}

double default_cutoff(const PairForceParams& p, double a_max) {
  return with_law(p, [&](const auto& law) { return law.default_cutoff(a_max, kDefaultCutoffTolerance); });
}

double resolved_cutoff(const PairForceParams& p, double a_max) {
  if (p.kind == PairForceParams::Kind::hertz) return std::max(p.cutoff, 0.0);
  return p.cutoff > 0.0 ? p.cutoff : default_cutoff(p, a_max);
}

namespace {

template <class Law>
EnergyDerivative shifted(const Law& law, double cutoff_gap, double r, double ai, double aj) {
  const double rc = ai + aj + cutoff_gap;
  if (!(r < rc)) return {};
  EnergyDerivative e = law(r, ai, aj);
  e.U -= law(rc, ai, aj).U;
  return e;
}

// The one pair loop: evaluates `law` on every listed pair within its cut-off and accumulates.
template <class Law>
void accumulate(const Law& law, double cutoff_gap, const std::vector<trees::NeighborPair>& pairs,
                const std::vector<double>& radius, std::vector<Vec3>& force, PairForceTotals* totals) {
  const long n = static_cast<long>(pairs.size());
  std::vector<EnergyDerivative> e(pairs.size());
  // Independent per-pair evaluation; the scatter below is serial so sums do not depend on threads.
#pragma omp parallel for schedule(static) if (n >= parallel::kPairForcePairs)
  for (long k = 0; k < n; ++k) {
    const auto& p = pairs[k];
    e[k] = shifted(law, cutoff_gap, p.dist, radius[p.i], radius[p.j]);
  }
  for (long k = 0; k < n; ++k) {
    const auto& p = pairs[k];
    if (e[k].U == 0.0 && e[k].dUdr == 0.0) continue;
    Vec3 F = Vec3::Zero();
    if (p.dist > 0.0) F = (-e[k].dUdr / p.dist) * p.r;  // force on i
    force[p.i] += F;
    force[p.j] -= F;
    if (totals) {
      totals->energy += e[k].U;
      const Mat3 w = p.r * F.transpose();
      totals->virial += w;
      if (totals->per_particle) {
        totals->particle_virial[p.i] += 0.5 * w;
        totals->particle_virial[p.j] += 0.5 * w;
      }
    }
  }
}

}  // namespace

EnergyDerivative pair_energy(const PairForceParams& p, double cutoff_gap, double r, double ai, double aj) {
  return with_law(p, [&](const auto& law) { return shifted(law, cutoff_gap, r, ai, aj); });
}

void add_pair_forces(const std::vector<PairForceParams>& laws, const std::vector<Vec3>& x,
                     const std::vector<double>& radius, const Domain& domain, std::vector<Vec3>& force,
                     PairForceTotals* totals) {
  if (x.size() != radius.size())
    throw std::invalid_argument("add_pair_forces: " + std::to_string(x.size()) + " positions but " +
                                std::to_string(radius.size()) + " radii");
  if (force.empty()) force.assign(x.size(), Vec3::Zero());
  if (force.size() != x.size()) throw std::invalid_argument("add_pair_forces: force has wrong size");
  if (totals && totals->per_particle && totals->particle_virial.size() != x.size())
    totals->particle_virial.assign(x.size(), Mat3::Zero());
  if (laws.empty() || x.size() < 2) return;

  double a_max = 0.0;
  for (double a : radius) a_max = std::max(a_max, a);
  std::vector<double> cut(laws.size());
  double search = 0.0;
  for (std::size_t l = 0; l < laws.size(); ++l) search = std::max(search, cut[l] = resolved_cutoff(laws[l], a_max));

  const auto pairs = trees::neighbor_pairs(x, radius, domain, search);
  for (std::size_t l = 0; l < laws.size(); ++l)
    with_law(laws[l], [&](const auto& law) { accumulate(law, cut[l], pairs, radius, force, totals); });
}

}  // namespace stokesian::forces
