#pragma once
// PME-style periodic far field: y = M x in O(N log N), M the Ewald-summed grand mobility of
// ewald_reference.hpp (Hasimoto split, truncated Faxen factors in the wave part, exact
// overlap-regularised kernel kept in the real part).
//
// Product, per call [docs/ewald.md s.3; cf. Sierou & Brady 2001; Lindbo & Tornberg 2010]:
//   wave part: spread the force density of F, T, S with the window and its gradient (3 grid fields
//              for every moment level, spread.hpp), 3D FFT, Oseen multiply and deconvolution
//              (kernel.hpp), inverse FFT, interpolate U and the velocity gradient (rotation, strain)
//              with the same windows (interpolate.hpp);
//   real part: sum over pairs with |r| < cutoff_gap + a_i + a_j of the real-space blocks
//              (ewald_split.hpp) plus the self part M_self_free - wave(r = 0) per particle
//              (real_space.hpp: cell-sorted pairs, tabulated scalars).
// FFTs: the 3D transform is split into 2D transforms of the direction-0 planes and 1D transforms of
// fixed blocks of direction-0 columns, each planned once (FFTW_ESTIMATE) and distributed over the
// OpenMP threads; every sub-transform is computed by the same plan whatever the thread count.
// Everything that depends only on the configuration (windows, slab colouring, pair scalars, FFTW
// plans, kernel factors) is prepared by set_configuration (or the configuration constructor):
// parameters, grid, plans and kernel factors are kept while particles, radii, box and strain are
// unchanged. apply() is then repeatable and its result is independent of the number of OpenMP
// threads. apply() uses work arrays owned by the object: one product at a time per object (it
// parallelises internally). Construct objects from one thread at a time (FFTW planning is not
// thread-safe). All parameters come from the tolerance (pme_parameters.hpp).
// Lees-Edwards: the grid lives on fractional coordinates of the sheared lattice (lattice.hpp) and
// the kernel uses the sheared reciprocal vectors; the strain is reduced first, so the operator is
// exactly periodic in the strain.
#include "engine/core/operators.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "ewald/lattice.hpp"
#include "ewald/pme_parameters.hpp"
#include "ewald/kernel.hpp"
#include "ewald/real_space.hpp"
#include "ewald/spread.hpp"

#include <memory>
#include <vector>

namespace stokesian::ewald {

class PmeFarField final : public MobilityOperator {
 public:
  // Without a configuration: call set_configuration before apply.
  explicit PmeFarField(const MobilitySpec& spec, const PmeOptions& opt = {});
  PmeFarField(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m, const Domain& domain,
              double tolerance, const PmeOptions& opt = {});
  ~PmeFarField() override;
  PmeFarField(const PmeFarField&) = delete;
  PmeFarField& operator=(const PmeFarField&) = delete;

  Moments moments() const override { return m_; }
  Eigen::Index size() const override { return Eigen::Index(n_) * dof_per_particle(m_); }
  void apply(const VecX& in, VecX& out) const override;
  const char* name() const override { return "pme"; }
  void set_configuration(const Configuration& c) override;
  bool set_configuration_uses_threads(long) const override { return true; }

  // New positions, same particles, radii, box and strain: keeps the parameters, grid and FFTW plans
  // and rebuilds windows, slab colouring and real-space pairs (the result equals a new object's).
  void update_positions(const std::vector<Vec3>& x);

  const PmeParameters& parameters() const { return p_; }
  std::size_t real_pairs() const { return real_.pairs(); }

  // The three parts separately (out is overwritten), for tests and timing.
  void apply_wave(const VecX& in, VecX& out) const;
  void apply_real(const VecX& in, VecX& out) const;  // real space + self

 private:
  void build(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain);
  void set_windows(const std::vector<Vec3>& x);
  void set_lattice();  // lattice, window derivatives' metric and Fourier kernel for domain_
  struct Fft;
  long n_;
  double mu_;
  Moments m_;
  double tolerance_;
  PmeOptions options_;
  Domain domain_;
  Lattice lattice_;
  PmeParameters p_;
  GridGeometry grid_;
  ParticleWindows windows_;
  SlabColouring colouring_;
  RealSpaceSum real_;
  std::vector<double> radius_;
  FourierKernel kernel_;
  std::unique_ptr<Fft> fft_;
};

}  // namespace stokesian::ewald
