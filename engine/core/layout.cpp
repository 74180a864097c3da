#include "engine/core/layout.hpp"

namespace stokesian {

RigidConstraints RigidConstraints::of(Moments m, const std::vector<char>& fixed, const std::vector<Vec3>& F,
                                      const std::vector<Vec3>& T, const FlowSample& flow) {
  RigidConstraints c;
  c.moments = m;
  c.n = long(flow.u.size());
  const int d = dof_per_particle(m);
  c.force = VecX::Zero(c.n * d);
  c.motion = VecX::Zero(c.n * d);
  for (long i = 0; i < c.n; ++i) {
    const std::size_t s = std::size_t(i);
    const bool fx = !fixed.empty() && fixed[s];
    for (int k = 0; k < std::min(d, 6); ++k) {
      const long q = i * d + k;
      if (fx) {
        c.motion_given.push_back(q);
        c.motion[q] = k < 3 ? -flow.u[s][k] : -flow.omega[s][k - 3];
      } else {
        c.force_given.push_back(q);
        c.force[q] = k < 3 ? F[s][k] : (T.empty() ? 0.0 : T[s][k - 3]);
      }
    }
    for (int k = 6; k < d; ++k) {
      c.motion_given.push_back(i * d + k);
      c.motion[i * d + k] = -flow.E[s][k - 6];
    }
  }
  return c;
}

HydroResult unpack_solution(Moments m, const FlowSample& flow, const VecX& relative, const VecX& moments,
                            const std::vector<char>& fixed) {
  const int d = dof_per_particle(m);
  const std::size_t n = flow.u.size();
  HydroResult res;
  res.U.resize(n);
  res.F.resize(n);
  if (d > 3) {
    res.Omega.resize(n);
    res.T.resize(n);
  }
  if (d > 6) res.S.resize(n);
  for (std::size_t s = 0; s < n; ++s) {
    const long i = long(s);
    const bool fx = !fixed.empty() && fixed[s];
    res.F[s] = moments.segment<3>(i * d);
    res.U[s] = fx ? Vec3::Zero() : Vec3(relative.segment<3>(i * d) + flow.u[s]);
    if (d > 3) {
      res.T[s] = moments.segment<3>(i * d + 3);
      res.Omega[s] = fx ? Vec3::Zero() : Vec3(relative.segment<3>(i * d + 3) + flow.omega[s]);
    }
    if (d > 6) res.S[s] = moments.segment<5>(i * d + 6);
  }
  return res;
}

}  // namespace stokesian
