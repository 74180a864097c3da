#pragma once
// A sphere beside walls of wall particles (issue 17), shared by the CI test (tests/test_channel.cpp)
// and the validation (bench/validate_slit.cpp): the flat-wall references and the constrained solve.
//   Faxen's parallel series      mu_par / mu_0  = 1 - 9/16 xi + 1/8 xi^3 - 45/256 xi^4 - 1/16 xi^5
//   Brenner's perpendicular one  mu_perp / mu_0 = 1 - 9/8 xi + 1/2 xi^3 (leading terms)
// xi = a / z, z the centre's distance from the wall's boundary plane (method note, validation 7).
#include "engine/hydrodynamics.hpp"

#include <cmath>
#include <vector>

namespace stokesian::test_support {

inline double faxen_parallel(double xi) {
  return 1 - 9.0 / 16 * xi + std::pow(xi, 3) / 8 - 45.0 / 256 * std::pow(xi, 4) - std::pow(xi, 5) / 16;
}
inline double brenner_perpendicular(double xi) { return 1 - 9.0 / 8 * xi + 0.5 * std::pow(xi, 3); }

// One sphere (radius 1) at centre x among the held wall particles (radius 1), pushed along axis d
// by the force 6 pi mu a (mu = 1): the sphere's velocity component d is its mobility in units of
// 1/(6 pi mu a). The sphere is the last particle of the result.
inline HydroResult sphere_among_walls(Hydrodynamics& h, const std::vector<Vec3>& walls, const Vec3& x, int d) {
  std::vector<Vec3> pos = walls;
  pos.push_back(x);
  std::vector<double> a(pos.size(), 1.0);
  std::vector<char> fixed(pos.size(), 1);
  fixed.back() = 0;
  std::vector<Vec3> F(pos.size(), Vec3::Zero()), T(pos.size(), Vec3::Zero());
  F.back()[d] = 6 * kPi;
  return h.solve(pos, a, fixed, F, T);
}

}  // namespace stokesian::test_support
