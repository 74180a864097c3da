#pragma once
// Far-field grand mobility M_inf of N spheres in an open domain (direct summation), and the
// free-draining (self-only) mobility.
//
// M_inf is assembled from the pair blocks of engine/kernels/mobility_pair.hpp. Implementations:
//   dense_mobility      - the reference: the full (dN x dN) matrix from the explicit tensors;
//   assemble_mobility   - the same matrix from the closed-form blocks (fill_pair_block), written
//                         in place, OpenMP over the block rows: the dense operator's fast path
//                         (equal to dense_mobility to round-off, tests/test_sd_dense_fast.cpp);
//   mobility_product    - matrix-free y = M x, O(N^2) work, OpenMP over the rows (each thread
//                         owns the output rows of its particles, so there are no write conflicts
//                         and the result does not depend on the thread count); separated pairs
//                         vectorised (direct_fast.cpp);
//   mobility_product_reference - its plain twin: one apply_pair per ordered pair.
// Vectors use the interleaved per-particle layout [F(3) T(3) S(5)] (engine/core/layout.hpp).
#include "engine/core/operators.hpp"
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian {

MatX dense_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m);

MatX assemble_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m);
// In place: M is resized (its storage reused when the size is unchanged).
void assemble_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m, MatX& M);
// The block rows of the given particles (ascending): rows is (d |particles|) x (d N).
void assemble_mobility_rows(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                            const std::vector<long>& particles, MatX& rows);

// y = M x (y is resized).
void mobility_product(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                      const VecX& in, VecX& out);
void mobility_product_reference(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                                const VecX& in, VecX& out);
// Which path mobility_product takes (tests): automatic (AVX2 + FMA when the CPU has them),
// baseline (the vectorised loop without AVX2), reference (mobility_product_reference).
enum class DirectKernels { automatic, baseline, reference };
void force_direct_kernels(DirectKernels k);

// Direct summation, open domains. Holds its own copy of the configuration.
class DirectFarField final : public MobilityOperator {
 public:
  explicit DirectFarField(const MobilitySpec& spec) : mu_(spec.viscosity), m_(spec.moments) {}
  DirectFarField(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m)
      : x_(x), a_(a), mu_(mu), m_(m) {}
  const char* name() const override { return "direct"; }
  Moments moments() const override { return m_; }
  Eigen::Index size() const override { return Eigen::Index(x_.size()) * dof_per_particle(m_); }
  void set_configuration(const Configuration& c) override;
  void apply(const VecX& in, VecX& out) const override { mobility_product(x_, a_, mu_, m_, in, out); }
  const MatX* dense() const override;  // assembled on first request per configuration
  bool dense_rows(const std::vector<long>& particles, MatX& rows) const override {
    assemble_mobility_rows(x_, a_, mu_, m_, particles, rows);
    return true;
  }

 private:
  std::vector<Vec3> x_;
  std::vector<double> a_;
  double mu_;
  Moments m_;
  mutable MatX dense_;
  mutable bool have_dense_ = false;
};

// Free draining: the self blocks only (1/(6 pi mu a) I, 1/(8 pi mu a^3) I, 3/(20 pi mu a^3) I),
// particles see no other particle.
class SelfMobility final : public MobilityOperator {
 public:
  explicit SelfMobility(const MobilitySpec& spec) : mu_(spec.viscosity), m_(spec.moments) {}
  const char* name() const override { return "self"; }
  Moments moments() const override { return m_; }
  Eigen::Index size() const override { return Eigen::Index(a_.size()) * dof_per_particle(m_); }
  void set_configuration(const Configuration& c) override { a_ = c.a; }
  void apply(const VecX& in, VecX& out) const override;
  const std::vector<double>& radii() const { return a_; }
  double viscosity() const { return mu_; }

 private:
  std::vector<double> a_;
  double mu_;
  Moments m_;
};

}  // namespace stokesian
