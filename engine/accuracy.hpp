#pragma once
// The one place where the scene's `[hydrodynamics] tolerance` becomes the knobs of every inner
// approximation (docs/accuracy.md). A solve's achieved error against the dense SD reference is
// tested to be at or below the requested tolerance (tests/test_sd_accelerated.cpp).
//
// With tolerance t the relative error e of an accelerated SD solve comes from
//   (a) the far-field products, relative error e_M <= far_field (the method's own promise: PME,
//       tests/test_ewald.cpp; exact for direct summation), amplified by the solve's sensitivity;
//   (b) the Krylov residual: |b - A W| <= krylov |b| on the row-scaled system of
//       engine/sd_accelerated.hpp, which is close to the identity, so the error in W is about the
//       residual times a modest condition number;
// and the measured amplification of both (bench/bench_asd.cpp, "tolerance sweep") sets the two
// factors below so that e <= t over the tested sweep (phi 0.1-0.5, gaps down to 1e-4 a, radius
// ratios to 10, F/FT/FTS, open/periodic/sheared, fixed particles).
#include "engine/core/scene.hpp"

namespace stokesian {

// The accelerated SD Krylov residual as a fraction of the tolerance (measured: engine/accuracy.cpp);
// the solver also uses it to recover the tolerance from its residual (engine/sd_accelerated.cpp).
inline constexpr double kKrylovFactor = 0.02;
// The same for scenes without held particles, whose residual maps onto the error without the held
// block's amplification (measured: engine/accuracy.cpp).
inline constexpr double kFreeKrylovFactor = 0.1;

struct AccuracyKnobs {
  double far_field = 1e-6;  // relative accuracy asked of far-field products (MobilitySpec::tolerance)
  double krylov = 1e-6;     // relative residual of the accelerated SD Krylov solve
  double mobility_cg = 1e-6;  // relative residual of the far-field constrained CG solve
  double brownian = 1e-6;     // relative change at which the Lanczos far-field Brownian force stops
};

// The knobs for a solve at `level` (far-field solves keep far_field = mobility_cg = tolerance,
// whose achieved error tests/test_mobility.cpp checks). radius_ratio = a_max / a_min of the
// particles (>= 1); held_particles: the scene has fixed particles (Stokesian dynamics then asks the
// far field a tenth more, engine/accuracy.cpp).
AccuracyKnobs derive_knobs(double tolerance, HydroModel level, double radius_ratio, bool held_particles);

}  // namespace stokesian
