#pragma once
// Basic types shared by every layer of the engine.
#include <Eigen/Dense>
#include "engine/core/random.hpp"

#include <cstddef>
#include <vector>

namespace stokesian {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;
using Rng = RandomStream;  // counter-based: a draw depends only on (seed, stream, index) (core/random.hpp)

constexpr double kPi = 3.14159265358979323846;

// Moments carried by each particle in a hydrodynamic solve (Durlofsky, Brady & Bossis 1987):
// F = force/velocity, FT = + torque/angular velocity, FTS = + stresslet/strain rate.
enum class Moments { F, FT, FTS };

// Degrees of freedom per particle in the interleaved layout [F(3) T(3) S(5)] used everywhere.
constexpr int dof_per_particle(Moments m) { return m == Moments::F ? 3 : (m == Moments::FT ? 6 : 11); }
constexpr bool has_torque(Moments m) { return m != Moments::F; }
constexpr bool has_stresslet(Moments m) { return m == Moments::FTS; }
const char* to_string(Moments m);

}  // namespace stokesian
