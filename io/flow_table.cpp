#include "io/flow_table.hpp"

#include "engine/core/errors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
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
