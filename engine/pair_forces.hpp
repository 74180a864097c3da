#pragma once
// Conservative central pair forces between spheres i, j (radii a_i, a_j; units a, kT).
//
// Every law is a pair energy U(r; a_i, a_j) of the centre distance r = |r_ij|, r_ij = x_i - x_j
// (minimum image), with surface gap h = r - a_i - a_j. The force on i is
//   F_i = -dU/dr r_ij / r,   F_j = -F_i                                   ([L24] eq. 2.18)
// ([T] eq. 2.6 writes the same sum with n_ab pointing from a to b, i.e. with the opposite sign).
// The pair virial sum is W = sum_pairs r_ij (x) F_i. References [L24], [T]: README.md.
//
// Laws (a_eff = a_i a_j / (a_i + a_j)):
//  Morse ([L24] eq. 2.17): U = -V0 [2 e^{-kappa h} - e^{-2 kappa h}], for all h; minimum -V0 at
//    h = 0 and the same expression repels overlapping spheres ([L24] after eq. 2.18).
//  DLVO ([T] s.2.2.2; s.5.2.2 refers back to it): U = U_vdW + U_dl + U_Born with
//    U_vdW = -(A/6) [2 a_i a_j/(r^2 - (a_i+a_j)^2) + 2 a_i a_j/(r^2 - (a_i-a_j)^2)
//                    + ln((r^2 - (a_i+a_j)^2)/(r^2 - (a_i-a_j)^2))]        (Hamaker 1937)
//      dU_vdW/dr = 32 A a_i^3 a_j^3 r / (3 P^2 M^2), P = r^2 - (a_i+a_j)^2, M = r^2 - (a_i-a_j)^2,
//      and with t = 4 a_i a_j / M the bracket equals sum_{k>=3} (k-2)/(2k) t^k, summed for small t
//      where the closed form cancels. Limits: -A a_eff/(6h) as h -> 0, -16 A a_i^3 a_j^3/(9 r^6).
//    U_dl (Hogg, Healy & Fuerstenau 1966, constant potential, Debye-Hueckel) with equal surface
//      potentials psi_0 on both spheres; the bracket of [T] then reduces to 2 ln(1 + e^{-kappa h}):
//      U_dl = pi eps a_eff 2 psi0^2 * 2 ln(1 + e^{-kappa h}) = 2 Z a_eff ln(1 + e^{-kappa h}),
//      Z = 2 pi eps psi0^2 (PairForceParams::surface_potential, kT/a).
//    or, for kappa a > 10, the linear superposition form (Bell, Levine & McCartney 1970):
//      U_dl = 64 pi eps (kT/e)^2 tanh^2(e psi0/4kT) (a_i a_j / r) e^{-kappa h}
//           = 2 Z g (a_i a_j / r) e^{-kappa h},  g = [tanh(psi~/4)/(psi~/4)]^2, psi~ = e psi0/kT.
//    U_Born (Feke et al. 1984 as quoted in [T] s.2.2.2, n = 12), R = r/a_i, lambda = a_j/a_i,
//      s = sigma/a_i:  U_Born = A s^6/37800 * (1/R) * sum_{k=1..4} N_k(R)/D_k^7 with
//        D1 = R-1+lambda, N1 = -R^2 - 7(lambda-1)R - 6(lambda^2-7lambda+1)
//        D2 = R+1-lambda, N2 = -R^2 + 7(lambda-1)R - 6(lambda^2-7lambda+1)
//        D3 = R+1+lambda, N3 =  R^2 + 7(lambda+1)R + 6(lambda^2+7lambda+1)
//        D4 = R-1-lambda, N4 =  R^2 - 7(lambda+1)R + 6(lambda^2+7lambda+1)
//      (4 (n-8)!/(n-2)! = 1/37800); small-gap limit A sigma^6 a_eff / (1260 h^7).
//    Gap floor: for h < h_min (PairForceParams::min_gap) the DLVO sum is continued linearly,
//      U(h) = U(h_min) + U'(h_min)(h - h_min): the force stays finite and continuous (constant
//      below h_min) and remains the exact derivative of the energy. Overlap needs a Hertz law as
//      well ([T] eq. 2.7 pairs DLVO with Hertz contact in the same way).
//  Repulsion (the short-range force of hard-sphere SD rheology: Bossis & Brady 1984; Sierou &
//    Brady 2002; Banchio & Brady 2003): |F| = F0 (tau a) e^{-tau h} / (1 - e^{-tau h}), from
//    U = -F0 a ln(1 - e^{-tau h}), a = 1 the reference radius (so F0 is the published force scale
//    in kT/a and tau a the published dimensionless decay); |F| grows as F0 a / h at contact and
//    decays as F0 tau a e^{-tau h} beyond the range 1/tau. Below h_min (PairForceParams::min_gap) it continues linearly as DLVO does
//    (constant force F(h_min), also for overlaps).
//  Hertz: U = (2/5) k_H delta^{5/2}, dU/dr = -k_H delta^{3/2}, delta = a_i + a_j - r > 0, else 0.
//  Harmonic spring on the gap: U = (k/2) (h - h_0)^2, dU/dr = k (h - h_0), for all h (overlap
//    included); rest gap h_0 >= 0, so the rest centre distance is a_i + a_j + h_0 for every pair
//    (polydisperse pairs alike). The law acts on every pair closer than its cut-off (there are no
//    bonds): a dimer, or well separated groups. Cut and shift as below; the default cut-off is the
//    stretched gap where the spring holds kHarmonicCutoffEnergy above its minimum,
//    h_c = h_0 + sqrt(2 E_c / k), so that a thermal pair (Boltzmann weight e^{-E_c/kT}) never
//    reaches it.
//
// Cut-off (cut and shift): U_c(r) = U(r) - U(a_i + a_j + h_c) for h < h_c, 0 beyond; the force is
// the exact derivative of U_c below h_c and jumps by the (small) force at h_c. Default h_c keeps
// each term below kDefaultCutoffTolerance of its energy scale (default_cutoff).
#include "engine/core/scene.hpp"
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian::forces {

// Energy U [kT] and its derivative dU/dr [kT/a] at one centre distance.
struct EnergyDerivative {
  double U = 0.0;
  double dUdr = 0.0;
};

// ---- Components, unregularised: valid for h = r - a_i - a_j > 0 ----
EnergyDerivative vdw_hamaker(double r, double ai, double aj, double hamaker);
EnergyDerivative born_feke(double r, double ai, double aj, double hamaker, double sigma);
EnergyDerivative double_layer_hhf(double r, double ai, double aj, double Z, double kappa);
EnergyDerivative double_layer_lsa(double r, double ai, double aj, double Z, double kappa, double psi_reduced);

// ---- Evaluators: the formula only, (r, a_i, a_j) -> (U, dU/dr), no cut-off ----
// Each law also gives its default gap cut-off [a] for spheres up to radius a_max: the gap beyond
// which every term is below `tol` of its energy scale.
struct MorseLaw {
  double depth, kappa;  // V0 [kT], kappa [1/a]
  EnergyDerivative operator()(double r, double ai, double aj) const;
  double default_cutoff(double a_max, double tol) const;  // ln(2/tol)/kappa
};

struct DlvoLaw {  // includes the min-gap floor
  double hamaker, kappa, Z, psi_reduced, sigma, min_gap;
  PairForceParams::DoubleLayer double_layer;
  EnergyDerivative operator()(double r, double ai, double aj) const;
  EnergyDerivative unregularised(double r, double ai, double aj) const;
  // max(ln(1/tol)/kappa (double layer, relative to 2 Z a_eff), gap where |U_vdW(a_max, a_max)| =
  // tol A, 2 min_gap); Born is far shorter-ranged.
  double default_cutoff(double a_max, double tol) const;
};

struct HertzLaw {
  double stiffness;  // k_H [kT/a^{5/2}]
  EnergyDerivative operator()(double r, double ai, double aj) const;
  double default_cutoff(double, double) const { return 0.0; }  // contact only
};

// Energy above the minimum at the harmonic spring's default cut-off [kT].
constexpr double kHarmonicCutoffEnergy = 100.0;

struct HarmonicLaw {
  double stiffness, rest_gap;  // k [kT/a^2], h_0 [a]
  EnergyDerivative operator()(double r, double ai, double aj) const;
  double default_cutoff(double, double) const;  // h_0 + sqrt(2 kHarmonicCutoffEnergy / k)
};

struct RepulsionLaw {
  double strength, decay, min_gap;  // F0 [kT/a], tau [1/a], h_min [a]
  EnergyDerivative operator()(double r, double ai, double aj) const;
  double default_cutoff(double, double tol) const;  // ln(1/tol)/tau: there U ~ F0 a e^{-tau h} = tol F0 a
};

// Build the evaluators; throw std::invalid_argument for kappa <= 0, (DLVO) min_gap <= 0,
// (harmonic) stiffness <= 0, rest_gap < 0, or a positive cutoff not beyond rest_gap.
MorseLaw morse_law(const PairForceParams& p);
DlvoLaw dlvo_law(const PairForceParams& p);
HertzLaw hertz_law(const PairForceParams& p);
HarmonicLaw harmonic_law(const PairForceParams& p);
RepulsionLaw repulsion_law(const PairForceParams& p);  // strength >= 0, decay > 0, min_gap > 0

// The one dispatch from a law's parameters to its evaluator: f(law) with the law of p.kind.
template <class F>
decltype(auto) with_law(const PairForceParams& p, F&& f) {
  switch (p.kind) {
    case PairForceParams::Kind::morse: return f(morse_law(p));
    case PairForceParams::Kind::dlvo: return f(dlvo_law(p));
    case PairForceParams::Kind::harmonic: return f(harmonic_law(p));
    case PairForceParams::Kind::repulsion: return f(repulsion_law(p));
    case PairForceParams::Kind::hertz: break;
  }
  return f(hertz_law(p));
}

// Relative energy left at the default cut-off.
constexpr double kDefaultCutoffTolerance = 1e-4;

// Default gap cut-off [a] for spheres up to radius a_max (the law's default_cutoff at
// kDefaultCutoffTolerance).
double default_cutoff(const PairForceParams& p, double a_max);
// p.cutoff if positive, else default_cutoff. Hertz: max(p.cutoff, 0).
double resolved_cutoff(const PairForceParams& p, double a_max);

// One law as the pair loop applies it: shifted at the gap cut-off h_c, zero for h >= h_c.
EnergyDerivative pair_energy(const PairForceParams& p, double cutoff_gap, double r, double ai, double aj);

struct PairForceTotals {
  double energy = 0.0;            // sum over pairs of the shifted pair energies [kT]
  Mat3 virial = Mat3::Zero();     // sum over pairs of r_ij F_i^T [kT]
  // Per particle: half the virial of each of its pairs, sum_j (1/2) r_ij F_ij^T [kT] (sums to
  // `virial`), filled when `per_particle` is set.
  bool per_particle = false;
  std::vector<Mat3> particle_virial;
};

// Adds the forces of all laws on all pairs (one trees::neighbor_pairs search with the largest
// range) to `force` (resized to N if empty, else must have N entries); optionally accumulates
// energy and virial into *totals. Pairs with coincident centres get no force (no direction).
// Periodic boxes must be at least twice the largest interaction range (trees/neighbor_list.hpp).
// Deterministic: pair terms are evaluated in parallel into a buffer and summed serially.
void add_pair_forces(const std::vector<PairForceParams>& laws, const std::vector<Vec3>& x,
                     const std::vector<double>& radius, const Domain& domain, std::vector<Vec3>& force,
                     PairForceTotals* totals = nullptr);

}  // namespace stokesian::forces
