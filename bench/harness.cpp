#include "bench/harness.hpp"

#include "stokesian/build_info.hpp"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

namespace stokesian::bench {

Cloud random_cloud(long n, double L, unsigned long seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Cloud c;
  for (long i = 0; i < n; ++i) {
    const double x = L * u(rng), y = L * u(rng), z = L * u(rng);
    c.x.emplace_back(x, y, z);
    c.a.push_back(0.5 + u(rng));
  }
  return c;
}

Options parse_options(int argc, char** argv) {
  // Line-buffered stdout, so a long run redirected to a file shows each printed line as it comes.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") o.quick = true;
    else if (a == "--out" && i + 1 < argc) o.out = argv[++i];
    else {
      std::fprintf(stderr, "usage: %s [--quick] [--out DIR]\n", argv[0]);
      std::exit(1);
    }
  }
  return o;
}

double env_number(const char* name, double fallback, double lo, double hi, bool integer) {
  const char* e = std::getenv(name);
  if (!e) return fallback;
  char* end = nullptr;
  const double v = std::strtod(e, &end);
  if (end == e || *end != '\0' || !(v >= lo && v <= hi) || (integer && v != std::floor(v))) {
    std::fprintf(stderr, "error: %s = \"%s\": expected %s in [%g, %g]\n", name, e, integer ? "an integer" : "a number",
                 lo, hi);
    std::exit(2);
  }
  return v;
}

std::map<std::string, std::string> machine_metadata() {
  std::map<std::string, std::string> m;
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  m["host"] = host;
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      m["cpu"] = line.substr(line.find(':') + 2);
      break;
    }
  m["logical_cores"] = std::to_string(std::thread::hardware_concurrency());
  m["omp_max_threads"] = std::to_string(omp_get_max_threads());
  m["compiler"] = build::compiler;
  m["build_type"] = build::build_type;
  m["git"] = build::git;
  m["version"] = build::version;
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  m["date"] = date;
  return m;
}

void Results::add(const std::map<std::string, double>& params, const std::map<std::string, double>& phases) {
  rows_.emplace_back(params, phases);
}

namespace {
std::string quote(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}
std::string object(const std::map<std::string, double>& m) {
  std::ostringstream o;
  o.precision(9);
  o << "{";
  bool first = true;
  for (const auto& [k, v] : m) {
    o << (first ? "" : ", ") << quote(k) << ": " << v;
    first = false;
  }
  return o.str() + "}";
}
}  // namespace

std::string Results::write(const std::string& dir) const {
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/" + name_ + ".json";
  std::ofstream o(path + ".tmp");
  o << "{\n  \"benchmark\": " << quote(name_) << ",\n  \"machine\": {";
  bool first = true;
  for (const auto& [k, v] : machine_metadata()) {
    o << (first ? "" : ", ") << quote(k) << ": " << quote(v);
    first = false;
  }
  o << "},\n  \"rows\": [\n";
  for (std::size_t i = 0; i < rows_.size(); ++i)
    o << "    {\"params\": " << object(rows_[i].first) << ", \"phases\": " << object(rows_[i].second) << "}"
      << (i + 1 < rows_.size() ? "," : "") << "\n";
  o << "  ]\n}\n";
  o.close();
  std::filesystem::rename(path + ".tmp", path);
  return path;
}

}  // namespace stokesian::bench
