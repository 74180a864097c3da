#include "io/xyz.hpp"

#include "engine/core/errors.hpp"
#include "io/h5md.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>

namespace stokesian::io {
namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::vector<std::string> split_ws(const std::string& line) {
  std::istringstream is(line);
  std::vector<std::string> out;
  for (std::string t; is >> t;) out.push_back(t);
  return out;
}

// key=value pairs of an extended-XYZ comment line; values may be "double quoted"; a bare key
// is a flag with value "T".
std::vector<std::pair<std::string, std::string>> parse_comment(const std::string& line, const std::string& where) {
  std::vector<std::pair<std::string, std::string>> kv;
  std::size_t i = 0;
  const std::size_t n = line.size();
  auto space = [&](std::size_t j) { return std::isspace(static_cast<unsigned char>(line[j])) != 0; };
  while (i < n) {
    while (i < n && space(i)) ++i;
    if (i >= n) break;
    const std::size_t k0 = i;
    while (i < n && !space(i) && line[i] != '=') ++i;
    std::string key = line.substr(k0, i - k0), value = "T";
    if (i < n && line[i] == '=') {
      ++i;
      if (i < n && line[i] == '"') {
        const auto close = line.find('"', i + 1);
        if (close == std::string::npos) throw IoError(where + ": unterminated quote after " + key + "=");
        value = line.substr(i + 1, close - i - 1);
        i = close + 1;
      } else {
        const std::size_t v0 = i;
        while (i < n && !space(i)) ++i;
        value = line.substr(v0, i - v0);
      }
    }
    kv.emplace_back(key, value);
  }
  return kv;
}

double to_double(const std::string& t, const std::string& where, const char* what) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (t.empty() || *end != '\0' || errno == ERANGE)
    throw IoError(where + ": cannot read " + what + " from \"" + t + "\"");
  return v;
}

std::int64_t to_int(const std::string& t, const std::string& where, const char* what) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(t.c_str(), &end, 10);
  if (t.empty() || *end != '\0' || errno == ERANGE)
    throw IoError(where + ": cannot read " + what + " from \"" + t + "\"");
  return v;
}

struct Columns {
  int total = 4, pos = 1, radius = -1, species = 0;
  bool from_properties = false;
};

Columns parse_properties(const std::string& props, const std::string& where) {
  Columns c;
  c.from_properties = true;
  c.pos = c.radius = c.species = -1;
  c.total = 0;
  std::vector<std::string> f;
  std::stringstream ss(props);
  for (std::string t; std::getline(ss, t, ':');) f.push_back(t);
  if (f.size() % 3 != 0) throw IoError(where + ": Properties must be name:type:count triples");
  for (std::size_t i = 0; i < f.size(); i += 3) {
    const std::string name = lower(f[i]), type = f[i + 1];
    const int count = static_cast<int>(to_int(f[i + 2], where, "a Properties column count"));
    if (count < 1) throw IoError(where + ": Properties column " + f[i] + " has count < 1");
    if (name == "pos" && count == 3 && type == "R") c.pos = c.total;
    if ((name == "radius" || name == "radii") && count == 1 && type == "R") c.radius = c.total;
    if ((name == "species" || name == "element") && count == 1 && type == "S") c.species = c.total;
    c.total += count;
  }
  if (c.pos < 0) throw IoError(where + ": Properties has no pos:R:3 column");
  return c;
}

struct Scanned {
  XyzFrame frame;
  std::streamoff offset = 0;  // byte offset of the frame's count line
};

// Read frames; stops early once `stop` returns true for a parsed frame (still included).
template <typename Stop>
std::vector<Scanned> scan(const std::string& path, Stop stop) {
  std::ifstream is(path);
  if (!is) throw IoError(path + ": cannot open XYZ file (" + std::strerror(errno) + ")");
  std::vector<Scanned> out;
  std::size_t lineno = 0;
  std::string line;
  auto where = [&] { return path + ":" + std::to_string(lineno); };
  while (true) {
    const std::streamoff offset = is.tellg();
    if (!std::getline(is, line)) break;
    ++lineno;
    auto head = split_ws(line);
    if (head.empty()) continue;  // blank lines between or after frames
    if (head.size() != 1) throw IoError(where() + ": expected the particle count, found \"" + line + "\"");
    const std::int64_t n = to_int(head[0], where(), "the particle count");
    if (n < 0) throw IoError(where() + ": negative particle count");
    if (!std::getline(is, line)) {
      ++lineno;
      throw IoError(where() + ": file ends before the comment line");
    }
    ++lineno;
    Scanned s;
    s.offset = offset;
    XyzFrame& fr = s.frame;
    Columns cols;
    for (const auto& [key, value] : parse_comment(line, where())) {
      const std::string k = lower(key);
      if (k == "properties") {
        cols = parse_properties(value, where());
      } else if (k == "lattice") {
        const auto t = split_ws(value);
        if (t.size() != 9) throw IoError(where() + ": Lattice needs 9 numbers");
        Mat3 m;
        for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = to_double(t[static_cast<std::size_t>(i)], where(), "Lattice");
        fr.lattice = m;
      } else if (k == "time") {
        fr.time = to_double(value, where(), "Time");
      } else if (k == "step") {
        fr.step = to_int(value, where(), "Step");
      }
    }
    fr.position.reserve(static_cast<std::size_t>(n));
    for (std::int64_t i = 0; i < n; ++i) {
      if (!std::getline(is, line)) {
        ++lineno;
        throw IoError(where() + ": file ends after " + std::to_string(i) + " of " + std::to_string(n) +
                      " particle lines");
      }
      ++lineno;
      const auto t = split_ws(line);
      const bool plain_radius = !cols.from_properties && t.size() == 5;
      if (static_cast<int>(t.size()) < cols.total)
        throw IoError(where() + ": expected " + std::to_string(cols.total) + " columns, found " + std::to_string(t.size()));
      Vec3 x;
      for (int k = 0; k < 3; ++k) x[k] = to_double(t[static_cast<std::size_t>(cols.pos + k)], where(), "a coordinate");
      fr.position.push_back(x);
      const int rc = plain_radius ? 4 : cols.radius;
      if (i == 0 && rc >= 0) fr.radius.reserve(static_cast<std::size_t>(n));
      if (rc >= 0) {
        if (i > 0 && fr.radius.size() != static_cast<std::size_t>(i))
          throw IoError(where() + ": radius column present on some lines only");
        const double a = to_double(t[static_cast<std::size_t>(rc)], where(), "a radius");
        if (!(a > 0.0) || !std::isfinite(a))
          throw IoError(where() + ": radius " + t[static_cast<std::size_t>(rc)] +
                        " of particle " + std::to_string(i) + " (allowed: a finite number > 0)");
        fr.radius.push_back(a);
      } else if (!fr.radius.empty()) {
        throw IoError(where() + ": radius column present on some lines only");
      }
      if (cols.species >= 0) fr.species.push_back(t[static_cast<std::size_t>(cols.species)]);
    }
    const bool done = stop(fr);
    out.push_back(std::move(s));
    if (done) break;
  }
  return out;
}

void put(std::ostream& os, double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  os << buf;
}

}  // namespace

std::vector<XyzFrame> read_xyz(const std::string& path) {
  auto scanned = scan(path, [](const XyzFrame&) { return false; });
  if (scanned.empty()) throw IoError(path + ": XYZ file holds no frame");
  std::vector<XyzFrame> out;
  out.reserve(scanned.size());
  for (auto& s : scanned) out.push_back(std::move(s.frame));
  return out;
}

std::vector<std::string> species_labels(const std::vector<double>& radius, const std::vector<char>& fixed) {
  std::vector<double> classes(radius);
  std::sort(classes.begin(), classes.end());
  classes.erase(std::unique(classes.begin(), classes.end()), classes.end());
  const bool numbered = classes.size() > 1 && classes.size() <= kMaxSizeClasses;
  std::vector<std::string> out(radius.size());
  for (std::size_t i = 0; i < radius.size(); ++i) {
    std::string label = !fixed.empty() && fixed[i] ? "F" : "M";
    if (numbered) label += std::to_string(std::lower_bound(classes.begin(), classes.end(), radius[i]) - classes.begin() + 1);
    out[i] = label;
  }
  return out;
}

void write_xyz_frame(std::ostream& os, const Frame& f, const Domain& domain, const std::vector<std::string>& species) {
  const std::vector<double>& pos = f.particles.at("position").values;
  const std::size_t n = pos.size() / 3;
  // Open channels: only the slots holding a particle (id >= 0); frames then differ in length.
  const auto id_field = f.particles.find("id");
  auto present = [&](std::size_t i) { return id_field == f.particles.end() || id_field->second.values[i] >= 0; };
  std::size_t shown = 0;
  for (std::size_t i = 0; i < n; ++i) shown += present(i) ? 1 : 0;
  if (!species.empty() && species.size() != n) throw IoError("XYZ export: species and position sizes differ");
  // Columns after pos, named as OVITO and ASE map them (radius -> Radius, velo -> Velocity,
  // omega -> Angular Velocity, forces -> Force); each only when the frame has it.
  struct Column {
    const char* field;
    const char* name;
    std::size_t width;
    const std::vector<double>* values = nullptr;
  };
  std::vector<Column> cols{{"radius", "radius", 1}, {"velocity", "velo", 3}, {"angular_velocity", "omega", 3},
                           {"force", "forces", 3},  {"torque", "torque", 3}};
  std::string props = "species:S:1:pos:R:3";
  for (auto& c : cols) {
    auto it = f.particles.find(c.field);
    if (it == f.particles.end()) continue;
    if (it->second.values.size() != c.width * n)
      throw IoError(std::string("XYZ export: ") + c.field + " and position sizes differ");
    c.values = &it->second.values;
    props += std::string(":") + c.name + ":R:" + std::to_string(c.width);
  }
  os << shown << '\n';
  if (domain.periodic()) {
    const Vec3& L = domain.box;
    const double m[9] = {L.x(), 0, 0, f.shear_strain * L.y(), L.y(), 0, 0, 0, L.z()};
    os << "Lattice=\"";
    for (int i = 0; i < 9; ++i) {
      if (i) os << ' ';
      put(os, m[i]);
    }
    os << "\" pbc=\"T T T\" ";
  } else {
    os << "pbc=\"F F F\" ";
  }
  os << "Properties=" << props << " Time=";
  put(os, f.time);
  os << " Step=" << f.step << '\n';
  for (std::size_t i = 0; i < n; ++i) {
    if (!present(i)) continue;
    os << (species.empty() ? std::string("M") : species[i]);
    for (int k = 0; k < 3; ++k) {
      os << ' ';
      put(os, pos[3 * i + std::size_t(k)]);
    }
    for (const auto& c : cols) {
      if (!c.values) continue;
      for (std::size_t k = 0; k < c.width; ++k) {
        os << ' ';
        put(os, (*c.values)[c.width * i + k]);
      }
    }
    os << '\n';
  }
}

namespace {

// Bytes of an XYZ file written by XyzWriter to keep when resuming at step `last`: every whole frame
// up to the first one that is after `last` or incomplete (a kill can cut the file anywhere: inside
// a line, between lines or frames). A line counts only when its newline is there. Throws when a
// complete frame is not one XyzWriter writes (no particle count, or no Step= on its comment line).
std::streamoff resumable_bytes(const std::string& path, std::int64_t last) {
  std::ifstream is(path, std::ios::binary);
  if (!is) throw IoError(path + ": cannot open the XYZ file to resume it (" + std::strerror(errno) + ")");
  std::streamoff keep = 0, pos = 0;
  std::size_t lineno = 0;
  std::string line;
  // The next complete line, or false at the end of the file or before a line without its newline.
  auto next = [&]() {
    if (!std::getline(is, line) || is.eof()) return false;
    pos += static_cast<std::streamoff>(line.size()) + 1;
    ++lineno;
    return true;
  };
  auto bad = [&](const std::string& what) {
    return IoError(path + ":" + std::to_string(lineno) + ": " + what +
                   "; cannot resume this XYZ export (not one written by stokesian run; move it away to resume: the new file then starts after the checkpoint, the trajectory holds every frame)");
  };
  while (next()) {
    if (line.empty()) {  // blank lines between frames are kept
      keep = pos;
      continue;
    }
    char* end = nullptr;
    const long long n = std::strtoll(line.c_str(), &end, 10);
    if (end == line.c_str() || *end != '\0' || n < 0) throw bad("expected the particle count, found \"" + line + "\"");
    if (!next()) break;
    const auto at = line.find(" Step=");
    if (at == std::string::npos) throw bad("the comment line has no Step=");
    if (std::strtoll(line.c_str() + at + 6, nullptr, 10) > last) break;
    bool whole = true;
    for (long long i = 0; i < n && whole; ++i) whole = next();
    if (!whole) break;
    keep = pos;
  }
  return keep;
}

}  // namespace

XyzWriter::XyzWriter(std::string path, Domain domain, std::vector<std::string> species,
                     std::optional<std::int64_t> keep_until_step)
    : path_(std::move(path)), domain_(domain), species_(std::move(species)) {
  if (keep_until_step && detail::exists(path_)) {
    // Keep the whole frames up to the checkpoint; drop later frames and a frame a kill cut short.
    const std::streamoff cut = resumable_bytes(path_, *keep_until_step);
    if (cut != static_cast<std::streamoff>(std::filesystem::file_size(path_))) {
      const std::string tmp = path_ + ".tmp";
      {
        std::ifstream in(path_, std::ios::binary);
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        std::vector<char> buf(static_cast<std::size_t>(cut));
        in.read(buf.data(), cut);
        out.write(buf.data(), cut);
        out.close();
        if (!in || !out) throw IoError(tmp + ": cannot rewrite the XYZ file for resuming");
      }
      detail::fsync_file(tmp);
      detail::durable_rename(tmp, path_);
    }
    os_.open(path_, std::ios::app);
  } else {
    os_.open(path_, std::ios::trunc);
  }
  if (!os_) throw IoError(path_ + ": cannot open XYZ file for writing (" + std::strerror(errno) + ")");
}

void XyzWriter::write(const Frame& f) {
  // Each frame goes to the file at once, whole: the file then holds every frame recorded before a
  // checkpoint when that checkpoint is written, whenever the process is killed.
  std::ostringstream frame;
  write_xyz_frame(frame, f, domain_, species_);
  const std::string text = frame.str();
  os_.write(text.data(), static_cast<std::streamsize>(text.size()));
  os_.flush();
  if (!os_) throw IoError(path_ + ": writing the XYZ frame at step " + std::to_string(f.step) + " failed");
}

void XyzWriter::flush() {
  os_.flush();
  if (!os_) throw IoError(path_ + ": flushing the XYZ file failed");
  detail::fsync_file(path_);
}

}  // namespace stokesian::io
