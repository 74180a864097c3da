#pragma once
// Far-field grand mobility M_inf of N spheres in an open domain (direct summation).
//
// M_inf is assembled from the pair blocks of engine/mobility_pair.hpp. Two implementations:
//   dense_mobility      - the reference: the full (dN x dN) matrix from the explicit tensors;
//   mobility_product    - matrix-free y = M x, O(N^2) work, OpenMP over the rows (each thread
//                         owns the output rows of its particles, so there are no write conflicts
//                         and the result does not depend on the thread count).
// Vectors use the interleaved per-particle layout [F(3) T(3) S(5)] (engine/types.hpp).
#include "engine/types.hpp"

#include <vector>

namespace stokesian {

struct Particles {
  const std::vector<Vec3>& position;
  const std::vector<double>& radius;
};

MatX dense_mobility(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m);

// y = M x (y is resized).
void mobility_product(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m,
                      const VecX& in, VecX& out);

// Abstract far-field operator so that direct, tree and Ewald methods plug into the same solvers.
class FarFieldOperator {
 public:
  virtual ~FarFieldOperator() = default;
  virtual Moments moments() const = 0;
  virtual Eigen::Index size() const = 0;
  virtual void apply(const VecX& in, VecX& out) const = 0;  // out = M in
  virtual const char* name() const = 0;
};

class DirectFarField final : public FarFieldOperator {
 public:
  DirectFarField(const std::vector<Vec3>& x, const std::vector<double>& a, double mu, Moments m)
      : x_(x), a_(a), mu_(mu), m_(m) {}
  Moments moments() const override { return m_; }
  Eigen::Index size() const override { return Eigen::Index(x_.size()) * dof_per_particle(m_); }
  void apply(const VecX& in, VecX& out) const override { mobility_product(x_, a_, mu_, m_, in, out); }
  const char* name() const override { return "direct"; }

 private:
  const std::vector<Vec3>& x_;
  const std::vector<double>& a_;
  double mu_;
  Moments m_;
};

}  // namespace stokesian
