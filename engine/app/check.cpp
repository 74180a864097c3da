#include "engine/app/check.hpp"

#include "engine/inflow.hpp"

#include "engine/app/run.hpp"

#include "engine/core/channel.hpp"
#include "engine/core/outline.hpp"
#include "engine/core/output.hpp"
#include "engine/observers.hpp"
#include "engine/pair_forces.hpp"
#include "engine/resources.hpp"
#include "lubrication/near_field.hpp"
#include "trees/neighbor_list.hpp"
#include "trees/placement.hpp"
#include "trees/walls.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace stokesian::app {

namespace {
// Steps' worth of evaluations the cost measurement runs: the first evaluation, then runs of 1, 1 and
// 3 steps, each with one extra final evaluation.
constexpr int kMeasuredEvaluations = 9;
}  // namespace

namespace {

// Per integrator: evaluations of the velocities per (accepted) step and the stability bound of
// m_rel k dt on the negative real axis (0 = adaptive, no fixed bound).
struct IntegratorCost {
  const char* name;
  int evaluations;
  double stability;
};
// fixman: the solve at x0 again with the Brownian force (set-up reused) and one at the midpoint;
// its deterministic part is the explicit midpoint rule (stable for m_rel k dt <= 2).
constexpr IntegratorCost kIntegratorCosts[] = {
    {"euler", 1, 2.0}, {"midpoint", 2, 2.0}, {"fixman", 3, 2.0}, {"rkf45", 6, 0.0}};

const IntegratorCost* integrator_cost(const std::string& name) {
  for (const auto& c : kIntegratorCosts)
    if (name == c.name) return &c;
  return nullptr;
}

double summed_dUdr(const std::vector<PairForceParams>& laws, double a_max, double r, double ai, double aj) {
  double d = 0.0;
  for (const auto& p : laws) d += forces::pair_energy(p, forces::resolved_cutoff(p, a_max), r, ai, aj).dUdr;
  return d;
}

double summed_U(const std::vector<PairForceParams>& laws, double a_max, double r, double ai, double aj) {
  double u = 0.0;
  for (const auto& p : laws) u += forces::pair_energy(p, forces::resolved_cutoff(p, a_max), r, ai, aj).U;
  return u;
}

double max_cutoff(const std::vector<PairForceParams>& laws, double a_max) {
  double h = 0.0;
  for (const auto& p : laws) h = std::max(h, forces::resolved_cutoff(p, a_max));
  return h;
}

// Relative mobility of spheres ai, aj along their line of centres at gap h (see check.hpp).
double relative_mobility(const Scene& scene, const ResolvedModel& model, double h, double ai, double aj) {
  const double mu = scene.fluid.viscosity;
  const double m_stokes = 1.0 / (6 * kPi * mu * ai) + 1.0 / (6 * kPi * mu * aj);
  if (model.level == HydroModel::free_draining) return m_stokes;
  // Far field: minus twice the Rotne-Prager-Yamakawa pair mobility along the line of centres,
  // 1/(4 pi mu r) [1 - (a_i^2 + a_j^2)/(3 r^2)], taken at contact for overlapping pairs (its
  // regularised form decreases further with overlap, so the contact value is the upper bound).
  const double r = h + ai + aj;
  const double rc = std::max(r, ai + aj);
  const double m_far = m_stokes - 2.0 / (4 * kPi * mu * rc) * (1 - (ai * ai + aj * aj) / (3 * rc * rc));
  if (model.level != HydroModel::stokesian) return m_far;
  if (2 * r / (ai + aj) >= lubrication::near_field_params(scene.hydro, model.moments).cutoff) return m_far;
  if (scene.hydro.lubrication == Lubrication::squeeze)
    return 1.0 / (1.0 / m_far + lubrication::squeeze_coefficient(h, ai, aj, mu, scene.hydro.squeeze));
  const double h_floor = scene.hydro.lubrication_min_gap * (ai + aj) / 2;
  const double a_eff = ai * aj / (ai + aj);
  return 1.0 / (1.0 / m_far + 6 * kPi * mu * a_eff * a_eff / std::max(h, h_floor));
}

// Wall contact (docs/channels.md, "Contact with wall particles"). Fixed particles see no ambient
// flow, so a sphere touching one is carried against it at the fluid's speed there, U_c, whatever
// the gap; with exact lubrication the approach resistance is capped at the floor h_f, so stopping
// the sphere takes a contact force of about F = 6 pi mu a_eff^2 U_c / h_f (a_eff = a a_w/(a + a_w),
// h_f = lubrication_min_gap (a + a_w)/2). U_c: the largest ambient speed at the six points one
// contact distance from each fixed particle along +-x, +-y, +-z (channel flows are zero outside the
// fluid, so only the points on the fluid side count).
struct WallContact {
  bool applies = false;
  double speed = 0.0;  // U_c [a/time]
  double force = 0.0;  // F [kT/a] at the scene's floor
  double force_at_1e2 = 0.0;  // F with lubrication_min_gap = 1e-2 (the fouling configs)
};

WallContact wall_contact(const Scene& scene, const ResolvedModel& model) {
  WallContact w;
  if (model.level != HydroModel::stokesian || scene.hydro.lubrication != Lubrication::exact ||
      scene.flow.kind == FlowParams::Kind::none)
    return w;
  double a_in = 0.0, a_w = 0.0;
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < scene.positions.size(); ++i)
    if (!scene.fixed[i]) a_in = std::max(a_in, scene.radii[i]);
  for (std::size_t i = 0; i < scene.positions.size(); ++i) {
    if (!scene.fixed[i]) continue;
    a_w = std::max(a_w, scene.radii[i]);
    for (int d = 0; d < 3; ++d)
      for (double sgn : {-1.0, 1.0}) pts.push_back(scene.positions[i] + sgn * (scene.radii[i] + a_in) * Vec3::Unit(d));
  }
  if (pts.empty() || a_in <= 0.0) return w;
  const auto field = make_ambient_field(scene.flow, scene.walls, scene.domain);
  FlowSample fs;
  field->sample(pts, fs);
  for (const Vec3& u : fs.u) w.speed = std::max(w.speed, u.norm());
  if (w.speed <= 0.0) return w;
  w.applies = true;
  const double a_eff = a_in * a_w / (a_in + a_w);
  const double drag = 6 * kPi * scene.fluid.viscosity * a_eff * a_eff * w.speed;
  w.force = drag / (scene.hydro.lubrication_min_gap * (a_in + a_w) / 2);
  w.force_at_1e2 = drag / (1e-2 * (a_in + a_w) / 2);
  return w;
}

std::string vec(const Vec3& v) {
  char b[96];
  std::snprintf(b, sizeof b, "(%.6g, %.6g, %.6g)", v.x(), v.y(), v.z());
  return b;
}

// Discards frames and checkpoints (cost measurement).
class NullSink final : public OutputSink {
 public:
  void record(const Frame&) override {}
  void checkpoint(const State&) override {}
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string duration(double s) {
  char b[64];
  if (s < 120) std::snprintf(b, sizeof b, "%.3g s", s);
  else if (s < 7200) std::snprintf(b, sizeof b, "%.3g min", s / 60);
  else if (s < 172800) std::snprintf(b, sizeof b, "%.3g h", s / 3600);
  else std::snprintf(b, sizeof b, "%.3g days", s / 86400);
  return b;
}

}  // namespace

std::vector<Overlap> initial_overlaps(const Scene& scene) {
  std::vector<Overlap> out;
  const auto& x = scene.positions;
  const auto& a = scene.radii;
  for (const auto& p : trees::nearest_image_pairs(x, a, scene.domain, 0.0)) {
    const double h = p.dist - a[std::size_t(p.i)] - a[std::size_t(p.j)];
    if (h < 0) out.push_back({p.i, p.j, h});
  }
  return out;
}

std::vector<OutsideBox> outside_box(const Scene& scene) {
  std::vector<OutsideBox> out;
  if (!scene.domain.periodic()) return out;
  for (std::size_t i = 0; i < scene.positions.size(); ++i) {
    const Vec3& x = scene.positions[i];
    bool inside = true;
    for (int c = 0; c < 3; ++c) inside = inside && x[c] >= 0.0 && x[c] < scene.domain.box[c];
    if (inside) continue;
    Vec3 w = x;
    scene.domain.wrap(w);
    out.push_back({int(i), x, w});
  }
  return out;
}

double pair_stiffness(const std::vector<PairForceParams>& laws, double a_max, double r, double ai, double aj) {
  const double e = 1e-7 * std::max(r, 1e-3);
  return (summed_dUdr(laws, a_max, r + e, ai, aj) - summed_dUdr(laws, a_max, r - e, ai, aj)) / (2 * e);
}

StiffnessBound stiffness_bound(const Scene& scene, const ResolvedModel& model) {
  StiffnessBound b;
  const auto& laws = scene.forces.pair;
  if (laws.empty()) {
    b.reason = "no pair forces";
    return b;
  }
  const IntegratorCost* ic = integrator_cost(model.integrator);
  if (!ic || ic->stability <= 0) {
    b.reason = "integrator " + model.integrator + " adapts its step";
    return b;
  }
  const auto [amin_it, amax_it] = std::minmax_element(scene.radii.begin(), scene.radii.end());
  const double amin = *amin_it, amax = *amax_it;
  const double h_top = max_cutoff(laws, amax);

  // Largest external force on one particle (the load that can press a pair together), and the
  // Stokes drag of the ambient flow's velocity difference across a pair at contact.
  double f_ext = 0.0;
  for (const Vec3& f : scene.forces.external_force) f_ext = std::max(f_ext, f.norm());
  if (scene.flow.kind == FlowParams::Kind::poiseuille && scene.walls.kind == ChannelParams::Kind::outline) {
    // The largest shear rate of the solved outline flow, over its grid nodes.
    const auto field = make_ambient_field(scene.flow, scene.walls, scene.domain);
    const auto& tf = dynamic_cast<const TabulatedFlow&>(*field);
    const FlowGrid& g = *scene.flow.grid;
    double rate = 0.0;
    for (double x : g.axis[0])
      for (double y : g.axis[1]) {
        Mat3 G;
        tf.velocity(Vec3(x, y, 0.0), &G);
        rate = std::max(rate, G.norm());
      }
    f_ext += 6 * kPi * scene.fluid.viscosity * amax * rate * 2 * amax;
  } else if (scene.flow.kind == FlowParams::Kind::poiseuille) {
    // The largest shear rate of a channel flow is at its walls: G H / (2 mu) (for a duct, bounded by
    // that of the slit of the same mean velocity and height times the duct's larger G).
    const ChannelFlow cf(scene.walls, scene.domain, scene.flow.mean_velocity);
    f_ext += 6 * kPi * scene.fluid.viscosity * amax * std::abs(cf.pressure_gradient_over_viscosity()) * 0.5 *
             scene.walls.height * 2 * amax;
  } else if (scene.flow.kind != FlowParams::Kind::none) {
    f_ext += 6 * kPi * scene.fluid.viscosity * amax * std::abs(scene.flow.rate) * 2 * amax;
  }
  // Smallest initial gap.
  double h0 = std::numeric_limits<double>::infinity();
  for (const auto& o : initial_overlaps(scene)) h0 = std::min(h0, o.gap);
  if (!std::isfinite(h0)) {
    const GapStats g = gap_statistics(scene.positions, scene.radii, scene.domain);
    h0 = g.min_gap;
  }

  const double radius_pairs[3][2] = {{amin, amin}, {amin, amax}, {amax, amax}};
  double worst = 0.0;  // largest k m_rel
  b.h_hi = h_top;
  b.h_lo = 0.0;
  bool first = true;
  for (const auto& rp : radius_pairs) {
    const double ai = rp[0], aj = rp[1];
    // Gap grid: uniform over [h_bottom, h_top] plus logarithmic points on both sides of contact.
    const double h_bottom = std::min(-0.5 * std::min(ai, aj), std::isfinite(h0) ? h0 : 0.0);
    std::vector<double> grid;
    const int nu = 4000;
    for (int k = 0; k <= nu; ++k) grid.push_back(h_bottom + (h_top - h_bottom) * k / nu);
    const double span = std::max(h_top, -h_bottom);
    for (int k = 0; k <= 600; ++k) {
      const double h = 1e-7 * std::pow(span / 1e-7, k / 600.0);
      grid.push_back(h);
      grid.push_back(-h);
    }
    if (std::isfinite(h0)) grid.push_back(h0);
    // Stay clear of the cut-off, where the shifted force jumps.
    const double h_max = h_top > 0 ? h_top * (1 - 1e-6) - 1e-9 : 0.0;
    grid.erase(std::remove_if(grid.begin(), grid.end(), [&](double h) { return h < h_bottom || h > h_max; }),
               grid.end());
    std::sort(grid.begin(), grid.end(), std::greater<double>());

    // Largest attraction over the range (pulls pairs together) and the energy minimum.
    double attraction = 0.0, u_min = std::numeric_limits<double>::infinity();
    for (double h : grid)
      if (h >= 0) {
        attraction = std::max(attraction, summed_dUdr(laws, amax, h + ai + aj, ai, aj));
        u_min = std::min(u_min, summed_U(laws, amax, h + ai + aj, ai, aj));
      }
    if (!std::isfinite(u_min)) u_min = 0.0;
    const double drive = f_ext + attraction;
    // Descend from contact until the repulsion balances the drive (and, with kT, the energy
    // climbed above the well reaches 10 kT).
    const auto reached = [&](double h) {
      const double r = h + ai + aj;
      const bool force_ok = -summed_dUdr(laws, amax, r, ai, aj) >= drive;
      const bool energy_ok = scene.fluid.kT <= 0 || summed_U(laws, amax, r, ai, aj) - u_min >= 10 * scene.fluid.kT;
      return force_ok && energy_ok;
    };
    double h_lo = h_bottom, above = 0.0;
    for (double h : grid) {
      if (h > 0) continue;
      if (reached(h)) {
        h_lo = h;
        // Refine between this grid point and the one above it (where the balance was not reached).
        if (h < 0)
          for (int it = 0; it < 60; ++it) {
            const double mid = 0.5 * (h_lo + above);
            (reached(mid) ? h_lo : above) = mid;
          }
        break;
      }
      above = h;
    }
    if (std::isfinite(h0)) h_lo = std::min(h_lo, h0);
    grid.push_back(h_lo);
    for (double h : grid) {
      if (h < h_lo) continue;
      const double r = h + ai + aj;
      const double k = pair_stiffness(laws, amax, r, ai, aj);
      const double m = relative_mobility(scene, model, h, ai, aj);
      if (first || k * m > worst) {
        first = false;
        worst = k * m;
        b.k = k;
        b.m_rel = m;
        b.gap = h;
        b.ai = ai;
        b.aj = aj;
      }
    }
    b.h_lo = std::min(b.h_lo, h_lo);
  }
  if (worst <= 0) {
    b.reason = "no restoring stiffness in the gap range reached";
    return b;
  }
  b.applies = true;
  b.dt_max = ic->stability / worst;
  return b;
}

DisplacementBound displacement_bound(const Scene& scene, const std::vector<Vec3>& u) {
  DisplacementBound d;
  const AmbientFlow flow = ambient_flow(scene.flow);
  for (const auto& p : trees::nearest_image_pairs(scene.positions, scene.radii, scene.domain, 1.0)) {
    const std::size_t i = std::size_t(p.i), j = std::size_t(p.j);
    const double h = p.dist - scene.radii[i] - scene.radii[j];
    if (h <= 0 || p.dist <= 0) continue;
    // d|r_ij|/dt = (U_i - U_j') . r_ij / |r_ij|, j' the image of j nearest to i (r_ij = x_i - x_j'):
    // in a sheared (Lees-Edwards) box an image moves with the ambient flow at its offset, so
    // U_j' = U_j + u_inf(x_j' - x_j). A pair closes when this is negative.
    const Vec3 offset = scene.positions[i] - p.r - scene.positions[j];
    const Vec3 uj = u[j] + (scene.domain.periodic() ? flow.velocity(offset) : Vec3::Zero());
    const double closing = -(u[i] - uj).dot(p.r) / p.dist;
    if (closing <= 0) continue;
    const double dt = 0.1 * h / closing;
    if (d.pair_i < 0 || dt < d.dt_max) {
      d.pair_i = p.i;
      d.pair_j = p.j;
      d.gap = h;
      d.closing_speed = closing;
      d.dt_max = dt;
    }
  }
  return d;
}

int check(Simulation& sim, const CheckOptions& opt, std::FILE* out) {
  const Scene& s = sim.scene();
  const ResolvedModel& model = sim.model();
  const std::size_t n = s.positions.size();
  const auto [amin, amax] = std::minmax_element(s.radii.begin(), s.radii.end());
  double vol = 0;
  for (double a : s.radii) vol += 4.0 / 3.0 * kPi * a * a * a;
  std::fprintf(out, "scene: %s\n", s.source.c_str());
  std::fprintf(out, "particles: %zu (radii %.4g to %.4g a", n, *amin, *amax);
  const long nfixed = std::count(s.fixed.begin(), s.fixed.end(), 1);
  if (nfixed) std::fprintf(out, ", %ld fixed", nfixed);
  std::fprintf(out, ")\n");
  if (s.walls.any()) {
    double vin = 0;
    for (std::size_t i = 0; i < s.interior_count(); ++i) vin += 4.0 / 3.0 * kPi * std::pow(s.radii[i], 3);
    std::fprintf(out, "walls: %s, %zu wall particles of radius %.4g a (gap %.4g a, %ld layer%s, thickness %.4g a)",
                 name_of(s.walls.kind), s.wall_count, s.walls.radius, s.walls.gap, s.walls.layers,
                 s.walls.layers > 1 ? "s" : "", wall_thickness(s.walls));
    if (s.walls.kind == ChannelParams::Kind::outline) {
      const Outline o = make_outline(s.walls);
      std::fprintf(out, ", outline of %zu edges enclosing %.4g a^2, inlet edge %ld (width %.4g a), monolayer depth %.4g a",
                   o.edges(), o.area, o.inlet, o.length(std::size_t(o.inlet)), s.walls.depth);
    } else if (s.walls.kind != ChannelParams::Kind::plane) {
      std::fprintf(out, ", height %.4g a", s.walls.height);
    }
    if (s.walls.kind == ChannelParams::Kind::duct) std::fprintf(out, ", width %.4g a", s.walls.width);
    std::fprintf(out, "\n  %zu interior particles", s.interior_count());
    if (s.domain.periodic() && s.walls.kind != ChannelParams::Kind::plane)
      std::fprintf(out, ", volume fraction %.4g of the fluid region", vin / fluid_volume(s.walls, s.domain.box));
    const double area = cross_section_area(s.walls, s.domain);
    if (area > 0) std::fprintf(out, "; cross-section %.4g a^2 (pressure_drop_particles)", area);
    std::fprintf(out, "\n");
    if (s.walls.kind == ChannelParams::Kind::outline) {
      // The channels of pressure_drop_branches and areal_fraction_branches (engine/core/outline.hpp).
      const Outline o = make_outline(s.walls);
      const OutlineBranches br = outline_branches(o);
      for (std::size_t b = 0; b < br.branch.size(); ++b) {
        const OutlineBranch& B = br.branch[b];
        std::fprintf(out, "  branch %zu (pressure_drop_branches, areal_fraction_branches [%zu]): opening%s", b, b,
                     B.openings.size() > 1 ? "s" : "");
        for (std::size_t k = 0; k < B.openings.size(); ++k) std::fprintf(out, "%s%zu", k ? ", " : " ", B.openings[k]);
        std::fprintf(out, ", flow along (%.3g, %.3g), width %.4g a, fluid area %.4g a^2\n", B.direction.x(),
                     B.direction.y(), B.width, B.area);
      }
    }
    if (s.inflow.enabled) {
      const Inflow in(s);
      std::fprintf(out,
                   "inflow: areal fraction %.4g of spheres of radius %.4g a through the inlet at %.4g particles/time "
                   "(%.4g per step), %zu slots; particles leave through the openings (engine/inflow.hpp)\n",
                   s.inflow.areal_fraction, s.inflow.radius, in.rate(), in.rate() * s.time.dt, in.slots());
    }
  }
  if (s.domain.periodic())
    std::fprintf(out, "domain: periodic box %.4g x %.4g x %.4g a, volume fraction %.4g%s\n", s.domain.box.x(),
                 s.domain.box.y(), s.domain.box.z(), vol / s.domain.box.prod(), s.walls.any() ? " (walls included)" : "");
  else
    std::fprintf(out, "domain: open\n");
  const IntegratorCost* ic = integrator_cost(model.integrator);
  std::fprintf(out, "time: %lld steps of dt = %.4g, from step %lld (t = %.4g) to step %lld (t = %.4g)\n",
               static_cast<long long>(s.time.steps), s.time.dt, static_cast<long long>(s.time.start_step),
               s.time.start_time, static_cast<long long>(s.time.last_step()),
               s.time.start_time + double(s.time.steps) * s.time.dt);
  std::fprintf(out, "%s\n", model.describe().c_str());

  // Forces.
  std::fprintf(out, "forces:\n");
  auto largest = [](const std::vector<Vec3>& v) {
    double m = 0;
    for (const Vec3& f : v) m = std::max(m, f.norm());
    return m;
  };
  if (s.forces.external_force.empty()) std::fprintf(out, "  external force: none\n");
  else if (s.forces.external_force.size() == 1)
    std::fprintf(out, "  external force: %s kT/a on every particle\n", vec(s.forces.external_force[0]).c_str());
  else
    std::fprintf(out, "  external force: per particle, largest |F| = %.4g kT/a\n", largest(s.forces.external_force));
  if (!s.forces.external_torque.empty()) {
    if (s.forces.external_torque.size() == 1)
      std::fprintf(out, "  external torque: %s kT on every particle\n", vec(s.forces.external_torque[0]).c_str());
    else
      std::fprintf(out, "  external torque: per particle, largest |T| = %.4g kT\n", largest(s.forces.external_torque));
  }
  // Energies print in the reference unit kT of docs/units.md; a scene whose fluid.kT is another
  // multiple of it also sees them in its own thermal energy.
  auto thermal = [&](double e) {
    char b[64] = "";
    if (s.fluid.kT > 0 && s.fluid.kT != 1.0) std::snprintf(b, sizeof b, " (%.4g x fluid.kT)", e / s.fluid.kT);
    return std::string(b);
  };
  for (const auto& p : s.forces.pair) {
    const double hc = forces::resolved_cutoff(p, *amax);
    const char* how = p.cutoff > 0 ? "" : " (default)";
    switch (p.kind) {
      case PairForceParams::Kind::morse:
        std::fprintf(out, "  pair: morse, depth %.4g kT%s, kappa %.4g /a, cut-off gap %.4g a%s\n", p.morse_depth,
                     thermal(p.morse_depth).c_str(), p.morse_kappa, hc, how);
        break;
      case PairForceParams::Kind::dlvo:
        std::fprintf(out,
                     "  pair: dlvo (%s), Hamaker %.4g kT%s, kappa %.4g /a, surface potential %.4g kT/a, Born sigma %.4g a, "
                     "min gap %.3g a, cut-off gap %.4g a%s\n",
                     name_of(p.double_layer), p.hamaker, thermal(p.hamaker).c_str(), p.debye_kappa, p.surface_potential,
                     p.born_sigma, p.min_gap, hc, how);
        break;
      case PairForceParams::Kind::hertz:
        std::fprintf(out, "  pair: hertz, stiffness k_H %.4g kT/a^2.5 (contact only)\n", p.hertz_stiffness);
        break;
      case PairForceParams::Kind::repulsion:
        std::fprintf(out, "  pair: repulsion, strength F0 %.4g kT/a, decay tau %.4g /a, min gap %.3g a, cut-off gap %.4g a%s\n",
                     p.repulsion_strength, p.repulsion_decay, p.min_gap, hc, how);
        break;
      case PairForceParams::Kind::harmonic:
        std::fprintf(out, "  pair: harmonic, stiffness %.4g kT/a^2, rest gap %.4g a, cut-off gap %.4g a%s\n",
                     p.harmonic_stiffness, p.harmonic_rest_gap, hc, how);
        break;
    }
  }
  if (s.forces.pair.empty()) std::fprintf(out, "  pair: none\n");
  if (s.fluid.kT > 0)
    std::fprintf(out, "  Brownian: fluid.kT = %.4g (in the reference kT), seed %llu\n", s.fluid.kT, (unsigned long long)s.seed);
  else std::fprintf(out, "  Brownian: none (kT = 0)\n");
  if (s.flow.kind != FlowParams::Kind::none) {
    char pe[96] = "";
    if (s.flow.peclet != 0.0) std::snprintf(pe, sizeof pe, " (from peclet %.4g = 6 pi mu a^3 rate / kT)", s.flow.peclet);
    if (s.flow.kind == FlowParams::Kind::poiseuille && s.walls.kind == ChannelParams::Kind::outline && s.flow.outline) {
      const Outline o = make_outline(s.walls);
      const OutlineFlow& f = *s.flow.outline;  // solved when the scene was read
      std::fprintf(out, "  ambient flow: pressure-driven 2D Stokes flow through the outline (solved on a %zu x %zu grid of "
                   "spacing %.4g a, %zu fluid nodes), inlet mean velocity %.4g a/time, (p_in - p_out)/mu = %.4g /time; outlets:",
                   f.grid.axis[0].size(), f.grid.axis[1].size(), f.h, f.fluid_nodes, s.flow.mean_velocity, f.pressure_drop_over_mu);
      const double Q = std::abs(f.flux[std::size_t(o.inlet)]);
      for (std::size_t k = 0; k < o.edges(); ++k)
        if (o.open[k] && long(k) != o.inlet)
          std::fprintf(out, " edge %zu %.4g of the flux", k, Q > 0 ? f.flux[k] / Q : 0.0);
      std::fprintf(out, "\n");
    } else if (s.flow.kind == FlowParams::Kind::poiseuille) {
      const ChannelFlow cf(s.walls, s.domain, s.flow.mean_velocity);
      std::fprintf(out, "  ambient flow: poiseuille through the %s, mean velocity %.4g a/time, centreline %.4g a/time, "
                   "-dp/dx = %.4g mu/(a time)\n",
                   name_of(s.walls.kind), s.flow.mean_velocity, cf.max_velocity(), cf.pressure_gradient_over_viscosity());
    } else if (s.flow.kind == FlowParams::Kind::tabulated) {
      const FlowGrid& g = *s.flow.grid;
      std::fprintf(out, "  ambient flow: tabulated, %s, grid %zu x %zu x %zu nodes over [%.4g, %.4g] x [%.4g, %.4g] x [%.4g, %.4g] a "
                   "(trilinear; zero outside)\n", g.path.c_str(), g.axis[0].size(), g.axis[1].size(), g.axis[2].size(),
                   g.axis[0].front(), g.axis[0].back(), g.axis[1].front(), g.axis[1].back(), g.axis[2].front(), g.axis[2].back());
    } else {
      std::fprintf(out, "  ambient flow: %s, rate %.4g /time%s\n", name_of(s.flow.kind), s.flow.rate, pe);
    }
  }

  const WallContact wc = wall_contact(s, model);
  if (wc.applies) {
    std::fprintf(out,
                 "  wall contact: fixed particles see no ambient flow; a sphere touching one is carried against it at up to "
                 "%.4g a/time, and stopping it takes a contact force of about %.4g kT/a (lubrication_min_gap = %.3g; "
                 "docs/channels.md, \"Contact with wall particles\")\n",
                 wc.speed, wc.force, s.hydro.lubrication_min_gap);
    if (s.hydro.lubrication_min_gap < 1e-3)
      std::fprintf(out,
                   "  WARNING: with [hydrodynamics] lubrication_min_gap = %.3g a sphere that reaches a fixed particle can "
                   "be driven into it (the run stops at [run] max_overlap); the channel configs set 1e-2, where the "
                   "force is about %.4g kT/a\n",
                   s.hydro.lubrication_min_gap, wc.force_at_1e2);
  }

  // Outputs.
  const long long frames = s.time.steps / s.output.every + 1 + (s.time.steps % s.output.every != 0 ? 1 : 0);
  std::string rec;
  for (const auto& r : s.output.record) rec += (rec.empty() ? "" : ", ") + (r == "all" ? std::string("all the model computes") : r);
  std::fprintf(out, "output:\n  trajectory: %s, a frame every %lld steps (%lld frames); per particle: position, radius%s%s\n",
               opt.out.c_str(), static_cast<long long>(s.output.every), frames, rec.empty() ? "" : ", ", rec.c_str());
  std::fprintf(out, "    (outputs the model does not compute are not written)\n");
  if (s.domain.periodic()) {
    // The bulk stress's parts (engine/observers.cpp, docs/rheology.md).
    std::string parts = "fluid";
    if (has_stresslet(model.moments)) parts += ", hydrodynamic";
    if (!s.forces.pair.empty()) parts += ", interparticle";
    if (model.brownian)
      parts += has_stresslet(model.moments) && model.integrator == "fixman" ? ", Brownian" : ", Brownian (-n kT I only: the Brownian stresslet needs FTS)";
    if (has_stresslet(model.moments) && model.fixed_particles) parts += ", fixed particles";
    std::fprintf(out, "  stress: %s%s\n", parts.c_str(),
                 s.flow.kind == FlowParams::Kind::simple_shear && s.flow.rate != 0.0
                     ? "; relative viscosity, N1 and N2 of each (`stokesian average` for time averages)"
                     : "");
  }
  if (s.output.checkpoint_every > 0)
    std::fprintf(out, "  checkpoint: %s.ckpt, every %lld steps and at the end\n", opt.out.c_str(),
                 static_cast<long long>(s.output.checkpoint_every));
  else
    std::fprintf(out, "  checkpoint: %s.ckpt, at the end only\n", opt.out.c_str());
  if (const std::string xyz = xyz_path(s, opt.out); !xyz.empty()) std::fprintf(out, "  xyz: %s\n", xyz.c_str());

  // Initial state.
  std::fprintf(out, "initial state:\n");
  const auto overlaps = initial_overlaps(s);
  for (const auto& o : overlaps)
    std::fprintf(out, "  ERROR overlap: particles %d and %d, gap %.6g a\n", o.i, o.j, o.gap);
  const auto outside = outside_box(s);
  for (const auto& o : outside)
    std::fprintf(out,
                 "  warning: particle %d at %s is outside the box [0, L); the run uses its periodic image %s "
                 "(forces and hydrodynamics see minimum images; frame 0 stores the position as given, later frames "
                 "the wrapped one with its image counts)\n",
                 o.i, vec(o.position).c_str(), vec(o.wrapped).c_str());
  const GapStats gaps = gap_statistics(s.positions, s.radii, s.domain);
  if (overlaps.empty()) {
    if (std::isfinite(gaps.min_gap) && gaps.min_gap < 1.0)
      std::fprintf(out, "  no overlapping pairs; smallest gap %.4g a\n", gaps.min_gap);
    else
      std::fprintf(out, "  no overlapping pairs; no pair closer than 1 a\n");
  }

  // Resources (the CLI has refused the scene already when the peak exceeds the available memory).
  const ResourceEstimate est = estimate_resources(s, model);
  {
    const MemoryBudget budget = memory_budget();
    std::fprintf(out, "resources (estimate; docs/reliability.md):\n%s\n", est.describe("  ").c_str());
    if (budget.known())
      std::fprintf(out, "  available memory: %s (%s); the peak is %.3g%% of it%s\n", format_bytes(budget.bytes).c_str(),
                   budget.source.c_str(), 100.0 * est.peak_bytes / budget.bytes,
                   est.peak_bytes > kMemoryWarnFraction * budget.bytes ? " (WARNING: above half)" : "");
    else
      std::fprintf(out, "  available memory: unknown (no /proc/meminfo, no STOKESIAN_MEMORY_LIMIT)\n");
  }

  // Cost.
  std::fprintf(out, "cost:\n");
  std::vector<Vec3> u0;  // velocities of the initial state (measured)
  if (!overlaps.empty()) {
    std::fprintf(out, "  not measured: the initial state has overlapping pairs\n");
  } else if (!opt.estimate) {
    std::fprintf(out, "  not measured (--no-estimate)\n");
  } else if (est.seconds_per_step * kMeasuredEvaluations > kAnnounceSeconds) {
    // check stays quick: the measurement below costs about kMeasuredEvaluations steps; above
    // kAnnounceSeconds in all it is not done (solve measures one evaluation).
    std::fprintf(out,
                 "  not measured: one step is estimated at about %.3g s, and measuring costs about %d steps (above %.0f s "
                 "in all); `stokesian solve` times one evaluation\n",
                 est.seconds_per_step, kMeasuredEvaluations, kAnnounceSeconds);
  } else {
    const State s0 = sim.present(sim.initial_state());
    auto t0 = std::chrono::steady_clock::now();
    const Evaluation ev = sim.evaluate(s0, s0.position, 0.0, true);
    const double t_first = seconds_since(t0);
    u0 = ev.hydro.U;
    // Per step: (a 3-step run minus a 1-step run) / 2, both from the initial state with the output
    // discarded, after a 1-step run that warms up what is built on first use; the set-up and the
    // extra final evaluation of a run cancel.
    double per_run[3];
    for (int k = 0; k < 3; ++k) {
      State st = sim.initial_state();
      NullSink sink;
      RunControl rc;
      rc.quiet = true;
      rc.max_steps = k == 2 ? 3 : 1;
      t0 = std::chrono::steady_clock::now();
      sim.run(st, sink, rc);
      per_run[k] = seconds_since(t0);
    }
    const double per_step = (per_run[2] - per_run[1]) / 2;
    const int threads = opt.threads > 0 ? opt.threads : omp_get_max_threads();
    std::fprintf(out, "  first evaluation of the initial state: %s (includes one-time set-up), %d thread(s)\n",
                 duration(t_first).c_str(), threads);
    std::fprintf(out, "  per step: %s (half the wall time of a 3-step run minus a 1-step run; %s)\n",
                 per_step > 0 ? duration(per_step).c_str() : "below the timing noise",
                 ic ? (std::to_string(ic->evaluations) + " evaluation(s) per step" +
                       (ic->stability <= 0 ? " per attempt" : "") + (model.brownian ? (model.drift ? " + Brownian force" : " + Brownian displacement") : ""))
                          .c_str()
                    : "unknown integrator");
    if (per_step > 0)
      std::fprintf(out, "  whole run: about %s for %lld steps (frame and checkpoint writing not included%s)\n",
                   duration(per_step * double(s.time.steps)).c_str(), static_cast<long long>(s.time.steps),
                   ic && ic->stability <= 0 ? "; adaptive steps may differ" : "");
    else
      std::fprintf(out, "  whole run: not estimated (a step is below the timing noise)\n");
  }

  // Step size.
  std::fprintf(out, "step size:\n");
  const StiffnessBound sb = stiffness_bound(s, model);
  if (!sb.applies) {
    std::fprintf(out, "  stiffness: not applied (%s)\n", sb.reason.c_str());
  } else {
    const char* verdict = s.time.dt <= sb.dt_max ? "ok" : "WARNING";
    std::fprintf(out,
                 "  stiffness %s: dt = %.4g, stable dt < %.4g (largest k m_rel over gaps %.4g to %.4g a: "
                 "k = d2U/dr2 = %.4g kT/a^2, m_rel = %.4g, at gap %.4g a, radii %.4g and %.4g)\n",
                 verdict, s.time.dt, sb.dt_max, sb.h_lo, sb.h_hi, sb.k, sb.m_rel, sb.gap, sb.ai, sb.aj);
    if (s.time.dt > sb.dt_max)
      std::fprintf(out, "  WARNING: dt = %.4g exceeds the stability limit of the stiffest pair force; use dt < %.4g\n",
                   s.time.dt, sb.dt_max);
  }
  if (!overlaps.empty()) {
    std::fprintf(out, "  displacement: not applied (overlapping pairs)\n");
  } else if (u0.empty()) {
    std::fprintf(out, "  displacement: not applied (needs the measured velocities; --no-estimate)\n");
  } else {
    const DisplacementBound d = displacement_bound(s, u0);
    if (d.pair_i < 0) {
      std::fprintf(out, "  displacement: ok (no pair closer than 1 a is closing)\n");
    } else {
      const bool ok = s.time.dt <= d.dt_max;
      std::fprintf(out,
                   "  displacement %s: particles %d and %d at gap %.4g a close at %.4g a/time, %.4g a per step "
                   "(limit 0.1 x gap); dt < %.4g\n",
                   ok ? "ok" : "WARNING", d.pair_i, d.pair_j, d.gap, d.closing_speed, d.closing_speed * s.time.dt,
                   d.dt_max);
      if (!ok)
        std::fprintf(out,
                     "  WARNING: with dt = %.4g particles %d and %d close more than a tenth of their gap in one step; "
                     "use dt < %.4g\n",
                     s.time.dt, d.pair_i, d.pair_j, d.dt_max);
    }
  }
  if (!overlaps.empty()) {
    std::fprintf(stderr, "stokesian: error: %s: %zu overlapping pair(s) in the initial state (listed above)\n",
                 s.source.c_str(), overlaps.size());
    return 2;
  }
  return 0;
}

}  // namespace stokesian::app
