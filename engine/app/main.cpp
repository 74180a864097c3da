// stokesian command-line interface.
//   stokesian run SCENE.toml [--out FILE.h5] [--threads N] [--resume] [--quiet]
//   stokesian solve SCENE.toml --out FILE.h5 [--threads N]
//   stokesian check SCENE.toml
// Exit status: 0 success, 1 usage, 2 scene/config error, 3 physics error, 4 file error.
#include "engine/app/run.hpp"
#include "engine/core/errors.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"
#include "stokesian/build_info.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

using namespace stokesian;

namespace {

const char* kUsage =
    "usage:\n"
    "  stokesian run SCENE.toml [--out FILE.h5] [--threads N] [--resume] [--quiet]\n"
    "  stokesian solve SCENE.toml --out FILE.h5 [--threads N]\n"
    "  stokesian check SCENE.toml\n"
    "  stokesian --version\n";

int usage(const std::string& msg) {
  std::fprintf(stderr, "stokesian: %s\n%s", msg.c_str(), kUsage);
  return 1;
}

void print_check(const Simulation& sim) {
  const Scene& s = sim.scene();
  const std::size_t n = s.positions.size();
  const auto [amin, amax] = std::minmax_element(s.radii.begin(), s.radii.end());
  double vol = 0;
  for (double a : s.radii) vol += 4.0 / 3.0 * kPi * a * a * a;
  std::printf("scene: %s\n", s.source.c_str());
  std::printf("particles: %zu (radii %.4g to %.4g a", n, *amin, *amax);
  const long nfixed = std::count(s.fixed.begin(), s.fixed.end(), 1);
  if (nfixed) std::printf(", %ld fixed", nfixed);
  std::printf(")\n");
  if (s.domain.periodic())
    std::printf("domain: periodic box %.4g x %.4g x %.4g a, volume fraction %.4g\n", s.domain.box.x(), s.domain.box.y(),
                s.domain.box.z(), vol / s.domain.box.prod());
  else
    std::printf("domain: open\n");
  std::printf("time: %lld steps of dt = %.4g\n", static_cast<long long>(s.time.steps), s.time.dt);
  std::printf("%s\n", sim.model().describe().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) return usage("no command");
  if (args[0] == "--version") {
    std::printf("stokesian %s (%s, %s, %s)\n", build::version, build::git, build::compiler, build::build_type);
    return 0;
  }
  const std::string cmd = args[0];
  if (cmd != "run" && cmd != "solve" && cmd != "check") return usage("unknown command \"" + cmd + "\"");
  std::string scene_path, out;
  int threads = 0;
  bool resume = false, quiet = false;
  for (std::size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](const char* name) -> std::string {
      if (i + 1 >= args.size()) throw std::invalid_argument(std::string(name) + " needs a value");
      return args[++i];
    };
    try {
      if (a == "--out") out = value("--out");
      else if (a == "--threads") {
        const std::string v = value("--threads");
        threads = std::stoi(v);
        if (threads < 1) throw std::invalid_argument("--threads must be >= 1, got " + v);
      } else if (a == "--resume" && cmd == "run") resume = true;
      else if (a == "--quiet") quiet = true;
      else if (!a.empty() && a[0] == '-') return usage("unknown option \"" + a + "\" for " + cmd);
      else if (scene_path.empty()) scene_path = a;
      else return usage("more than one scene file given");
    } catch (const std::exception& e) {
      return usage(e.what());
    }
  }
  if (scene_path.empty()) return usage("no scene file given");
  if (cmd == "solve" && out.empty()) return usage("solve needs --out FILE.h5");
  if (out.empty()) out = std::filesystem::path(scene_path).stem().string() + ".h5";
  if (threads > 0) omp_set_num_threads(threads);

  try {
    Simulation sim(io::load_scene(scene_path));
    if (cmd == "check") {
      print_check(sim);
      return 0;
    }
    if (!quiet) std::fprintf(stderr, "%s\n", sim.model().describe().c_str());
    if (cmd == "solve") {
      app::solve(sim, out);
      if (!quiet) std::fprintf(stderr, "wrote %s\n", out.c_str());
      return 0;
    }
    app::RunOptions opt;
    opt.out = out;
    opt.resume = resume;
    opt.quiet = quiet;
    const long steps = app::run(sim, opt);
    if (!quiet) std::fprintf(stderr, "%ld steps, wrote %s\n", steps, out.c_str());
    return 0;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "stokesian: error: %s\n", e.what());
    return 2;
  } catch (const PhysicsError& e) {
    std::fprintf(stderr, "stokesian: physics error: %s\n", e.what());
    return 3;
  } catch (const IoError& e) {
    std::fprintf(stderr, "stokesian: file error: %s\n", e.what());
    return 4;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stokesian: error: %s\n", e.what());
    return 4;
  }
}
