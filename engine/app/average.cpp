#include "engine/app/average.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/statistics.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stokesian::app {

void parse_window(const std::string& option, const std::string& text, AverageOptions& opt) {
  const auto colon = text.find(':');
  auto fail = [&](const std::string& why) {
    throw std::invalid_argument(option + " " + text + ": " + why + " (expected A:B, two numbers with A < B" +
                                (option == "--window" ? ", 0 <= A < B <= 1)" : ")"));
  };
  if (colon == std::string::npos) fail("no ':'");
  double a = 0, b = 0;
  try {
    std::size_t ia = 0, ib = 0;
    a = std::stod(text.substr(0, colon), &ia);
    b = std::stod(text.substr(colon + 1), &ib);
    if (ia != colon || ib != text.size() - colon - 1) fail("not two numbers");
  } catch (const std::logic_error&) {
    fail("not two numbers");
  }
  if (!(a < b) || !std::isfinite(a) || !std::isfinite(b)) fail("A must be below B");
  if (option == "--window" && (a < 0.0 || b > 1.0)) fail("fractions outside [0, 1]");
  opt.axis = option == "--strain" ? AverageOptions::Axis::strain
             : option == "--time" ? AverageOptions::Axis::time
                                  : AverageOptions::Axis::fraction;
  opt.from = a;
  opt.to = b;
}

int average(const std::string& trajectory, const AverageOptions& opt, std::FILE* out) {
  const io::TrajectoryInfo info = io::inspect_trajectory(trajectory);
  double rate = 0.0;
  if (opt.axis == AverageOptions::Axis::strain) {
    const Scene s = io::parse_scene(info.scene_toml, trajectory + " (stored scene)");
    if (s.flow.kind != FlowParams::Kind::simple_shear || s.flow.rate == 0.0)
      throw ConfigError(trajectory + ": --strain needs a run in simple shear (its scene has [flow] kind = \"" +
                        name_of(s.flow.kind) + "\"); use --time or --window");
    rate = std::abs(s.flow.rate);
  }
  const std::vector<io::ObservableSeries> all = io::read_observables(trajectory);
  for (const std::string& name : opt.observables)
    if (std::none_of(all.begin(), all.end(), [&](const io::ObservableSeries& o) { return o.name == name; })) {
      std::string have;
      for (const auto& o : all) have += (have.empty() ? "" : ", ") + o.name;
      throw ConfigError(trajectory + ": no observable \"" + name + "\" (it has: " + have + ")");
    }
  const char* axis = opt.axis == AverageOptions::Axis::strain ? "strain" : opt.axis == AverageOptions::Axis::time ? "time" : "fraction of the recorded time";
  std::fprintf(out, "# %s: averages over %s %g to %g; se by blocking (docs/sweeps.md)\n", trajectory.c_str(), axis,
               opt.from, opt.to);
  std::fprintf(out, "# %-38s %15s %12s %7s %7s  %s\n", "observable", "mean", "se", "samples", "blocks", "unit");
  for (const io::ObservableSeries& o : all) {
    if (!opt.observables.empty() && std::find(opt.observables.begin(), opt.observables.end(), o.name) == opt.observables.end())
      continue;
    if (o.time.empty()) continue;
    double lo = opt.from, hi = opt.to;
    if (opt.axis == AverageOptions::Axis::fraction) {
      const double t0 = o.time.front(), t1 = o.time.back();
      lo = t0 + opt.from * (t1 - t0);
      hi = t0 + opt.to * (t1 - t0);
    } else if (opt.axis == AverageOptions::Axis::strain) {
      lo = opt.from / rate;  // strain = rate * time, time from the start of the (first) run
      hi = opt.to / rate;
    }
    // Frame times are sums of steps: the window's ends are taken with a rounding margin.
    const double margin = 1e-9 * std::max(std::abs(o.time.back() - o.time.front()), std::abs(hi));
    lo -= margin;
    hi += margin;
    for (std::size_t c = 0; c < o.components; ++c) {
      std::vector<double> x;
      for (std::size_t k = 0; k < o.time.size(); ++k)
        if (o.time[k] >= lo && o.time[k] <= hi && std::isfinite(o.value[k * o.components + c]))
          x.push_back(o.value[k * o.components + c]);
      const stats::MeanError me = stats::blocked_mean(std::move(x));
      const std::string label = o.components > 1 ? o.name + "[" + std::to_string(c) + "]" : o.name;
      std::fprintf(out, "  %-38s %15.8g %12.4g %7zu %7zu  %s\n", label.c_str(), me.mean, me.se, me.n, me.blocks,
                   o.unit.empty() ? "-" : o.unit.c_str());
    }
  }
  return 0;
}

}  // namespace stokesian::app
