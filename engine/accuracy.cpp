#include "engine/accuracy.hpp"

namespace stokesian {

namespace {
// Safety factors measured with bench_asd's tolerance sweep (see engine/accuracy.hpp).
constexpr double kFarFieldFactor = 0.1;
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
