// Sweep files: parsing, expansion into runs and validation of every expanded scene (sweep.hpp,
// docs/sweeps.md).
#include "io/sweep.hpp"

#include "engine/core/errors.hpp"
#include "io/scene_toml.hpp"

#include <toml++/toml.h>

#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace stokesian::io {
namespace {

std::string where(const std::string& file, const toml::node* n) {
  std::string s = file;
  if (n && n->source().begin.line) s += ":" + std::to_string(n->source().begin.line);
  return s;
}

[[noreturn]] void fail(const std::string& file, const toml::node* n, const std::string& msg) {
  throw ConfigError(where(file, n) + ": " + msg);
}

void only(const std::string& file, const toml::table& t, const std::string& table, const std::set<std::string>& allowed) {
  for (auto&& [k, v] : t)
    if (!allowed.count(std::string(k.str()))) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(file, &v, table + " " + std::string(k.str()) + ": unknown key (allowed: " + list + ")");
    }
}

// TOML text of a value (shortest round-trip numbers; strings quoted).
std::string text_of(const toml::node& n) {
  if (auto v = n.as_floating_point()) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v->get());
    std::string s(buf, r.ptr);
    if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
    return s;
  }
  if (auto v = n.as_integer()) return std::to_string(v->get());
  if (auto v = n.as_boolean()) return v->get() ? "true" : "false";
  if (auto v = n.as_string()) {
    std::string s = "\"";
    for (char c : v->get()) {
      if (c == '"' || c == '\\') s += '\\';
      if (static_cast<unsigned char>(c) < 0x20) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\u%04x", unsigned(c));
        s += buf;
        continue;
      }
      s += c;
    }
    return s + "\"";
  }
  if (auto a = n.as_array()) {
    std::string s = "[";
    for (std::size_t i = 0; i < a->size(); ++i) s += (i ? ", " : "") + text_of(*a->get(i));
    return s + "]";
  }
  std::ostringstream o;
  if (auto t = n.as_table()) o << toml::toml_formatter(*t, toml::format_flags::none);
  return "{" + o.str() + "}";
}

// One segment of a key path: a name and an optional array index ("pair[1]").
struct Segment {
  std::string name;
  long index = -1;
};

std::vector<Segment> split_key(const std::string& key, const std::string& file, const toml::node* n) {
  std::vector<Segment> out;
  std::size_t p = 0;
  while (p <= key.size()) {
    const std::size_t q = std::min(key.find('.', p), key.size());
    std::string part = key.substr(p, q - p);
    Segment s;
    const std::size_t b = part.find('[');
    if (b != std::string::npos) {
      long idx = -1;
      const auto r = std::from_chars(part.data() + b + 1, part.data() + part.size(), idx);
      if (r.ec != std::errc() || idx < 0 || r.ptr != part.data() + part.size() - 1 || part.back() != ']')
        fail(file, n, "key \"" + key + "\": malformed array index in \"" + part + "\" (allowed: name[i], i >= 0)");
      s.index = idx;
      part = part.substr(0, b);
    }
    if (part.empty()) fail(file, n, "key \"" + key + "\": empty name (allowed: dotted scene keys, e.g. \"fluid.kT\")");
    s.name = part;
    out.push_back(s);
    p = q + 1;
  }
  return out;
}

// Puts `value` (moved, so that it keeps its file and line) at the key path in `root`, creating
// missing tables on the way.
void set_key(toml::table& root, const std::string& key, toml::node&& value, const std::string& file, const toml::node* at) {
  const auto segs = split_key(key, file, at);
  toml::table* t = &root;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const Segment& s = segs[i];
    const bool last = i + 1 == segs.size();
    if (s.index >= 0) {
      toml::array* arr = t->get_as<toml::array>(s.name);
      if (!arr || std::size_t(s.index) >= arr->size())
        fail(file, at, "key \"" + key + "\": the base scene has no element " + std::to_string(s.index) + " of \"" + s.name +
                           "\" (it has " + std::to_string(arr ? arr->size() : 0) + ")");
      if (last) {
        value.visit([&](auto&& v) { arr->replace(arr->begin() + s.index, std::move(v)); });
        return;
      }
      t = arr->get_as<toml::table>(std::size_t(s.index));
      if (!t) fail(file, at, "key \"" + key + "\": element " + std::to_string(s.index) + " of \"" + s.name + "\" is not a table");
      continue;
    }
    if (last) {
      value.visit([&](auto&& v) { t->insert_or_assign(s.name, std::move(v)); });
      return;
    }
    if (!t->contains(s.name)) t->insert(s.name, toml::table{});
    toml::table* next = t->get_as<toml::table>(s.name);
    if (!next) fail(file, at, "key \"" + key + "\": \"" + s.name + "\" is not a table in the base scene");
    t = next;
  }
}

std::string read_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

toml::table parse_toml(const std::string& text, const std::string& path) {
  try {
    return toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw ConfigError(path + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
}

// One factor of the expansion: its keys and, per level, the value nodes' positions in the sweep
// file (factor f, level l, key k) -> index path into a fresh parse of the sweep file.
struct Factor {
  std::string table;  // "[[grid]]" or "[[zip]]"
  std::size_t entry = 0;
  std::vector<std::string> keys;
  std::size_t levels = 0;
  const toml::node* at = nullptr;
};

// The value node of (factor, level, key) inside a parsed sweep table.
toml::node* level_node(toml::table& sweep, const Factor& f, std::size_t level, std::size_t key) {
  toml::array* entries = sweep.get_as<toml::array>(f.table == "[[grid]]" ? "grid" : "zip");
  toml::table* e = entries->get_as<toml::table>(f.entry);
  toml::array* values = e->get_as<toml::array>("values");
  toml::node* v = values->get(level);
  if (f.table == "[[zip]]") v = v->as_array()->get(key);
  return v;
}

}  // namespace

std::int64_t replica_seed(std::int64_t seed, int replica) {
  if (replica == 0) return seed;
  std::uint64_t z = std::uint64_t(seed) + 0x9E3779B97F4A7C15ull * std::uint64_t(replica + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return std::int64_t(z >> 33);
}

Sweep parse_sweep(const std::string& text, const std::string& path) {
  Sweep sw;
  sw.path = path;
  const toml::table root = parse_toml(text, path);
  only(path, root, "top level", {"base", "set", "grid", "zip", "replicas", "summary", "slurm"});

  const toml::node* bn = root.get("base");
  if (!bn || !bn->is_string()) fail(path, bn ? bn : nullptr, "base: required, a string (the base scene's path, relative to the sweep file)");
  std::string base = bn->as_string()->get();
  if (!base.empty() && base[0] != '/') {
    const auto dir = std::filesystem::path(path).parent_path();
    base = (dir.empty() ? std::filesystem::path(base) : dir / base).lexically_normal().string();
  }
  sw.base = base;
  if (!std::filesystem::exists(base)) fail(path, bn, "base = \"" + bn->as_string()->get() + "\": no such file (" + base + ")");

  std::vector<Factor> factors;
  std::set<std::string> swept;
  auto add_key = [&](const std::string& k, const toml::node* at) {
    if (k == "replica") fail(path, at, "key \"replica\": reserved for the replica column");
    if (!swept.insert(k).second) fail(path, at, "key \"" + k + "\": swept twice");
    split_key(k, path, at);
  };
  for (const char* kind : {"grid", "zip"}) {
    const toml::node* n = root.get(kind);
    if (!n) continue;
    const std::string T = std::string("[[") + kind + "]]";
    const toml::array* arr = n->as_array();
    if (!arr || !arr->is_array_of_tables()) fail(path, n, T + ": expected an array of tables");
    for (std::size_t e = 0; e < arr->size(); ++e) {
      const toml::table& t = *arr->get_as<toml::table>(e);
      Factor f;
      f.table = T;
      f.entry = e;
      f.at = &t;
      const toml::node* vn = t.get("values");
      if (std::string(kind) == "grid") {
        only(path, t, T, {"key", "values"});
        const toml::node* kn = t.get("key");
        if (!kn || !kn->is_string()) fail(path, kn ? kn : &t, T + " key: required, a string (a dotted scene key, e.g. \"fluid.kT\")");
        f.keys = {kn->as_string()->get()};
        add_key(f.keys[0], kn);
      } else {
        only(path, t, T, {"keys", "values"});
        const toml::node* kn = t.get("keys");
        const toml::array* ka = kn ? kn->as_array() : nullptr;
        if (!ka || ka->empty()) fail(path, kn ? kn : &t, T + " keys: required, a non-empty array of dotted scene keys");
        for (const auto& k : *ka) {
          if (!k.is_string()) fail(path, &k, T + " keys: every entry must be a string");
          f.keys.push_back(k.as_string()->get());
          add_key(f.keys.back(), &k);
        }
      }
      const toml::array* va = vn ? vn->as_array() : nullptr;
      if (!va || va->empty()) fail(path, vn ? vn : &t, T + " values: required, a non-empty array");
      if (std::string(kind) == "zip")
        for (const auto& v : *va) {
          const toml::array* tuple = v.as_array();
          if (!tuple || tuple->size() != f.keys.size())
            fail(path, &v, T + " values: every entry must be an array of " + std::to_string(f.keys.size()) +
                               " values, one per key (got " + text_of(v) + ")");
        }
      f.levels = va->size();
      factors.push_back(f);
    }
  }
  for (const auto& f : factors) sw.columns.insert(sw.columns.end(), f.keys.begin(), f.keys.end());
  // [set]: keys given one value for every run (not columns of the summary).
  std::vector<std::string> set_keys;
  if (const toml::node* sn = root.get("set")) {
    const toml::table* st = sn->as_table();
    if (!st) fail(path, sn, "[set]: expected a table of \"dotted.scene.key\" = value");
    for (auto&& [k, v] : *st) {
      const std::string key(k.str());
      if (v.is_table())
        fail(path, &v, "[set] " + key + ": a table; write each scene key quoted and whole, e.g. \"time.steps\" = 1000");
      add_key(key, &v);
      set_keys.push_back(key);
    }
  }

  if (const toml::node* rn = root.get("replicas")) {
    const toml::table* rt = rn->as_table();
    if (!rt) fail(path, rn, "[replicas]: expected a table");
    only(path, *rt, "[replicas]", {"count"});
    const toml::node* cn = rt->get("count");
    if (!cn || !cn->is_integer() || cn->as_integer()->get() < 1 || cn->as_integer()->get() > 10000)
      fail(path, cn ? cn : rn, "[replicas] count: required, an integer from 1 to 10000");
    sw.replicas = int(cn->as_integer()->get());
    if (sw.replicas > 1) sw.columns.push_back("replica");  // one replica is no factor: no column
  }

  if (const toml::node* sn = root.get("summary")) {
    const toml::table* st = sn->as_table();
    if (!st) fail(path, sn, "[summary]: expected a table");
    only(path, *st, "[summary]", {"observables", "window"});
    if (const toml::node* on = st->get("observables")) {
      const toml::array* oa = on->as_array();
      if (!oa) fail(path, on, "[summary] observables: expected an array of observable names");
      for (const auto& o : *oa) {
        if (!o.is_string()) fail(path, &o, "[summary] observables: every entry must be a string");
        sw.summary.observables.push_back(o.as_string()->get());
      }
    }
    if (const toml::node* wn = st->get("window")) {
      const toml::array* wa = wn->as_array();
      const bool ok = wa && wa->size() == 2 && (*wa)[0].is_number() && (*wa)[1].is_number();
      const double b = ok ? (*wa)[0].value<double>().value() : 0, e = ok ? (*wa)[1].value<double>().value() : 0;
      if (!ok || !(b >= 0.0 && b < e && e <= 1.0))
        fail(path, wn, "[summary] window = " + text_of(*wn) + ": expected [begin, end] with 0 <= begin < end <= 1 (fractions of the recorded time span)");
      sw.summary.window_begin = b;
      sw.summary.window_end = e;
    }
  }

  if (const toml::node* ln = root.get("slurm")) {
    const toml::table* lt = ln->as_table();
    if (!lt) fail(path, ln, "[slurm]: expected a table");
    only(path, *lt, "[slurm]", {"partition", "time", "cpus_per_task", "mem", "account", "extra"});
    auto str = [&](const char* k, std::string& out) {
      if (const toml::node* n = lt->get(k)) {
        if (!n->is_string() || n->as_string()->get().find('\n') != std::string::npos)
          fail(path, n, std::string("[slurm] ") + k + ": expected a one-line string");
        out = n->as_string()->get();
      }
    };
    str("partition", sw.slurm.partition);
    str("time", sw.slurm.time);
    str("mem", sw.slurm.mem);
    str("account", sw.slurm.account);
    if (const toml::node* n = lt->get("cpus_per_task")) {
      if (!n->is_integer() || n->as_integer()->get() < 1 || n->as_integer()->get() > 1024)
        fail(path, n, "[slurm] cpus_per_task: expected an integer from 1 to 1024");
      sw.slurm.cpus_per_task = int(n->as_integer()->get());
    }
    if (const toml::node* n = lt->get("extra")) {
      const toml::array* a = n->as_array();
      if (!a) fail(path, n, "[slurm] extra: expected an array of strings (#SBATCH options)");
      for (const auto& x : *a) {
        if (!x.is_string() || x.as_string()->get().find('\n') != std::string::npos)
          fail(path, &x, "[slurm] extra: every entry must be a one-line string");
        sw.slurm.extra.push_back(x.as_string()->get());
      }
    }
  }

  // Expansion: mixed-radix counter over the factors (last fastest), replicas innermost.
  std::size_t total = std::size_t(sw.replicas);
  for (const auto& f : factors) total *= f.levels;
  if (total > 100000) fail(path, nullptr, "the sweep expands to " + std::to_string(total) + " runs (allowed at most 100000)");
  const std::string base_text = read_file(base, "base scene");
  for (std::size_t r = 0; r < total; ++r) {
    SweepRun run;
    run.index = r;
    char name[32];
    std::snprintf(name, sizeof name, "run_%04zu", r);
    run.name = name;
    std::size_t rest = r;
    run.replica = int(rest % std::size_t(sw.replicas));
    rest /= std::size_t(sw.replicas);
    std::vector<std::size_t> level(factors.size());
    for (std::size_t f = factors.size(); f-- > 0;) {
      level[f] = rest % factors[f].levels;
      rest /= factors[f].levels;
    }
    // Fresh parses, so that the moved value nodes keep their file and line for error messages.
    toml::table scene = parse_toml(base_text, base);
    toml::table fresh = parse_toml(text, path);
    for (const auto& key : set_keys) {
      toml::node* v = fresh.get_as<toml::table>("set")->get(key);
      set_key(scene, key, std::move(*v), path, v);
    }
    std::string label;
    for (std::size_t f = 0; f < factors.size(); ++f)
      for (std::size_t k = 0; k < factors[f].keys.size(); ++k) {
        toml::node* v = level_node(fresh, factors[f], level[f], k);
        const std::string t = text_of(*v);
        run.values.push_back(t);
        label += (label.empty() ? "" : ", ") + factors[f].keys[k] + " = " + t;
        set_key(scene, factors[f].keys[k], std::move(*v), path, v);
      }
    if (sw.replicas > 1) {
      run.values.push_back(std::to_string(run.replica));
      label += (label.empty() ? "" : ", ") + std::string("replica ") + std::to_string(run.replica);
      // Every seed the scene uses: the thermal noise's and, for generated particles, the placement's.
      auto derive = [&](toml::table* t, const char* key) {
        const std::int64_t s = t->get(key) && t->get(key)->is_integer() ? t->get(key)->as_integer()->get() : 1;
        t->insert_or_assign(key, replica_seed(s, run.replica));
      };
      if (!scene.contains("brownian")) scene.insert("brownian", toml::table{});
      if (toml::table* b = scene.get_as<toml::table>("brownian")) derive(b, "seed");
      if (toml::table* p = scene.get_as<toml::table>("particles"))
        if (p->contains("generate")) derive(p, "seed");
    }
    try {
      run.scene = resolved_toml(parse_scene(scene, base));
    } catch (const ConfigError& e) {
      throw ConfigError(std::string(e.what()) + " (in " + run.name + " of " + path + ": " + (label.empty() ? "the base scene" : label) + ")");
    }
    sw.runs.push_back(std::move(run));
  }
  return sw;
}

Sweep load_sweep(const std::string& path) { return parse_sweep(read_file(path, "sweep file"), path); }

}  // namespace stokesian::io
