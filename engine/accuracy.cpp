#include "engine/accuracy.hpp"

namespace stokesian {

namespace {
// Factors measured with tests/test_sd_accelerated.cpp (96 cases, tolerances 1e-3..1e-8): with the
// far field at the scene's tolerance (PME's achieved error sits 10-100x below its request,
// tests/test_ewald.cpp) and the Krylov residual at 0.02 t, the largest achieved error was 0.52 t
// (periodic phi 0.45 with fixed particles, F, t = 1e-3); with a Krylov factor of 0.1 it reached
// 1.5 t (open phi 0.3 with fixed particles, FTS), so 0.02 keeps a margin of 2.
constexpr double kFarFieldFactor = 1.0;
constexpr double kKrylovFactor = 0.02;
}  // namespace

AccuracyKnobs derive_knobs(double t, HydroModel level) {
  AccuracyKnobs k;
  k.far_field = level == HydroModel::stokesian ? kFarFieldFactor * t : t;
  k.krylov = kKrylovFactor * t;
  k.mobility_cg = t;
  return k;
}

}  // namespace stokesian
