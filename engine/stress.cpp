#include "engine/stress.hpp"

#include <stdexcept>

namespace stokesian {

std::vector<StressPart> bulk_stress(const StressInput& in) {
  if (!(in.volume > 0.0)) throw std::invalid_argument("bulk_stress: the volume must be positive (periodic box)");
  const double inv_v = 1.0 / in.volume;
  std::vector<StressPart> parts;
  parts.push_back({"fluid", 2.0 * in.viscosity * in.E});
  // The solve's stresslets are exerted on the fluid: S^H = -S (engine/stress.hpp).
  if (in.hydrodynamic) parts.push_back({"hydrodynamic", -inv_v * in.stresslet_mobile});
  if (in.interparticle) parts.push_back({"interparticle", -inv_v * in.virial});
  if (in.brownian)
    parts.push_back({"brownian", -(double(in.mobile) * inv_v * in.kT) * Mat3::Identity() - inv_v * in.brownian_stresslet});
  if (in.hydrodynamic && in.fixed) parts.push_back({"fixed", -inv_v * in.stresslet_fixed});
  Mat3 total = Mat3::Zero();
  for (const StressPart& p : parts) total += p.sigma;
  parts.push_back({"total", total});
  return parts;
}

}  // namespace stokesian
