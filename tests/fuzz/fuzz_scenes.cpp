// Seeded scene fuzzer (issue 10): generates malformed and extreme scenes from the shipped configs and
// a few minimal scenes, runs `stokesian check` on each and `stokesian solve` on a fraction, each in
// its own empty folder under memory, CPU and wall-time limits, and classifies every run:
//
//   crash            killed by a signal other than our timeout
//   hang             still running at the wall timeout (killed) without having announced slow work
//   slow_announced   a valid scene whose work the engine announced on stderr with its estimate
//                    ("stokesian: note: ... is estimated at about X s", docs/reliability.md) before
//                    the wall timeout ended it; killed early when the estimate alone exceeds the
//                    timeout. Not a failure: counted and listed.
//   nan_output       solve exited 0 but its .h5 holds a non-finite number (except the documented
//                    +inf of observables/min_gap for a single particle, and the NaN of an open
//                    channel's empty slots, id -1; docs/output.md)
//   invalid_accepted the docs (docs/scene.md) call the scene invalid, yet the command exited 0
//   unclear_error    exit 2 whose message lacks the scene file, the offending key or file, the line
//                    or the allowed range (where the case requires them); std::bad_alloc
//   wrote_on_error   files left in the run folder after a non-zero exit (or any file from check)
//   valid_rejected   the docs call the scene valid, yet it was refused without a documented reason
//                    (documented: exit 2 with a memory/time estimate, exit 3 naming particles)
//   wrong_exit       an exit status the docs do not give for this case (e.g. 4 for a scene error)
//   ok
//
// Every case carries its expectation from the docs: "invalid" (exit 2, nothing written, message
// naming the file and key), "valid" (exit 0 or a documented refusal) or "any" (a mutation whose
// validity depends on the combination; either outcome is fine, but never a crash, hang, NaN or an
// unclear message). Usage:
//   fuzz_scenes --cases N --seed S --stokesian PATH --work DIR [--report out.json]
//               [--solve-fraction F] [--jobs J] [--configs DIR] [--timeout SECONDS] [--keep]
// Exit status: 0 when every failing class is empty, 1 otherwise, 64 on a usage error.
#include <hdf5.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// Deterministic random numbers (splitmix64; no standard-library distributions, so a seed gives the
// same cases everywhere).
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) { return n ? std::size_t(next() % n) : 0; }
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }
  bool chance(double p) { return uniform() < p; }
  template <class T>
  const T& pick(const std::vector<T>& v) { return v[below(v.size())]; }
};

// ---------------------------------------------------------------------------------------------
// A scene as ordered tables of key = value text (enough for the shipped configs and our mutations).
struct KV {
  std::string key, value;
};
struct Table {
  std::string name;  // "" = top level
  bool array = false;
  std::vector<KV> kv;
  const KV* find(const std::string& k) const {
    for (const auto& e : kv)
      if (e.key == k) return &e;
    return nullptr;
  }
  void set(const std::string& k, const std::string& v) {
    for (auto& e : kv)
      if (e.key == k) {
        e.value = v;
        return;
      }
    kv.push_back({k, v});
  }
  void erase(const std::string& k) {
    kv.erase(std::remove_if(kv.begin(), kv.end(), [&](const KV& e) { return e.key == k; }), kv.end());
  }
};
struct Model {
  std::vector<Table> tabs;
  Table* find(const std::string& name) {
    for (auto& t : tabs)
      if (t.name == name && !t.array) return &t;
    return nullptr;
  }
  Table& table(const std::string& name) {
    if (Table* t = find(name)) return *t;
    tabs.push_back({name, false, {}});
    return tabs.back();
  }
  std::vector<Table*> pairs() {
    std::vector<Table*> out;
    for (auto& t : tabs)
      if (t.array && t.name == "forces.pair") out.push_back(&t);
    return out;
  }
  std::string get(const std::string& table, const std::string& key) {
    Table* t = find(table);
    const KV* e = t ? t->find(key) : nullptr;
    return e ? e->value : "";
  }
  bool periodic() { return get("domain", "kind") == "\"periodic\""; }
  std::string text() const {
    std::ostringstream o;
    for (const auto& t : tabs) {
      if (!t.name.empty()) o << (t.array ? "[[" : "[") << t.name << (t.array ? "]]" : "]") << "\n";
      for (const auto& e : t.kv) o << e.key << " = " << e.value << "\n";
      o << "\n";
    }
    return o.str();
  }
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// Reads the simple TOML of the shipped configs: headers, key = value, values spanning lines while
// brackets are open; comments outside strings dropped.
Model parse_simple(const std::string& text) {
  Model m;
  m.tabs.push_back({"", false, {}});
  std::istringstream is(text);
  std::string line, pending_key, pending;
  int depth = 0;
  auto strip = [](const std::string& l) {
    bool in = false;
    for (std::size_t i = 0; i < l.size(); ++i) {
      if (l[i] == '"') in = !in;
      if (l[i] == '#' && !in) return l.substr(0, i);
    }
    return l;
  };
  while (std::getline(is, line)) {
    line = trim(strip(line));
    if (line.empty()) continue;
    if (depth > 0) {
      pending += " " + line;
    } else if (line[0] == '[') {
      const bool arr = line.rfind("[[", 0) == 0;
      const std::string name = trim(line.substr(arr ? 2 : 1, line.find(']') - (arr ? 2 : 1)));
      m.tabs.push_back({name, arr, {}});
      continue;
    } else {
      const auto eq = line.find('=');
      pending_key = trim(line.substr(0, eq));
      pending = trim(line.substr(eq + 1));
    }
    depth = 0;
    for (char c : pending) depth += c == '[' ? 1 : c == ']' ? -1 : 0;
    if (depth == 0) m.tabs.back().kv.push_back({pending_key, pending});
  }
  if (m.tabs.front().kv.empty()) m.tabs.erase(m.tabs.begin());
  return m;
}

// ---------------------------------------------------------------------------------------------
// Cases.
enum class Expect { invalid, valid, any };
const char* name_of(Expect e) { return e == Expect::invalid ? "invalid" : e == Expect::valid ? "valid" : "any"; }

struct Case {
  int id = 0;
  std::string base, mutation, detail;
  std::string text;                               // scene text (used as is)
  std::map<std::string, std::string> files;       // extra files beside the scene
  Expect expect = Expect::any;
  std::vector<std::string> names;  // an "invalid" message must contain one of these (key or file)
  bool need_line = false;          // ... and "scene.toml:<line>" (or "<file>:<line>" of a named file)
  bool need_allowed = false;       // ... and the word "allowed"
  bool solve = false;
};

struct Base {
  std::string name;
  Model model;
};

std::vector<Base> load_bases(const std::string& configs) {
  std::vector<Base> bases;
  std::vector<fs::path> paths;
  for (const auto& e : fs::directory_iterator(configs))
    if (e.path().extension() == ".toml") paths.push_back(e.path());
  std::sort(paths.begin(), paths.end());
  for (const auto& p : paths) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    Model m = parse_simple(ss.str());
    // Files a config names relative to its folder (a flow table) are named absolutely: the cases
    // run from their own folders.
    for (const char* table : {"flow", "particles"}) {
      const std::string v = m.get(table, "file");
      const std::size_t q0 = v.find('"'), q1 = q0 == std::string::npos ? q0 : v.find('"', q0 + 1);
      if (q1 == std::string::npos) continue;
      const std::string rel = v.substr(q0 + 1, q1 - q0 - 1);
      if (!rel.empty() && rel[0] != '/')
        m.table(table).set("file", "\"" + (p.parent_path() / rel).lexically_normal().string() + "\"");
    }
    bases.push_back({p.stem().string(), m});
  }
  // Minimal scenes (fast to solve).
  bases.push_back({"min_two", parse_simple("[particles]\npositions = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]]\n"
                                           "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n")});
  bases.push_back({"min_gen_open", parse_simple("[particles]\ngenerate = \"random\"\ncount = 20\nvolume_fraction = 0.05\n"
                                                "seed = 5\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n")});
  bases.push_back({"min_periodic", parse_simple("[domain]\nkind = \"periodic\"\nbox = [10.0, 10.0, 10.0]\n"
                                                "[particles]\ngenerate = \"lattice\"\ncount = 8\n"
                                                "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n")});
  bases.push_back({"min_brownian", parse_simple("[fluid]\nkT = 1.0\n[particles]\npositions = [[0.0, 0.0, 0.0], "
                                                "[2.5, 0.0, 0.0], [0.0, 3.0, 0.0]]\nradii = [1.0, 0.5, 1.5]\n"
                                                "[[forces.pair]]\nkind = \"morse\"\n[time]\ndt = 0.001\nsteps = 10\n")});
  bases.push_back({"min_xyz", parse_simple("[particles]\nfile = \"particles.xyz\"\n")});
  return bases;
}

// A numeric scene key and its documented range (docs/scene.md).
struct Spec {
  std::string table, key;
  bool integer;
  double lo, hi;
  bool lo_open;
  bool sure;  // an in-range value keeps the scene valid (else "any": it interacts with the rest)
  enum Where { all, generate, random, periodic, flow, morse, dlvo, hertz, pair } where;
};

const double kLongMax = 9223372036854775807.0;
std::vector<Spec> specs() {
  return {
      {"domain", "shear_strain", false, -1e9, 1e9, false, true, Spec::periodic},
      {"fluid", "viscosity", false, 0, 1e12, true, true, Spec::all},
      {"fluid", "kT", false, 0, 1e12, false, false, Spec::all},
      {"particles", "radius", false, 1e-3, 1e3, false, false, Spec::all},
      {"particles", "count", true, 1, 1e7, false, false, Spec::generate},
      {"particles", "volume_fraction", false, 0, 0.74, true, false, Spec::generate},
      {"particles", "radius_ratio", false, 0.01, 100, false, false, Spec::generate},
      {"particles", "large_fraction", false, 0, 1, false, false, Spec::generate},
      {"particles", "sigma", false, 0, 2, false, false, Spec::generate},
      {"particles", "seed", true, 0, kLongMax, false, true, Spec::generate},
      {"particles", "equilibration_sweeps", true, 0, 1e6, false, false, Spec::random},
      {"particles", "min_gap", false, 0, 1, false, false, Spec::generate},
      {"forces.pair", "cutoff", false, 0, 1e6, false, false, Spec::pair},
      {"forces.pair", "depth", false, 0, 1e12, false, false, Spec::morse},
      {"forces.pair", "kappa", false, 0, 1e6, true, false, Spec::morse},
      {"forces.pair", "hamaker", false, 0, 1e12, false, false, Spec::dlvo},
      {"forces.pair", "debye_kappa", false, 0, 1e6, true, false, Spec::dlvo},
      {"forces.pair", "surface_potential", false, 0, 1e12, false, false, Spec::dlvo},
      {"forces.pair", "surface_potential_reduced", false, 0, 1e3, false, false, Spec::dlvo},
      {"forces.pair", "born_sigma", false, 0, 1, false, false, Spec::dlvo},
      {"forces.pair", "min_gap", false, 0, 1, true, false, Spec::dlvo},
      {"forces.pair", "stiffness", false, 0, 1e15, true, false, Spec::hertz},
      {"flow", "rate", false, -1e12, 1e12, false, false, Spec::flow},
      {"hydrodynamics", "tolerance", false, 1e-14, 0.1, false, true, Spec::all},
      {"hydrodynamics", "lubrication_cutoff", false, 2, 100, true, false, Spec::all},
      {"hydrodynamics", "lubrication_taper", false, 0, 98, false, false, Spec::all},  // <= cutoff - 2: "any"
      {"hydrodynamics", "lubrication_min_gap", false, 1e-8, 0.1, false, false, Spec::all},
      {"brownian", "seed", true, 0, kLongMax, false, true, Spec::all},
      {"time", "dt", false, 0, 1e12, true, true, Spec::all},
      {"time", "steps", true, 0, kLongMax / 2, false, true, Spec::all},
      {"time", "start_step", true, 0, kLongMax / 2, false, true, Spec::all},
      {"time", "start_time", false, -1e300, 1e300, false, true, Spec::all},
      {"time", "rkf_tolerance", false, 1e-14, 1, false, true, Spec::all},
      {"output", "every", true, 1, kLongMax, false, false, Spec::all},
      {"output", "checkpoint_every", true, 0, kLongMax, false, false, Spec::all},
  };
}

// Number texts: (TOML text, value, is an integer literal, parses as TOML).
struct Num {
  std::string text;
  double value;
  bool integer, parses;
};
std::vector<Num> numbers() {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  return {{"nan", nan, false, true},
          {"inf", inf, false, true},
          {"-inf", -inf, false, true},
          {"-1", -1, true, true},
          {"-1.0", -1, false, true},
          {"0", 0, true, true},
          {"0.0", 0, false, true},
          {"-0.0", 0, false, true},
          {"1e-300", 1e-300, false, true},
          {"1e-12", 1e-12, false, true},
          {"1e308", 1e308, false, true},
          {"1e12", 1e12, false, true},
          {"1e13", 1e13, false, true},
          {"1000000", 1e6, true, true},
          {"9223372036854775807", kLongMax, true, true},
          {"-9223372036854775808", -kLongMax, true, true},
          {"99999999999999999999", 1e20, true, false},
          {"1", 1, true, true},
          {"0.5", 0.5, false, true},
          {"2", 2, true, true},
          {"7.5", 7.5, false, true},
          {"100", 100, true, true}};
}

struct Generator {
  Rng rng;
  std::vector<Base> bases;
  std::vector<Spec> spec = specs();
  std::vector<Num> nums = numbers();

  static bool has_gen(Model& m) { return !m.get("particles", "generate").empty(); }

  Case make(int id) {
    Case c;
    c.id = id;
    const Base& b = rng.pick(bases);
    c.base = b.name;
    Model m = b.model;
    if (b.name == "min_xyz") c.files["particles.xyz"] = "3\nProperties=species:S:1:pos:R:3:radius:R:1\n"
                                                        "M 0 0 0 1\nM 3 0 0 1\nM 0 3.5 0 1.5\n";
    static const std::vector<std::pair<std::string, int>> classes = {
        {"structure", 14}, {"number", 26}, {"count_box", 12}, {"particle_file", 14},
        {"unknown_key", 10}, {"generator_key", 6}, {"coincident", 5}, {"extreme_valid", 13}};
    int total = 0;
    for (const auto& k : classes) total += k.second;
    int r = int(rng.below(std::size_t(total)));
    std::string cls;
    for (const auto& k : classes)
      if ((r -= k.second) < 0) {
        cls = k.first;
        break;
      }
    c.mutation = cls;
    if (cls == "structure") structure(c, m);
    else if (cls == "number") number(c, m);
    else if (cls == "count_box") count_box(c, m);
    else if (cls == "particle_file") particle_file(c, m);
    else if (cls == "unknown_key") unknown_key(c, m);
    else if (cls == "generator_key") generator_key(c, m);
    else if (cls == "coincident") coincident(c, m);
    else extreme_valid(c, m);
    if (c.text.empty()) c.text = m.text();
    return c;
  }

  void invalid(Case& c, std::vector<std::string> names, bool line, bool allowed) {
    c.expect = Expect::invalid;
    c.names = std::move(names);
    c.need_line = line;
    c.need_allowed = allowed;
  }

  // TOML structure: nesting, dotted keys, huge texts, truncation, binary bytes, duplicates, types.
  void structure(Case& c, Model& m) {
    const int kind = int(rng.below(10));
    const std::vector<std::size_t> sizes = {65, 1000, 100000, 200000};
    const std::size_t n = rng.pick(sizes);
    std::string body = m.text();
    if (kind == 0) {  // table header with n parts
      std::string h = "[a";
      for (std::size_t i = 1; i < n; ++i) h += ".a";
      c.detail = "table header with " + std::to_string(n) + " dotted parts";
      c.text = body + h + "]\nx = 1\n";
      invalid(c, {"dotted parts"}, true, true);
    } else if (kind == 1) {  // dotted key with n parts
      std::string k = "a";
      for (std::size_t i = 1; i < n; ++i) k += ".a";
      c.detail = "dotted key with " + std::to_string(n) + " parts";
      c.text = k + " = 1\n" + body;
      invalid(c, {"dotted parts"}, true, true);
    } else if (kind == 2) {  // nested arrays
      c.detail = "array nested " + std::to_string(n) + " deep";
      c.text = body + "[output]\nrecord = " + std::string(n, '[') + std::string(n, ']') + "\n";
      if (m.find("output")) c.text = std::string("[output]\nauthor = ") + std::string(n, '[') + std::string(n, ']') + "\n" + body;
      invalid(c, {"nested"}, true, true);
    } else if (kind == 3) {  // nested inline tables
      std::string v;
      for (std::size_t i = 0; i < n; ++i) v += "{a = ";
      v += "1";
      for (std::size_t i = 0; i < n; ++i) v += "}";
      c.detail = "inline tables nested " + std::to_string(n) + " deep";
      c.text = "x = " + v + "\n" + body;
      invalid(c, {"nested"}, true, true);
    } else if (kind == 4) {  // huge string
      const int size = int(rng.below(3));  // documented: strings at most 4096 bytes, texts 16 MiB
      const std::size_t len = size == 2 ? (std::size_t(17) << 20) : size == 1 ? (std::size_t(1) << 20) : 4000;
      c.detail = "a string of " + std::to_string(len) + " bytes in [output] author";
      m.table("output").set("author", "\"" + std::string(len, 'A') + "\"");
      c.text = m.text();
      if (size == 2) invalid(c, {"bytes"}, false, true);
      else if (size == 1) invalid(c, {"author"}, true, true);
      else c.expect = Expect::valid;
    } else if (kind == 5) {  // truncated text
      const std::size_t cut = rng.below(body.size());
      c.detail = "text truncated at byte " + std::to_string(cut) + " of " + std::to_string(body.size());
      c.text = body.substr(0, cut);
      c.expect = Expect::any;
    } else if (kind == 6) {  // binary bytes
      std::string junk;
      const std::size_t k = 1 + rng.below(16);
      for (std::size_t i = 0; i < k; ++i) junk += char(rng.below(256));
      const std::size_t at = rng.below(body.size() + 1);
      c.detail = std::to_string(k) + " random bytes at byte " + std::to_string(at);
      c.text = body.substr(0, at) + junk + body.substr(at);
      c.expect = Expect::any;
    } else if (kind == 7) {  // duplicate key
      std::vector<std::pair<std::size_t, std::size_t>> where;
      for (std::size_t t = 0; t < m.tabs.size(); ++t)
        for (std::size_t k = 0; k < m.tabs[t].kv.size(); ++k) where.push_back({t, k});
      const auto [t, k] = rng.pick(where);
      const KV dup = m.tabs[t].kv[k];
      m.tabs[t].kv.push_back(dup);
      c.detail = "duplicate key " + dup.key + " in [" + m.tabs[t].name + "]";
      c.text = m.text();
      invalid(c, {dup.key}, true, false);
    } else if (kind == 8) {  // duplicate table
      std::vector<std::size_t> plain;
      for (std::size_t t = 0; t < m.tabs.size(); ++t)
        if (!m.tabs[t].array && !m.tabs[t].name.empty()) plain.push_back(t);
      const Table dup = m.tabs[rng.pick(plain)];
      c.detail = "duplicate table [" + dup.name + "]";
      c.text = m.text() + "[" + dup.name + "]\n";
      invalid(c, {dup.name}, true, false);
    } else {  // wrong value type
      std::vector<std::pair<std::size_t, std::size_t>> where;
      for (std::size_t t = 0; t < m.tabs.size(); ++t)
        for (std::size_t k = 0; k < m.tabs[t].kv.size(); ++k) where.push_back({t, k});
      const auto [t, k] = rng.pick(where);
      KV& e = m.tabs[t].kv[k];
      const bool is_string = !e.value.empty() && e.value[0] == '"';
      const bool is_array = !e.value.empty() && e.value[0] == '[';
      std::vector<std::string> wrong = {"true", "{ x = 1 }", "1979-05-27T07:32:00Z"};
      if (!is_string) wrong.push_back("\"12\"");
      if (is_string || is_array) wrong.push_back("12");
      if (!is_array) wrong.push_back("[1, 2]");
      const std::string v = rng.pick(wrong);
      c.detail = "[" + m.tabs[t].name + "] " + e.key + " = " + v + " (was " + e.value.substr(0, 40) + ")";
      const bool xyz_bool = e.key == "xyz" && v == "true";
      e.value = v;
      c.text = m.text();
      if (xyz_bool) c.expect = Expect::valid;
      else invalid(c, {e.key}, true, false);
    }
  }

  // One numeric key set to an extreme value; the expectation from its documented range.
  void number(Case& c, Model& m) {
    std::vector<const Spec*> ok;
    const bool gen = has_gen(m);
    const std::string pattern = m.get("particles", "generate");
    for (const auto& s : spec) {
      if (s.where == Spec::generate && !gen) continue;
      if (s.where == Spec::random && pattern != "\"random\"") continue;
      if (s.where == Spec::periodic && !m.periodic()) continue;
      if (s.key == "count" && m.periodic() && m.find("particles")->find("volume_fraction")) continue;
      if (s.key == "volume_fraction" && m.periodic() && m.find("particles")->find("count")) continue;
      ok.push_back(&s);
    }
    const Spec& s = *rng.pick(ok);
    const Num& v = rng.pick(nums);
    Table* t = nullptr;
    if (s.table == "forces.pair") {
      const char* kind = s.where == Spec::morse ? "\"morse\"" : s.where == Spec::dlvo ? "\"dlvo\"" : "\"hertz\"";
      for (Table* p : m.pairs())
        if (s.where == Spec::pair || p->find("kind")->value == kind) t = p;
      if (!t) {
        m.tabs.push_back({"forces.pair", true, {{"kind", s.where == Spec::pair ? "\"hertz\"" : kind}}});
        t = &m.tabs.back();
      }
    } else {
      t = &m.table(s.table);
    }
    if (s.where == Spec::flow && !t->find("kind")) t->set("kind", "\"simple_shear\"");
    t->set(s.key, v.text);
    c.detail = "[" + s.table + "] " + s.key + " = " + v.text;
    bool in_range = v.parses && std::isfinite(v.value) && v.value >= s.lo && v.value <= s.hi &&
                    !(s.lo_open && v.value == s.lo) && (!s.integer || v.integer);
    if (s.integer && v.integer && v.text == "-9223372036854775808") in_range = s.lo < -1e18;
    if (s.key == "every" || s.key == "checkpoint_every") {
      const long every = s.key == "every" ? long(v.value) : std::atol(m.get("output", "every").c_str());
      const long ck = s.key == "checkpoint_every" ? long(v.value)
                                                  : std::atol(m.get("output", "checkpoint_every").c_str());
      if (in_range && ck > 0 && every > 0 && ck % every != 0) {
        invalid(c, {"checkpoint_every"}, true, false);
        return;
      }
    }
    if (s.key == "shear_strain" && in_range) {
      c.expect = Expect::valid;
      return;
    }
    if (s.key == "radius" && t->find("radii")) {  // documented: radius or radii, not both
      invalid(c, {"radius"}, true, false);
      return;
    }
    if (!in_range) invalid(c, {s.key}, true, v.parses && !(s.integer && !v.integer) && v.text != "nan");
    else c.expect = s.sure ? Expect::valid : Expect::any;
    // Documented: a NaN is "not a number in range", and the message still gives the range.
    if (!in_range && v.text == "nan") c.need_allowed = true;
  }

  // Counts, boxes and volume fractions.
  void count_box(Case& c, Model& m) {
    const int kind = int(rng.below(6));
    if (kind <= 1) {  // count in an open domain
      Model g = parse_simple("[particles]\ngenerate = \"lattice\"\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n");
      if (rng.chance(0.5)) g.table("particles").set("generate", "\"random\"");
      const std::vector<std::string> counts = {"10000000", "10000001", "100000000", "1000000000", "1000000000000",
                                               "-5", "0", "1e7", "3000000", "1"};
      const std::string n = rng.pick(counts);
      g.table("particles").set("count", n);
      m = g;
      c.detail = "open domain, generate = " + g.get("particles", "generate") + ", count = " + n;
      const double v = std::atof(n.c_str());
      if (n.find('e') != std::string::npos || v < 1 || v > 1e7) invalid(c, {"count"}, true, n.find('e') == std::string::npos);
      else c.expect = Expect::valid;
    } else if (kind == 2) {  // huge or bad boxes
      const std::vector<std::string> boxes = {"[1e12, 1e12, 1e12]", "[1e308, 16.0, 16.0]", "[1e6, 1e6, 1e6]",
                                              "[-10.0, 10.0, 10.0]", "[0.0, 10.0, 10.0]", "[10.0, 10.0]",
                                              "[nan, 10.0, 10.0]", "[inf, 10.0, 10.0]", "[1000001.0, 10.0, 10.0]"};
      const std::string box = rng.pick(boxes);
      Model g = parse_simple("[domain]\nkind = \"periodic\"\n[particles]\ngenerate = \"random\"\ncount = 10\n");
      g.table("domain").set("box", box);
      m = g;
      c.detail = "[domain] box = " + box + " with count = 10";
      if (box == "[1e6, 1e6, 1e6]") c.expect = Expect::valid;
      else invalid(c, {"box"}, true, box != "[10.0, 10.0]");
    } else if (kind == 3) {  // volume fraction from a huge box
      const std::vector<std::string> boxes = {"[1e6, 1e6, 1e6]", "[1e5, 1e5, 1e5]", "[1000.0, 1000.0, 1000.0]",
                                              "[300.0, 300.0, 300.0]", "[1e6, 16.0, 16.0]"};
      const std::vector<std::string> phis = {"1e-12", "1e-300", "0.1", "0.3"};
      const std::string box = rng.pick(boxes), phi = rng.pick(phis);
      Model g = parse_simple("[domain]\nkind = \"periodic\"\n[particles]\ngenerate = \"random\"\n");
      g.table("domain").set("box", box);
      g.table("particles").set("volume_fraction", phi);
      m = g;
      c.detail = "[domain] box = " + box + ", volume_fraction = " + phi;
      // count = round(phi V / (4/3 pi)) must lie in [1, 1e7].
      const double L = box == "[1e6, 1e6, 1e6]" ? 1e18 : box == "[1e5, 1e5, 1e5]" ? 1e15
                     : box == "[1000.0, 1000.0, 1000.0]" ? 1e9 : box == "[300.0, 300.0, 300.0]" ? 2.7e7 : 2.56e8;
      const double count = std::round(std::atof(phi.c_str()) * L / (4.0 / 3.0 * M_PI));
      if (count < 1 || count > 1e7) invalid(c, {"volume_fraction"}, true, true);
      else c.expect = Expect::valid;
    } else if (kind == 4) {  // volume fraction beyond what the generator reaches
      const std::vector<std::string> phis = {"0.5", "0.53", "0.55", "0.6", "0.62", "0.7", "0.74", "0.75", "-0.1"};
      const std::string phi = rng.pick(phis);
      const std::string pattern = rng.chance(0.5) ? "\"random\"" : "\"lattice\"";
      const bool periodic = rng.chance(0.5);
      Model g = parse_simple(periodic ? "[domain]\nkind = \"periodic\"\nbox = [12.0, 12.0, 12.0]\n[particles]\n"
                                      : "[particles]\ncount = 200\n");
      g.table("particles").set("generate", pattern);
      g.table("particles").set("volume_fraction", phi);
      m = g;
      c.detail = (periodic ? "periodic box 12, " : "open, count 200, ") + std::string("generate = ") + pattern +
                 ", volume_fraction = " + phi;
      const double v = std::atof(phi.c_str());
      // Documented limits (docs/scene.md): random up to 0.6; lattice while the spacing is at least
      // 2 a + min_gap (open sphere: spacing (4 pi / (3 phi))^(1/3) a; periodic box L: L / ceil(count^(1/3))
      // with count = round(phi L^3 / (4/3 pi))).
      bool ok = v > 0;
      if (ok && pattern == "\"random\"") {
        const double count = std::round(v * 1728.0 / (4.0 / 3.0 * M_PI));
        ok = (periodic ? count * 4.0 / 3.0 * M_PI / 1728.0 : v) <= 0.6;
      } else if (ok) {
        const double count = std::round(v * 1728.0 / (4.0 / 3.0 * M_PI));
        const double spacing = periodic ? 12.0 / std::ceil(std::cbrt(count) - 1e-9) : std::cbrt(4.0 * M_PI / (3.0 * v));
        ok = spacing >= 2.001;
      }
      if (!ok) invalid(c, {"volume_fraction"}, true, true);
      // Near 0.6 random may stall, and earlier in small open regions (documented).
      else c.expect = v > (periodic ? 0.55 : 0.45) && pattern == "\"random\"" ? Expect::any : Expect::valid;
    } else {  // negative / zero / non-integer counts with a periodic box
      const std::vector<std::string> counts = {"-1", "0", "2.5", "\"10\"", "20000000", "1"};
      const std::string n = rng.pick(counts);
      Model g = parse_simple("[domain]\nkind = \"periodic\"\nbox = [20.0, 20.0, 20.0]\n[particles]\ngenerate = \"lattice\"\n");
      g.table("particles").set("count", n);
      m = g;
      c.detail = "periodic box 20, lattice, count = " + n;
      if (n == "1") c.expect = Expect::valid;
      else invalid(c, {"count"}, true, n == "-1" || n == "0" || n == "20000000");
    }
  }

  // Particle files.
  void particle_file(Case& c, Model& m) {
    const bool periodic = rng.chance(0.3);
    m = parse_simple(std::string(periodic ? "[domain]\nkind = \"periodic\"\nbox = [10.0, 10.0, 10.0]\n" : "") +
                     "[particles]\nfile = \"p.xyz\"\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n");
    const std::string head = "Properties=species:S:1:pos:R:3:radius:R:1\n";
    std::vector<std::string> lines = {"M 0 0 0 1", "M 3 0 0 1", "M 0 3 0 1", "M 3 3 1 1"};
    auto file = [&](std::size_t n) {
      std::string s = std::to_string(n) + "\n" + head;
      for (const auto& l : lines) s += l + "\n";
      return s;
    };
    const int kind = int(rng.below(13));
    std::string f;
    const std::string pfile = "p.xyz";
    switch (kind) {
      case 0:
        lines[1 + rng.below(3)] = rng.chance(0.5) ? "M nan 0 0 1" : "M 0 inf 0 1";
        f = file(4);
        c.detail = "XYZ with a non-finite coordinate";
        invalid(c, {pfile}, true, true);
        break;
      case 1:
        f = file(6);
        c.detail = "XYZ count line 6, 4 particle lines";
        invalid(c, {pfile}, true, false);
        break;
      case 2:
        f = file(2);  // two extra lines read as the next frame's count: not a count
        c.detail = "XYZ count line 2, 4 particle lines";
        invalid(c, {pfile}, true, false);
        break;
      case 3:
        f = file(4).substr(0, file(4).size() - 9);
        c.detail = "XYZ truncated inside the last line";
        c.expect = Expect::any;  // the cut may leave a valid shorter line
        break;
      case 4:
        m.table("particles").set("file", "\"missing.xyz\"");
        c.detail = "particle file missing";
        invalid(c, {"missing.xyz"}, true, false);
        break;
      case 5:
        f = "";
        c.detail = "empty XYZ file";
        invalid(c, {pfile}, true, false);
        break;
      case 6:
        lines[rng.below(4)] = rng.pick(std::vector<std::string>{"M 0 0 0 0", "M 0 0 0 -1", "M 0 0 0 1e-300",
                                                                "M 0 0 0 nan", "M 0 0 0 1e300", "M 0 0 0 5000"});
        f = file(4);
        c.detail = "XYZ with a radius out of range";
        invalid(c, {pfile}, true, true);
        break;
      case 7:
        lines = {"M 0 0 0 1", "M 25 0 0 1", "M -13 4 0 1", "M 3 3 1e6 1"};
        f = file(4);
        c.detail = "XYZ positions outside the box (periodic: wrapped, documented)";
        c.expect = Expect::valid;
        break;
      case 8:
        lines[2] = "M 0 0 0 1";  // coincides with particle 0
        f = file(4);
        c.detail = "XYZ with two coincident particles";
        invalid(c, {"particles 0 and 2", "particles 2 and 0"}, true, true);
        break;
      case 9:
        f = std::string("\x89HDF\r\n\x1a\n", 8) + std::string(100, '\0');
        m.table("particles").set("file", "\"p.h5\"");
        c.files["p.h5"] = f;
        c.detail = "a .h5 particle file that is not HDF5";
        invalid(c, {"p.h5"}, true, false);
        f.clear();
        break;
      case 10:
        m.table("particles").set("radius", "2.0");
        f = file(4);
        c.detail = "radius given beside a file with a radius column";
        invalid(c, {"radius"}, true, false);
        break;
      case 11:
        lines = {"M 0 0 0", "M 3 0 0", "M 0 3 0", "M 3 3 1"};
        f = std::to_string(4) + "\nplain comment\n";
        for (const auto& l : lines) f += l + "\n";
        m.table("particles").set("radius", rng.pick(std::vector<std::string>{"1.0", "0.5", "nan", "0", "5.0"}));
        c.detail = "XYZ without radii, radius = " + m.get("particles", "radius");
        if (m.get("particles", "radius") == "1.0" || m.get("particles", "radius") == "0.5") c.expect = Expect::valid;
        else if (m.get("particles", "radius") == "5.0") invalid(c, {"particles 0 and 1", "particles 1 and 0"}, true, true);
        else invalid(c, {"radius"}, true, true);
        break;
      default:
        f = file(4);
        m.table("particles").set("fixed", "[true, false]");
        c.detail = "fixed has 2 entries for a file of 4 particles";
        invalid(c, {"fixed"}, true, false);
        break;
    }
    if (kind != 4 && kind != 9) c.files[pfile] = f;
    c.text = m.text();
  }

  void unknown_key(Case& c, Model& m) {
    const std::vector<std::string> extra = {"domain", "fluid", "forces", "flow", "hydrodynamics", "brownian", "time", "output"};
    m.table(rng.pick(extra));  // perhaps a table the base lacks
    std::vector<Table*> tabs;
    for (auto& t : m.tabs) tabs.push_back(&t);
    Table* t = tabs[rng.below(tabs.size())];
    static const std::map<std::string, std::vector<std::string>> typos = {
        {"forces.pair", {"kinds", "Kind", "depht", "stifness", "cut_off"}},
        {"particles", {"count_", "positons", "radius_ratios", "volumefraction", "seeds"}},
        {"domain", {"boxes", "periodic", "knd"}},
        {"fluid", {"viscosty", "kt", "temperature"}},
        {"forces", {"external_forces", "gravty"}},
        {"flow", {"rates", "type"}},
        {"hydrodynamics", {"models", "moment", "lubrication_cutof"}},
        {"brownian", {"sed", "kT"}},
        {"time", {"Dt", "step", "integrater"}},
        {"output", {"records", "every_", "checkpoint"}},
        {"", {"particle", "hydro", "version"}}};
    const auto it = typos.find(t->name);
    const std::string key = it == typos.end() ? "unknown_key" : rng.pick(it->second);
    if (t->name == "forces.pair" && key == "kinds" && rng.chance(0.5)) {
      const std::string kind = t->find("kind") ? t->find("kind")->value : "\"hertz\"";
      t->erase("kind");
      t->set("kinds", kind);
      c.detail = "[[forces.pair]] kinds = " + kind + " instead of kind";
    } else {
      t->set(key, "1");
      c.detail = "[" + t->name + "] unknown key " + key;
    }
    invalid(c, {key}, true, true);
  }

  void generator_key(Case& c, Model& m) {
    if (has_gen(m) || m.get("particles", "generate").empty()) {
      if (!m.find("particles") || has_gen(m))
        m = parse_simple("[particles]\npositions = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]]\n");
    }
    const std::vector<std::pair<std::string, std::string>> keys = {
        {"count", "\"x\""}, {"count", "10"}, {"volume_fraction", "nan"}, {"volume_fraction", "0.1"},
        {"size_distribution", "\"bogus\""}, {"seed", "-3"}, {"seed", "3"}, {"region", "\"cube\""},
        {"equilibration_sweeps", "5"}, {"min_gap", "0.1"}, {"radius_ratio", "2.0"}, {"sigma", "0.1"},
        {"large_fraction", "0.5"}};
    const auto& [k, v] = rng.pick(keys);
    m.table("particles").set(k, v);
    c.detail = "generator key " + k + " = " + v + " with " + (m.get("particles", "file").empty() ? "positions" : "file");
    invalid(c, {k}, true, false);
  }

  void coincident(Case& c, Model& m) {
    const std::vector<std::string> second = {"[0.0, 0.0, 0.0]", "[1e-12, 0.0, 0.0]", "[0.5, 0.0, 0.0]",
                                             "[1.0, 0.0, 0.0]", "[1.49, 0.0, 0.0]", "[1.51, 0.0, 0.0]",
                                             "[1.999999, 0.0, 0.0]"};
    const std::string p = rng.pick(second);
    m = parse_simple("[particles]\npositions = [[0.0, 0.0, 0.0], " + p + ", [6.0, 0.0, 0.0]]\n"
                     "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n");
    c.detail = "particle 1 at " + p + " (particle 0 at the origin, radius 1)";
    const double x = std::atof(p.c_str() + 1);
    if (2.0 - x > 0.5) invalid(c, {"particles 0 and 1", "particles 1 and 0"}, true, true);
    else c.expect = Expect::valid;  // small overlaps: regularised (documented)
  }

  void extreme_valid(Case& c, Model& m) {
    const std::vector<std::pair<std::string, std::string>> scenes = {
        {"one particle", "[particles]\npositions = [[0.0, 0.0, 0.0]]\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"radii ratio 100", "[particles]\npositions = [[0.0, 0.0, 0.0], [150.0, 0.0, 0.0]]\nradii = [1.0, 100.0]\n"
                            "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"smallest radii", "[particles]\npositions = [[0.0, 0.0, 0.0], [0.003, 0.0, 0.0]]\nradii = [0.001, 0.001]\n"
                           "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"largest radii", "[particles]\npositions = [[0.0, 0.0, 0.0], [3000.0, 0.0, 0.0]]\nradii = [1000.0, 1000.0]\n"
                          "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"gap 1e-8", "[particles]\npositions = [[0.0, 0.0, 0.0], [2.00000001, 0.0, 0.0]]\n"
                     "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"touching", "[particles]\npositions = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]\n"
                     "[forces]\nexternal_force = [1.0, 0.0, -1.0]\n"},
        {"largest box, one particle", "[domain]\nkind = \"periodic\"\nbox = [1e6, 1e6, 1e6]\n[particles]\n"
                                      "positions = [[0.0, 0.0, 0.0]]\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"flat box", "[domain]\nkind = \"periodic\"\nbox = [1e6, 3.0, 3.0]\n[particles]\n"
                     "positions = [[0.0, 0.0, 0.0]]\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"count 1 periodic", "[domain]\nkind = \"periodic\"\nbox = [5.0, 5.0, 5.0]\n[particles]\ngenerate = \"random\"\n"
                             "count = 1\n[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"},
        {"huge forces", "[particles]\npositions = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]]\n"
                        "[forces]\nexternal_force = [1e12, -1e12, 1e12]\nexternal_torque = [1e12, 0.0, 0.0]\n"},
        {"tiny forces", "[particles]\npositions = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]]\n"
                        "[forces]\nexternal_force = [1e-300, 0.0, 0.0]\n"},
        {"hot", "[fluid]\nkT = 1e6\n[particles]\npositions = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]]\n"},
        {"strain", "[domain]\nkind = \"periodic\"\nbox = [8.0, 8.0, 8.0]\nshear_strain = 1e9\n[particles]\n"
                   "positions = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]]\n[flow]\nkind = \"simple_shear\"\nrate = 1.0\n"},
        {"dense lattice", "[domain]\nkind = \"periodic\"\nbox = [10.01, 10.01, 10.01]\n[particles]\ngenerate = \"lattice\"\n"
                          "count = 125\n"},
        {"wide lognormal", "[particles]\ngenerate = \"random\"\ncount = 50\nsize_distribution = \"lognormal\"\n"
                           "sigma = 0.5\nvolume_fraction = 0.05\n"},
        {"stokesian pair at contact", "[particles]\npositions = [[0.0, 0.0, 0.0], [2.0000001, 0.0, 0.0]]\n"
                                      "[hydrodynamics]\nmodel = \"stokesian\"\nmoments = \"FTS\"\n[flow]\n"
                                      "kind = \"simple_shear\"\nrate = 1.0\n"},
    };
    const auto& [what, text] = rng.pick(scenes);
    m = parse_simple(text);
    c.detail = what;
    c.expect = Expect::valid;
  }
};

// ---------------------------------------------------------------------------------------------
// Running.
struct Run {
  std::size_t case_index;
  std::string command;  // "check" or "solve"
  fs::path dir;         // empty folder the command runs in
  pid_t pid = 0;
  std::chrono::steady_clock::time_point start;
  bool timed_out = false;
  double announced_s = -1;  // the estimate of a "stokesian: note: ... estimated at about X s" line
  int status = 0;
  double seconds = 0;
  std::string cls, why, message;
  int exit_code = -1, signal = 0;
};

struct Options {
  long cases = 100;
  std::uint64_t seed = 1;
  std::string stokesian, work, report, configs;
  double solve_fraction = 0.3, timeout = 20;
  int jobs = 2;
  bool keep = false;
};

void write_file(const fs::path& p, const std::string& s) {
  std::ofstream o(p, std::ios::binary);
  o << s;
}

std::string read_text(const fs::path& p, std::size_t max = 1 << 16) {
  std::ifstream in(p, std::ios::binary);
  std::string s(max, '\0');
  in.read(s.data(), std::streamsize(max));
  s.resize(std::size_t(in.gcount()));
  return s;
}

pid_t launch(const Options& o, const Case& c, Run& r, const fs::path& scene) {
  std::vector<std::string> args = {o.stokesian, r.command, scene.string(), "--threads", "1"};
  if (r.command == "solve") args.insert(args.end(), {"--out", (r.dir / "out.h5").string(), "--quiet"});
  (void)c;
  const std::string out = (r.dir.parent_path() / (r.command + ".stdout")).string();
  const std::string err = (r.dir.parent_path() / (r.command + ".stderr")).string();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    if (chdir(r.dir.c_str()) != 0) _exit(120);
    const rlim_t as = rlim_t(3) << 30;
    rlimit lim{as, as};
    setrlimit(RLIMIT_AS, &lim);
    const rlim_t cpu = rlim_t(o.timeout * 2 + 5);
    rlimit cl{cpu, cpu + 5};
    setrlimit(RLIMIT_CPU, &cl);
    rlimit core{0, 0};
    setrlimit(RLIMIT_CORE, &core);
    if (!freopen(out.c_str(), "w", stdout) || !freopen(err.c_str(), "w", stderr)) _exit(121);
    setenv("OMP_NUM_THREADS", "1", 1);
    // The memory limit imposed here, told to the engine the documented way (docs/cli.md), so that
    // its estimates refuse what this limit cannot hold instead of running into std::bad_alloc.
    setenv("STOKESIAN_MEMORY_LIMIT", "3G", 1);
    setpgid(0, 0);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(122);
  }
  return pid;
}

// Every floating-point dataset of an HDF5 file, checked for non-finite values. Returns "" or a
// description of the first bad value.
struct H5Scan {
  std::string bad;
  std::vector<double> id;  // open channels: particles/all/id/value, frames x slots (empty slots -1)
  std::size_t slots = 0;
};
herr_t visit_dataset(hid_t obj, const char* name, const H5O_info_t* info, void* data) {
  auto* scan = static_cast<H5Scan*>(data);
  if (info->type != H5O_TYPE_DATASET || !scan->bad.empty()) return 0;
  const hid_t ds = H5Dopen2(obj, name, H5P_DEFAULT);
  if (ds < 0) return 0;
  const hid_t type = H5Dget_type(ds);
  if (H5Tget_class(type) == H5T_FLOAT) {
    const hid_t space = H5Dget_space(ds);
    const hssize_t n = H5Sget_simple_extent_npoints(space);
    if (n > 0 && n < (hssize_t(1) << 27)) {
      std::vector<double> v(static_cast<std::size_t>(n));
      // docs/output.md: min_gap is +inf for a single particle (no pair); anything else non-finite
      // is a defect.
      const std::string path = name;
      const bool inf_ok = path.size() >= 13 && path.compare(path.size() - 13, 13, "min_gap/value") == 0;
      // docs/output.md: an open channel's empty slots (id -1) hold NaN in every float element.
      const bool per_particle = path.rfind("particles/all/", 0) == 0 && path.size() > 6 &&
                                path.compare(path.size() - 6, 6, "/value") == 0 && !scan->id.empty();
      const std::size_t per_frame = per_particle ? v.size() / (scan->id.size() / scan->slots) : 0;
      auto empty_slot = [&](std::size_t i) {
        if (!per_particle || per_frame % scan->slots != 0) return false;
        const std::size_t comps = per_frame / scan->slots, frame = i / per_frame, slot = (i % per_frame) / comps;
        return scan->id[frame * scan->slots + slot] < 0;
      };
      if (H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0)
        for (std::size_t i = 0; i < v.size(); ++i)
          if (!std::isfinite(v[i]) && !(inf_ok && v[i] > 0 && std::isinf(v[i])) && !(std::isnan(v[i]) && empty_slot(i))) {
            std::ostringstream o;
            o << name << "[" << i << "] = " << v[i];
            scan->bad = o.str();
            break;
          }
    }
    H5Sclose(space);
  }
  H5Tclose(type);
  H5Dclose(ds);
  return 0;
}

std::string nonfinite_in(const fs::path& h5) {
  const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return "";
  H5Scan scan;
  if (H5Lexists(f, "particles", H5P_DEFAULT) > 0 && H5Lexists(f, "particles/all", H5P_DEFAULT) > 0 &&
      H5Lexists(f, "particles/all/id", H5P_DEFAULT) > 0) {
    const hid_t ds = H5Dopen2(f, "particles/all/id/value", H5P_DEFAULT);
    if (ds >= 0) {
      const hid_t space = H5Dget_space(ds);
      hsize_t dims[2] = {0, 0};
      if (H5Sget_simple_extent_ndims(space) == 2 && H5Sget_simple_extent_dims(space, dims, nullptr) == 2 && dims[1] > 0) {
        scan.id.resize(dims[0] * dims[1]);
        scan.slots = dims[1];
        if (H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, scan.id.data()) < 0) scan.id.clear();
      }
      H5Sclose(space);
      H5Dclose(ds);
    }
  }
#if H5_VERSION_GE(1, 12, 0)
  H5Ovisit3(f, H5_INDEX_NAME, H5_ITER_NATIVE, visit_dataset, &scan, H5O_INFO_BASIC);
#else
  H5Ovisit(f, H5_INDEX_NAME, H5_ITER_NATIVE, visit_dataset, &scan);
#endif
  H5Fclose(f);
  return scan.bad;
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// The error line(s) of stderr: lines starting "stokesian:".
std::string error_message(const std::string& err) {
  std::istringstream is(err);
  std::string line, out;
  while (std::getline(is, line))
    if (line.rfind("stokesian:", 0) == 0) out += (out.empty() ? "" : " | ") + line;
  return out.empty() ? err.substr(0, 400) : out;
}

// Whether `msg` names `scene` with a line number (scene:digits).
bool names_line(const std::string& msg, const std::string& file) {
  for (std::size_t at = msg.find(file + ":"); at != std::string::npos; at = msg.find(file + ":", at + 1)) {
    const std::size_t d = at + file.size() + 1;
    if (d < msg.size() && std::isdigit(static_cast<unsigned char>(msg[d]))) return true;
  }
  return false;
}

void classify(const Case& c, Run& r, const std::string& scene) {
  const std::string err = read_text(r.dir.parent_path() / (r.command + ".stderr"));
  r.message = error_message(err);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(r.dir)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  auto set = [&](const char* cls, const std::string& why) {
    r.cls = cls;
    r.why = why;
  };
  if (r.timed_out && r.announced_s >= 0 && c.expect != Expect::invalid)
    return set("slow_announced", "announced an estimate of about " + std::to_string(long(r.announced_s)) +
                                     " s, ended at the wall timeout");
  if (r.timed_out) return set("hang", "no exit within the wall timeout");
  if (WIFSIGNALED(r.status)) {
    r.signal = WTERMSIG(r.status);
    return set("crash", std::string("killed by signal ") + std::to_string(r.signal) + " (" + strsignal(r.signal) + ")");
  }
  r.exit_code = WEXITSTATUS(r.status);
  const int code = r.exit_code;
  std::string files;
  for (const auto& f : left) files += (files.empty() ? "" : ", ") + f;
  if (code != 0 && !left.empty()) return set("wrote_on_error", "exit " + std::to_string(code) + " left " + files);
  if (r.command == "check" && !left.empty()) return set("wrote_on_error", "check wrote " + files);
  if (code == 0 && r.command == "solve") {
    const fs::path out = r.dir / "out.h5";
    if (fs::exists(out)) {
      const std::string bad = nonfinite_in(out);
      if (!bad.empty()) return set("nan_output", bad);
    }
  }
  if (has(r.message, "bad_alloc")) return set("unclear_error", "std::bad_alloc names nothing");
  const bool resource = code == 2 && (has(r.message, "memory") || has(r.message, "GB") || has(r.message, "GiB"));
  const bool physics_named = code == 3 && (has(r.message, "particle") || has(r.message, "pair"));
  // Documented (docs/cli.md): check exits 2 on any overlap in the initial state, listing the pairs.
  const bool check_overlap = code == 2 && r.command == "check" && has(r.message, "overlapping pair");
  if (c.expect == Expect::invalid) {
    if (code == 0) return set("invalid_accepted", "exit 0");
    if (code != 2 && !resource) return set("wrong_exit", "exit " + std::to_string(code) + " (expected 2)");
  } else if (c.expect == Expect::valid) {
    if (code == 0 || resource || physics_named || check_overlap) return set("ok", "");
    return set("valid_rejected", "exit " + std::to_string(code));
  } else {
    if (code == 0 || resource || physics_named || check_overlap) return set("ok", "");
    if (code != 2) return set("wrong_exit", "exit " + std::to_string(code) + " (expected 0 or 2)");
  }
  // Exit 2: the message must name the scene file, the key or file, the line and the range.
  if (!has(r.message, scene)) return set("unclear_error", "no scene file name");
  if (c.expect == Expect::invalid) {
    bool named = false;
    for (const auto& n : c.names) named = named || has(r.message, n);
    if (!named) return set("unclear_error", "does not name " + c.names.front());
    if (c.need_line) {
      bool line = names_line(r.message, scene);
      for (const auto& [f, body] : c.files) line = line || names_line(r.message, f);
      if (!line) return set("unclear_error", "no line number");
    }
    if (c.need_allowed && !has(r.message, "allowed")) return set("unclear_error", "no allowed range");
  } else if (!has(r.message, "] ") && !has(r.message, "TOML")) {
    return set("unclear_error", "names no key");
  }
  set("ok", "");
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (unsigned char ch : s) {
    if (ch == '"' || ch == '\\') o += '\\', o += char(ch);
    else if (ch == '\n') o += "\\n";
    else if (ch < 0x20 || ch >= 0x7f) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", ch);
      o += b;
    } else o += char(ch);
  }
  return o;
}

int usage(const char* msg) {
  std::fprintf(stderr,
               "fuzz_scenes: %s\nusage: fuzz_scenes --cases N --seed S --stokesian PATH --work DIR [--report out.json]\n"
               "                   [--solve-fraction F] [--jobs J] [--configs DIR] [--timeout SECONDS] [--keep]\n",
               msg);
  return 64;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
#ifdef STOKESIAN_SOURCE_DIR
  o.configs = std::string(STOKESIAN_SOURCE_DIR) + "/configs";
#endif
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--keep") {
      o.keep = true;
      continue;
    }
    if (i + 1 >= argc) return usage(("missing value after " + a).c_str());
    const std::string v = argv[++i];
    if (a == "--cases") o.cases = std::atol(v.c_str());
    else if (a == "--seed") o.seed = std::strtoull(v.c_str(), nullptr, 10);
    else if (a == "--stokesian") o.stokesian = v;
    else if (a == "--work") o.work = v;
    else if (a == "--report") o.report = v;
    else if (a == "--solve-fraction") o.solve_fraction = std::atof(v.c_str());
    else if (a == "--jobs") o.jobs = std::max(1, std::atoi(v.c_str()));
    else if (a == "--configs") o.configs = v;
    else if (a == "--timeout") o.timeout = std::atof(v.c_str());
    else return usage(("unknown option " + a).c_str());
  }
  if (o.stokesian.empty() || o.work.empty() || o.cases < 1) return usage("--stokesian, --work and --cases >= 1 are required");
  if (!fs::exists(o.stokesian)) return usage(("no such executable: " + o.stokesian).c_str());
  o.stokesian = fs::absolute(o.stokesian).string();
  const fs::path work = fs::absolute(o.work);
  fs::remove_all(work);
  fs::create_directories(work);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);

  Generator gen{Rng{o.seed * 0x2545F4914F6CDD1DULL + 1}, load_bases(o.configs)};
  std::vector<Case> cases;
  std::vector<Run> runs;
  for (long i = 0; i < o.cases; ++i) {
    Case c = gen.make(int(i));
    c.solve = gen.rng.chance(o.solve_fraction);
    const fs::path dir = work / ("case_" + std::to_string(i));
    fs::create_directories(dir);
    write_file(dir / "scene.toml", c.text);
    for (const auto& [name, body] : c.files) write_file(dir / name, body);
    for (const char* cmd : {"check", "solve"}) {
      if (std::string(cmd) == "solve" && !c.solve) continue;
      Run r;
      r.case_index = cases.size();
      r.command = cmd;
      r.dir = dir / (std::string(cmd) + "_run");
      fs::create_directories(r.dir);
      runs.push_back(r);
    }
    cases.push_back(std::move(c));
  }

  // Run with at most `jobs` children at once; kill the process group at the wall timeout.
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t next = 0, done = 0;
  std::map<pid_t, std::size_t> live;
  while (done < runs.size()) {
    while (live.size() < std::size_t(o.jobs) && next < runs.size()) {
      Run& r = runs[next];
      const fs::path scene = r.dir.parent_path() / "scene.toml";
      r.start = std::chrono::steady_clock::now();
      r.pid = launch(o, cases[r.case_index], r, scene);
      if (r.pid > 0) setpgid(r.pid, r.pid);
      live[r.pid] = next++;
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid > 0 && live.count(pid)) {
      Run& r = runs[live[pid]];
      r.status = status;
      r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - r.start).count();
      live.erase(pid);
      ++done;
      continue;
    }
    const auto now = std::chrono::steady_clock::now();
    for (auto& [p, idx] : live) {
      Run& r = runs[idx];
      const double elapsed = std::chrono::duration<double>(now - r.start).count();
      // A run still going after a second: has it announced slow work with an estimate?
      if (!r.timed_out && r.announced_s < 0 && elapsed > 1.0) {
        const std::string err = read_text(r.dir.parent_path() / (r.command + ".stderr"));
        const std::string tag = "is estimated at about ";
        if (const auto at = err.find(tag); at != std::string::npos && err.find("stokesian: note:") != std::string::npos)
          r.announced_s = std::atof(err.c_str() + at + tag.size());
      }
      if (!r.timed_out && (elapsed > o.timeout || r.announced_s > o.timeout)) {
        r.timed_out = true;
        kill(-p, SIGKILL);
        kill(p, SIGKILL);
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const std::vector<std::string> failing = {"crash", "hang", "nan_output", "invalid_accepted", "unclear_error",
                                            "wrote_on_error", "valid_rejected", "wrong_exit"};
  std::map<std::string, std::map<std::string, long>> counts;  // command -> class -> n
  std::map<std::string, std::vector<const Run*>> examples;
  for (auto& r : runs) {
    const fs::path scene = r.dir.parent_path() / "scene.toml";
    classify(cases[r.case_index], r, scene.string());
    ++counts[r.command][r.cls];
    ++counts["all"][r.cls];
    if (r.cls != "ok") examples[r.cls].push_back(&r);
  }
  // Folders of cases whose runs were all ok are removed (unless --keep).
  if (!o.keep) {
    std::set<std::size_t> bad;
    for (const auto& r : runs)
      if (r.cls != "ok") bad.insert(r.case_index);
    for (std::size_t i = 0; i < cases.size(); ++i)
      if (!bad.count(i)) fs::remove_all(work / ("case_" + std::to_string(i)));
  }

  long failures = 0;
  std::printf("fuzz_scenes: %ld cases, seed %llu, %zu runs (%ld check, %ld solve) in %.1f s\n", o.cases,
              (unsigned long long)o.seed, runs.size(), counts["check"]["ok"] + counts["check"]["slow_announced"] + [&] {
                long n = 0;
                for (const auto& f : failing) n += counts["check"][f];
                return n;
              }(),
              [&] {
                long n = counts["solve"]["ok"] + counts["solve"]["slow_announced"];
                for (const auto& f : failing) n += counts["solve"][f];
                return n;
              }(),
              wall);
  std::printf("%-18s %8s %8s %8s\n", "class", "check", "solve", "all");
  for (const auto& cls : std::vector<std::string>{"ok", "slow_announced", "crash", "hang", "nan_output", "invalid_accepted",
                                                  "unclear_error", "wrote_on_error", "valid_rejected", "wrong_exit"}) {
    std::printf("%-18s %8ld %8ld %8ld\n", cls.c_str(), counts["check"][cls], counts["solve"][cls], counts["all"][cls]);
    if (cls != "ok" && cls != "slow_announced") failures += counts["all"][cls];
  }
  std::vector<std::string> listed = failing;
  listed.insert(listed.begin(), "slow_announced");
  for (const auto& cls : listed) {
    const auto& ex = examples[cls];
    for (std::size_t k = 0; k < ex.size() && k < 4; ++k) {
      const Run& r = *ex[k];
      const Case& c = cases[r.case_index];
      std::printf("  %s: case %d (%s %s, %s; expected %s): %s\n    %s\n", cls.c_str(), c.id, r.command.c_str(),
                  c.base.c_str(), c.detail.substr(0, 160).c_str(), name_of(c.expect), r.why.c_str(),
                  r.message.substr(0, 300).c_str());
    }
  }
  if (!o.report.empty()) {
    std::ofstream j(o.report);
    j << "{\n  \"cases\": " << o.cases << ",\n  \"seed\": " << o.seed << ",\n  \"solve_fraction\": " << o.solve_fraction
      << ",\n  \"timeout_s\": " << o.timeout << ",\n  \"wall_s\": " << wall << ",\n  \"counts\": {";
    bool first = true;
    for (const auto& [cmd, m] : counts) {
      j << (first ? "" : ",") << "\n    \"" << cmd << "\": {";
      bool f2 = true;
      for (const auto& [cls, n] : m) {
        j << (f2 ? "" : ", ") << "\"" << cls << "\": " << n;
        f2 = false;
      }
      j << "}";
      first = false;
    }
    j << "\n  },\n  \"failures\": [";
    first = true;
    for (const auto& r : runs) {
      if (r.cls == "ok") continue;
      const Case& c = cases[r.case_index];
      j << (first ? "" : ",") << "\n    {\"case\": " << c.id << ", \"command\": \"" << r.command << "\", \"class\": \""
        << r.cls << "\", \"why\": \"" << json_escape(r.why) << "\", \"base\": \"" << c.base << "\", \"mutation\": \""
        << c.mutation << "\", \"detail\": \"" << json_escape(c.detail.substr(0, 300)) << "\", \"expect\": \""
        << name_of(c.expect) << "\", \"exit\": " << r.exit_code << ", \"seconds\": " << r.seconds
        << ", \"message\": \"" << json_escape(r.message.substr(0, 600)) << "\", \"folder\": \""
        << json_escape(r.dir.parent_path().string()) << "\"}";
      first = false;
    }
    j << "\n  ]\n}\n";
  }
  std::printf("fuzz_scenes: %s (%ld failing runs)\n", failures ? "FAILED" : "passed", failures);
  return failures ? 1 : 0;
}
