#pragma once
// Conventional Stokesian dynamics with dense linear algebra: the reference solver.
//
//   R = (M_inf)^{-1} + R_nf          [Durlofsky, Brady & Bossis 1987, eq. 2.17; Brady & Bossis 1988]
//
// with M_inf the far-field grand mobility (engine/far_field.hpp dense, or ewald/ewald_reference.hpp
// in periodic boxes) and R_nf the pairwise
// near-field correction (lubrication/near_field.hpp). In the generalised layout
// [F T S] = R [U - U_inf, Omega - Omega_inf, -E_inf]:
//   resistance problem: given velocities and E_inf -> F, T, S (one product with R);
//   mobility problem:   given F, T (mobile particles), U = Omega = 0 (fixed particles) and E_inf,
//     the unknown velocities V of the mobile particles solve R_vv V = f - R_vk k, where k holds
//     the known entries (-E_inf; zero velocities of fixed particles), and then the remaining
//     rows give S and the holding forces of fixed particles. R_vv is solved by dense Cholesky.
// O(N^3): meant for small N and as the oracle of the accelerated solver.
#include "engine/flow.hpp"
#include "engine/hydrodynamics.hpp"
#include "lubrication/near_field.hpp"

namespace stokesian {

class DenseStokesianDynamics {
 public:
  DenseStokesianDynamics(Moments m, double mu, const AmbientFlow& flow, lubrication::NearFieldParams p = {});

  // R = M_inf^{-1} + R_nf; M_inf direct (open domain) or Ewald-summed (periodic, Lees-Edwards).
  MatX resistance(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain = Domain{},
                  lubrication::NearFieldStats* stats = nullptr) const;

  HydroResult mobility_problem(const std::vector<Vec3>& x, const std::vector<double>& a, const std::vector<char>& fixed,
                               const std::vector<Vec3>& F, const std::vector<Vec3>& T, const Domain& domain = Domain{},
                               lubrication::NearFieldStats* stats = nullptr) const;

  // Given particle velocities (U, Omega relative to nothing: absolute) -> F, T, S.
  HydroResult resistance_problem(const std::vector<Vec3>& x, const std::vector<double>& a, const std::vector<Vec3>& U,
                                 const std::vector<Vec3>& Omega, const Domain& domain = Domain{}) const;

 private:
  Moments m_;
  double mu_;
  AmbientFlow flow_;
  lubrication::NearField near_;
};

}  // namespace stokesian
