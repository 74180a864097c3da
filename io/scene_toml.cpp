#include "io/scene_toml.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/memory.hpp"
#include "io/flow_table.hpp"
#include "io/h5md.hpp"
#include "io/xyz.hpp"
#include "trees/neighbor_list.hpp"
#include "trees/placement.hpp"
#include "trees/walls.hpp"
#include "engine/core/channel.hpp"
#include "engine/core/outline.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace stokesian::io {
namespace {

class Reader {
 public:
  explicit Reader(std::string source, std::map<std::string, int>* lines = nullptr)
      : source_(std::move(source)), lines_(lines) {}

  // The node of `key` in `t` (nullptr if absent); remembers its line as "table.key".
  const toml::node* get(const toml::table& t, const std::string& table, const std::string& key) const {
    const toml::node* n = t.get(key);
    if (n && lines_) (*lines_)[table + "." + key] = int(n->source().begin.line);
    return n;
  }

  [[noreturn]] void fail(const toml::node* node, const std::string& where, const std::string& msg) const {
    std::ostringstream o;
    // A node parsed from another file (a value a sweep file put into this scene) names that file.
    o << (node && node->source().path && !node->source().path->empty() ? *node->source().path : source_);
    if (node && node->source().begin.line) o << ":" << node->source().begin.line;
    o << ": " << where << ": " << msg;
    throw ConfigError(o.str());
  }

  // Rejects keys of `t` not in `allowed`.
  void only(const toml::table& t, const std::string& table, const std::set<std::string>& allowed) const {
    for (auto&& [k, v] : t) {
      if (!allowed.count(std::string(k.str()))) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(&v, "[" + table + "] " + std::string(k.str()), "unknown key (allowed: " + list + ")");
      }
    }
  }

  double number(const toml::table& t, const std::string& table, const std::string& key, double def, double lo,
                double hi, bool lo_open = false) const {
    const toml::node* n = get(t, table, key);
    if (!n) return def;
    double v;
    if (auto i = n->value_exact<int64_t>()) v = double(*i);
    else if (auto d = n->value_exact<double>()) v = *d;
    else fail(n, where(table, key), "expected a number, got " + type_name(*n) + " (allowed " + range(lo, hi, lo_open) + ")");
    if (!(v >= lo && v <= hi) || (lo_open && v == lo)) {
      std::ostringstream o;
      o << "value " << v << " out of range (allowed " << (lo_open ? "(" : "[") << lo << ", " << hi << "])";
      fail(n, where(table, key), o.str());
    }
    return v;
  }

  long integer(const toml::table& t, const std::string& table, const std::string& key, long def, long lo, long hi) const {
    const toml::node* n = get(t, table, key);
    if (!n) return def;
    auto i = n->value_exact<int64_t>();
    if (!i)
      fail(n, where(table, key),
           "expected an integer, got " + type_name(*n) + " (allowed an integer in [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "])");
    if (*i < lo || *i > hi) {
      std::ostringstream o;
      o << "value " << *i << " out of range (allowed [" << lo << ", " << hi << "])";
      fail(n, where(table, key), o.str());
    }
    return long(*i);
  }

  std::string choice(const toml::table& t, const std::string& table, const std::string& key, const std::string& def,
                     const std::vector<std::string>& allowed) const {
    const toml::node* n = get(t, table, key);
    if (!n) return def;
    auto s = n->value_exact<std::string>();
    if (!s) fail(n, where(table, key), "expected a string, got " + type_name(*n) + " (allowed: " + quoted_list(allowed) + ")");
    check_length(n, where(table, key), *s);
    if (std::find(allowed.begin(), allowed.end(), *s) == allowed.end())
      fail(n, where(table, key), "\"" + *s + "\" is not one of " + quoted_list(allowed));
    return *s;
  }

  std::string string(const toml::table& t, const std::string& table, const std::string& key, const std::string& def) const {
    const toml::node* n = get(t, table, key);
    if (!n) return def;
    auto s = n->value_exact<std::string>();
    if (!s) fail(n, where(table, key), "expected a string, got " + type_name(*n));
    check_length(n, where(table, key), *s);
    return *s;
  }

  // Every string value (names, paths, the author) is at most kMaxString bytes: longer ones are
  // mistakes, and some end up in HDF5 attributes, which cannot hold them.
  static constexpr std::size_t kMaxString = 4096;
  void check_length(const toml::node* n, const std::string& w, const std::string& s) const {
    if (s.size() > kMaxString)
      fail(n, w, "a string of " + std::to_string(s.size()) + " bytes (allowed at most " + std::to_string(kMaxString) +
                     " bytes)");
  }

  template <class E>
  E name(const toml::table& t, const std::string& table, const std::string& key, E def) const {
    return *parse_name<E>(choice(t, table, key, name_of(def), name_list<E>()));
  }

  bool boolean(const toml::table& t, const std::string& table, const std::string& key, bool def) const {
    const toml::node* n = get(t, table, key);
    if (!n) return def;
    auto b = n->value_exact<bool>();
    if (!b) fail(n, where(table, key), "expected true or false, got " + type_name(*n));
    return *b;
  }

  Vec3 vec3(const toml::node& n, const std::string& w) const {
    const toml::array* a = n.as_array();
    if (!a || a->size() != 3) fail(&n, w, "expected an array of 3 numbers");
    Vec3 v;
    for (int c = 0; c < 3; ++c) {
      const toml::node& e = *a->get(std::size_t(c));
      if (auto i = e.value_exact<int64_t>()) v[c] = double(*i);
      else if (auto d = e.value_exact<double>()) v[c] = *d;
      else fail(&e, w, "expected a number, got " + type_name(e));
      if (!std::isfinite(v[c])) fail(&e, w, "component " + std::to_string(c) + " is not a finite number (allowed: finite numbers)");
    }
    return v;
  }

  // One vector for all particles ([x, y, z]) or one per particle ([[x, y, z], ...]).
  std::vector<Vec3> vec3_list(const toml::table& t, const std::string& table, const std::string& key) const {
    const toml::node* n = get(t, table, key);
    if (!n) return {};
    const toml::array* a = n->as_array();
    if (!a || a->empty()) fail(n, where(table, key), "expected [x, y, z] or a list of [x, y, z]");
    if (!a->get(0)->is_array()) return {vec3(*n, where(table, key))};
    std::vector<Vec3> out;
    for (const auto& e : *a) out.push_back(vec3(e, where(table, key)));
    return out;
  }

  static std::string where(const std::string& table, const std::string& key) { return "[" + table + "] " + key; }
  static std::string range(double lo, double hi, bool lo_open) {
    std::ostringstream o;
    o << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
    return o.str();
  }
  static std::string brief(double v) {
    std::ostringstream o;
    o << v;
    return o.str();
  }
  static std::string type_name(const toml::node& n) {
    switch (n.type()) {
      case toml::node_type::string: return "a string";
      case toml::node_type::integer: return "an integer";
      case toml::node_type::floating_point: return "a float";
      case toml::node_type::boolean: return "a boolean";
      case toml::node_type::array: return "an array";
      case toml::node_type::table: return "a table";
      default: return "a date/time";
    }
  }
  const std::string& source() const { return source_; }

 private:
  std::string source_;
  std::map<std::string, int>* lines_;
};

// Particle sizes: every radius finite in [kMinRadius, kMaxRadius] a and max/min <= kMaxRadiusRatio,
// the size ratio range over which the lubrication resistance functions are validated
// (docs/lubrication.md: lambda in [0.01, 100]). Periodic box edges up to kMaxBoxEdge a; at most
// kMaxCount generated particles.
constexpr double kMinRadius = 1e-3, kMaxRadius = 1e3, kMaxRadiusRatio = 100.0, kMaxBoxEdge = 1e6;
constexpr long kMaxCount = 10000000;
constexpr double kRandomMaxPhi = 0.6;  // generate = "random" (trees/placement.cpp refuses beyond it too)

const toml::table& sub(const Reader& r, const toml::table& root, const std::string& name) {
  static const toml::table empty;
  const toml::node* n = root.get(name);
  if (!n) return empty;
  if (!n->is_table()) r.fail(n, "[" + name + "]", "expected a table");
  return *n->as_table();
}

// from_run: set when the particles come from a trajectory (its last frame continues that run).
void read_particles(const Reader& R, const toml::table& t, Scene& s, const std::string& base_dir,
                    std::optional<Snapshot>& from_run) {
  const std::string T = "particles";
  R.only(t, T, {"positions", "radii", "radius", "file", "generate", "count", "volume_fraction", "size_distribution",
                "radius_ratio", "large_fraction", "sigma", "seed", "fixed", "region", "equilibration_sweeps", "min_gap",
                "ln_mean", "ln_variance", "segregation"});
  const bool has_pos = t.contains("positions"), has_file = t.contains("file"), has_gen = t.contains("generate");
  if (int(has_pos) + int(has_file) + int(has_gen) != 1)
    R.fail(&t, "[particles] positions/file/generate",
           std::string(has_pos + has_file + has_gen == 0 ? "none of these keys is given" : "more than one of these keys is given") +
               " (allowed: exactly one of positions, file, generate)");
  // Keys of the generator (`radius` also sizes positions and radius-less XYZ files).
  for (const char* key : {"count", "volume_fraction", "size_distribution", "radius_ratio", "large_fraction", "sigma",
                          "seed", "region", "equilibration_sweeps", "min_gap", "ln_mean", "ln_variance", "segregation"})
    if (!has_gen && t.contains(key))
      R.fail(t.get(key), std::string("[particles] ") + key,
             std::string("only meaningful with generate (it applies only to generated particles, not to ") +
                 (has_pos ? "positions" : "file") + ")");
  if (has_pos) {
    const toml::array* a = t.get("positions")->as_array();
    if (!a || a->empty()) R.fail(t.get("positions"), "[particles] positions", "expected a non-empty list of [x, y, z]");
    for (const auto& e : *a) s.positions.push_back(R.vec3(e, "[particles] positions"));
    if (t.contains("radii")) {
      const toml::array* r = t.get("radii")->as_array();
      if (!r) R.fail(t.get("radii"), "[particles] radii", "expected a list of numbers");
      if (r->size() != s.positions.size()) {
        std::ostringstream o;
        o << "has " << r->size() << " entries for " << s.positions.size() << " positions";
        R.fail(t.get("radii"), "[particles] radii", o.str());
      }
      for (const auto& e : *r) {
        auto v = e.value<double>();
        if (!v || !std::isfinite(*v) || *v < kMinRadius || *v > kMaxRadius) {
          std::ostringstream o;
          o << "radius " << s.radii.size() << " is " << (v ? Reader::brief(*v) : Reader::type_name(e))
            << " (allowed [" << kMinRadius << ", " << kMaxRadius << "] a)";
          R.fail(&e, "[particles] radii", o.str());
        }
        s.radii.push_back(*v);
      }
      if (t.contains("radius")) R.fail(t.get("radius"), "[particles] radius", "give radius or radii, not both");
    } else {
      s.radii.assign(s.positions.size(), R.number(t, T, "radius", 1.0, kMinRadius, kMaxRadius));
    }
  } else if (has_file) {
    std::string path = R.string(t, T, "file", "");
    if (!path.empty() && path[0] != '/') path = base_dir + "/" + path;
    try {
      if (path.size() > 3 && (path.substr(path.size() - 3) == ".h5" || path.substr(path.size() - 5) == ".hdf5")) {
        const auto f = read_last_frame(path);
        s.positions = f.position;
        s.radii = f.radius;
        from_run = f;
      } else {
        const auto frames = read_xyz(path);
        if (frames.empty()) throw std::runtime_error(path + ": no frames");
        s.positions = frames.back().position;
        s.radii = frames.back().radius;
      }
    } catch (const std::exception& e) {
      R.fail(t.get("file"), "[particles] file", e.what());
    }
    // `radius` sizes only a file without radii; beside a file that has them it would be ignored.
    const double radius = R.number(t, T, "radius", 1.0, kMinRadius, kMaxRadius);
    if (t.contains("radius") && !s.radii.empty())
      R.fail(t.get("radius"), "[particles] radius",
             "the file " + path + " gives a radius per particle; radius applies only to a file without radii "
             "(allowed: remove radius, or the file's radius column)");
    if (s.radii.empty()) s.radii.assign(s.positions.size(), radius);
  } else {
    PlacementParams p;
    p.pattern = R.choice(t, T, "generate", "random", {"random", "lattice"}) == "lattice"
                    ? PlacementParams::Pattern::lattice : PlacementParams::Pattern::random;
    p.volume_fraction = R.number(t, T, "volume_fraction", 0.1, 0.0, 0.74, true);
    p.radius = R.number(t, T, "radius", 1.0, kMinRadius, kMaxRadius);
    const std::string sd =
        R.choice(t, T, "size_distribution", "monodisperse", {"monodisperse", "bidisperse", "lognormal", "bimodal"});
    p.sizes = sd == "bidisperse" ? PlacementParams::Sizes::bidisperse
            : sd == "lognormal" ? PlacementParams::Sizes::lognormal
            : sd == "bimodal"   ? PlacementParams::Sizes::bimodal : PlacementParams::Sizes::monodisperse;
    p.radius_ratio = R.number(t, T, "radius_ratio", 2.0, 1.0 / kMaxRadiusRatio, kMaxRadiusRatio);
    p.large_fraction = R.number(t, T, "large_fraction", 0.5, 0.0, 1.0);
    p.sigma = R.number(t, T, "sigma", 0.2, 0.0, 2.0);
    // The thesis's lognormal LN(m, s^2): m the mean and s^2 the variance of ln a, i.e. radius = e^m
    // (the median) and sigma = s.
    if (t.contains("ln_mean") || t.contains("ln_variance")) {
      const char* key = t.contains("ln_mean") ? "ln_mean" : "ln_variance";
      if (p.sizes != PlacementParams::Sizes::lognormal)
        R.fail(t.get(key), std::string("[particles] ") + key, "only meaningful with size_distribution = \"lognormal\"");
      if (!t.contains("ln_mean") || !t.contains("ln_variance"))
        R.fail(t.get(key), "[particles] ln_mean/ln_variance", "give both (the mean and the variance of ln a)");
      for (const char* other : {"radius", "sigma"})
        if (t.contains(other))
          R.fail(t.get(other), std::string("[particles] ") + other,
                 "give ln_mean and ln_variance or radius and sigma, not both (radius = exp(ln_mean), sigma = sqrt(ln_variance))");
      const double m = R.number(t, T, "ln_mean", 0.0, std::log(kMinRadius), std::log(kMaxRadius));
      const double v = R.number(t, T, "ln_variance", 0.04, 0.0, 4.0);
      p.radius = std::exp(m);
      p.sigma = std::sqrt(v);
    }
    {
      const std::string seg = R.choice(t, T, "segregation", "none", {"none", "large_up", "large_down"});
      p.segregation = seg == "large_up"     ? PlacementParams::Segregation::large_up
                      : seg == "large_down" ? PlacementParams::Segregation::large_down
                                            : PlacementParams::Segregation::none;
      if (p.segregation != PlacementParams::Segregation::none) {
        if (p.sizes != PlacementParams::Sizes::bidisperse && p.sizes != PlacementParams::Sizes::bimodal)
          R.fail(t.get("segregation"), "[particles] segregation",
                 "needs two species (size_distribution = \"bidisperse\" or \"bimodal\")");
        if (s.domain.periodic() || (t.contains("region") && R.string(t, T, "region", "sphere") != "sphere"))
          R.fail(t.get("segregation"), "[particles] segregation", "needs an open domain with region = \"sphere\"");
      }
    }
    p.seed = std::uint64_t(R.integer(t, T, "seed", 1, 0, std::numeric_limits<long>::max()));
    p.min_gap = R.number(t, T, "min_gap", p.min_gap, 0.0, 1.0);
    if (t.contains("equilibration_sweeps") && p.pattern != PlacementParams::Pattern::random)
      R.fail(t.get("equilibration_sweeps"), "[particles] equilibration_sweeps", "only meaningful with generate = \"random\"");
    p.equilibration_sweeps = R.integer(t, T, "equilibration_sweeps", p.equilibration_sweeps, 0, 1000000);
    p.channel = s.walls;
    if (t.contains("region") && s.domain.periodic())
      R.fail(t.get("region"), "[particles] region", "only meaningful in an open domain (a periodic box is filled whole)");
    p.region = R.choice(t, T, "region", "sphere", {"sphere", "cube"}) == "cube" ? PlacementParams::Region::cube
                                                                             : PlacementParams::Region::sphere;
    // Open domains: count is required and volume_fraction sets the filled region. Periodic boxes:
    // the box fixes the volume, so give count or volume_fraction, not both.
    if (s.walls.kind == ChannelParams::Kind::outline) {
      // A monolayer at z = 0 in the outline's fluid (trees/walls.hpp fill_outline).
      if (p.pattern != PlacementParams::Pattern::random)
        R.fail(t.get("generate"), "[particles] generate", "an outline is filled with generate = \"random\"");
      if (p.sizes != PlacementParams::Sizes::monodisperse)
        R.fail(t.get("size_distribution"), "[particles] size_distribution", "an outline is filled with one size (monodisperse)");
      if (t.contains("volume_fraction"))
        R.fail(t.get("volume_fraction"), "[particles] volume_fraction",
               "not used in an outline: give count (its areal fraction is count pi a^2 / fluid area)");
      if (!t.contains("count")) R.fail(&t, "[particles] count", "required with generate in an outline");
      p.count = R.integer(t, T, "count", 0, 1, 100000);
      try {
        s.positions = fill_outline(s.walls, p.count, p.radius, p.min_gap, p.seed);
      } catch (const std::invalid_argument& e) {
        R.fail(t.get("count"), "[particles] count", e.what());
      }
      s.radii.assign(s.positions.size(), p.radius);
    } else {
    if (s.domain.periodic()) {
      if (t.contains("count") == t.contains("volume_fraction"))
        R.fail(&t, "[particles] count/volume_fraction", "in a periodic box give exactly one of count and volume_fraction");
      if (t.contains("count")) {
        p.count = R.integer(t, T, "count", 0, 1, kMaxCount);
        p.volume_fraction = 0.0;
      } else {
        const double a3 = p.radius * p.radius * p.radius;
        double mean_a3 = a3;
        if (p.sizes == PlacementParams::Sizes::bidisperse || p.sizes == PlacementParams::Sizes::bimodal)
          mean_a3 = a3 * (1.0 - p.large_fraction + p.large_fraction * std::pow(p.radius_ratio, 3));
        if (p.sizes == PlacementParams::Sizes::lognormal || p.sizes == PlacementParams::Sizes::bimodal)
          mean_a3 *= std::exp(4.5 * p.sigma * p.sigma);
        // Checked as a number before anything is allocated for it.
        const double count = std::round(p.volume_fraction * fluid_volume(s.walls, s.domain.box) / (4.0 / 3.0 * kPi * mean_a3));
        if (!(count >= 1 && count <= double(kMaxCount))) {
          std::ostringstream o;
          o << "value " << p.volume_fraction << " gives count = round(phi V / mean sphere volume) = " << count
            << " in this box (allowed count 1 to " << kMaxCount << ")";
          R.fail(t.get("volume_fraction"), "[particles] volume_fraction", o.str());
        }
        p.count = long(count);
      }
    } else {
      if (!t.contains("count")) R.fail(&t, "[particles] count", "required with generate in an open domain");
      if (s.walls.any() && s.walls.kind != ChannelParams::Kind::outline)
        R.fail(t.get("generate"), "[particles] generate",
               "fills a channel only in a periodic box (an open domain's walls are finite patches); give positions or file");
      p.count = R.integer(t, T, "count", 0, 1, kMaxCount);
    }
    // Memory of the generated particles, checked before any is placed (docs/reliability.md).
    if (const MemoryBudget mb = memory_budget(); mb.known() && kBytesPerParticle * double(p.count) > mb.bytes) {
      const bool by_count = t.contains("count");
      R.fail(t.get(by_count ? "count" : "volume_fraction"), by_count ? "[particles] count" : "[particles] volume_fraction",
             std::to_string(p.count) + " particles need about " + format_bytes(kBytesPerParticle * double(p.count)) +
                 " of memory before any hydrodynamics (" + format_bytes(kBytesPerParticle) +
                 " each), but only " + format_bytes(mb.bytes) + " is available (" + mb.source +
                 ") (allowed: at most " + std::to_string(long(mb.bytes / kBytesPerParticle)) + " particles here)");
    }
    // The volume fraction a generator can reach (docs/scene.md, docs/configurations.md): "random" up
    // to kRandomMaxPhi (kRsaMaxVolumeFraction without equilibration); "lattice" while the simple
    // cubic spacing leaves every pair min_gap apart (at most pi/6 for one size). Checked here, before
    // any placement work, and a placement failure is reported against the key that sets the
    // fraction (volume_fraction, or count in a periodic box given by count).
    const char* phi_key = t.contains("volume_fraction") || !t.contains("count") ? "volume_fraction" : "count";
    const std::string phi_where = std::string("[particles] ") + phi_key;
    const toml::node* phi_node = t.get(phi_key) ? t.get(phi_key) : t.get("generate");
    double phi = p.volume_fraction;
    if (s.domain.periodic()) {
      double mean_a3 = p.radius * p.radius * p.radius;
      if (p.sizes == PlacementParams::Sizes::bidisperse || p.sizes == PlacementParams::Sizes::bimodal)
        mean_a3 *= 1.0 - p.large_fraction + p.large_fraction * std::pow(p.radius_ratio, 3);
      if (p.sizes == PlacementParams::Sizes::lognormal || p.sizes == PlacementParams::Sizes::bimodal)
        mean_a3 *= std::exp(4.5 * p.sigma * p.sigma);
      phi = double(p.count) * 4.0 / 3.0 * kPi * mean_a3 / fluid_volume(s.walls, s.domain.box);
    }
    const std::string limits =
        "allowed: generate = \"random\" up to volume fraction " + Reader::brief(kRandomMaxPhi) + " (" +
        Reader::brief(kRsaMaxVolumeFraction) + " with equilibration_sweeps = 0); \"lattice\" while the lattice "
        "spacing is at least 2 a_max + min_gap, for one size up to pi/6 (2a/(2a + min_gap))^3 = " +
        Reader::brief(kPi / 6 * std::pow(2 * p.radius / (2 * p.radius + p.min_gap), 3)) + " in an open sphere";
    if (p.pattern == PlacementParams::Pattern::random) {
      const double cap = p.equilibration_sweeps == 0 ? kRsaMaxVolumeFraction : kRandomMaxPhi;
      if (phi > cap * (1 + 1e-9)) {
        std::ostringstream o;
        o << "volume fraction " << phi << (s.domain.periodic() && !t.contains("volume_fraction") ? " (from count)" : "")
          << " is beyond what random placement reaches (" << limits << ")";
        R.fail(phi_node, phi_where, o.str());
      }
    }
    // A placement that takes long is announced with its estimate, so that a slow start is never
    // mistaken for a hang (docs/reliability.md).
    if (const double est = placement_seconds_estimate(p); est > kAnnounceSeconds)
      std::fprintf(stderr, "stokesian: note: %s: placing %ld particles (generate = \"%s\") is estimated at about %.0f s\n",
                   s.source.c_str(), p.count, p.pattern == PlacementParams::Pattern::lattice ? "lattice" : "random", est);
    try {
      const Placement pl = place_particles(p, s.domain.periodic() ? s.domain.box : Vec3::Zero());
      s.positions = pl.position;
      s.radii = pl.radius;
    } catch (const std::invalid_argument& e) {
      R.fail(phi_node, phi_where + " (generate = \"" + R.choice(t, T, "generate", "random", {"random", "lattice"}) + "\")",
             std::string(e.what()) + " (" + limits + ")");
    }
    }
  }
  s.fixed.assign(s.positions.size(), 0);
  if (const toml::node* n = t.get("fixed")) {
    const toml::array* a = n->as_array();
    if (!a || a->size() != s.positions.size())
      R.fail(n, "[particles] fixed", "expected one true/false per particle");
    for (std::size_t i = 0; i < a->size(); ++i) {
      auto b = a->get(i)->value_exact<bool>();
      if (!b) R.fail(a->get(i), "[particles] fixed", "expected true or false");
      s.fixed[i] = *b ? 1 : 0;
    }
  }
}

// Every particle source: finite positions, radii in range, and (for given positions or a file)
// no two particles overlapping by more than half the smaller radius (a coincident or nearly
// coincident pair is an input mistake; the lubrication regularisation covers small overlaps only).
void check_particles(const Reader& R, const toml::table& t, const Scene& s, const std::string& base_dir) {
  const char* key = t.contains("positions") ? "positions" : t.contains("file") ? "file" : "generate";
  std::string origin = "";
  if (std::string(key) == "file") {
    std::string path = t.get("file")->value_or(std::string());
    if (!path.empty() && path[0] != '/') path = base_dir + "/" + path;
    origin = " of " + path;
  }
  const toml::node* node = t.get(key);
  const std::string w = std::string("[particles] ") + key;
  const std::size_t n = s.positions.size();
  if (s.radii.size() != n) R.fail(node, w, "has " + std::to_string(s.radii.size()) + " radii for " + std::to_string(n) + " positions");
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& x = s.positions[i];
    if (!x.allFinite()) {
      std::ostringstream o;
      o << "particle " << i << origin << " has the non-finite position [" << x.x() << ", " << x.y() << ", " << x.z()
        << "] (allowed: finite numbers)";
      R.fail(node, w, o.str());
    }
    if (!(s.radii[i] >= kMinRadius && s.radii[i] <= kMaxRadius)) {
      std::ostringstream o;
      o << "particle " << i << origin << " has radius " << s.radii[i] << " (allowed [" << kMinRadius << ", "
        << kMaxRadius << "] a)";
      R.fail(node, w, o.str());
    }
  }
  if (n == 0) return;
  const auto [lo, hi] = std::minmax_element(s.radii.begin(), s.radii.end());
  if (*hi / *lo > kMaxRadiusRatio) {
    std::ostringstream o;
    o << "radius ratio max/min = " << *hi << "/" << *lo << " = " << *hi / *lo << " (particles "
      << hi - s.radii.begin() << " and " << lo - s.radii.begin() << "; allowed at most " << kMaxRadiusRatio
      << ", the validated size-ratio range of the lubrication functions)";
    R.fail(node, w, o.str());
  }
  if (std::string(key) == "generate") return;  // generated particles keep a gap by construction
  for (const auto& p : trees::nearest_image_pairs(s.positions, s.radii, s.domain, 0.0)) {
    const double ai = s.radii[std::size_t(p.i)], aj = s.radii[std::size_t(p.j)];
    const double overlap = ai + aj - p.dist;
    if (overlap > 0.5 * std::min(ai, aj)) {
      std::ostringstream o;
      o << "particles " << p.i << " and " << p.j << origin << " overlap by " << overlap << " a (centres " << p.dist
        << " a apart, radii " << ai << " and " << aj << "; allowed overlap at most half the smaller radius)";
      R.fail(node, w, o.str());
    }
  }
}


// [walls] (docs/channels.md): the channel geometry and its wall particles (generated later, after
// the interior particles, by append_walls).
void read_walls(const Reader& R, const toml::table& t, Scene& s) {
  const std::string T = "walls";
  R.only(t, T, {"kind", "height", "width", "length", "depth", "radius", "gap", "layers", "sections", "outline", "openings", "inlet"});
  ChannelParams& c = s.walls;
  c.kind = R.name(t, T, "kind", ChannelParams::Kind::none);
  if (!c.any()) {
    for (const char* key : {"height", "width", "length", "depth", "radius", "gap", "layers", "sections", "outline", "openings", "inlet"})
      if (t.contains(key)) R.fail(t.get(key), std::string("[walls] ") + key, "only meaningful with a wall kind (kind = \"plane\", \"slit\", \"duct\" or \"outline\")");
    return;
  }
  const bool per = s.domain.periodic();
  using K = ChannelParams::Kind;
  if (c.kind == K::outline) {
    for (const char* key : {"height", "width", "length"})
      if (t.contains(key)) R.fail(t.get(key), std::string("[walls] ") + key, "not used with kind = \"outline\" (the outline gives the geometry)");
    if (per) R.fail(t.get("kind"), "[walls] kind", "\"outline\" is for open domains (its walls and monolayer are not periodic)");
    for (const char* key : {"outline", "openings", "inlet"})
      if (!t.contains(key)) R.fail(&t, std::string("[walls] ") + key, "required with kind = \"outline\"");
    const toml::array* pts = t.get("outline")->as_array();
    if (!pts || pts->size() < 3) R.fail(t.get("outline"), "[walls] outline", "expected a list of at least 3 vertices [x, y] (a)");
    for (const auto& e : *pts) {
      const toml::array* xy = e.as_array();
      std::array<double, 2> v{};
      bool ok = xy && xy->size() == 2;
      for (std::size_t k = 0; ok && k < 2; ++k) {
        if (auto i = xy->get(k)->value_exact<int64_t>()) v[k] = double(*i);
        else if (auto d = xy->get(k)->value_exact<double>()) v[k] = *d;
        else ok = false;
        ok = ok && std::isfinite(v[k]) && std::abs(v[k]) <= kMaxBoxEdge;
      }
      if (!ok) R.fail(&e, "[walls] outline", "each vertex is [x, y], two finite numbers of magnitude at most " + Reader::brief(kMaxBoxEdge) + " (a)");
      c.outline.push_back(v);
    }
    const toml::array* op = t.get("openings")->as_array();
    if (!op || op->empty()) R.fail(t.get("openings"), "[walls] openings", "expected a list of edge indices (edge k runs from vertex k to k + 1)");
    for (const auto& e : *op) {
      auto i = e.value_exact<int64_t>();
      if (!i) R.fail(&e, "[walls] openings", "expected edge indices (integers)");
      c.openings.push_back(long(*i));
    }
    c.inlet = R.integer(t, T, "inlet", -1, 0, long(c.outline.size()) - 1);
    c.radius = R.number(t, T, "radius", 1.0, kMinRadius, kMaxRadius);
    c.depth = R.number(t, T, "depth", 2.0 * c.radius, 0.0, kMaxBoxEdge, true);
    c.gap = R.number(t, T, "gap", c.gap, 0.0, 100.0);
    c.layers = R.integer(t, T, "layers", 1, 1, 10);
    c.sections = R.integer(t, T, "sections", 1, 1, 10000);
    try {
      make_outline(c);
    } catch (const std::invalid_argument& e) {
      R.fail(t.get("outline"), "[walls] outline", e.what());
    }
    return;
  }
  for (const char* key : {"outline", "openings", "inlet"})
    if (t.contains(key)) R.fail(t.get(key), std::string("[walls] ") + key, "only meaningful with kind = \"outline\"");
  auto need = [&](const char* key, bool needed, const std::string& why) {
    if (needed && !t.contains(key)) R.fail(&t, std::string("[walls] ") + key, "required " + why);
    if (!needed && t.contains(key)) R.fail(t.get(key), std::string("[walls] ") + key, "not used " + why);
  };
  need("height", c.kind != K::plane, std::string("with kind = \"") + name_of(c.kind) + "\"");
  need("width", c.kind == K::duct, std::string("with kind = \"") + name_of(c.kind) + "\"");
  need("length", !per, per ? "in a periodic box (the walls span the box along x)" : "in an open domain (the walls' extent along x)");
  need("depth", !per && c.kind != K::duct,
       per ? "in a periodic box (the walls span the box along z)"
       : c.kind == K::duct ? "with kind = \"duct\" (its side walls bound z)"
                           : "in an open domain (the walls' extent along z)");
  if (per && c.kind == K::plane)
    R.fail(t.get("kind"), "[walls] kind", "\"plane\" is for open domains; in a periodic box use \"slit\" (a plane wall repeats as a stack of slits)");
  c.height = R.number(t, T, "height", 0.0, 0.0, kMaxBoxEdge, true);
  c.width = R.number(t, T, "width", 0.0, 0.0, kMaxBoxEdge, true);
  c.length = R.number(t, T, "length", 0.0, 0.0, kMaxBoxEdge);
  c.depth = R.number(t, T, "depth", 0.0, 0.0, kMaxBoxEdge);
  c.radius = R.number(t, T, "radius", 1.0, kMinRadius, kMaxRadius);
  c.gap = R.number(t, T, "gap", c.gap, 0.0, 100.0);
  c.layers = R.integer(t, T, "layers", 1, 1, 10);
  c.sections = R.integer(t, T, "sections", 1, 1, 10000);
}

// Appends the wall particles (fixed) after the interior particles and checks that every interior
// particle lies in the fluid region. A trajectory of a channel run holds its wall particles last:
// those equal to the generated ones are dropped from the file's particles first.
void append_walls(const Reader& R, const toml::table& pt, const toml::table& root, Scene& s, bool from_file) {
  if (!s.walls.any()) return;
  const toml::table& wt = *root.get("walls")->as_table();
  std::vector<Vec3> w;
  try {
    w = wall_particles(s.walls, s.domain);
  } catch (const std::invalid_argument& e) {
    R.fail(wt.get("kind"), "[walls] kind", e.what());
  }
  if (double(w.size()) > double(kMaxCount)) {
    std::ostringstream o;
    o << "gives " << w.size() << " wall particles (allowed at most " << kMaxCount << ")";
    R.fail(wt.get("kind"), "[walls] kind", o.str());
  }
  const char* key = pt.contains("positions") ? "positions" : pt.contains("file") ? "file" : "generate";
  if (from_file || pt.contains("file")) {
    std::size_t n = s.positions.size();
    bool same = n >= w.size();
    for (std::size_t k = 0; same && k < w.size(); ++k) {
      const std::size_t i = n - w.size() + k;
      Vec3 d = s.positions[i] - w[k];
      if (s.domain.periodic()) d = s.domain.minimum_image(d);
      same = d.norm() <= 1e-9 * (1.0 + w[k].norm()) && std::abs(s.radii[i] - s.walls.radius) <= 1e-12;
    }
    if (same) {
      s.positions.resize(n - w.size());
      s.radii.resize(n - w.size());
      s.fixed.resize(n - w.size());
    }
  }
  if (const long i = first_outside_channel(s.walls, s.domain, s.positions); i >= 0) {
    std::ostringstream o;
    const Vec3& x = s.positions[std::size_t(i)];
    o << "particle " << i << " at [" << x.x() << ", " << x.y() << ", " << x.z() << "] lies outside the fluid region of "
      << "[walls] kind = \"" << name_of(s.walls.kind) << "\" (centre " << channel_centre(s.domain).transpose()
      << "; docs/channels.md)";
    R.fail(pt.get(key), std::string("[particles] ") + key, o.str());
  }
  s.wall_count = w.size();
  for (const Vec3& x : w) {
    s.positions.push_back(x);
    s.radii.push_back(s.walls.radius);
    s.fixed.push_back(1);
  }
}

PairForceParams read_pair(const Reader& R, const toml::table& t, std::size_t index) {
  const std::string T = "forces.pair." + std::to_string(index);
  PairForceParams p;
  // Unknown keys first (a misspelt `kind` is reported as itself, not as a missing `kind`); keys of
  // another kind are refused below, once the kind is known.
  R.only(t, T, {"kind", "cutoff", "depth", "kappa", "hamaker", "debye_kappa", "surface_potential",
                "surface_potential_reduced", "born_sigma", "min_gap", "double_layer", "stiffness", "rest_gap", "strength",
                "decay"});
  const std::string kind = R.choice(t, T, "kind", "", name_list<PairForceParams::Kind>());
  if (kind.empty())
    R.fail(&t, "[[forces.pair]] kind", "required (" + quoted_list(name_list<PairForceParams::Kind>()) + ")");
  p.cutoff = R.number(t, T, "cutoff", 0.0, 0.0, 1e6);
  if (kind == "morse") {
    p.kind = PairForceParams::Kind::morse;
    R.only(t, T, {"kind", "cutoff", "depth", "kappa"});
    p.morse_depth = R.number(t, T, "depth", p.morse_depth, 0.0, 1e12);
    p.morse_kappa = R.number(t, T, "kappa", p.morse_kappa, 0.0, 1e6, true);
  } else if (kind == "dlvo") {
    p.kind = PairForceParams::Kind::dlvo;
    R.only(t, T, {"kind", "cutoff", "hamaker", "debye_kappa", "surface_potential", "surface_potential_reduced",
                  "born_sigma", "min_gap", "double_layer"});
    p.hamaker = R.number(t, T, "hamaker", p.hamaker, 0.0, 1e12);
    p.debye_kappa = R.number(t, T, "debye_kappa", p.debye_kappa, 0.0, 1e6, true);
    p.surface_potential = R.number(t, T, "surface_potential", p.surface_potential, 0.0, 1e12);
    p.surface_potential_reduced = R.number(t, T, "surface_potential_reduced", p.surface_potential_reduced, 0.0, 1e3);
    p.born_sigma = R.number(t, T, "born_sigma", p.born_sigma, 0.0, 1.0);
    p.min_gap = R.number(t, T, "min_gap", p.min_gap, 0.0, 1.0, true);
    p.double_layer = R.name(t, T, "double_layer", PairForceParams::DoubleLayer::hhf);
  } else if (kind == "harmonic") {
    p.kind = PairForceParams::Kind::harmonic;
    R.only(t, T, {"kind", "cutoff", "stiffness", "rest_gap"});
    p.harmonic_stiffness = R.number(t, T, "stiffness", p.harmonic_stiffness, 0.0, 1e12, true);
    p.harmonic_rest_gap = R.number(t, T, "rest_gap", p.harmonic_rest_gap, 0.0, 1e6);
    if (p.cutoff > 0.0 && !(p.cutoff > p.harmonic_rest_gap)) {
      std::ostringstream o;
      o << "cutoff = " << p.cutoff << " must exceed rest_gap = " << p.harmonic_rest_gap
        << " (the spring's minimum would be cut off); allowed (rest_gap, 1e6], or 0 for the default";
      R.fail(R.get(t, T, "cutoff"), R.where(T, "cutoff"), o.str());
    }
  } else if (kind == "repulsion") {
    p.kind = PairForceParams::Kind::repulsion;
    R.only(t, T, {"kind", "cutoff", "strength", "decay", "min_gap"});
    p.repulsion_strength = R.number(t, T, "strength", p.repulsion_strength, 0.0, 1e12);
    p.repulsion_decay = R.number(t, T, "decay", p.repulsion_decay, 0.0, 1e8, true);
    p.min_gap = R.number(t, T, "min_gap", p.min_gap, 0.0, 1.0, true);
  } else {
    p.kind = PairForceParams::Kind::hertz;
    R.only(t, T, {"kind", "cutoff", "stiffness"});
    p.hertz_stiffness = R.number(t, T, "stiffness", p.hertz_stiffness, 0.0, 1e15, true);
  }
  return p;
}

std::string dir_of(const std::string& path) {
  const auto p = std::filesystem::path(path).parent_path();
  return p.empty() ? "." : p.string();
}

// Limits checked on the raw text before toml++ parses it: its parser recurses once per nesting
// level and per dotted-key part, so an unbounded text could exhaust the stack (a crash instead of
// an error). The scan follows TOML's lexical structure just far enough (strings, comments,
// brackets, keys) to count both; everything else is left to the parser.
constexpr std::size_t kMaxSceneBytes = std::size_t(16) << 20;  // 16 MiB
constexpr std::size_t kMaxNesting = 64;   // open [ and { at once (arrays, inline tables, headers)
constexpr int kMaxKeyParts = 64;          // dotted parts of one key or table header

void check_text_shape(const std::string& text, const std::string& source) {
  if (text.size() > kMaxSceneBytes)
    throw ConfigError(source + ": scene text has " + std::to_string(text.size()) + " bytes (allowed at most " +
                      std::to_string(kMaxSceneBytes) + " bytes = 16 MiB)");
  long line = 1;
  auto fail = [&](const std::string& msg) { throw ConfigError(source + ":" + std::to_string(line) + ": " + msg); };
  std::vector<char> stack;  // 'H' table header, '[' array, '{' inline table
  bool key = true;          // reading a key: line start at top level, in a header, after '{' or ',' of an inline table
  int parts = 1;
  const std::size_t n = text.size();
  auto open = [&](char c) {
    stack.push_back(c);
    if (stack.size() > kMaxNesting)
      fail("arrays, inline tables and headers nested " + std::to_string(stack.size()) + " deep (allowed at most " +
           std::to_string(kMaxNesting) + " levels)");
  };
  for (std::size_t i = 0; i < n; ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      if (stack.empty()) key = true, parts = 1;
      continue;
    }
    if (c == '#') {
      while (i + 1 < n && text[i + 1] != '\n') ++i;
      continue;
    }
    if (c == '"' || c == '\'') {  // skip a string (escapes only in basic strings)
      const bool multi = text.compare(i, 3, std::string(3, c)) == 0;
      std::size_t j = i + (multi ? 3 : 1);
      for (; j < n; ++j) {
        if (c == '"' && text[j] == '\\') { if (j + 1 < n && text[j + 1] == '\n') ++line; ++j; continue; }
        if (text[j] == '\n') { if (!multi) break; ++line; continue; }
        if (text[j] == c && (!multi || text.compare(j, 3, std::string(3, c)) == 0)) break;
      }
      if (multi) while (j + 3 < n && text[j + 3] == c) ++j;  // up to two quotes may end the content
      i = multi ? std::min(n, j + 3) - 1 : (j < n && text[j] == '\n' ? j - 1 : j);
      continue;
    }
    if (key) {
      if (c == '.') {
        if (++parts > kMaxKeyParts)
          fail("a key or table header with more than " + std::to_string(kMaxKeyParts) +
               " dotted parts (allowed 1 to " + std::to_string(kMaxKeyParts) + " parts)");
      } else if (c == '=') {
        key = false, parts = 1;
      } else if (c == '[' && stack.empty()) {
        open('H');
        if (i + 1 < n && text[i + 1] == '[') ++i;
        parts = 1;
      } else if (c == ']' && !stack.empty() && stack.back() == 'H') {
        stack.pop_back();
        if (i + 1 < n && text[i + 1] == ']') ++i;
        key = false;
      } else if (c == '}' && !stack.empty() && stack.back() == '{') {
        stack.pop_back();
        key = false;
      }
      continue;
    }
    if (c == '[' || c == '{') {
      open(c);
      key = c == '{', parts = 1;
    } else if (c == ']' || c == '}') {
      if (!stack.empty()) stack.pop_back();
    } else if (c == ',' && !stack.empty() && stack.back() == '{') {
      key = true, parts = 1;
    }
  }
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& source) {
  check_text_shape(text, source);
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    // The offending line is quoted (shortened, bytes outside printable ASCII as \xNN), so that the
    // message names the key even when the parser's description does not.
    const auto line_no = e.source().begin.line;
    std::string quoted;
    std::size_t begin = 0;
    for (std::size_t k = 1; k < line_no && begin != std::string::npos; ++k) {
      begin = text.find('\n', begin);
      if (begin != std::string::npos) ++begin;
    }
    if (line_no >= 1 && begin != std::string::npos && begin < text.size()) {
      const std::size_t end = std::min(text.find('\n', begin), text.size());
      for (std::size_t k = begin; k < end && quoted.size() < 80; ++k) {
        const unsigned char ch = static_cast<unsigned char>(text[k]);
        if (ch >= 0x20 && ch < 0x7f) {
          quoted += char(ch);
        } else {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\x%02X", ch);
          quoted += buf;
        }
      }
      if (end - begin > 80) quoted += "...";
    }
    std::ostringstream o;
    o << source << ":" << line_no << ": TOML syntax error: " << e.description();
    if (!quoted.empty()) o << " (in the line: " << quoted << ")";
    throw ConfigError(o.str());
  }
  return parse_scene(root, source);
}

Scene parse_scene(const toml::table& root, const std::string& source) {
  Scene s;
  s.source = source;
  Reader R(source, &s.lines);
  R.only(root, "top level", {"domain", "fluid", "walls", "particles", "inflow", "forces", "flow", "hydrodynamics", "brownian", "time", "output", "run"});

  const toml::table& dom = sub(R, root, "domain");
  R.only(dom, "domain", {"kind", "box", "shear_strain"});
  s.domain.kind = R.name(dom, "domain", "kind", Domain::Kind::open);
  if (const toml::node* b = dom.get("box")) {
    s.domain.box = R.vec3(*b, "[domain] box");
    if (s.domain.box.minCoeff() <= 0 || s.domain.box.maxCoeff() > kMaxBoxEdge) {
      std::ostringstream o;
      o << "edges [" << s.domain.box.x() << ", " << s.domain.box.y() << ", " << s.domain.box.z()
        << "] out of range (allowed every edge in (0, " << kMaxBoxEdge << "] a)";
      R.fail(b, "[domain] box", o.str());
    }
    if (!s.domain.periodic()) R.fail(b, "[domain] box", "only meaningful with kind = \"periodic\"");
  } else if (s.domain.periodic()) {
    R.fail(&dom, "[domain] box", "required with kind = \"periodic\"");
  }
  s.domain.shear_strain = R.number(dom, "domain", "shear_strain", 0.0, -1e9, 1e9);
  if (s.domain.shear_strain != 0 && !s.domain.periodic())
    R.fail(dom.get("shear_strain"), "[domain] shear_strain", "only meaningful with kind = \"periodic\"");

  const toml::table& fl = sub(R, root, "fluid");
  R.only(fl, "fluid", {"viscosity", "kT"});
  s.fluid.viscosity = R.number(fl, "fluid", "viscosity", 1.0, 0.0, 1e12, true);
  s.fluid.kT = R.number(fl, "fluid", "kT", 0.0, 0.0, 1e12);

  read_walls(R, sub(R, root, "walls"), s);

  if (!root.contains("particles")) R.fail(&root, "[particles]", "required table is missing");
  std::optional<Snapshot> from_run;
  read_particles(R, sub(R, root, "particles"), s, dir_of(source), from_run);
  if (from_run) {
    // Continuing a run: its box and lattice strain come with its positions.
    const toml::node* file = sub(R, root, "particles").get("file");
    std::ostringstream box;
    box << "[" << from_run->box.x() << ", " << from_run->box.y() << ", " << from_run->box.z() << "]";
    if (from_run->periodic && !s.domain.periodic())
      R.fail(file, "[particles] file", "holds a run in the periodic box " + box.str() +
                                           "; an open domain would drop its periodic images: set [domain] kind = "
                                           "\"periodic\" and box = " + box.str() + " to continue it");
    if (from_run->periodic && ((s.domain.box - from_run->box).cwiseAbs().maxCoeff() > 1e-12 * from_run->box.maxCoeff())) {
      std::ostringstream o;
      o << "holds a run in the box " << box.str() << ", but [domain] box is [" << s.domain.box.x() << ", "
        << s.domain.box.y() << ", " << s.domain.box.z() << "]: its positions belong to its own box";
      R.fail(file, "[particles] file", o.str());
    }
    if (from_run->periodic && !dom.contains("shear_strain")) s.domain.shear_strain = from_run->shear_strain;
  }

  append_walls(R, sub(R, root, "particles"), root, s, from_run.has_value());
  check_particles(R, sub(R, root, "particles"), s, dir_of(source));

  const toml::table& fo = sub(R, root, "forces");
  R.only(fo, "forces", {"external_force", "external_torque", "pair", "gravity"});
  s.forces.external_force = R.vec3_list(fo, "forces", "external_force");
  s.forces.external_torque = R.vec3_list(fo, "forces", "external_torque");
  for (const auto* key : {"external_force", "external_torque"}) {
    const auto& v = std::string(key) == "external_force" ? s.forces.external_force : s.forces.external_torque;
    if (v.size() > 1 && v.size() != s.interior_count()) {
      std::ostringstream o;
      o << "has " << v.size() << " vectors for " << s.interior_count() << " particles (give 1 or one per particle"
        << (s.wall_count ? "; wall particles take none" : "") << ")";
      R.fail(fo.get(key), std::string("[forces] ") + key, o.str());
    }
  }
  // Wall particles (last) get no given load: they are held in place, their forces are solved for.
  for (auto* v : {&s.forces.external_force, &s.forces.external_torque})
    if (v->size() > 1) v->resize(s.positions.size(), Vec3::Zero());
  // gravity: the force on a sphere of radius 1 a; particle i gets gravity * a_i^3, added to its
  // external_force (the sum is stored per particle, so the resolved scene lists it explicitly).
  if (const toml::node* gn = R.get(fo, "forces", "gravity")) {
    const Vec3 g = R.vec3(*gn, "[forces] gravity");
    std::vector<Vec3> f(s.positions.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Vec3 base = s.forces.external_force.empty() ? Vec3::Zero()
                        : s.forces.external_force.size() == 1 ? s.forces.external_force[0]
                                                              : s.forces.external_force[i];
      f[i] = base + g * (s.radii[i] * s.radii[i] * s.radii[i]);
    }
    s.forces.external_force = f;
  }
  if (const toml::node* pn = fo.get("pair")) {
    const toml::array* arr = pn->as_array();
    if (!arr) R.fail(pn, "[[forces.pair]]", "expected an array of tables ([[forces.pair]])");
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const toml::table* pt = arr->get(i)->as_table();
      if (!pt) R.fail(arr->get(i), "[[forces.pair]]", "expected a table");
      s.forces.pair.push_back(read_pair(R, *pt, i));
    }
  }

  const toml::table& flow = sub(R, root, "flow");
  R.only(flow, "flow", {"kind", "rate", "peclet", "mean_velocity", "grid_spacing", "file", "file_hash"});
  s.flow.kind = R.name(flow, "flow", "kind", FlowParams::Kind::none);
  if (s.flow.kind == FlowParams::Kind::tabulated) {
    // A field exported by a fluid solver (io/flow_table.hpp); the resolved scene keeps its path and
    // hash, so that a resumed or re-run scene refuses a changed file.
    for (const char* key : {"rate", "peclet", "mean_velocity"})
      if (flow.contains(key))
        R.fail(flow.get(key), std::string("[flow] ") + key, "not used with kind = \"tabulated\" (the file gives the flow)");
    if (!flow.contains("file")) R.fail(&flow, "[flow] file", "required with kind = \"tabulated\"");
    std::string path = R.string(flow, "flow", "file", "");
    if (!path.empty() && path[0] != '/') path = dir_of(source) + "/" + path;
    try {
      auto grid = std::make_shared<FlowGrid>(read_flow_table(path));
      grid->path = std::filesystem::absolute(path).lexically_normal().string();
      s.flow.grid = grid;
    } catch (const std::exception& e) {
      R.fail(flow.get("file"), "[flow] file", e.what());
    }
    if (flow.contains("file_hash")) {
      char hex[20];
      std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)s.flow.grid->hash);
      const std::string want = R.string(flow, "flow", "file_hash", "");
      if (want != hex)
        R.fail(flow.get("file_hash"), "[flow] file_hash",
               "the flow table " + s.flow.grid->path + " has changed (hash " + hex + ", the scene recorded " + want +
                   "); restore the file or start a new run without file_hash");
    }
  } else {
    for (const char* key : {"file", "file_hash"})
      if (flow.contains(key)) R.fail(flow.get(key), std::string("[flow] ") + key, "only meaningful with kind = \"tabulated\"");
  }
  if (s.flow.kind == FlowParams::Kind::poiseuille) {
    // Pressure-driven flow through the [walls] channel (engine/core/channel.hpp).
    for (const char* key : {"rate", "peclet"})
      if (flow.contains(key))
        R.fail(flow.get(key), std::string("[flow] ") + key, "not used with kind = \"poiseuille\" (give mean_velocity)");
    if (s.walls.kind != ChannelParams::Kind::slit && s.walls.kind != ChannelParams::Kind::duct &&
        s.walls.kind != ChannelParams::Kind::outline)
      R.fail(flow.get("kind"), "[flow] kind", "\"poiseuille\" flows through a channel: set [walls] kind = \"slit\", \"duct\" or \"outline\"");
    if (!flow.contains("mean_velocity")) R.fail(&flow, "[flow] mean_velocity", "required with kind = \"poiseuille\"");
    s.flow.mean_velocity = R.number(flow, "flow", "mean_velocity", 0.0, -1e12, 1e12);
    if (s.walls.kind == ChannelParams::Kind::outline) {
      // The 2D Stokes flow through the outline, solved here (engine/core/outline.hpp).
      s.flow.grid_spacing = R.number(flow, "flow", "grid_spacing", 0.0, 0.0, kMaxBoxEdge);
      try {
        const Outline o = make_outline(s.walls);
        s.flow.grid_spacing = outline_grid_spacing(o, s.flow.grid_spacing);
        auto solved = std::make_shared<const OutlineFlow>(solve_outline_flow(o, s.flow.mean_velocity, s.flow.grid_spacing));
        s.flow.outline = solved;
        s.flow.grid = std::shared_ptr<const FlowGrid>(solved, &solved->grid);
      } catch (const std::invalid_argument& e) {
        R.fail(flow.contains("grid_spacing") ? flow.get("grid_spacing") : flow.get("kind"),
               flow.contains("grid_spacing") ? "[flow] grid_spacing" : "[flow] kind", e.what());
      }
    } else if (flow.contains("grid_spacing")) {
      R.fail(flow.get("grid_spacing"), "[flow] grid_spacing", "only meaningful with [walls] kind = \"outline\" (its 2D flow is solved on a grid)");
    }
  } else {
    for (const char* key : {"mean_velocity", "grid_spacing"})
      if (flow.contains(key)) R.fail(flow.get(key), std::string("[flow] ") + key, "only meaningful with kind = \"poiseuille\"");
  }
  s.flow.rate = R.number(flow, "flow", "rate", 0.0, -1e12, 1e12);
  if (flow.contains("peclet")) {
    // Pe = 6 pi mu a^3 rate / kT with a = 1 (docs/rheology.md): the rate follows from Pe and kT.
    if (flow.contains("rate"))
      R.fail(flow.get("peclet"), "[flow] peclet", "give either rate or peclet, not both (peclet sets rate = peclet kT / (6 pi mu))");
    if (s.flow.kind == FlowParams::Kind::none)
      R.fail(flow.get("peclet"), "[flow] peclet", "needs a flow: set [flow] kind = \"simple_shear\" or \"planar_extension\"");
    if (!(s.fluid.kT > 0.0))
      R.fail(flow.get("peclet"), "[flow] peclet", "needs [fluid] kT > 0 (Pe = 6 pi mu a^3 rate / kT); give rate for an athermal scene");
    s.flow.peclet = R.number(flow, "flow", "peclet", 0.0, -1e12, 1e12);
    s.flow.rate = s.flow.peclet * s.fluid.kT / (6.0 * kPi * s.fluid.viscosity);
  }
  if (s.flow.kind != FlowParams::Kind::none && s.flow.kind != FlowParams::Kind::poiseuille &&
      s.flow.kind != FlowParams::Kind::tabulated && !flow.contains("rate") && !flow.contains("peclet"))
    R.fail(&flow, "[flow] rate", "required when kind is not \"none\" (or give peclet)");

  // [inflow] (engine/inflow.hpp): particles fed through the inlet of an outline channel.
  if (root.contains("inflow")) {
    const toml::table& in = sub(R, root, "inflow");
    R.only(in, "inflow", {"areal_fraction", "capacity", "radius", "min_gap"});
    if (s.walls.kind != ChannelParams::Kind::outline)
      R.fail(&in, "[inflow]", "particles enter through the inlet of a channel outline: set [walls] kind = \"outline\"");
    if (s.flow.kind != FlowParams::Kind::poiseuille || !(s.flow.mean_velocity > 0.0))
      R.fail(&in, "[inflow]", "needs the flow that carries the particles in: [flow] kind = \"poiseuille\" with mean_velocity > 0");
    if (!in.contains("areal_fraction")) R.fail(&in, "[inflow] areal_fraction", "required (areal fraction of the incoming monolayer)");
    InflowParams& p = s.inflow;
    p.enabled = true;
    p.areal_fraction = R.number(in, "inflow", "areal_fraction", 0.0, 0.0, 0.5, true);
    p.radius = R.number(in, "inflow", "radius", 1.0, 0.0, 1e3, true);
    p.min_gap = R.number(in, "inflow", "min_gap", 0.1, 0.0, 10.0);
    const Outline o = make_outline(s.walls);
    const double w = o.length(std::size_t(o.inlet));
    if (2.0 * (p.radius + p.min_gap) >= w) {
      std::ostringstream m;
      m << "radius " << p.radius << " with min_gap " << p.min_gap << " does not fit across the inlet of width " << w
        << " (allowed: 2 (radius + min_gap) < inlet width)";
      R.fail(in.contains("radius") ? in.get("radius") : in.get("min_gap") ? in.get("min_gap") : &in, "[inflow] radius", m.str());
    }
    // Default: the scene's particles plus room for the channel at twice the incoming fraction.
    const long room = long(std::ceil(2.0 * p.areal_fraction * o.area / (kPi * p.radius * p.radius)));
    p.capacity = R.integer(in, "inflow", "capacity", long(s.interior_count()) + room, 1, 1000000);
    if (std::size_t(p.capacity) < s.interior_count())
      R.fail(in.get("capacity"), "[inflow] capacity",
             "value " + std::to_string(p.capacity) + " is below the scene's " + std::to_string(s.interior_count()) +
                 " particles (allowed: at least the particles the scene starts with)");
    for (std::size_t i = 0; i < s.interior_count(); ++i)
      if (s.fixed[i])
        R.fail(&in, "[inflow]", "the scene's particles are all mobile in an open channel (particle " + std::to_string(i) +
                                   " is fixed; fixed particles come from [walls])");
  }

  const toml::table& hy = sub(R, root, "hydrodynamics");
  R.only(hy, "hydrodynamics", {"model", "moments", "solver", "far_field", "tolerance", "lubrication_cutoff",
                                 "lubrication_taper", "lubrication_min_gap", "lubrication", "squeeze_contact_gap",
                                 "squeeze_slip_gap", "squeeze_transition_gap"});
  s.hydro.model = R.name(hy, "hydrodynamics", "model", HydroModel::auto_);
  s.hydro.moments = R.name(hy, "hydrodynamics", "moments", MomentChoice::auto_);
  // A registered method or "auto": checked against the registry by model resolution.
  s.hydro.far_field = R.string(hy, "hydrodynamics", "far_field", s.hydro.far_field);
  s.hydro.solver = R.choice(hy, "hydrodynamics", "solver", "auto", {"auto", "dense", "accelerated"});
  s.hydro.tolerance = R.number(hy, "hydrodynamics", "tolerance", 1e-6, 1e-14, 0.1);
  // lubrication_cutoff, lubrication_taper: "auto" or a number (docs/scene.md; resolved by
  // lubrication::near_field_params). A taper must leave s_in = cutoff - taper >= 2.
  auto is_auto = [&](const char* key, bool def) {
    const toml::node* n = R.get(hy, "hydrodynamics", key);
    if (!n || !n->is_string()) return n ? false : def;
    if (n->value_exact<std::string>() != "auto")
      R.fail(n, std::string("[hydrodynamics] ") + key,
             "\"" + *n->value_exact<std::string>() + "\" is not \"auto\" or a number (allowed: \"auto\" or " +
                 (std::string(key) == "lubrication_cutoff" ? "a number in (2, 100])" : "a number in [0, 98])"));
    return true;
  };
  s.hydro.lubrication_cutoff_auto = is_auto("lubrication_cutoff", HydroParams{}.lubrication_cutoff_auto);
  if (!s.hydro.lubrication_cutoff_auto)
    s.hydro.lubrication_cutoff = R.number(hy, "hydrodynamics", "lubrication_cutoff", 4.0, 2.0, 100.0, true);
  s.hydro.lubrication_taper_auto = is_auto("lubrication_taper", true);
  if (!s.hydro.lubrication_taper_auto) {
    s.hydro.lubrication_taper = R.number(hy, "hydrodynamics", "lubrication_taper", 0.0, 0.0, 98.0);
    if (!s.hydro.lubrication_cutoff_auto && s.hydro.lubrication_taper > s.hydro.lubrication_cutoff - 2.0) {
      std::ostringstream o;
      o << "value " << s.hydro.lubrication_taper << " out of range (allowed [0, " << s.hydro.lubrication_cutoff - 2.0
        << "]: the band [lubrication_cutoff - lubrication_taper, lubrication_cutoff] must start at 2 or above)";
      R.fail(R.get(hy, "hydrodynamics", "lubrication_taper"), "[hydrodynamics] lubrication_taper", o.str());
    }
  }
  s.hydro.lubrication_min_gap = R.number(hy, "hydrodynamics", "lubrication_min_gap", 1e-6, 1e-8, 0.1);
  s.hydro.lubrication = R.name(hy, "hydrodynamics", "lubrication", Lubrication::exact);
  {
    SqueezeParams& q = s.hydro.squeeze;
    q.contact_gap = R.number(hy, "hydrodynamics", "squeeze_contact_gap", q.contact_gap, 1e-12, 0.1);
    q.slip_gap = R.number(hy, "hydrodynamics", "squeeze_slip_gap", q.slip_gap, 1e-10, 1.0);
    q.transition_gap = R.number(hy, "hydrodynamics", "squeeze_transition_gap", q.transition_gap, 1e-8, 2.0);
    if (!(q.contact_gap < q.slip_gap && q.slip_gap < q.transition_gap)) {
      std::ostringstream o;
      o << "squeeze_contact_gap = " << q.contact_gap << ", squeeze_slip_gap = " << q.slip_gap
        << ", squeeze_transition_gap = " << q.transition_gap << " are not increasing (allowed: contact < slip < transition)";
      const char* key = q.contact_gap >= q.slip_gap ? "squeeze_contact_gap" : "squeeze_transition_gap";
      R.fail(R.get(hy, "hydrodynamics", key), std::string("[hydrodynamics] ") + key, o.str());
    }
  }

  const toml::table& br = sub(R, root, "brownian");
  R.only(br, "brownian", {"seed", "stress_every"});
  s.seed = std::uint64_t(R.integer(br, "brownian", "seed", 1, 0, std::numeric_limits<long>::max()));
  if (const toml::node* n = R.get(br, "brownian", "stress_every"); n && n->is_string()) {
    if (n->value_exact<std::string>() != "auto")
      R.fail(n, "[brownian] stress_every",
             "\"" + *n->value_exact<std::string>() + "\" is not \"auto\" or an integer (allowed: \"auto\" or an integer in [0, 1000000000])");
    s.brownian_stress_every = -1;
  } else {
    s.brownian_stress_every = R.integer(br, "brownian", "stress_every", -1, 0, 1000000000);
  }

  const toml::table& rn = sub(R, root, "run");  // failure policy (docs/reliability.md)
  R.only(rn, "run", {"max_overlap"});
  s.run.max_overlap = R.number(rn, "run", "max_overlap", 0.5, 0.0, 2.0);

  const toml::table& ti = sub(R, root, "time");
  R.only(ti, "time", {"dt", "steps", "integrator", "rkf_tolerance", "start_step", "start_time"});
  s.time.dt = R.number(ti, "time", "dt", 1e-3, 0.0, 1e12, true);
  s.time.steps = R.integer(ti, "time", "steps", 0, 0, std::numeric_limits<long>::max());
  // A continued run counts on from the file's last frame (so its noise streams, keyed by step, do
  // not repeat); steps are the steps taken in this run.
  s.time.start_step = R.integer(ti, "time", "start_step", from_run ? long(from_run->step) : 0, 0,
                                std::numeric_limits<long>::max() / 2);
  s.time.start_time = R.number(ti, "time", "start_time", from_run ? from_run->time : 0.0, -1e300, 1e300);
  if (s.time.steps > std::numeric_limits<long>::max() / 2)
    R.fail(ti.get("steps"), "[time] steps",
           std::to_string(s.time.steps) + " is too many (allowed: 0 to " + std::to_string(std::numeric_limits<long>::max() / 2) + ")");
  s.time.integrator = R.string(ti, "time", "integrator", s.time.integrator);  // checked by model resolution
  s.time.rkf_tolerance = R.number(ti, "time", "rkf_tolerance", 1e-6, 1e-14, 1.0);

  const toml::table& out = sub(R, root, "output");
  R.only(out, "output", {"every", "checkpoint_every", "record", "xyz", "author", "cloud", "cloud_link", "cloud_min_fraction",
                          "cluster_gap"});
  s.output.every = R.integer(out, "output", "every", 1, 1, std::numeric_limits<long>::max());
  s.output.checkpoint_every = R.integer(out, "output", "checkpoint_every", 0, 0, std::numeric_limits<long>::max());
  if (s.output.checkpoint_every > 0 && s.output.checkpoint_every % s.output.every != 0)
    R.fail(out.get("checkpoint_every"), "[output] checkpoint_every",
           "must be a multiple of [output] every (" + std::to_string(s.output.every) + ")");
  // xyz: false | true (<out stem>.xyz beside --out) | "path" (relative to the folder of --out).
  if (const toml::node* xn = R.get(out, "output", "xyz")) {
    if (const auto b = xn->value_exact<bool>()) {
      s.output.xyz = *b;
      s.output.xyz_path.clear();
    } else if (const auto p = xn->value_exact<std::string>()) {
      R.check_length(xn, "[output] xyz", *p);
      s.output.xyz = !p->empty();  // "" (written by 0.1.0 for no export) = false
      s.output.xyz_path = *p;
    } else {
      R.fail(xn, "[output] xyz", "expected true, false or a path, got " + Reader::type_name(*xn));
    }
  }
  s.output.author = R.string(out, "output", "author", "");
  // Cloud observables: true | false | "auto" (a settling cloud: open domain, gravity, no walls or inflow).
  {
    bool settling = !s.domain.periodic() && !s.walls.any() && !s.inflow.enabled && fo.contains("gravity") &&
                    s.interior_count() >= 2;
    if (const toml::node* cn = R.get(out, "output", "cloud")) {
      if (const auto b = cn->value_exact<bool>()) settling = *b;
      else if (const auto t = cn->value_exact<std::string>(); !t || *t != "auto")
        R.fail(cn, "[output] cloud", "expected true, false or \"auto\"");
    }
    if (settling && s.domain.periodic())
      R.fail(out.get("cloud"), "[output] cloud", "cloud observables need an open domain (this scene is periodic)");
    s.output.cloud = settling;
    s.output.cloud_min_fraction = R.number(out, "output", "cloud_min_fraction", 0.05, 0.0, 1.0, true);
    // Default link: kCloudLinkSpacings x (V/N)^(1/3), V the sphere of radius sqrt(5/3) x rms distance
    // of the interior centres from their centroid (the radius of a uniform sphere of that rms).
    double link = 0.0;
    const std::size_t n = s.interior_count();
    if (settling && n >= 2) {
      Vec3 c = Vec3::Zero();
      for (std::size_t i = 0; i < n; ++i) c += s.positions[i];
      c /= double(n);
      double r2 = 0.0;
      for (std::size_t i = 0; i < n; ++i) r2 += (s.positions[i] - c).squaredNorm();
      const double R0 = std::sqrt(5.0 / 3.0 * r2 / double(n));
      link = kCloudLinkSpacings * std::cbrt(4.0 / 3.0 * kPi * R0 * R0 * R0 / double(n));
    }
    s.output.cloud_link = R.number(out, "output", "cloud_link", link > 0 ? link : 1.0, 0.0, 1e12, true);
  }
  if (out.contains("cluster_gap")) s.output.cluster_gap = R.number(out, "output", "cluster_gap", 0.1, 0.0, 1e6);

  if (const toml::node* rn = R.get(out, "output", "record")) {
    const toml::array* a = rn->as_array();
    if (!a) R.fail(rn, "[output] record", "expected a list of names");
    // Names are checked against the registered outputs when the run is set up.
    std::set<std::string> names;
    for (const auto& e : *a) {
      auto v = e.value_exact<std::string>();
      if (!v) R.fail(&e, "[output] record", "expected a string, got " + Reader::type_name(e));
      R.check_length(&e, "[output] record", *v);
      names.insert(*v);
    }
    s.output.record.assign(names.begin(), names.end());
    if (names.count("all") && names.size() > 1)
      R.fail(rn, "[output] record", "\"all\" stands alone (it means every output the model computes)");
    if (s.output.record == kEveryParticleOutput) s.output.record = {"all"};
  }

  // Consistency checks across tables.
  for (std::size_t i = 0; i < s.positions.size(); ++i)
    if (s.domain.periodic()) {
      for (int c = 0; c < 3; ++c)
        if (2 * s.radii[i] >= s.domain.box[c]) {
          std::ostringstream o;
          o << "particle " << i << " of radius " << s.radii[i] << " does not fit in the box";
          R.fail(dom.get("box"), "[domain] box", o.str());
        }
    }
  s.toml = resolved_toml(s);
  return s;
}

std::string resolved_toml(const Scene& s) {
  auto vec = [](const Vec3& v) { return toml::array{v.x(), v.y(), v.z()}; };
  auto vec_list = [&](const std::vector<Vec3>& list) {
    toml::array a;
    for (const Vec3& v : list) a.push_back(vec(v));
    return a;
  };
  toml::table root;
  toml::table dom{{"kind", name_of(s.domain.kind)}};
  if (s.domain.periodic()) {
    dom.insert("box", vec(s.domain.box));
    dom.insert("shear_strain", s.domain.shear_strain);
  }
  root.insert("domain", dom);
  root.insert("fluid", toml::table{{"viscosity", s.fluid.viscosity}, {"kT", s.fluid.kT}});
  // Interior particles only: the wall particles follow from [walls].
  const std::size_t ni = s.interior_count();
  auto interior = [&](const std::vector<Vec3>& v) {
    return v.size() > 1 ? std::vector<Vec3>(v.begin(), v.begin() + long(std::min(ni, v.size()))) : v;
  };
  if (s.walls.any()) {
    toml::table w{{"kind", name_of(s.walls.kind)}, {"radius", s.walls.radius}, {"gap", s.walls.gap},
                  {"layers", int64_t(s.walls.layers)}, {"sections", int64_t(s.walls.sections)}};
    if (s.walls.kind == ChannelParams::Kind::outline) {
      toml::array pts, open;
      for (const auto& v : s.walls.outline) pts.push_back(toml::array{v[0], v[1]});
      for (long e : s.walls.openings) open.push_back(int64_t(e));
      w.insert("outline", pts);
      w.insert("openings", open);
      w.insert("inlet", int64_t(s.walls.inlet));
      w.insert("depth", s.walls.depth);
    } else if (s.walls.kind != ChannelParams::Kind::plane) {
      w.insert("height", s.walls.height);
    }
    if (s.walls.kind == ChannelParams::Kind::duct) w.insert("width", s.walls.width);
    if (!s.domain.periodic() && s.walls.kind != ChannelParams::Kind::outline) {
      w.insert("length", s.walls.length);
      if (s.walls.kind != ChannelParams::Kind::duct) w.insert("depth", s.walls.depth);
    }
    root.insert("walls", w);
  }
  toml::array radii, fixed;
  for (std::size_t i = 0; i < ni; ++i) radii.push_back(s.radii[i]);
  for (std::size_t i = 0; i < ni; ++i) fixed.push_back(bool(s.fixed[i]));
  root.insert("particles", toml::table{{"positions", vec_list(interior(s.positions))}, {"radii", radii}, {"fixed", fixed}});
  if (s.inflow.enabled)
    root.insert("inflow", toml::table{{"areal_fraction", s.inflow.areal_fraction}, {"capacity", int64_t(s.inflow.capacity)},
                                      {"radius", s.inflow.radius}, {"min_gap", s.inflow.min_gap}});
  toml::table forces;
  if (!s.forces.external_force.empty()) forces.insert("external_force", vec_list(interior(s.forces.external_force)));
  if (!s.forces.external_torque.empty()) forces.insert("external_torque", vec_list(interior(s.forces.external_torque)));
  toml::array pair;
  for (const PairForceParams& p : s.forces.pair) {
    toml::table t{{"cutoff", p.cutoff}};
    t.insert("kind", name_of(p.kind));
    if (p.kind == PairForceParams::Kind::morse) {
      t.insert("depth", p.morse_depth);
      t.insert("kappa", p.morse_kappa);
    } else if (p.kind == PairForceParams::Kind::dlvo) {
      t.insert("hamaker", p.hamaker);
      t.insert("debye_kappa", p.debye_kappa);
      t.insert("surface_potential", p.surface_potential);
      t.insert("surface_potential_reduced", p.surface_potential_reduced);
      t.insert("born_sigma", p.born_sigma);
      t.insert("min_gap", p.min_gap);
      t.insert("double_layer", name_of(p.double_layer));
    } else if (p.kind == PairForceParams::Kind::repulsion) {
      t.insert("strength", p.repulsion_strength);
      t.insert("decay", p.repulsion_decay);
      t.insert("min_gap", p.min_gap);
    } else if (p.kind == PairForceParams::Kind::harmonic) {
      t.insert("stiffness", p.harmonic_stiffness);
      t.insert("rest_gap", p.harmonic_rest_gap);
    } else {
      t.insert("stiffness", p.hertz_stiffness);
    }
    pair.push_back(t);
  }
  if (!pair.empty()) forces.insert("pair", pair);
  root.insert("forces", forces);
  if (s.flow.kind == FlowParams::Kind::poiseuille) {
    toml::table f{{"kind", name_of(s.flow.kind)}, {"mean_velocity", s.flow.mean_velocity}};
    if (s.walls.kind == ChannelParams::Kind::outline) f.insert("grid_spacing", s.flow.grid_spacing);
    root.insert("flow", f);
  } else if (s.flow.kind == FlowParams::Kind::tabulated && s.flow.grid) {
    char hex[20];
    std::snprintf(hex, sizeof hex, "%016llx", (unsigned long long)s.flow.grid->hash);
    root.insert("flow", toml::table{{"kind", name_of(s.flow.kind)}, {"file", s.flow.grid->path}, {"file_hash", std::string(hex)}});
  } else if (s.flow.peclet != 0.0) root.insert("flow", toml::table{{"kind", name_of(s.flow.kind)}, {"peclet", s.flow.peclet}});
  else root.insert("flow", toml::table{{"kind", name_of(s.flow.kind)}, {"rate", s.flow.rate}});
  toml::table hydro{{"model", name_of(s.hydro.model)},
                    {"moments", name_of(s.hydro.moments)},
                    {"far_field", s.hydro.far_field},
                    {"solver", s.hydro.solver},
                    {"tolerance", s.hydro.tolerance},
                    {"lubrication_min_gap", s.hydro.lubrication_min_gap},
                    {"lubrication", name_of(s.hydro.lubrication)}};
  if (s.hydro.lubrication == Lubrication::squeeze) {
    hydro.insert("squeeze_contact_gap", s.hydro.squeeze.contact_gap);
    hydro.insert("squeeze_slip_gap", s.hydro.squeeze.slip_gap);
    hydro.insert("squeeze_transition_gap", s.hydro.squeeze.transition_gap);
  }
  if (s.hydro.lubrication_cutoff_auto) hydro.insert("lubrication_cutoff", "auto");
  else hydro.insert("lubrication_cutoff", s.hydro.lubrication_cutoff);
  if (s.hydro.lubrication_taper_auto) hydro.insert("lubrication_taper", "auto");
  else hydro.insert("lubrication_taper", s.hydro.lubrication_taper);
  root.insert("hydrodynamics", hydro);
  toml::table brownian{{"seed", int64_t(s.seed)}};
  if (s.brownian_stress_every < 0) brownian.insert("stress_every", "auto");
  else brownian.insert("stress_every", int64_t(s.brownian_stress_every));
  root.insert("brownian", brownian);
  root.insert("run", toml::table{{"max_overlap", s.run.max_overlap}});
  root.insert("time", toml::table{{"dt", s.time.dt},
                                  {"steps", int64_t(s.time.steps)},
                                  {"start_step", int64_t(s.time.start_step)},
                                  {"start_time", s.time.start_time},
                                  {"integrator", s.time.integrator},
                                  {"rkf_tolerance", s.time.rkf_tolerance}});
  toml::array record;
  for (const auto& name : s.output.record) record.push_back(name);
  root.insert("output", toml::table{{"every", int64_t(s.output.every)},
                                    {"checkpoint_every", int64_t(s.output.checkpoint_every)},
                                    {"record", record},
                                    {"author", s.output.author},
                                    {"cloud", s.output.cloud},
                                    {"cloud_link", s.output.cloud_link},
                                    {"cloud_min_fraction", s.output.cloud_min_fraction}});
  if (s.output.cluster_gap >= 0.0) root["output"].as_table()->insert("cluster_gap", s.output.cluster_gap);
  if (!s.output.xyz || s.output.xyz_path.empty()) root["output"].as_table()->insert("xyz", s.output.xyz);
  else root["output"].as_table()->insert("xyz", s.output.xyz_path);
  std::ostringstream o;
  o.precision(17);
  o << "# Fully resolved scene (every key explicit; generated particles listed). Re-run it as is.\n" << root << "\n";
  return o.str();
}

bool same_scene(const std::string& a, const std::string& b) { return scene_differences(a, b).empty(); }

namespace {

// A leaf value as TOML text, shortened for messages.
std::string brief_value(const toml::node& n) {
  std::ostringstream o;
  o.precision(17);
  if (const auto* s = n.as_string()) {
    o << '"' << s->get() << '"';
  } else if (const auto* f = n.as_floating_point()) {
    // The shortest text that reads back as the same double (0.1, not 0.10000000000000001).
    for (int digits = 1; digits <= 17; ++digits) {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.*g", digits, f->get());
      if (std::strtod(buf, nullptr) == f->get() || digits == 17) {
        o << buf << (std::strpbrk(buf, ".eni") ? "" : ".0");  // a float stays one in TOML: 1.0, not 1
        break;
      }
    }
  } else {
    o << toml::node_view<const toml::node>(&n);
  }
  std::string t = o.str();
  constexpr std::size_t kMax = 60;
  if (t.size() > kMax) t = t.substr(0, kMax - 3) + "...";
  return t;
}

// Keys whose values differ between two resolved scene tables, as "[table] key: a -> b".
void table_differences(const toml::table& a, const toml::table& b, const std::string& table,
                       std::vector<std::string>& out) {
  std::set<std::string> keys;
  for (const auto& [k, v] : a) keys.insert(std::string(k.str()));
  for (const auto& [k, v] : b) keys.insert(std::string(k.str()));
  for (const auto& key : keys) {
    const toml::node* x = a.get(key);
    const toml::node* y = b.get(key);
    if (x && y && x->is_table() && y->is_table()) {
      table_differences(*x->as_table(), *y->as_table(), table.empty() ? key : table + "." + key, out);
      continue;
    }
    const std::string vx = x ? brief_value(*x) : "(absent)", vy = y ? brief_value(*y) : "(absent)";
    std::ostringstream fx, fy;  // full texts: a long value may differ after the shortened part
    fx.precision(17);
    fy.precision(17);
    if (x) fx << toml::node_view<const toml::node>(x);
    if (y) fy << toml::node_view<const toml::node>(y);
    if (bool(x) != bool(y) || fx.str() != fy.str())
      out.push_back((table.empty() ? "" : "[" + table + "] ") + key + ": " + vx + " -> " + vy);
  }
}

}  // namespace

std::vector<std::string> scene_differences(const std::string& a, const std::string& b) {
  if (a == b) return {};
  Scene sa, sb;
  try {
    sa = parse_scene(a, "stored scene");
  } catch (const ConfigError& e) {
    return {std::string("the stored scene does not parse: ") + e.what()};
  }
  try {
    sb = parse_scene(b, "this scene");
  } catch (const ConfigError& e) {
    return {std::string("this scene does not parse: ") + e.what()};
  }
  // Scenes stored before [time] integrator had "auto" say "euler" where none was given, and the
  // model chose as "auto" does now. An explicit "euler" runs what "auto" picks for the same scene
  // (where "auto" picks fixman, "euler" was and is refused), so the two are the same run.
  if ((sa.time.integrator == "euler" && sb.time.integrator == "auto") ||
      (sa.time.integrator == "auto" && sb.time.integrator == "euler"))
    sa.time.integrator = sb.time.integrator = "auto";
  // Scenes stored between [brownian] stress_every's introduction and its "auto" say 1 where none was
  // given. "auto" samples every step with an ambient flow, and no sample is taken without thermal
  // motion, so there the two are the same run.
  const bool same_sampling = sa.flow.kind != FlowParams::Kind::none || sa.fluid.kT == 0.0;
  if (same_sampling && ((sa.brownian_stress_every == 1 && sb.brownian_stress_every < 0) ||
                        (sa.brownian_stress_every < 0 && sb.brownian_stress_every == 1)))
    sa.brownian_stress_every = sb.brownian_stress_every = -1;
  const std::string ra = resolved_toml(sa), rb = resolved_toml(sb);
  if (ra == rb) return {};
  std::vector<std::string> out;
  table_differences(toml::parse(ra), toml::parse(rb), "", out);
  if (out.empty()) out.push_back("the resolved scene texts differ");
  return out;
}

Scene load_scene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_scene(ss.str(), path);
}

}  // namespace stokesian::io
