#include "engine/sd_dense.hpp"

#include "engine/errors.hpp"
#include "engine/far_field.hpp"
#include "ewald/ewald_reference.hpp"

#include <sstream>

namespace stokesian {

DenseStokesianDynamics::DenseStokesianDynamics(Moments m, double mu, const AmbientFlow& flow,
                                               lubrication::NearFieldParams p)
    : m_(m), mu_(mu), flow_(flow), near_(m, mu, p) {}

MatX DenseStokesianDynamics::resistance(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                                        lubrication::NearFieldStats* stats) const {
  const MatX M = domain.periodic() ? ewald::ewald_mobility(x, a, mu_, m_, domain) : dense_mobility(x, a, mu_, m_);
  Eigen::LLT<MatX> llt(M);
  if (llt.info() != Eigen::Success) throw PhysicsError("far-field mobility is not positive definite");
  MatX R = llt.solve(MatX::Identity(M.rows(), M.cols()));
  R += MatX(near_.assemble(x, a, domain, stats));
  return 0.5 * (R + R.transpose());
}

HydroResult DenseStokesianDynamics::mobility_problem(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                     const std::vector<char>& fixed, const std::vector<Vec3>& F,
                                                     const std::vector<Vec3>& T, const Domain& domain,
                                                     lubrication::NearFieldStats* stats) const {
  const int d = dof_per_particle(m_);
  const long n = long(x.size()), N = n * d;
  const MatX R = resistance(x, a, domain, stats);
  // Unknown velocity entries v (mobile particles' U, Omega) and known entries k.
  std::vector<long> v, k;
  VecX known = VecX::Zero(N), f = VecX::Zero(N);
  const Vec5 Einf = to_vec5(flow_.E);
  for (long i = 0; i < n; ++i) {
    const bool fx = !fixed.empty() && fixed[std::size_t(i)];
    for (int c = 0; c < std::min(d, 6); ++c) {
      const long q = i * d + c;
      if (fx) {
        k.push_back(q);  // velocity relative to the ambient flow is -u_inf (particle at rest)
        known[q] = c < 3 ? -flow_.velocity(x[std::size_t(i)])[c] : -flow_.Omega[c - 3];
      } else {
        v.push_back(q);
        f[q] = c < 3 ? F[std::size_t(i)][c] : (T.empty() ? 0.0 : T[std::size_t(i)][c - 3]);
      }
    }
    for (int c = 6; c < d; ++c) {
      k.push_back(i * d + c);
      known[i * d + c] = -Einf[c - 6];
    }
  }
  MatX Rvv(v.size(), v.size());
  VecX rhs(v.size());
  for (std::size_t p = 0; p < v.size(); ++p) {
    double s = f[v[p]];
    for (long q : k) s -= R(v[p], q) * known[q];
    rhs[long(p)] = s;
    for (std::size_t q = 0; q < v.size(); ++q) Rvv(long(p), long(q)) = R(v[p], v[q]);
  }
  Eigen::LLT<MatX> llt(Rvv);
  if (llt.info() != Eigen::Success) throw PhysicsError("SD resistance matrix is not positive definite");
  const VecX V = llt.solve(rhs);
  VecX gen = known;  // full generalised velocity [U - U_inf, Omega - Omega_inf, -E_inf]
  for (std::size_t p = 0; p < v.size(); ++p) gen[v[p]] = V[long(p)];
  return unpack_solution(m_, x, flow_, gen, R * gen, fixed);
}

HydroResult DenseStokesianDynamics::resistance_problem(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                       const std::vector<Vec3>& U, const std::vector<Vec3>& Omega,
                                                       const Domain& domain) const {
  const int d = dof_per_particle(m_);
  const long n = long(x.size());
  VecX gen = VecX::Zero(n * d);
  const Vec5 Einf = to_vec5(flow_.E);
  for (long i = 0; i < n; ++i) {
    const std::size_t s = std::size_t(i);
    gen.segment<3>(i * d) = U[s] - flow_.velocity(x[s]);
    if (d > 3) gen.segment<3>(i * d + 3) = (Omega.empty() ? Vec3::Zero() : Omega[s]) - flow_.Omega;
    if (d > 6) gen.segment<5>(i * d + 6) = -Einf;
  }
  const VecX FTS = resistance(x, a, domain) * gen;
  HydroResult res;
  res.U = U;
  res.Omega = Omega;
  for (long i = 0; i < n; ++i) {
    res.F.push_back(FTS.segment<3>(i * d));
    if (d > 3) res.T.push_back(FTS.segment<3>(i * d + 3));
    if (d > 6) res.S.push_back(FTS.segment<5>(i * d + 6));
  }
  return res;
}

}  // namespace stokesian
