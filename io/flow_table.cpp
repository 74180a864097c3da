#include "io/flow_table.hpp"

#include "engine/core/errors.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

namespace stokesian::io {

namespace {

[[noreturn]] void fail(const std::string& path, long line, const std::string& what) {
  throw ConfigError(path + (line > 0 ? ":" + std::to_string(line) : "") + ": " + what);
}

// Distinct values of v (sorted), merging values closer than 1e-9 of the axis' extent.
std::vector<double> distinct(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const double tol = 1e-9 * std::max(1.0, v.back() - v.front());
  std::vector<double> out;
  for (double x : v)
    if (out.empty() || x - out.back() > tol) out.push_back(x);
  return out;
}

std::size_t position_of(const std::vector<double>& ax, double v) {
  const auto it = std::lower_bound(ax.begin(), ax.end(), v - 1e-9 * std::max(1.0, ax.back() - ax.front()));
  return std::size_t(it - ax.begin());
}

// Legacy VTK (header of flow_table.hpp): a cursor over the file's bytes that reads
// whitespace-separated tokens (ASCII) or big-endian binary values.
class VtkReader {
 public:
  VtkReader(const std::string& path, const std::string& text) : path_(path), t_(text) {}
  long line() const { return long(std::count(t_.begin(), t_.begin() + long(p_), '\n')) + 1; }
  [[noreturn]] void fail(const std::string& what) const { io::fail(path_, line(), what); }
  bool eof() const { return p_ >= t_.size(); }
  bool at_end() {
    skip_space();
    return p_ >= t_.size();
  }
  std::string token() {
    skip_space();
    if (p_ >= t_.size()) fail("the file ends early (legacy VTK)");
    const std::size_t b = p_;
    while (p_ < t_.size() && !std::isspace(static_cast<unsigned char>(t_[p_]))) ++p_;
    return t_.substr(b, p_ - b);
  }
  std::string rest_of_line() {
    const std::size_t b = p_, e = t_.find('\n', p_);
    p_ = e == std::string::npos ? t_.size() : e + 1;
    return t_.substr(b, (e == std::string::npos ? t_.size() : e) - b);
  }
  long integer(const char* what) {
    const std::string s = token();
    char* end = nullptr;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (end == s.c_str() || *end != '\0' || v < 0) fail(std::string(what) + ": \"" + s + "\" is not a count");
    return v;
  }
  double number(const char* what) {
    const std::string s = token();
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (end == s.c_str() || *end != '\0') fail(std::string(what) + ": \"" + s + "\" is not a number");
    return v;
  }
  // n values of VTK type `type` (ASCII tokens, or big-endian bytes after the header's line end).
  std::vector<double> values(std::size_t n, const std::string& type, bool binary, const std::string& what) {
    std::vector<double> v(n);
    if (!binary) {
      for (double& x : v) x = number(what.c_str());
      return v;
    }
    rest_of_line();  // the binary block starts after the line naming it
    const std::size_t size = type == "double" ? 8 : type == "float" ? 4 : type == "int" || type == "unsigned_int" ? 4
                           : type == "short" || type == "unsigned_short" ? 2 : type == "char" || type == "unsigned_char" ? 1 : 0;
    if (size == 0) fail(what + ": binary data of type \"" + type + "\" is not read (float, double, int, short, char)");
    if (p_ + n * size > t_.size()) fail(what + ": the file ends inside its binary data");
    for (std::size_t k = 0; k < n; ++k) {
      std::uint64_t bits = 0;
      for (std::size_t b = 0; b < size; ++b) bits = bits << 8 | static_cast<unsigned char>(t_[p_ + k * size + b]);
      if (type == "double") {
        double d;
        std::memcpy(&d, &bits, 8);
        v[k] = d;
      } else if (type == "float") {
        const std::uint32_t b32 = std::uint32_t(bits);
        float f;
        std::memcpy(&f, &b32, 4);
        v[k] = f;
      } else if (type == "int") {
        v[k] = double(std::int32_t(std::uint32_t(bits)));
      } else if (type == "short") {
        v[k] = double(std::int16_t(std::uint16_t(bits)));
      } else if (type == "char") {
        v[k] = double(std::int8_t(std::uint8_t(bits)));
      } else {
        v[k] = double(bits);
      }
    }
    p_ += n * size;
    return v;
  }

 private:
  void skip_space() {
    while (p_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[p_]))) ++p_;
  }
  const std::string& path_;
  const std::string& t_;
  std::size_t p_ = 0;
};

FlowGrid read_vtk(const std::string& path, const std::string& text, FlowGrid g) {
  VtkReader r(path, text);
  r.rest_of_line();  // "# vtk DataFile Version x.y"
  r.rest_of_line();  // title
  const std::string format = r.token();
  if (format != "ASCII" && format != "BINARY") r.fail("format \"" + format + "\" (allowed: ASCII, BINARY)");
  const bool binary = format == "BINARY";
  if (r.token() != "DATASET") r.fail("expected DATASET");
  const std::string dataset = r.token();
  if (dataset != "STRUCTURED_POINTS" && dataset != "RECTILINEAR_GRID")
    r.fail("DATASET " + dataset + " is not read (allowed: STRUCTURED_POINTS, RECTILINEAR_GRID; ParaView's "
           "Resample To Image turns any mesh into STRUCTURED_POINTS)");
  long dim[3] = {0, 0, 0};
  double origin[3] = {0, 0, 0}, spacing[3] = {1, 1, 1};
  std::array<std::vector<double>, 3> coords;
  std::size_t points = 0;
  // Geometry keywords until POINT_DATA.
  for (;;) {
    const std::string k = r.token();
    if (k == "DIMENSIONS") {
      for (long& d : dim) d = r.integer("DIMENSIONS");
    } else if (k == "ORIGIN") {
      for (double& o : origin) o = r.number("ORIGIN");
    } else if (k == "SPACING" || k == "ASPECT_RATIO") {
      for (double& h : spacing) h = r.number("SPACING");
    } else if (k == "X_COORDINATES" || k == "Y_COORDINATES" || k == "Z_COORDINATES") {
      const int c = k[0] - 'X';
      const long n = r.integer(k.c_str());
      const std::string type = r.token();
      coords[std::size_t(c)] = r.values(std::size_t(n), type, binary, k);
    } else if (k == "POINT_DATA") {
      points = std::size_t(r.integer("POINT_DATA"));
      break;
    } else if (k == "CELL_DATA") {
      r.fail("CELL_DATA: the velocity must be given at the points (POINT_DATA)");
    } else if (k == "FIELD") {
      r.fail("FIELD data before POINT_DATA is not read");
    } else {
      r.fail("unexpected keyword \"" + k + "\" in the geometry of a " + dataset);
    }
  }
  for (int c = 0; c < 3; ++c) {
    if (dim[c] < 1) r.fail("DIMENSIONS must be three counts of at least 1");
    std::vector<double>& ax = g.axis[std::size_t(c)];
    if (dataset == "STRUCTURED_POINTS") {
      if (!(spacing[c] > 0)) r.fail("SPACING must be positive");
      ax.resize(std::size_t(dim[c]));
      for (long i = 0; i < dim[c]; ++i) ax[std::size_t(i)] = origin[c] + double(i) * spacing[c];
    } else {
      ax = coords[std::size_t(c)];
      if (long(ax.size()) != dim[c]) r.fail(std::string(1, char('X' + c)) + "_COORDINATES: " + std::to_string(ax.size()) +
                                            " values for DIMENSIONS " + std::to_string(dim[c]));
      for (std::size_t i = 1; i < ax.size(); ++i)
        if (!(ax[i] > ax[i - 1])) r.fail(std::string(1, char('X' + c)) + "_COORDINATES must increase");
    }
  }
  const std::size_t n = std::size_t(dim[0]) * std::size_t(dim[1]) * std::size_t(dim[2]);
  if (points != n) r.fail("POINT_DATA " + std::to_string(points) + " for " + std::to_string(n) + " grid points");
  // Point arrays: 3-component ones are velocity candidates; vtkValidPointMask (ParaView's resampling:
  // 0 where the point fell outside the solver's mesh) marks points without data.
  std::vector<std::pair<std::string, std::vector<double>>> vectors;
  std::vector<double> mask;
  while (!r.at_end()) {
    const std::string k = r.token();
    if (k == "VECTORS" || k == "NORMALS") {
      const std::string name = r.token(), type = r.token();
      vectors.emplace_back(name, r.values(3 * n, type, binary, k + " " + name));
    } else if (k == "SCALARS") {
      const std::string name = r.token(), type = r.token();
      std::string next = r.token();
      long comp = 1;
      if (next != "LOOKUP_TABLE") {
        comp = std::strtol(next.c_str(), nullptr, 10);
        if (comp < 1 || comp > 4) r.fail("SCALARS " + name + ": " + next + " components (allowed: 1 to 4)");
        next = r.token();
      }
      if (next != "LOOKUP_TABLE") r.fail("SCALARS " + name + ": expected LOOKUP_TABLE");
      r.token();  // the table's name
      std::vector<double> v = r.values(std::size_t(comp) * n, type, binary, "SCALARS " + name);
      if (name == "vtkValidPointMask" && comp == 1) mask = std::move(v);
    } else if (k == "FIELD") {
      r.token();  // the field's name
      const long arrays = r.integer("FIELD");
      for (long a = 0; a < arrays; ++a) {
        const std::string name = r.token();
        const long comp = r.integer("FIELD array components"), tuples = r.integer("FIELD array tuples");
        const std::string type = r.token();
        std::vector<double> v = r.values(std::size_t(comp) * std::size_t(tuples), type, binary, "FIELD array " + name);
        if (std::size_t(tuples) != n) continue;  // not a point array
        if (comp == 3) vectors.emplace_back(name, std::move(v));
        if (comp == 1 && name == "vtkValidPointMask") mask = std::move(v);
      }
    } else if (k == "CELL_DATA") {
      break;  // cell arrays follow: not needed
    } else if (k == "METADATA") {
      // ParaView's METADATA block (INFORMATION entries) ends at an empty line; skip to it.
      r.rest_of_line();
      while (!r.eof() && r.rest_of_line().find_first_not_of(" \t\r") != std::string::npos) {
      }
    } else {
      r.fail("unexpected keyword \"" + k + "\" in POINT_DATA (read: VECTORS, SCALARS, FIELD)");
    }
  }
  // The velocity: the only 3-component array, or the one named U, u, velocity or Velocity.
  const std::pair<std::string, std::vector<double>>* vel = vectors.size() == 1 ? &vectors[0] : nullptr;
  for (const auto& v : vectors)
    if (!vel && (v.first == "U" || v.first == "u" || v.first == "velocity" || v.first == "Velocity")) vel = &v;
  if (!vel) {
    std::string names;
    for (const auto& v : vectors) names += (names.empty() ? "" : ", ") + v.first;
    io::fail(path, 0, vectors.empty() ? "no 3-component point array (the velocity) in the VTK file"
                                      : "which 3-component point array is the velocity? (" + names +
                                            "; name it U or velocity)");
  }
  g.u.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    g.u[k] = Vec3(vel->second[3 * k], vel->second[3 * k + 1], vel->second[3 * k + 2]);
    if (!mask.empty() && mask[k] == 0.0) g.u[k] = Vec3::Constant(std::nan(""));
  }
  return g;
}

}  // namespace

FlowGrid read_flow_table(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, 0, "cannot open the flow table");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  FlowGrid g;
  g.path = path;
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a 64
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  g.hash = h;
  if (text.rfind("# vtk DataFile", 0) == 0) return read_vtk(path, text, std::move(g));

  std::vector<std::array<double, 6>> rows;
  std::vector<long> row_line;
  int columns = 0;
  std::istringstream lines(text);
  std::string line;
  long no = 0;
  while (std::getline(lines, line)) {
    ++no;
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t' || c == '\r') c = ' ';
    const std::size_t first = line.find_first_not_of(' ');
    if (first == std::string::npos || line[first] == '#' || line[first] == '%') continue;
    std::istringstream f(line);
    std::vector<double> vals;
    std::string tok;
    bool numeric = true;
    while (f >> tok) {
      char* end = nullptr;
      const double v = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0') {
        numeric = false;
        break;
      }
      vals.push_back(v);
    }
    if (!numeric) {
      if (rows.empty() && columns == 0) continue;  // a header of column names
      fail(path, no, "not a row of numbers: \"" + line.substr(0, 80) + "\"");
    }
    if (columns == 0) {
      if (vals.size() != 6 && vals.size() != 4)
        fail(path, no, std::to_string(vals.size()) + " columns (allowed: x y z u v w, or x y u v for a 2D field)");
      columns = int(vals.size());
    } else if (int(vals.size()) != columns) {
      fail(path, no, std::to_string(vals.size()) + " columns, the first row had " + std::to_string(columns));
    }
    std::array<double, 6> r{};
    if (columns == 6) {
      for (int c = 0; c < 6; ++c) r[std::size_t(c)] = vals[std::size_t(c)];
    } else {
      r = {vals[0], vals[1], 0.0, vals[2], vals[3], 0.0};
    }
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(r[std::size_t(c)])) fail(path, no, "a non-finite coordinate");
    rows.push_back(r);
    row_line.push_back(no);
  }
  if (rows.empty()) fail(path, 0, "no grid nodes in the flow table");
  for (int c = 0; c < 3; ++c) {
    std::vector<double> v(rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) v[k] = rows[k][std::size_t(c)];
    g.axis[std::size_t(c)] = distinct(v);
  }
  const std::size_t nx = g.axis[0].size(), ny = g.axis[1].size(), nz = g.axis[2].size();
  if (nx * ny * nz != rows.size()) {
    std::ostringstream o;
    o << rows.size() << " nodes do not form a complete rectilinear grid (" << nx << " x " << ny << " x " << nz
      << " distinct x, y, z values = " << nx * ny * nz << " nodes)";
    fail(path, 0, o.str());
  }
  g.u.assign(rows.size(), Vec3::Constant(std::nan("")));
  std::vector<char> seen(rows.size(), 0);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const std::size_t id = g.index(position_of(g.axis[0], rows[k][0]), position_of(g.axis[1], rows[k][1]),
                                   position_of(g.axis[2], rows[k][2]));
    if (seen[id]) fail(path, row_line[k], "a grid node given twice");
    seen[id] = 1;
    g.u[id] = Vec3(rows[k][3], rows[k][4], rows[k][5]);
  }
  return g;
}

}  // namespace stokesian::io
