#pragma once
// Ewald-summed periodic grand mobility, dense: the oracle for the PME far field.
//
// M = sum over lattice images of the real-space blocks + (1/V) sum_{k != 0} of the wave blocks
// + self correction, exactly as in ewald/ewald_split.hpp [docs/ewald.md (E6); cf. Beenakker 1986;
// Brady, Phillips, Lester & Bossis 1988]. The k = 0 term is dropped: the mean pressure
// gradient balances the net force on the suspension. Lees-Edwards: the images sit at
// n1 a1 + n2 a2 + n3 a3 with a2 = (gamma Ly, Ly, 0) and the wave vectors at k = B n
// (ewald/lattice.hpp). Both sums are taken to |r| < tail / xi and |k| < 2 xi tail, where every
// neglected term is below exp(-tail^2) times a polynomial (tail = 7.5: < 1e-22), so the result is
// converged to rounding and independent of xi (tested to 1e-13).
// Cost: O(N^2 (images + wave vectors)) with about 2 * (4 pi / 3) (tail / (xi V^(1/3)))^3 of each;
// meant for N up to a few hundred. The real-space blocks use the closed forms of
// mobility::fill_pair_block; the wave sum is one real matrix product Y Y^T with four columns per
// wave vector (ewald_reference.cpp), so it runs at dense matrix-product speed.
#include "engine/core/operators.hpp"
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian::ewald {

struct EwaldReferenceOptions {
  double xi = 0.0;    // splitting parameter [1/a]; 0 = sqrt(pi) / V^(1/3) (balanced sums)
  double tail = 7.5;  // xi r_max = k_max / (2 xi): truncation of both sums
  bool real = true;   // include the real-space sum and the self correction
  bool wave = true;   // include the wave-space sum
};

// Dense (dN x dN) periodic grand mobility, layout [F(3) T(3) S(5)] per particle.
MatX ewald_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                    const Domain& domain, const EwaldReferenceOptions& opt = {});
// Its block rows of the given particles (ascending): (d |rows|) x (d N), the same sums.
MatX ewald_mobility_rows(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                         const Domain& domain, const std::vector<long>& rows, const EwaldReferenceOptions& opt = {});

// Dense Ewald operator: the matrix is built on first use per configuration and kept while the
// configuration is unchanged (positions, radii, box and strain all equal), e.g. for repeated
// Brownian draws; dense_rows builds only the rows asked for.
class EwaldFarField final : public MobilityOperator {
 public:
  explicit EwaldFarField(const MobilitySpec& spec, const EwaldReferenceOptions& opt = {})
      : mu_(spec.viscosity), m_(spec.moments), opt_(opt) {}
  EwaldFarField(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m, const Domain& domain,
                const EwaldReferenceOptions& opt = {})
      : mu_(mu), m_(m), opt_(opt) {
    set_configuration({x, a, domain});
  }
  Moments moments() const override { return m_; }
  Eigen::Index size() const override { return Eigen::Index(config_.x.size()) * dof_per_particle(m_); }
  void set_configuration(const Configuration& c) override;
  bool set_configuration_uses_threads(long) const override { return true; }
  void apply(const VecX& in, VecX& out) const override { out.noalias() = matrix() * in; }
  const char* name() const override { return "ewald"; }
  const MatX* dense() const override { return &matrix(); }
  bool dense_rows(const std::vector<long>& particles, MatX& rows) const override;
  const MatX& matrix() const;

 private:
  double mu_;
  Moments m_;
  EwaldReferenceOptions opt_;
  StoredConfiguration config_;  // the configuration set
  mutable bool built_ = false;  // whether M_ belongs to it
  mutable MatX M_;
};

}  // namespace stokesian::ewald
