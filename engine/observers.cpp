#include "engine/observers.hpp"

#include "engine/core/channel.hpp"
#include "engine/core/outline.hpp"
#include "engine/core/errors.hpp"
#include "engine/core/flow.hpp"
#include "engine/core/sym_traceless.hpp"
#include "engine/pair_forces.hpp"
#include "engine/stress.hpp"
#include "trees/clusters.hpp"
#include "trees/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace stokesian {

namespace {

// First range of the gap search [a]; doubled until a pair is found.
constexpr double kGapSearchRange = 1.0;

const std::vector<std::string> kSymmetricComponents{"xx", "xy", "xz", "yy", "yz", "zz"};

std::vector<double> six_per_particle(const std::vector<Vec5>& S) {
  std::vector<double> v;
  v.reserve(6 * S.size());
  for (const Vec5& s : S) {
    const Vec6 c = six_components(s);
    v.insert(v.end(), c.data(), c.data() + 6);
  }
  return v;
}

Registry<ParticleOutputEntry> make_particle_outputs() {
  Registry<ParticleOutputEntry> r("per-particle output");
  auto always = [](const ResolvedModel&) { return true; };
  auto rotations = [](const ResolvedModel& m) { return has_torque(m.moments); };
  r.add({"velocity", {"velocity", {3}, {}, units::velocity}, always, "",
         [](const State&, const Evaluation& ev, Frame& f) { f.set_particles("velocity", ev.hydro.U); }});
  r.add({"angular_velocity", {"angular_velocity", {3}, {}, units::angular_velocity}, rotations, "moments = \"FT\" or \"FTS\"",
         [](const State&, const Evaluation& ev, Frame& f) { f.set_particles("angular_velocity", ev.hydro.Omega); }});
  r.add({"force", {"force", {3}, {}, units::force}, always, "", [](const State& s, const Evaluation& ev, Frame& f) {
           std::vector<Vec3> F = ev.force;
           for (std::size_t i = 0; i < s.size(); ++i)
             if (!s.fixed.empty() && s.fixed[i]) F[i] = ev.hydro.F[i];  // fixed particles: the force on the fluid
           f.set_particles("force", F);
         }});
  r.add({"torque", {"torque", {3}, {}, units::energy}, rotations, "moments = \"FT\" or \"FTS\"",
         [](const State&, const Evaluation& ev, Frame& f) { f.set_particles("torque", ev.torque); }});
  r.add({"stresslet", {"stresslet", {6}, kSymmetricComponents, units::energy}, [](const ResolvedModel& m) { return has_stresslet(m.moments); }, "moments = \"FTS\"",
         [](const State&, const Evaluation& ev, Frame& f) {
           f.particles["stresslet"] = Field{{6}, six_per_particle(ev.hydro.S), units::energy, false};
         }});
  // Per-particle stress ([L24] eqs. 2.36-2.37 per particle; method note P15, P16): the particle's
  // share of the bulk stress of engine/stress.hpp (hydrodynamic and interparticle parts) over its
  // own volume, sigma_i = (S^H_i - sum_j (1/2) r_ij F_ij^T) / (4/3 pi a_i^3), S^H_i = -S_i the
  // stresslet of the fluid's traction on it (the solve returns S_i, exerted on the fluid); the
  // pair virial replaces [L24]'s origin-dependent -x F^P. An isolated sphere in a straining flow
  // has 5 mu E_inf (Einstein). The Brownian stresslet is a mean over steps, not a per-frame
  // per-particle value, and is not included.
  r.add({"particle_stress", {"particle_stress", {6}, kSymmetricComponents, units::stress},
         [](const ResolvedModel& m) { return has_stresslet(m.moments); }, "moments = \"FTS\"",
         [](const State& s, const Evaluation& ev, Frame& f) {
           std::vector<double> v;
           v.reserve(6 * s.size());
           for (std::size_t i = 0; i < s.size(); ++i) {
             Mat3 m = -from_vec5(ev.hydro.S[i]);
             if (!ev.pair.particle_virial.empty()) m -= ev.pair.particle_virial[i];
             const Vec6 c = six_components(Mat3(m / (4.0 / 3.0 * kPi * std::pow(s.radius[i], 3))));
             v.insert(v.end(), c.data(), c.data() + 6);
           }
           f.particles["particle_stress"] = Field{{6}, v, units::stress, false};
         }});
  return r;
}

// position and radius: every trajectory has them (position first: it is the file's clock).
class Positions final : public Observer {
 public:
  void declare(std::vector<FieldSpec>& p) const override {
    p.push_back({"position", {3}, {}, units::length});
    p.push_back({"radius", {}, {}, units::length});
  }
  void observe(const State& s, const Evaluation&, Frame& f) const override {
    f.set_particles("position", s.position);
    f.set_particles("radius", s.radius);
  }
};

// Periodic boxes: image counts (engine/core/state.hpp), so that position + image . edges is the
// unwrapped position (H5MD's `image` element).
class Images final : public Observer {
 public:
  void declare(std::vector<FieldSpec>& p) const override { p.push_back({"image", {3}, {}, "", true}); }
  void observe(const State& s, const Evaluation&, Frame& f) const override {
    Field& out = f.particles["image"];
    out = Field{{3}, std::vector<double>(3 * s.size(), 0.0), "", true};
    for (std::size_t i = 0; i < s.image.size(); ++i)
      for (int c = 0; c < 3; ++c) out.values[3 * i + std::size_t(c)] = s.image[i][std::size_t(c)];
  }
};

class RecordedOutput final : public Observer {
 public:
  explicit RecordedOutput(const ParticleOutputEntry& e) : e_(e) {}
  void declare(std::vector<FieldSpec>& p) const override { p.push_back(e_.spec); }
  void observe(const State& s, const Evaluation& ev, Frame& f) const override { e_.fill(s, ev, f); }

 private:
  const ParticleOutputEntry& e_;
};

class StressletSum final : public Observer {
 public:
  void observe(const State&, const Evaluation& ev, Frame& f) const override {
    Mat3 total = Mat3::Zero();
    for (const Vec5& S : ev.hydro.S) total += from_vec5(S);
    const Vec6 t6 = six_components(total);
    f.observables["stresslet_sum"] = Field{{6}, std::vector<double>(t6.data(), t6.data() + 6), units::energy, false};
  }
};

// Periodic boxes: the bulk stress by contribution (engine/stress.hpp), and in simple shear the
// relative viscosity and normal-stress differences of each contribution.
class BulkStress final : public Observer {
 public:
  BulkStress(const Scene& scene, const ResolvedModel& m)
      : mu_(scene.fluid.viscosity),
        kT_(scene.fluid.kT),
        E_(ambient_flow(scene.flow).E),
        rate_(scene.flow.kind == FlowParams::Kind::simple_shear ? scene.flow.rate : 0.0),
        fts_(has_stresslet(m.moments)),
        pairs_(!scene.forces.pair.empty()),
        brownian_(m.brownian),
        brownian_stresslet_(m.brownian_stress_every > 0) {}  // resolve_model: periodic, FTS, fixman
  void observe(const State& s, const Evaluation& ev, Frame& f) const override {
    StressInput in;
    in.volume = s.domain.box.prod();
    in.viscosity = mu_;
    in.E = E_;
    for (std::size_t i = 0; i < s.size(); ++i) in.mobile += s.fixed.empty() || !s.fixed[i];
    in.hydrodynamic = fts_ && ev.hydro.S.size() == s.size();
    if (in.hydrodynamic)
      for (std::size_t i = 0; i < s.size(); ++i)
        (!s.fixed.empty() && s.fixed[i] ? in.stresslet_fixed : in.stresslet_mobile) += from_vec5(ev.hydro.S[i]);
    in.fixed = in.mobile < long(s.size());
    in.interparticle = pairs_;
    in.virial = ev.pair.virial;
    in.brownian = brownian_;
    in.kT = kT_;
    if (brownian_stresslet_) {
      if (s.brownian_samples > 0) in.brownian_stresslet = s.brownian_stresslet_sum / double(s.brownian_samples);
      f.set_count("brownian_samples", s.brownian_samples);
    }
    for (const StressPart& p : bulk_stress(in)) {
      const std::string suffix = p.name == "total" ? "" : "_" + p.name;
      const Vec6 c = six_components(p.sigma);
      f.observables["stress" + suffix] = Field{{6}, std::vector<double>(c.data(), c.data() + 6), units::stress, false};
      if (rate_ != 0.0) {
        f.set_scalar("relative_viscosity" + suffix, shear_viscosity(p.sigma, mu_, rate_));
        f.set_scalar("N1" + suffix, normal_difference_1(p.sigma), units::stress);
        f.set_scalar("N2" + suffix, normal_difference_2(p.sigma), units::stress);
      }
    }
  }

 private:
  double mu_, kT_;
  Mat3 E_;
  double rate_;
  bool fts_, pairs_, brownian_, brownian_stresslet_;
};

// Channels ([walls], engine/core/channel.hpp, docs/channels.md). The solve's F of a held particle is
// the force it exerts on the fluid (the fluid's force on it is -F); P is the pair force the mobile
// particles exert on it (deposits held by attraction, contact). Its load, what holds it in place
// against fluid and particles, is L = P - F, and C = F - P the force the constraint applies.
//   wall_force: sum of F over the wall particles (the fluid's part alone).
//   pressure_drop_particles (slit, duct): sum_{held} L_x / A = -sum_{held} (F_x - P_x) / A over every
//     held particle (walls and any fixed obstacle), A the cross-section (Lee et al. 2024 §3.2, read as
//     in method note P17). The fluid's momentum balance: the solids' total force on it is
//     sum_held F + sum_mobile F, and a quasi-static mobile particle's F is its non-hydrodynamic
//     force, so pairs between mobile particles cancel and those with held ones leave -P; with no
//     external force on the mobile particles (and the Brownian forces averaging out) that total is
//     sum_held (F - P). Dropping P would miss the drag on deposits and clogs that attraction holds
//     to the walls, and count the lubrication push of spheres pulled onto a wall without the pull.
//   Outline: the same along the inlet's inward normal; per branch (engine/core/outline.hpp)
//     pressure_drop_branches = (sum_{held in b} -F . d_b + sum_{mobile in b} Q . d_b) / (width_b x
//     depth), Q a mobile particle's pair forces on the held ones (sum_m Q = sum_h P), and
//     areal_fraction_branches = sum_{interior in b} pi a^2 / (fluid area of b).
//   wall_shear_stress, wall_normal_stress [walls][sections]: per wall (slit: bottom, top; duct: also
//     the side walls at -z, +z) and per section along x, the fluid's streamwise force on its wall
//     particles per wall area, sum(-F_x) / A_ws, and the force pushing them out of the fluid,
//     sum(F . n) / A_ws (n the wall's normal into the fluid); A_ws = section length x wall span.
//   volume_fraction_sections [sections]: interior particle volume (by centre) over the section's
//     fluid volume.
// Sections split x into `[walls] sections` equal parts: [0, Lx) in a periodic box, the walls' extent
// [-length/2, length/2] about the centre in an open domain (particles beyond go to the end sections).
class ChannelOutputs final : public Observer {
 public:
  explicit ChannelOutputs(const Scene& scene)
      : c_(scene.walls),
        d_(scene.domain),
        walls_(scene.wall_count),
        area_(cross_section_area(scene.walls, scene.domain)),
        sections_(std::max(1L, scene.walls.sections)),
        pair_laws_(scene.forces.pair) {
    x0_ = d_.periodic() ? 0.0 : -0.5 * c_.length;
    len_ = d_.periodic() ? d_.box.x() : c_.length;
    nw_ = c_.kind == ChannelParams::Kind::duct ? 4 : c_.kind == ChannelParams::Kind::slit ? 2 : 1;
    if (c_.kind == ChannelParams::Kind::outline) {
      o_ = make_outline(c_);
      for (std::size_t k = 0; k < o_.edges(); ++k)
        if (!o_.open[k]) wall_edge_.push_back(k);
      nw_ = int(wall_edge_.size());
      double lo = o_.v[0].x(), hi = lo;
      for (const Vec2& p : o_.v) {
        lo = std::min(lo, p.x());
        hi = std::max(hi, p.x());
      }
      x0_ = lo;
      len_ = hi - lo;
      for (int k = 0; k < sections_; ++k)
        section_area_.push_back(o_.area_between(lo + len_ * k / sections_, lo + len_ * (k + 1) / sections_));
      streamwise_ = -o_.outward_normal(std::size_t(o_.inlet));
      branches_ = outline_branches(o_);
    }
  }
  void observe(const State& s, const Evaluation& ev, Frame& f) const override {
    if (c_.kind == ChannelParams::Kind::outline) return observe_outline(s, ev, f);
    observe_straight(s, ev, f);
  }
  // Outline (monolayer): walls are the outline's wall edges in order; sections split each edge into
  // `sections` equal parts; shear along the edge's direction (vertex k to k + 1), normal out of the
  // fluid; stresses per wall area (section length x depth). pressure_drop_particles takes the held
  // forces along the inlet's inward normal; areal_fraction_sections: interior particles' pi a^2 (by
  // centre) over the fluid area of each section of x.
  void observe_outline(const State& s, const Evaluation& ev, Frame& f) const {
    const std::size_t n = s.size(), ns = std::size_t(sections_), nw = wall_edge_.size();
    Vec3 wall = Vec3::Zero();
    double held_s = 0.0;
    const std::vector<OutlineBranch>& br = branches_.branch;
    std::vector<double> shear(nw * ns, 0.0), normal(nw * ns, 0.0), areal(ns, 0.0);
    std::vector<double> branch_drop(br.size(), 0.0), branch_areal(br.size(), 0.0);
    // Per branch, the fluid's part of a held particle's load goes to the held particle's branch and
    // a mobile particle's pull on the held ones (Q) to the mobile particle's branch: a deposit at a
    // corner touching wall particles of two branches presses and pulls them by far more than its
    // drag, and only the sum is its load (the total drop takes every part along the inlet alike).
    const PairLoads pl = pair_loads(s);
    for (std::size_t i = 0; i < n && i < ev.hydro.F.size(); ++i) {
      const Vec3& F = ev.hydro.F[i];
      const Vec2 x(s.position[i].x(), s.position[i].y()), F2(F.x(), F.y());
      const Vec2 P2(pl.on_held[i].x(), pl.on_held[i].y()), Q2(pl.of_mobile[i].x(), pl.of_mobile[i].y());
      const bool held = !s.fixed.empty() && s.fixed[i];
      if (held) held_s += (F2 - P2).dot(streamwise_);
      if (i < n - walls_) {
        areal[section(x.x())] += kPi * s.radius[i] * s.radius[i];
        long b = branches_.of_point(x);
        if (b >= 0 && o_.contains(x)) branch_areal[std::size_t(b)] += kPi * s.radius[i] * s.radius[i];
        if (b >= 0 && held) branch_drop[std::size_t(b)] -= F2.dot(br[std::size_t(b)].direction);
        if (!held && Q2 != Vec2::Zero()) {
          if (b < 0) b = branches_.of_wall_particle(o_, x, o_.nearest_wall(x));  // beyond an opening
          if (b >= 0) branch_drop[std::size_t(b)] += Q2.dot(br[std::size_t(b)].direction);
        }
        continue;
      }
      wall += F;
      const std::size_t e = o_.nearest_wall(x);
      if (const long b = branches_.of_wall_particle(o_, x, e); b >= 0) branch_drop[std::size_t(b)] -= F2.dot(br[std::size_t(b)].direction);
      const std::size_t w = std::size_t(std::find(wall_edge_.begin(), wall_edge_.end(), e) - wall_edge_.begin());
      const Vec2 t = (o_.b(e) - o_.a(e)).normalized();
      const double along = std::clamp((x - o_.a(e)).dot(t) / o_.length(e), 0.0, 1.0 - 1e-12);
      const std::size_t sec = std::size_t(along * double(ns));
      shear[w * ns + sec] += -F2.dot(t);
      normal[w * ns + sec] += F2.dot(-o_.outward_normal(e));
    }
    for (std::size_t w = 0; w < nw; ++w)
      for (std::size_t k = 0; k < ns; ++k) {
        const double A = o_.length(wall_edge_[w]) / double(ns) * c_.depth;
        shear[w * ns + k] /= A;
        normal[w * ns + k] /= A;
      }
    for (std::size_t k = 0; k < ns; ++k) areal[k] /= section_area_[k] > 0 ? section_area_[k] : 1.0;
    f.observables["wall_force"] = Field{{3}, {wall.x(), wall.y(), wall.z()}, units::force, false};
    f.observables["wall_shear_stress"] = Field{{nw_, sections_}, shear, units::stress, false};
    f.observables["wall_normal_stress"] = Field{{nw_, sections_}, normal, units::stress, false};
    f.set_scalar("pressure_drop_particles", -held_s / area_, units::stress);
    f.observables["areal_fraction_sections"] = Field{{sections_}, areal, "", false};
    for (std::size_t b = 0; b < br.size(); ++b) {
      branch_drop[b] /= br[b].width * c_.depth;
      branch_areal[b] /= br[b].area > 0 ? br[b].area : 1.0;
    }
    const int nb = int(br.size());
    f.observables["pressure_drop_branches"] = Field{{nb}, branch_drop, units::stress, false};
    f.observables["areal_fraction_branches"] = Field{{nb}, branch_areal, "", false};
  }
  void observe_straight(const State& s, const Evaluation& ev, Frame& f) const {
    const std::size_t n = s.size();
    Vec3 wall = Vec3::Zero();
    double held_x = 0.0;
    const std::size_t ns = std::size_t(sections_), nw = std::size_t(nw_);
    std::vector<double> shear(nw * ns, 0.0), normal(nw * ns, 0.0), vol(ns, 0.0);
    const Vec3 ctr = channel_centre(d_);
    const std::vector<Vec3> P = pair_loads(s).on_held;
    for (std::size_t i = 0; i < n && i < ev.hydro.F.size(); ++i) {
      const Vec3& F = ev.hydro.F[i];
      if (!s.fixed.empty() && s.fixed[i]) held_x += F.x() - P[i].x();
      const std::size_t sec = section(s.position[i].x());
      if (i < n - walls_) {
        vol[sec] += 4.0 / 3.0 * kPi * std::pow(s.radius[i], 3);
        continue;
      }
      wall += F;
      // Which wall: the boundary the particle lies furthest beyond (duct corners go to the y walls).
      const Vec3 r = s.position[i] - ctr;
      std::size_t w = 0;
      Vec3 normal_in(0, 1, 0);
      if (c_.kind != ChannelParams::Kind::plane) {
        const bool zwall = c_.kind == ChannelParams::Kind::duct &&
                           std::abs(r.z()) - 0.5 * c_.width > std::abs(r.y()) - 0.5 * c_.height;
        if (zwall) {
          w = r.z() < 0 ? 2 : 3;
          normal_in = Vec3(0, 0, r.z() < 0 ? 1.0 : -1.0);
        } else {
          w = r.y() < 0 ? 0 : 1;
          normal_in = Vec3(0, r.y() < 0 ? 1.0 : -1.0, 0);
        }
      }
      shear[w * ns + sec] += -F.x();
      normal[w * ns + sec] += F.dot(normal_in);
    }
    const double seg = len_ / double(ns);
    for (std::size_t w = 0; w < nw; ++w) {
      const double span = w >= 2 ? c_.height : c_.kind == ChannelParams::Kind::duct ? c_.width
                                                : (d_.periodic() ? d_.box.z() : c_.depth);
      for (std::size_t k = 0; k < ns; ++k) {
        shear[w * ns + k] /= seg * span;
        normal[w * ns + k] /= seg * span;
      }
    }
    f.observables["wall_force"] = Field{{3}, {wall.x(), wall.y(), wall.z()}, units::force, false};
    f.observables["wall_shear_stress"] = Field{{nw_, sections_}, shear, units::stress, false};
    f.observables["wall_normal_stress"] = Field{{nw_, sections_}, normal, units::stress, false};
    if (area_ > 0.0) {
      f.set_scalar("pressure_drop_particles", -held_x / area_, units::stress);
      for (double& v : vol) v /= seg * area_;
      f.observables["volume_fraction_sections"] = Field{{sections_}, vol, "", false};
    }
  }

 private:
  // Pair loads between the mobile and the held particles, from the pair forces of all particles
  // less those within each group (wall particles a small gap apart attract each other):
  //   on_held[h]: P_h, the pull and push of the mobile particles on held particle h;
  //   of_mobile[m]: Q_m, what mobile particle m exerts on the held ones in all (Newton's third law:
  //     minus the held particles' force on m), so sum_m Q_m = sum_h P_h.
  struct PairLoads {
    std::vector<Vec3> on_held, of_mobile;
  };
  PairLoads pair_loads(const State& s) const {
    PairLoads r{std::vector<Vec3>(s.size(), Vec3::Zero()), std::vector<Vec3>(s.size(), Vec3::Zero())};
    if (pair_laws_.empty() || s.fixed.empty()) return r;
    std::vector<Vec3> all;
    forces::add_pair_forces(pair_laws_, s.position, s.radius, s.domain, all);
    for (const bool held : {true, false}) {
      std::vector<Vec3> x, among;
      std::vector<double> a;
      std::vector<std::size_t> ids;
      for (std::size_t i = 0; i < s.size(); ++i)
        if (bool(s.fixed[i]) == held) {
          ids.push_back(i);
          x.push_back(s.position[i]);
          a.push_back(s.radius[i]);
        }
      forces::add_pair_forces(pair_laws_, x, a, s.domain, among);
      for (std::size_t k = 0; k < ids.size(); ++k) {
        const Vec3 cross = all[ids[k]] - among[k];  // from the other group
        (held ? r.on_held : r.of_mobile)[ids[k]] = held ? cross : Vec3(-cross);
      }
    }
    return r;
  }
  std::size_t section(double x) const {
    double t = (x - x0_) / len_;
    if (d_.periodic()) t -= std::floor(t);
    const long k = long(std::floor(t * double(sections_)));
    return std::size_t(std::clamp(k, 0L, long(sections_) - 1));
  }
  ChannelParams c_;
  Domain d_;
  std::size_t walls_;
  double area_;
  int sections_ = 1, nw_ = 1;
  double x0_ = 0.0, len_ = 1.0;
  Outline o_;
  std::vector<std::size_t> wall_edge_;
  OutlineBranches branches_;
  std::vector<double> section_area_;
  Vec2 streamwise_ = Vec2(1.0, 0.0);
  std::vector<PairForceParams> pair_laws_;
};

// Settling clouds ([output] cloud; docs/clouds.md). Cloud members: the interior particles in
// friends-of-friends components (trees/clusters.hpp, centre distance <= cloud_link) that hold at
// least cloud_min_fraction of the interior particles; the others are lost (to the tail).
//   cloud_particles, cloud_lost, cloud_parts (components counted as clouds: 1 until it breaks up);
//   cloud_centroid, cloud_velocity: mean position and velocity of the members; mean_velocity: of
//     all interior particles;
//   cloud_radius: sqrt(5/3 <|x - c|^2>) over the members (the radius of a uniform sphere);
//   cloud_gyration: eigenvalues of <(x - c)(x - c)^T>, largest first (R^2/5 each for a sphere);
//   cloud_axis_fraction: the share of members within 0.25 cloud_radius of the line through c along
//     the mean external force (1 - (15/16)^{3/2} = 0.0923 for a uniform sphere; ~0 once a torus
//     has opened its centre).
class CloudOutputs final : public Observer {
 public:
  explicit CloudOutputs(const Scene& scene)
      : n_(scene.interior_count()), link_(scene.output.cloud_link), min_fraction_(scene.output.cloud_min_fraction) {
    Vec3 f = Vec3::Zero();
    for (std::size_t i = 0; i < scene.forces.external_force.size() && i < n_; ++i) f += scene.forces.external_force[i];
    axis_ = f.norm() > 0 ? Vec3(f.normalized()) : Vec3(0, 0, -1);
  }
  void observe(const State& s, const Evaluation& ev, Frame& f) const override {
    const std::vector<Vec3> x(s.position.begin(), s.position.begin() + long(n_));
    const trees::Clusters c = trees::link_by_centres(x, s.domain, link_);
    const double need = min_fraction_ * double(n_);
    std::vector<char> member(n_, 0);
    std::int64_t parts = 0, count = 0;
    for (const auto& m : c.members) {
      if (double(m.size()) < need) break;  // sorted by decreasing size
      ++parts;
      for (int i : m) member[std::size_t(i)] = 1;
      count += std::int64_t(m.size());
    }
    Vec3 centre = Vec3::Zero(), v = Vec3::Zero(), v_all = Vec3::Zero();
    const bool have_v = ev.hydro.U.size() >= n_;
    for (std::size_t i = 0; i < n_; ++i) {
      if (have_v) v_all += ev.hydro.U[i];
      if (!member[i]) continue;
      centre += x[i];
      if (have_v) v += ev.hydro.U[i];
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    Mat3 g = Mat3::Zero();
    double axis_share = nan, radius = nan;
    if (count > 0) {
      centre /= double(count);
      v /= double(count);
      for (std::size_t i = 0; i < n_; ++i)
        if (member[i]) g += (x[i] - centre) * (x[i] - centre).transpose();
      g /= double(count);
      radius = std::sqrt(5.0 / 3.0 * g.trace());
      long near_axis = 0;
      for (std::size_t i = 0; i < n_; ++i)
        if (member[i]) {
          const Vec3 r = x[i] - centre;
          near_axis += (r - r.dot(axis_) * axis_).norm() < 0.25 * radius;
        }
      axis_share = double(near_axis) / double(count);
    } else {
      centre = v = Vec3::Constant(nan);
    }
    Eigen::SelfAdjointEigenSolver<Mat3> es(g, Eigen::EigenvaluesOnly);
    const Vec3 ev3 = count > 0 ? Vec3(es.eigenvalues().reverse()) : Vec3::Constant(nan);
    if (have_v) v_all /= double(n_);
    auto vec = [](const Vec3& a) { return std::vector<double>{a.x(), a.y(), a.z()}; };
    f.set_count("cloud_particles", count);
    f.set_count("cloud_lost", std::int64_t(n_) - count);
    f.set_count("cloud_parts", parts);
    f.observables["cloud_centroid"] = Field{{3}, vec(centre), units::length, false};
    if (have_v) {
      f.observables["cloud_velocity"] = Field{{3}, vec(v), units::velocity, false};
      f.observables["mean_velocity"] = Field{{3}, vec(v_all), units::velocity, false};
    }
    f.set_scalar("cloud_radius", radius, units::length);
    f.observables["cloud_gyration"] = Field{{3}, vec(ev3), units::area, false};
    f.set_scalar("cloud_axis_fraction", axis_share, "");
  }

 private:
  std::size_t n_;
  double link_, min_fraction_;
  Vec3 axis_;
};

// In-run cluster counts ([output] cluster_gap; definitions in trees/clusters.hpp, docs/clusters.md):
// clusters of the interior, mobile particles by surface gap <= cluster_gap; singlets, doublets and
// triplets, and the largest cluster's size.
class ClusterCounts final : public Observer {
 public:
  explicit ClusterCounts(const Scene& scene) : gap_(scene.output.cluster_gap), walls_(scene.wall_count) {}
  void observe(const State& s, const Evaluation&, Frame& f) const override {
    std::vector<char> skip(s.size(), 0);
    for (std::size_t i = 0; i < s.size(); ++i)
      skip[i] = (!s.fixed.empty() && s.fixed[i]) || i >= s.size() - std::min(s.size(), walls_);
    const trees::Clusters c = trees::find_clusters(s.position, s.radius, s.domain, gap_, &skip);
    const std::vector<long> h = trees::size_histogram(c);
    auto count = [&](std::size_t n) { return std::int64_t(n < h.size() ? h[n] : 0); };
    f.set_count("clusters", std::int64_t(c.members.size()));
    f.set_count("clusters_singlets", count(1));
    f.set_count("clusters_doublets", count(2));
    f.set_count("clusters_triplets", count(3));
    f.set_count("clusters_largest", std::int64_t(c.members.empty() ? 0 : c.members[0].size()));
  }

 private:
  double gap_;
  std::size_t walls_;
};

class Gaps final : public Observer {
 public:
  void observe(const State& s, const Evaluation& ev, Frame& f) const override {
    const GapStats g = ev.gaps ? *ev.gaps : gap_statistics(s.position, s.radius, s.domain);
    f.set_count("overlaps", std::int64_t(g.overlaps));
    f.set_scalar("min_gap", g.min_gap, units::length);
  }
};

class RunStatistics final : public Observer {
 public:
  void observe(const State& s, const Evaluation& ev, Frame& f) const override {
    f.set_scalar("pair_energy", ev.pair.energy, units::energy);
    f.set_count("krylov_iterations", std::int64_t(ev.hydro.iterations));
    // Near-contact policy (docs/brownian.md): how many lubrication pairs sit at the regularised gap.
    if (ev.hydro.regularised_pairs >= 0) f.set_count("regularised_pairs", std::int64_t(ev.hydro.regularised_pairs));
    f.set_scalar("dt", s.dt, units::time);
  }
};

}  // namespace

const Registry<ParticleOutputEntry>& particle_outputs() {
  static const Registry<ParticleOutputEntry> r = make_particle_outputs();
  return r;
}

std::vector<std::unique_ptr<Observer>> make_observers(const Scene& scene, const ResolvedModel& model) {
  std::vector<std::unique_ptr<Observer>> obs;
  obs.push_back(std::make_unique<Positions>());
  if (scene.domain.periodic()) obs.push_back(std::make_unique<Images>());
  const auto& rec = scene.output.record;
  const bool all = rec.size() == 1 && rec[0] == "all";
  if (!all)
    for (const auto& name : rec) {
      const ParticleOutputEntry* e = particle_outputs().find(name);
      if (!e)
        throw ConfigError(scene.where("output", "record") + ": \"" + name + "\" is not one of " +
                          quoted_list(particle_outputs().names()) + " (or \"all\")");
      if (!e->available(model))
        throw ConfigError(scene.where("output", "record") + ": \"" + name + "\" needs " + e->needs +
                          ", but this scene resolves to moments = \"" + name_of(model.moments) +
                          "\" (see `stokesian check`); set [hydrodynamics] moments or leave " + name + " out");
    }
  for (const auto& e : particle_outputs().entries())
    if ((all || std::count(rec.begin(), rec.end(), e.name)) && e.available(model))
      obs.push_back(std::make_unique<RecordedOutput>(e));
  if (has_stresslet(model.moments)) obs.push_back(std::make_unique<StressletSum>());
  if (scene.domain.periodic()) obs.push_back(std::make_unique<BulkStress>(scene, model));
  if (scene.walls.any()) obs.push_back(std::make_unique<ChannelOutputs>(scene));
  if (scene.output.cloud) obs.push_back(std::make_unique<CloudOutputs>(scene));
  if (scene.output.cluster_gap >= 0.0) obs.push_back(std::make_unique<ClusterCounts>(scene));
  obs.push_back(std::make_unique<Gaps>());
  obs.push_back(std::make_unique<RunStatistics>());
  return obs;
}

GapSurvey survey_gaps(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain, double range,
                      std::size_t keep, const std::vector<char>* fixed) {
  GapSurvey out;
  out.stats.min_gap = INFINITY;
  if (x.size() < 2) return out;
  for (const auto& p : trees::nearest_image_pairs(x, a, domain, range)) {
    const double ai = a[std::size_t(p.i)], aj = a[std::size_t(p.j)];
    const double gap = p.dist - ai - aj;
    if (!(gap < range)) continue;
    if (fixed && !fixed->empty() && (*fixed)[std::size_t(p.i)] && (*fixed)[std::size_t(p.j)]) continue;
    ++out.within;
    out.stats.min_gap = std::min(out.stats.min_gap, gap);
    out.stats.overlaps += gap < 0;
    if (keep > 0) out.worst.push_back({p.i, p.j, gap, -gap / std::min(ai, aj)});
  }
  // The `keep` deepest, ties by index (deterministic).
  auto deeper = [](const PairGap& u, const PairGap& v) {
    return u.depth != v.depth ? u.depth > v.depth : (u.i != v.i ? u.i < v.i : u.j < v.j);
  };
  if (out.worst.size() > keep) {
    std::partial_sort(out.worst.begin(), out.worst.begin() + long(keep), out.worst.end(), deeper);
    out.worst.resize(keep);
  } else {
    std::sort(out.worst.begin(), out.worst.end(), deeper);
  }
  return out;
}

std::string describe_pairs(const std::vector<PairGap>& pairs) {
  std::string s;
  char buf[160];
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%s(%ld, %ld) gap %.3g a", k ? ", " : "", pairs[k].i, pairs[k].j, pairs[k].gap);
    s += buf;
    if (pairs[k].depth > 0) {
      std::snprintf(buf, sizeof buf, " (overlap %.3g of the smaller radius)", pairs[k].depth);
      s += buf;
    }
  }
  return s;
}

GapStats gap_statistics(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                        const std::vector<char>* fixed) {
  // Every gap is below the largest centre distance, which is below the diagonal of the particles'
  // bounding box (open) or of the box (periodic): past it, no pair exists (a single particle).
  Vec3 lo = x.empty() ? Vec3::Zero() : x[0], hi = lo;
  for (const Vec3& p : x) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double limit = domain.periodic() ? domain.box.norm() : (hi - lo).norm();
  for (double range = kGapSearchRange;; range *= 2.0) {
    const GapSurvey s = survey_gaps(x, a, domain, range, 0, fixed);
    if (s.within > 0 || range > limit || x.size() < 2) return s.stats;
  }
}

GapSurvey survey_overlaps(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                          std::size_t keep, GapStats& stats, const std::vector<char>* fixed) {
  GapSurvey near = survey_gaps(x, a, domain, kGapSearchRange, keep, fixed);
  stats = near.within > 0 || x.size() < 2 ? near.stats : gap_statistics(x, a, domain, fixed);
  // Overlapping pairs have positive depth, so the `keep` deepest pairs in range hold the `keep`
  // deepest overlapping ones: drop the rest, and restate the statistics for range 0.
  near.worst.erase(std::remove_if(near.worst.begin(), near.worst.end(), [](const PairGap& p) { return !(p.gap < 0.0); }),
                   near.worst.end());
  near.within = near.stats.overlaps;
  if (!(near.stats.min_gap < 0.0)) near.stats.min_gap = INFINITY;
  return near;
}

}  // namespace stokesian
