#include "engine/brownian.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/krylov.hpp"

#include <cmath>
#include <sstream>

namespace stokesian {

namespace {
// Lanczos cap for M^{-1/2} psi: it converges like CG on the well-conditioned far-field mobility,
// in tens of iterations; the cap only marks a failure.
constexpr int kLanczosCap = 300;
}  // namespace

std::vector<char> force_given_flags(Moments m, long n, const std::vector<char>& fixed) {
  const int d = dof_per_particle(m), dv = d > 6 ? 6 : d;
  std::vector<char> g(std::size_t(n * d), 0);
  for (long i = 0; i < n; ++i) {
    if (!fixed.empty() && fixed[std::size_t(i)]) continue;
    for (int k = 0; k < dv; ++k) g[std::size_t(i * d + k)] = 1;
  }
  return g;
}

VecX self_resistance(const std::vector<double>& a, double mu, Moments m) {
  const int d = dof_per_particle(m);
  VecX D(long(a.size()) * d);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double r = a[i], r3 = r * r * r;
    for (int c = 0; c < d; ++c)
      D[long(i) * d + c] = c < 3 ? 6.0 * kPi * mu * r : c < 6 ? 8.0 * kPi * mu * r3 : 20.0 / 3.0 * kPi * mu * r3;
  }
  return D;
}

VecX far_field_brownian_force(const MobilityOperator& M, const std::vector<char>& given, double scale,
                              double tol, Rng& rng, LanczosReport* report) {
  const long size = long(M.size());
  VecX psi(size), y;
  for (auto& v : psi) v = rng.normal();
  const LinearOperator A = [&M](const VecX& in, VecX& out) { M.apply(in, out); };
  const KrylovResult kr = lanczos_power(A, psi, y, -0.5, tol, kLanczosCap);
  if (report) report->iterations = kr.iterations;
  if (!kr.converged) {
    std::ostringstream o;
    o << "far-field Brownian force M^(-1/2) psi: the Lanczos iteration " << describe(kr) << " after "
      << kr.iterations << " iterations (last relative change " << kr.relative_residual << ", tolerance " << tol
      << ", cap " << kLanczosCap << ")";
    throw PhysicsError(o.str());
  }
  for (long q = 0; q < size; ++q) y[q] = given[std::size_t(q)] ? scale * y[q] : 0.0;
  return y;
}

}  // namespace stokesian
