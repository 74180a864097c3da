#include "engine/accuracy.hpp"

#include <algorithm>

namespace stokesian {

namespace {
// Factors measured with tests/test_sd_accelerated.cpp (96 cases, tolerances 1e-3..1e-8). Krylov:
// with the residual at 0.02 t the Krylov part of the error stays below 0.5 t (with 0.1 it reached
// 1.5 t: open phi 0.3 with fixed particles, FTS). Scenes without held particles take 0.1 t
// (kFreeKrylovFactor, 2026-11-29): over the 60 free cases of that sweep the worst error went from
// 0.20 t to 0.24 t (sheared phi 0.3, FTS, t = 1e-3; 0.40 t at 0.2) for 1-4 fewer iterations per
// solve (sheared phi 0.3 FTS at 1e-3: 23 -> 19). Far field: the PME meets its tolerance on the
// relative error of the whole product M x (tests/test_ewald.cpp), with the achieved error between
// t/10 and t since issue 12 (before, 10-100x below t). The SD errors are checked per block (U,
// Omega, S, holding forces): at far field t, periodic phi 0.45 with fixed particles reached 0.97 t,
// and in polydisperse suspensions the blocks of the large spheres, which the small spheres' larger
// mobilities hide in ||M x||, reached 4.5 t (sheared, radius ratio 4, stresslets ~ a^3). Asking the
// far field 0.25 t (a_min / a_max)^3 brings the worst case over the sweep to 0.32 t.
// Held (fixed) particles: their holding forces can be far smaller than the right-hand side (a wall
// of wall particles where the ambient flow vanishes, beside mobile spheres carrying forces), and
// the far-field error reaches them amplified: in a periodic slit at FT the holding forces' error
// was 1.4-1.6 t with the factor above and 0.13-0.19 t (one case 0.92 t) with a tenth of it
// (tests/test_sd_accelerated.cpp, "held-row preconditioner"). Their Krylov residual is refined by
// the solver itself (engine/sd_accelerated.hpp).
constexpr double kFarFieldFactor = 0.25;
constexpr double kHeldFarFieldFactor = 0.1;
}  // namespace

AccuracyKnobs derive_knobs(double t, HydroModel level, double radius_ratio, bool held_particles) {
  AccuracyKnobs k;
  const double r = radius_ratio > 1.0 ? radius_ratio : 1.0;
  const double held = held_particles ? kHeldFarFieldFactor : 1.0;
  // 1e-14: the tightest tolerance a far-field method accepts (the scene's own floor).
  k.far_field = level == HydroModel::stokesian ? std::max(1e-14, kFarFieldFactor * held * t / (r * r * r)) : t;
  k.krylov = (held_particles ? kKrylovFactor : kFreeKrylovFactor) * t;  // engine/accuracy.hpp
  k.mobility_cg = t;
  // The Brownian force's relative error enters the noise covariance as about twice itself (tested
  // against the dense sampler, tests/test_brownian.cpp).
  k.brownian = t;
  return k;
}

}  // namespace stokesian
