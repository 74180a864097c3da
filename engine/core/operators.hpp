#pragma once
// The far-field mobility as an operator: the interface every far-field method implements (direct
// summation, Ewald, PME, and next the octree), so that solvers, the Brownian square root and the
// conformance test see them alike.
//
//   y = M_inf x,  x = [F T S] per particle, y = [U Omega E] per particle (engine/core/layout.hpp),
//
// M_inf the grand mobility of the particles at one configuration. An operator is made once per
// run from a MobilitySpec (the method derives its own knobs from the tolerance) and moved to each
// new configuration with set_configuration, keeping whatever does not depend on it (parameters,
// grids, FFT plans, trees): the plan / set points / execute lifecycle.
#include "engine/core/domain.hpp"
#include "engine/core/types.hpp"

#include <vector>

namespace stokesian {

// Positions and radii of N spheres in a domain (borrowed: valid for the duration of a call).
struct Configuration {
  const std::vector<Vec3>& x;
  const std::vector<double>& a;
  const Domain& domain;
};

// An owned copy of a configuration, for objects that keep work between calls and must know
// whether a new configuration is the one they already hold.
struct StoredConfiguration {
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain domain;
  bool valid = false;
  bool same_as(const Configuration& c) const { return valid && x == c.x && a == c.a && domain == c.domain; }
  void store(const Configuration& c) {
    x = c.x;
    a = c.a;
    domain = c.domain;
    valid = true;
  }
};

struct MobilitySpec {
  Moments moments = Moments::F;
  double viscosity = 1.0;   // mu
  double tolerance = 1e-6;  // requested relative accuracy of products (methods with knobs)
  // Products expected per configuration (set_configuration): methods whose set-up costs about a
  // product weigh it by 1 / this when they choose their knobs (PME). 0 = price the product alone.
  // A cost hint only: the accuracy does not depend on it.
  double products_per_configuration = 0.0;
};

class MobilityOperator {
 public:
  virtual ~MobilityOperator() = default;
  virtual const char* name() const = 0;
  virtual Moments moments() const = 0;
  virtual Eigen::Index size() const = 0;
  // Moves the operator to configuration c (copies what it needs; c may go away afterwards).
  virtual void set_configuration(const Configuration& c) = 0;
  // out = M in (out is resized). Repeatable; one product at a time per object.
  virtual void apply(const VecX& in, VecX& out) const = 0;
  // The dense matrix when the method has it (reference methods); nullptr otherwise.
  virtual const MatX* dense() const { return nullptr; }
  // The rows of the dense matrix that belong to the given particles (ascending, distinct): rows is
  // set to (d |particles|) x (d N), row d k + c the entry c of particles[k], equal to those rows
  // of dense() up to round-off, without forming the rest. False when the method cannot.
  virtual bool dense_rows(const std::vector<long>& particles, MatX& rows) const {
    (void)particles;
    (void)rows;
    return false;
  }
  // Whether set_configuration for n particles runs OpenMP loops over every thread (the step's
  // task graph then runs it alone rather than beside other phases).
  virtual bool set_configuration_uses_threads(long n) const {
    (void)n;
    return false;
  }
};

}  // namespace stokesian
