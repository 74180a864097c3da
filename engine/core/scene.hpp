#pragma once
// Parameters of a scene, as plain structs with their defaults in one place. io/scene_toml.cpp maps
// the TOML scene file one-to-one onto these; docs/scene.md documents every key with unit and
// default. Units: lengths in the reference radius a, viscosity mu, energy kT (docs/units.md).
#include "engine/core/domain.hpp"
#include "engine/core/names.hpp"
#include "engine/core/types.hpp"

#include <cstdint>
#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace stokesian {

struct FluidParams {
  double viscosity = 1.0;  // mu, in units of the reference viscosity
  double kT = 0.0;         // thermal energy in units of the reference kT; 0 = athermal
};

// One pair-force law. Only the fields of the chosen kind are used (docs/scene.md). The laws and
// their regularisation are stated in engine/pair_forces.hpp.
struct PairForceParams {
  enum class Kind { morse, dlvo, hertz, harmonic, repulsion } kind = Kind::morse;
  double cutoff = 0.0;  // surface-gap cutoff h = r - a_i - a_j beyond which the force is zero [a]; 0 = law's default
                        // (energy shifted to vanish there; default from forces::default_cutoff)
  // Morse (Lee et al. 2024 [L24] eq. 2.17): phi = -V0 [2 exp(-kappa h) - exp(-2 kappa h)]
  double morse_depth = 1.0;   // V0 [kT-units energy]
  double morse_kappa = 5.0;   // kappa [1/a]
  // DLVO ([T] s.2.2.2): Hamaker vdW + constant-potential double layer + Born repulsion.
  // Alumina in water ([T] s.5.3.2: A = 4.76e-20 J, eps_r = 81, T = 298 K, 7 mM, |psi0| = 37 mV,
  // sigma = 7 A) for spheres of physical radius a_phys, with kT = 4.1143e-21 J:
  //   hamaker = A/kT = 11.569;  debye_kappa = a_phys / 3.6925 nm (kappa^2 = 2 N_A e^2 I/(eps kT));
  //   surface_potential = 2 pi eps_r eps_0 psi0^2 a_phys / kT = 1.4994e9 m^-1 * a_phys;
  //   surface_potential_reduced = e psi0/kT = 1.4408;  born_sigma = 0.7 nm / a_phys.
  //   a_phys = 369.25 nm gives debye_kappa = 100, surface_potential = 553.65, born_sigma = 1.8958e-3.
  double hamaker = 1.0;            // A [kT]
  double debye_kappa = 10.0;       // inverse Debye length kappa [1/a]
  double surface_potential = 1.0;  // psi_0 expressed through the prefactor 2 pi eps psi0^2 [kT/a]; same psi0 on all particles
  double born_sigma = 0.01;        // Born collision parameter sigma, O(5 A) (Feke et al. 1984) [a]; 0 = no Born term
  double min_gap = 1e-4;           // gap floor h_min: below it the DLVO energy continues linearly (constant force) [a]
  enum class DoubleLayer { hhf, lsa };
  DoubleLayer double_layer = DoubleLayer::hhf;  // hhf = Hogg-Healy-Fuerstenau; lsa = linear superposition (Bell et al. 1970), kappa a > 10
  double surface_potential_reduced = 0.0;       // e psi0/kT, only for the lsa tanh(e psi0/4kT) saturation; 0 = linearised [1]
  // Hertz contact: U = (2/5) k_H delta^{5/2}, F = k_H delta^{3/2} along the line of centres for
  // overlap delta = a_i + a_j - r > 0 ([T] eq. 2.7 writes k' delta^{2.5}: k' = (2/5) k_H). [L24], [T]: README.md.
  double hertz_stiffness = 1000.0;  // k_H [kT / a^{5/2}]
  // Harmonic spring on the surface gap: U = (k/2) (h - h_0)^2 (engine/pair_forces.hpp).
  double harmonic_stiffness = 100.0;  // k [kT / a^2]
  double harmonic_rest_gap = 0.0;     // h_0 [a]
  // Short-range repulsion of hard-sphere rheology (engine/pair_forces.hpp):
  // |F| = F0 tau a e^{-tau h} / (1 - e^{-tau h}), a = 1, floored below min_gap like DLVO.
  double repulsion_strength = 1.0;   // F0 [kT/a]
  double repulsion_decay = 1000.0;   // tau [1/a]
};

template <>
struct Names<PairForceParams::Kind> {
  static constexpr NameTable<PairForceParams::Kind, 5> table{
      {{PairForceParams::Kind::morse, "morse"}, {PairForceParams::Kind::dlvo, "dlvo"}, {PairForceParams::Kind::hertz, "hertz"},
       {PairForceParams::Kind::harmonic, "harmonic"}, {PairForceParams::Kind::repulsion, "repulsion"}}};
};
template <>
struct Names<PairForceParams::DoubleLayer> {
  static constexpr NameTable<PairForceParams::DoubleLayer, 2> table{
      {{PairForceParams::DoubleLayer::hhf, "hhf"}, {PairForceParams::DoubleLayer::lsa, "lsa"}}};
};

struct ForceParams {
  std::vector<Vec3> external_force;   // one entry for all particles, or one per particle [kT/a]
  std::vector<Vec3> external_torque;  // idem [kT]
  std::vector<PairForceParams> pair;
};

// A velocity field on a rectilinear grid (io/flow_table.hpp reads it; engine/core/channel.hpp
// interpolates it). Node (i, j, k) holds u[(k * ny + j) * nx + i]; NaN marks a node without data.
struct FlowGrid {
  std::array<std::vector<double>, 3> axis;  // increasing node coordinates along x, y, z [a]
  std::vector<Vec3> u;                      // [a/time]
  std::string path;                         // the file it came from
  std::uint64_t hash = 0;                   // FNV-1a 64 of the file's bytes
  std::size_t index(std::size_t i, std::size_t j, std::size_t k) const {
    return (k * axis[1].size() + j) * axis[0].size() + i;
  }
};

struct OutlineFlow;  // engine/core/outline.hpp

struct FlowParams {
  enum class Kind { none, simple_shear, planar_extension, poiseuille, tabulated } kind = Kind::none;
  std::shared_ptr<const FlowGrid> grid;  // tabulated: the field
  double rate = 0.0;  // shear or extension rate [1/time]
  double mean_velocity = 0.0;  // poiseuille: mean velocity U over the channel's (outline: inlet's) cross-section [a/time]
  double grid_spacing = 0.0;   // poiseuille through an outline: spacing of the 2D Stokes grid [a] (0 = automatic)
  // poiseuille through an outline: the flow solved when the scene was read (`grid` points into it)
  std::shared_ptr<const OutlineFlow> outline;
  // Peclet number Pe = 6 pi mu a^3 rate / kT (a = 1, the reference radius; docs/rheology.md), when
  // the scene gave it instead of `rate` (0 = not given); `rate` then holds Pe kT / (6 pi mu).
  double peclet = 0.0;
};

template <>
struct Names<FlowParams::Kind> {
  static constexpr NameTable<FlowParams::Kind, 5> table{{{FlowParams::Kind::none, "none"},
                                                         {FlowParams::Kind::simple_shear, "simple_shear"},
                                                         {FlowParams::Kind::planar_extension, "planar_extension"},
                                                         {FlowParams::Kind::poiseuille, "poiseuille"},
                                                         {FlowParams::Kind::tabulated, "tabulated"}}};
};

// Walls of immobile wall particles bounding a channel (the [walls] table; geometry, placement and
// the channel flows: engine/core/channel.hpp, trees/walls.hpp, docs/channels.md).
struct ChannelParams {
  enum class Kind { none, plane, slit, duct, outline } kind = Kind::none;
  double height = 0.0;  // H: fluid gap between the walls normal to y [a] (slit, duct)
  double width = 0.0;   // W: fluid gap between the walls normal to z [a] (duct)
  double length = 0.0;  // open domains: extent of the walls along x [a]
  double depth = 0.0;   // open domains, plane and slit: extent of the walls along z [a]
  double radius = 1.0;  // wall-particle radius r_w [a]
  double gap = 0.05;    // surface gap between neighbouring wall particles in a layer [a]
  long sections = 1;   // sections along x of the wall-stress and volume-fraction outputs
  long layers = 1;      // layers per wall; layer k sits (2 r_w + gap) k / sqrt(2) further out,
                        // shifted by half a spacing along both wall directions (closing the pores);
                        // outline: a row k (2 r_w + gap) sqrt(3)/2 further out, shifted half a spacing
  // outline (engine/core/outline.hpp): polygon vertices (x, y) [a], edge k from vertex k to k + 1
  // (the last closes it); the edges listed in `openings` carry no wall, one of them is the inlet.
  std::vector<std::array<double, 2>> outline;
  std::vector<long> openings;
  long inlet = -1;
  bool any() const { return kind != Kind::none; }
  double spacing() const { return 2.0 * radius + gap; }
};

template <>
struct Names<ChannelParams::Kind> {
  static constexpr NameTable<ChannelParams::Kind, 5> table{{{ChannelParams::Kind::none, "none"},
                                                            {ChannelParams::Kind::plane, "plane"},
                                                            {ChannelParams::Kind::slit, "slit"},
                                                            {ChannelParams::Kind::duct, "duct"},
                                                            {ChannelParams::Kind::outline, "outline"}}};
};

// Hydrodynamic level, cheapest first: free draining -> far field -> Stokesian dynamics.
enum class HydroModel { auto_, free_draining, far_field, stokesian };
enum class MomentChoice { auto_, F, FT, FTS };

template <>
struct Names<HydroModel> {
  static constexpr NameTable<HydroModel, 4> table{{{HydroModel::auto_, "auto"},
                                                   {HydroModel::free_draining, "free_draining"},
                                                   {HydroModel::far_field, "far_field"},
                                                   {HydroModel::stokesian, "stokesian"}}};
};
template <>
struct Names<MomentChoice> {
  static constexpr NameTable<MomentChoice, 4> table{
      {{MomentChoice::auto_, "auto"}, {MomentChoice::F, "F"}, {MomentChoice::FT, "FT"}, {MomentChoice::FTS, "FTS"}}};
};

// Near field: pairs with s = 2r/(a_i+a_j) below the cutoff get lubrication, switched off smoothly over
// a band [s_in, s_cut] (lubrication/cutoff.hpp); gaps are floored at the minimum symmetric gap
// (lubrication/near_field.hpp uses the same defaults). The explicit default 4 with no taper is
// published SD; lubrication::near_field_params() resolves "auto".
constexpr double kDefaultLubricationCutoff = 4.0, kDefaultLubricationMinGap = 1e-6;

// Near-field level of Stokesian dynamics: exact two-sphere lubrication (lubrication/near_field.hpp)
// or the thesis's normal squeeze force (lubrication/squeeze.hpp).
enum class Lubrication { exact, squeeze };
template <>
struct Names<Lubrication> {
  static constexpr NameTable<Lubrication, 2> table{{{Lubrication::exact, "exact"}, {Lubrication::squeeze, "squeeze"}}};
};
/// Gaps of the squeeze model [a] (thesis s.5.2.2 defaults in units of the reference radius).
struct SqueezeParams {
  double contact_gap = 1e-6;     // d_c,min: smaller surface gaps are evaluated here
  double slip_gap = 1e-3;        // d_l,slip: the slip form below
  double transition_gap = 0.25;  // d_l,trans: the no-slip form from here on, a blend in between
};

struct HydroParams {
  HydroModel model = HydroModel::auto_;
  MomentChoice moments = MomentChoice::auto_;
  std::string far_field = "auto";  // a registered far-field method (engine/methods.cpp) or "auto"
  std::string solver = "auto";     // Stokesian-dynamics solver: "auto", "dense" or "accelerated"
  double tolerance = 1e-6;  // relative accuracy of far-field products and iterative solves
  // lubrication_cutoff = "auto": the band from `tolerance` (lubrication::cutoff_for_tolerance); a number
  // (default 4): that s_cut, with the band [s_cut - lubrication_taper, s_cut]. The default is the
  // published one so that scenes and stored runs of earlier versions keep their meaning.
  bool lubrication_cutoff_auto = false;
  double lubrication_cutoff = kDefaultLubricationCutoff;   // explicit s_cut (not auto): no near field from 2r/(a_i+a_j) = this on [1]
  // lubrication_taper = "auto" (default): 0.5 with an automatic cutoff, 0 (hard step, published SD)
  // with an explicit one; a number: the band's width s_cut - s_in [1].
  bool lubrication_taper_auto = true;
  double lubrication_taper = 0.0;
  double lubrication_min_gap = kDefaultLubricationMinGap;  // regularised minimum symmetric gap xi = 2r/(a_i+a_j) - 2 [1]
  Lubrication lubrication = Lubrication::exact;  // near-field level of model = "stokesian"
  SqueezeParams squeeze;                         // its gaps when lubrication = squeeze
};

struct TimeParams {
  double dt = 1e-3;      // time step [time unit]
  std::int64_t steps = 0;       // steps to take from start_step
  std::int64_t start_step = 0;  // step and time of the initial state (a continued run: the file's last frame)
  double start_time = 0.0;
  std::int64_t last_step() const { return start_step + steps; }
  // "auto": the model chooses (fixman where Brownian motion needs the thermal drift, else euler;
  // engine/model.cpp), or a registered integrator (engine/methods.cpp).
  std::string integrator = "auto";
  double rkf_tolerance = 1e-6;  // local error per step for rkf45 [a]
};

// Every per-particle output; 0.1.0 wrote this list for its default, read back as {"all"}.
inline const std::vector<std::string> kEveryParticleOutput{"angular_velocity", "force", "stresslet", "torque", "velocity"};

struct OutputParams {
  std::int64_t every = 1;              // frames every N steps from the start, and at the last step
  std::int64_t checkpoint_every = 0;   // checkpoint every N steps; 0 = at the end only
  // Optional per-particle outputs (registered in engine/observers.cpp), sorted, no repeats.
  // {"all"} (the default) = every one the resolved model computes; named outputs must be computed
  // by the model, or the scene is refused (a stresslet needs FTS, angular ones FT).
  std::vector<std::string> record{"all"};
  // Extended-XYZ export (docs/output.md): off, or on at xyz_path relative to the folder of the
  // trajectory (--out); an empty xyz_path means <trajectory stem>.xyz beside the trajectory.
  bool xyz = false;
  std::string xyz_path;
  std::string author;                  // H5MD /h5md/author name; "" = the login name of the user
  // Cloud observables (engine/observers.cpp, docs/clouds.md): on for a settling cloud (resolved at
  // load: open domain, [forces] gravity, no walls, no inflow, unless set). Friends-of-friends
  // linking length [a] (resolved at load: kCloudLinkSpacings mean centre spacings of the initial
  // cloud) and the smallest share of the particles that counts as a cloud.
  bool cloud = false;
  double cloud_link = 0.0;
  double cloud_min_fraction = 0.05;
  // In-run cluster counts (docs/clusters.md): bonds h_ij <= cluster_gap [a]; < 0 = not recorded.
  double cluster_gap = -1.0;
};
inline constexpr double kCloudLinkSpacings = 1.5;

// What a run does when its state goes bad (docs/reliability.md, "Failure policies during a run").
struct RunPolicy {
  // The run stops (exit 3, resumable checkpoint) when a pair overlaps deeper than this fraction
  // of its smaller radius: a_i + a_j - r > max_overlap min(a_i, a_j) [1].
  double max_overlap = 0.5;
};

// [inflow] (docs/channels.md, "Open channels"): particles enter an outline channel through its inlet
// and leave through its openings (engine/inflow.hpp).
struct InflowParams {
  bool enabled = false;
  double areal_fraction = 0.0;  // phi_A = n_A pi r^2 of the incoming monolayer, n_A its centres per area [1]
  long capacity = 0;            // particle slots (most particles present at once) [count]
  double radius = 1.0;          // radius of the inserted particles [a]
  double min_gap = 0.1;         // surface gap an inserted particle keeps from every other and from the walls [a]
};

struct Scene {
  std::string source;  // path of the scene file (for messages)
  Domain domain;
  FluidParams fluid;
  std::vector<Vec3> positions;
  std::vector<double> radii;
  std::vector<char> fixed;
  // [walls]: its wall particles are the last wall_count entries of positions/radii/fixed (fixed).
  ChannelParams walls;
  std::size_t wall_count = 0;
  std::size_t interior_count() const { return positions.size() - wall_count; }
  InflowParams inflow;
  ForceParams forces;
  FlowParams flow;
  HydroParams hydro;
  std::uint64_t seed = 1;  // Brownian random seed
  // Steps between samples of the Brownian stresslet (engine/stress.hpp); 0: none; -1: "auto"
  // (resolve_model: every step with an ambient flow, else none). Sampled only where the stress is
  // recorded (periodic box, FTS, Fixman integrator).
  std::int64_t brownian_stress_every = -1;
  TimeParams time;
  OutputParams output;
  RunPolicy run;
  std::string toml;  // the scene as resolved TOML text (stored in outputs)
  // Line of each key in the source, "table.key" -> line (0 = unknown), so that checks made after
  // parsing (model resolution) still name file, line and key.
  std::map<std::string, int> lines;
  // "file:line: [table] key" (line omitted when unknown).
  std::string where(const std::string& table, const std::string& key) const {
    auto it = lines.find(table + "." + key);
    const std::string at = it != lines.end() && it->second > 0 ? ":" + std::to_string(it->second) : "";
    return source + at + ": [" + table + "] " + key;
  }
};

}  // namespace stokesian
