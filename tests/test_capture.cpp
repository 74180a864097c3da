// Two spheres in simple shear under the thesis's alumina DLVO forces (tests/support/capture.hpp,
// docs/capture.md): a head-on pair is captured and then orbits in the secondary minimum at the
// thesis's centre distance; a pair far off axis passes; the critical offset lies between and falls
// as the shear rate grows.
#include "support/capture.hpp"

#include <doctest/doctest.h>

using namespace stokesian;
using test_support::Outcome;
using test_support::run_pair;

TEST_CASE("DLVO capture in shear: captured near the axis at the secondary minimum, escaped far off it") {
  // Force scale F0 = 1 kT/a (docs/capture.md), gdot* = 8; lambda = 0.5 (minimum at r = 1.552).
  const auto near = run_pair(0.5, 8.0, 1.0, 0.5, 0.0);
  CHECK(near.outcome == Outcome::captured);
  CHECK(near.gap + 1.5 == doctest::Approx(1.552).epsilon(2e-3));  // orbiting in the secondary minimum
  CHECK(run_pair(0.5, 8.0, 1.0, 1.5, 0.0).outcome == Outcome::escaped);
  // Out of the shear plane (theta = pi/3) the same offset is captured as well.
  CHECK(run_pair(0.5, 8.0, 1.0, 0.5, M_PI / 3).outcome == Outcome::captured);
  // Stronger shear against the same well: an offset captured at gdot* = 8 passes at gdot* = 64.
  CHECK(run_pair(0.5, 8.0, 1.0, 0.8, 0.0).outcome == Outcome::captured);
  CHECK(run_pair(0.5, 64.0, 1.0, 0.8, 0.0).outcome == Outcome::escaped);
  // Equal spheres: minimum at r = 2.051.
  const auto eq = run_pair(1.0, 8.0, 1.0, 0.4, 0.0);
  CHECK(eq.outcome == Outcome::captured);
  CHECK(eq.gap + 2.0 == doctest::Approx(2.051).epsilon(2e-3));
}

TEST_CASE("DLVO capture in shear with the thesis's squeeze lubrication: head-on pairs are held at high shear too") {
  // The squeeze force acts on the particles' own relative velocity; were it applied to the velocity
  // relative to the ambient flow, the straining flow would pull every doublet out of the well at
  // gdot* = 64 (lubrication/squeeze.hpp). F0 = 0.667 kT/a, the squeeze model's calibration.
  const auto head_on = run_pair(1.0, 64.0, 0.667, 0.3, 0.0, "squeeze");
  CHECK(head_on.outcome == Outcome::captured);
  CHECK(head_on.gap + 2.0 == doctest::Approx(2.051).epsilon(2e-3));
  CHECK(run_pair(1.0, 64.0, 0.667, 1.2, 0.0, "squeeze").outcome == Outcome::escaped);
  const auto small = run_pair(0.5, 8.0, 0.667, 0.5, 0.0, "squeeze");
  CHECK(small.outcome == Outcome::captured);
  CHECK(small.gap + 1.5 == doctest::Approx(1.552).epsilon(2e-3));
}
