#pragma once
// Memory the process may use: MemAvailable of /proc/meminfo (what the kernel can hand out without
// swapping), lowered by the environment variable STOKESIAN_MEMORY_LIMIT when set (docs/cli.md).
// Used by the resource estimates (engine/resources.hpp) and by scene loading before particles are
// generated (io/scene_toml.cpp). Header only, so that every layer above core can use it.
#include "engine/core/errors.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace stokesian {

// Memory per particle of a scene before any hydrodynamics: positions, radii, the resolved TOML
// text stored in every output, state, forces and the per-stage evaluation arrays (measured about
// 0.85 KB per particle through loading, checking and one evaluation at N = 10^6; rounded up).
inline constexpr double kBytesPerParticle = 1024.0;

// Work estimated to take longer than this (placement, one evaluation) is announced on stderr with
// its estimate before it starts ("stokesian: note: ... is estimated at about X s"), and `check`
// does not measure a step estimated to take longer (docs/reliability.md).
inline constexpr double kAnnounceSeconds = 10.0;

struct MemoryBudget {
  double bytes = 0.0;   // usable bytes; 0 when unknown (no /proc/meminfo and no limit)
  std::string source;   // "MemAvailable", "STOKESIAN_MEMORY_LIMIT" or "unknown"
  bool known() const { return bytes > 0.0; }
};

// "1.5 GB" style text for a byte count (powers of 1024: KiB, MiB, GiB, TiB written as KB, MB, GB, TB).
inline std::string format_bytes(double b) {
  const char* unit[] = {"B", "KB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (b >= 1024.0 && u < 6) {
    b /= 1024.0;
    ++u;
  }
  char s[64];
  if (u == 6 && b >= 1024.0) std::snprintf(s, sizeof s, "%.3g EB", b);
  else std::snprintf(s, sizeof s, u == 0 ? "%.0f %s" : "%.3g %s", b, unit[u]);
  return s;
}

// STOKESIAN_MEMORY_LIMIT: a positive number of bytes with an optional suffix K, M, G or T (powers
// of 1024), e.g. "512M", "8G". Anything else is a ConfigError naming the variable and the value.
inline double parse_memory_limit(const char* text) {
  const std::string v = text;
  char* end = nullptr;
  errno = 0;
  double x = std::strtod(v.c_str(), &end);
  std::string suffix = end ? std::string(end) : std::string();
  double scale = 1.0;
  if (suffix.size() == 1) {
    switch (suffix[0]) {
      case 'k': case 'K': scale = 1024.0; break;
      case 'm': case 'M': scale = 1024.0 * 1024.0; break;
      case 'g': case 'G': scale = 1024.0 * 1024.0 * 1024.0; break;
      case 't': case 'T': scale = 1024.0 * 1024.0 * 1024.0 * 1024.0; break;
      default: scale = 0.0;
    }
  } else if (!suffix.empty()) {
    scale = 0.0;
  }
  x *= scale;
  if (v.empty() || end == v.c_str() || errno == ERANGE || scale == 0.0 || !std::isfinite(x) || !(x >= 1.0))
    throw ConfigError("environment variable STOKESIAN_MEMORY_LIMIT = \"" + v +
                      "\": not a memory size (allowed: a positive number of bytes, optionally followed by K, M, G "
                      "or T, e.g. 8G)");
  return x;
}

// MemAvailable from /proc/meminfo (bytes), 0 when it cannot be read.
inline double mem_available() {
  std::FILE* f = std::fopen("/proc/meminfo", "r");
  if (!f) return 0.0;
  char line[256];
  double kb = 0.0;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, "MemAvailable:", 13) == 0) {
      kb = std::strtod(line + 13, nullptr);
      break;
    }
  std::fclose(f);
  return kb * 1024.0;
}

// What this process may use now: the smaller of MemAvailable and STOKESIAN_MEMORY_LIMIT.
inline MemoryBudget memory_budget() {
  MemoryBudget b;
  b.bytes = mem_available();
  b.source = b.bytes > 0 ? "MemAvailable in /proc/meminfo" : "unknown";
  if (const char* lim = std::getenv("STOKESIAN_MEMORY_LIMIT"); lim && *lim) {
    const double x = parse_memory_limit(lim);
    if (!(b.bytes > 0) || x < b.bytes) {
      b.bytes = x;
      b.source = "STOKESIAN_MEMORY_LIMIT";
    }
  }
  return b;
}

}  // namespace stokesian
