#include "engine/app/cli.hpp"

#include "engine/app/check.hpp"
#include "engine/app/run.hpp"
#include "engine/app/average.hpp"
#include "engine/app/clusters.hpp"
#include "engine/app/sweep.hpp"
#include "engine/core/errors.hpp"
#include "engine/progress.hpp"
#include "engine/resources.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"
#include "stokesian/build_info.hpp"

#include <CLI/CLI.hpp>
#include <omp.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>
#include <optional>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace stokesian::app {

namespace {

constexpr int kMaxThreads = 1024;

// Validators that name the value and the allowed range (CLI11 prefixes the option name).
CLI::Validator integer_in(long lo, long hi) {
  const std::string range = std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [=](std::string& v) -> std::string {
        long x = 0;
        const char* b = v.data();
        const char* e = b + v.size();
        const auto r = std::from_chars(b, e, x);
        if (r.ec != std::errc() || r.ptr != e)
          return "\"" + v + "\" is not an integer; allowed: an integer from " + range;
        if (x < lo || x > hi) return "\"" + v + "\" is out of range; allowed: an integer from " + range;
        return {};
      },
      "");
}

CLI::Validator nonnegative_number() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        char* end = nullptr;
        errno = 0;
        const double x = std::strtod(v.c_str(), &end);
        if (v.empty() || end != v.c_str() + v.size() || errno == ERANGE || !(x >= 0) || !std::isfinite(x))
          return "\"" + v + "\" is not a number >= 0; allowed: a finite number of seconds >= 0";
        return {};
      },
      "");
}

std::string exe_dir() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : p.parent_path().string();
}

// Default trajectory path of a scene: its stem + ".h5" in the working directory.
std::string default_out(const std::string& scene) { return fs::path(scene).stem().string() + ".h5"; }

void report(const char* kind, const std::exception& e) { std::fprintf(stderr, "stokesian: %s: %s\n", kind, e.what()); }

// What a scene command was doing, and its resource estimate once made: named when memory runs out.
struct Activity {
  std::string doing = "loading the scene";
  std::optional<ResourceEstimate> estimate;
};

// Out of memory despite the estimate (or before it could be made): exit status 5, naming what was
// being done and the estimate (docs/cli.md).
int out_of_memory(const Activity& a) {
  const MemoryBudget budget = memory_budget();
  std::string est = "no estimate was made yet";
  if (a.estimate && !a.estimate->components.empty()) {
    const ResourceComponent& big = a.estimate->largest();
    est = "the estimated peak was " + format_bytes(a.estimate->peak_bytes) + " (largest part: " + big.name + ", " +
          format_bytes(big.bytes) + ")";
  }
  std::fprintf(stderr,
               "stokesian: out of memory while %s: %s; available now: %s (%s). The estimate missed what this scene "
               "needs: please report it with the scene (docs/reliability.md); lower the particle count or the "
               "accuracy, or run on a machine with more memory\n",
               a.doing.c_str(), est.c_str(), budget.known() ? format_bytes(budget.bytes).c_str() : "unknown",
               budget.source.c_str());
  return 5;
}

// Runs the scene commands, mapping errors to exit statuses.
template <class F>
int guarded(const Activity& activity, F&& f) {
  try {
    return f();
  } catch (const std::bad_alloc&) {
    return out_of_memory(activity);
  } catch (const ConfigError& e) {
    report("error", e);
    return 2;
  } catch (const PhysicsError& e) {
    report("physics error", e);
    return 3;
  } catch (const IoError& e) {
    report("file error", e);
    return 4;
  } catch (const std::exception& e) {
    report("error", e);
    return 4;
  }
}

// What `plot` charts: a trajectory, or a sweep's summary table (its folder or summary.csv).
struct PlotRequest {
  std::string input, png, python;
  long frame = -1;
  std::string projection = "xy";
  std::string x, y, series;  // sweep tables
};

int plot(const PlotRequest& req) {
  const std::string& traj = req.input;
  if (!fs::exists(traj)) {
    std::fprintf(stderr, "stokesian: file error: %s: no such file\n", traj.c_str());
    return 4;
  }
  const bool table = fs::is_directory(traj) || fs::path(traj).extension() == ".csv";
  if (table && req.y.empty()) {
    std::fprintf(stderr, "stokesian: plot %s: a sweep's table needs --y OBSERVABLE (docs/sweeps.md)\n", traj.c_str());
    return 1;
  }
  if (!table && !(req.x.empty() && req.y.empty() && req.series.empty())) {
    std::fprintf(stderr, "stokesian: plot %s: --x, --y and --series chart a sweep's table (a folder or summary.csv)\n",
                 traj.c_str());
    return 1;
  }
  const std::string name = table ? "stokesian_sweep_plot.py" : "stokesian_plot.py";
  std::vector<std::string> searched;
  const std::string script = find_plot_script(&searched, name);
  if (script.empty()) {
    std::string where;
    for (const auto& s : searched) where += "\n  " + s;
    std::fprintf(stderr, "stokesian: file error: the plot script %s was not found; looked in:%s\n", name.c_str(),
                 where.c_str());
    return 4;
  }
  std::string png = req.png;
  if (png.empty())
    png = table ? ((fs::is_directory(traj) ? fs::path(traj) : fs::path(traj).parent_path()) / (req.y + ".png")).string()
                : fs::path(traj).replace_extension(".png").string();
  // Interpreter: --python, else /usr/bin/python3, else python3 on PATH.
  std::string python = req.python;
  if (python.empty()) python = access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> args{python, script, traj, "--out", png};
  if (table) {
    for (const auto& [opt, v] : {std::pair{"--x", req.x}, {"--y", req.y}, {"--series", req.series}})
      if (!v.empty()) {
        args.push_back(opt);
        args.push_back(v);
      }
  } else {
    args.insert(args.end(), {"--frame", std::to_string(req.frame), "--projection", req.projection});
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) {
    std::fprintf(stderr, "stokesian: error: fork: %s\n", std::strerror(errno));
    return 4;
  }
  if (pid == 0) {
    execvp(argv[0], argv.data());
    std::fprintf(stderr, "stokesian: error: cannot run %s: %s\n", argv[0], std::strerror(errno));
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      std::fprintf(stderr, "stokesian: error: waitpid: %s\n", std::strerror(errno));
      return 4;
    }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    std::fprintf(stderr, "wrote %s\n", png.c_str());
    return 0;
  }
  // The script exits 1 for a bad request (e.g. a frame the file does not have), having said why.
  if (WIFEXITED(status) && WEXITSTATUS(status) == 1) return 1;
  std::fprintf(stderr, "stokesian: file error: plotting failed (%s %s exited with status %d)\n", python.c_str(),
               script.c_str(), WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  return 4;
}

}  // namespace

std::string find_plot_script(std::vector<std::string>* searched, const std::string& name) {
  std::vector<std::string> places;
  const std::string dir = exe_dir();
  if (!dir.empty()) places.push_back((fs::path(dir) / ".." / "share" / "stokesian" / name).lexically_normal().string());
  places.push_back((fs::path(STOKESIAN_PLOT_INSTALLED).parent_path() / name).string());
  places.push_back((fs::path(STOKESIAN_PLOT_SOURCE).parent_path() / name).string());
  if (searched) *searched = places;
  for (const auto& p : places)
    if (fs::is_regular_file(p)) return p;
  return {};
}

int main_cli(int argc, char** argv) {
  CLI::App app{"Stokesian dynamics of colloidal suspensions (docs/cli.md).", "stokesian"};
  app.option_defaults()->always_capture_default();
  const std::string version = std::string("stokesian ") + build::version + " (" + build::git + ", " + build::compiler +
                              ", " + build::build_type + ")";
  app.set_version_flag("--version", version, "Print the version and build, then exit");
  app.require_subcommand(1);  // one of run, solve, check, plot, sweep, average, clusters
  app.footer(
      "Exit status: 0 success, 1 usage, 2 scene/config error (also: more memory than available), 3 physics error,\n"
      "4 file error, 5 out of memory although the estimate fitted, 6 a sweep ended with failed or unfinished runs.\n"
      "Run `stokesian COMMAND --help` for the options of a command.");

  std::string scene, out, python, projection = "xy";
  int threads = 0;
  double progress_interval = -1;
  bool resume = false, quiet = false, no_estimate = false;
  std::string threads_text;

  auto add_scene = [&](CLI::App* c) {
    c->add_option("scene", scene, "Scene file (TOML; docs/scene.md)")->required()->type_name("SCENE.toml");
  };
  auto add_threads = [&](CLI::App* c) {
    c->add_option("--threads", threads_text,
                  "OpenMP threads, an integer from 1 to " + std::to_string(kMaxThreads) +
                      "; default: OMP_NUM_THREADS, else all cores")
        ->check(integer_in(1, kMaxThreads))
        ->type_name("INT")
        ->default_str("OpenMP default");
  };

  CLI::App* run = app.add_subcommand("run", "Run a scene: write its trajectory and checkpoints");
  add_scene(run);
  run->add_option("--out", out, "Trajectory file (H5MD); default: the scene's name with .h5, in the working directory")
      ->type_name("FILE.h5")
      ->default_str("SCENE.h5");
  add_threads(run);
  run->add_flag("--resume", resume, "Continue an interrupted or stopped run from FILE.h5.ckpt (after a physics stop, [time] dt and [run] keys may change; docs/reliability.md)");
  run->add_flag("--quiet", quiet, "No model description and no progress on stderr");
  run->add_option("--progress-interval", progress_interval,
                  "Seconds between progress lines (a number >= 0); default 0.5 on a terminal, 10 otherwise")
      ->check(nonnegative_number())
      ->type_name("SECONDS")
      ->default_str("0.5|10");

  CLI::App* solve = app.add_subcommand("solve", "One hydrodynamic solve of the initial state, written as one frame");
  add_scene(solve);
  solve->add_option("--out", out, "Output file (H5MD)")->required()->type_name("FILE.h5");
  add_threads(solve);
  solve->add_flag("--quiet", quiet, "No model description on stderr");

  CLI::App* check = app.add_subcommand(
      "check", "Validate a scene and report the resolved model, forces, outputs, initial overlaps, cost and step-size limits");
  add_scene(check);
  check->add_option("--out", out, "Trajectory path the run would write (reported); default as for run")
      ->type_name("FILE.h5")
      ->default_str("SCENE.h5");
  add_threads(check);
  check->add_flag("--no-estimate", no_estimate, "Do not evaluate the initial state (no cost estimate, no displacement check)");

  CLI::App* plot_cmd = app.add_subcommand(
      "plot", "Chart a trajectory (observables, particle statistics, a snapshot) or a sweep's table (PNG)");
  std::string traj;
  PlotRequest plot_req;
  plot_cmd->add_option("trajectory", traj, "Trajectory written by run or solve, or a sweep's folder or summary.csv")
      ->required()
      ->type_name("FILE.h5|DIR");
  plot_cmd->add_option("--y", plot_req.y, "Sweep table: the observable (or numeric column) on the vertical axis")
      ->type_name("NAME");
  plot_cmd->add_option("--x", plot_req.x, "Sweep table: the swept key on the horizontal axis; default the first")
      ->type_name("KEY");
  plot_cmd->add_option("--series", plot_req.series, "Sweep table: the swept key giving one line per value")
      ->type_name("KEY");
  plot_cmd->add_option("--out", out, "Image file; default: the trajectory's name with .png")
      ->type_name("FILE.png")
      ->default_str("FILE.png");
  std::string frame_text = "-1";
  plot_cmd->add_option("--frame", frame_text, "Frame of the snapshot, an integer; negative counts from the end")
      ->check(integer_in(-2147483647L, 2147483647L))
      ->type_name("INT");
  plot_cmd->add_option("--projection", projection, "Plane of the snapshot")
      ->check(CLI::IsMember({"xy", "xz", "yz"}))
      ->type_name("PLANE");
  plot_cmd->add_option("--python", python,
                       "Python 3 with numpy, matplotlib, h5py; default /usr/bin/python3, else python3 on PATH")
      ->type_name("PATH")
      ->default_str("/usr/bin/python3");

  CLI::App* sweep_cmd = app.add_subcommand(
      "sweep", "Run a sweep file: one run per expanded scene, J at a time, resumable; summary table (docs/sweeps.md)");
  std::string sweep_file, jobs_text = "1", sweep_threads_text = "1", run_text;
  SweepOptions sweep_opt;
  sweep_cmd->add_option("sweep", sweep_file, "Sweep file (TOML; docs/sweeps.md)")->required()->type_name("SWEEP.toml");
  sweep_cmd->add_option("--out", sweep_opt.out, "Folder of the sweep's runs and summary")->required()->type_name("DIR");
  sweep_cmd->add_option("--jobs", jobs_text, "Runs at a time, an integer from 1 to 1024")
      ->check(integer_in(1, 1024))
      ->type_name("INT");
  sweep_cmd->add_option("--threads", sweep_threads_text, "OpenMP threads per run, an integer from 1 to 1024")
      ->check(integer_in(1, kMaxThreads))
      ->type_name("INT");
  sweep_cmd->add_option("--run", run_text, "Run only this run (its index, from 0), no summary (what each Slurm array task calls)")
      ->check(integer_in(0, 99999))
      ->type_name("INT");
  sweep_cmd->add_flag("--slurm", sweep_opt.slurm, "Write DIR/sweep.sbatch (a Slurm job array, one task per run) instead of running");
  sweep_cmd->add_flag("--summary", sweep_opt.summary_only, "Only (re)write DIR/summary.csv and summary.h5 from the runs' files");
  sweep_cmd->add_flag("--retry-failed", sweep_opt.retry_failed, "Run failed runs again (resuming from their checkpoints)");
  sweep_cmd->add_flag("--quiet", sweep_opt.quiet, "No progress lines");

  CLI::App* average_cmd = app.add_subcommand(
      "average", "Time averages of a trajectory's observables over a strain, time or fraction window, with blocked errors");
  std::string average_file, strain_text, time_text, window_text, observables_text;
  average_cmd->add_option("trajectory", average_file, "Trajectory written by run")->required()->type_name("FILE.h5");
  average_cmd->add_option("--strain", strain_text, "Window in accumulated shear strain rate*t (simple shear runs)")
      ->type_name("A:B");
  average_cmd->add_option("--time", time_text, "Window in time")->type_name("A:B");
  average_cmd->add_option("--window", window_text, "Window as fractions of the recorded time span")
      ->type_name("A:B")
      ->default_str("0.5:1");
  average_cmd->add_option("--observables", observables_text, "Comma-separated observable names; default all")
      ->type_name("NAMES");

  CLI::App* clusters_cmd = app.add_subcommand(
      "clusters", "Cluster analysis of a trajectory: clusters by surface gap, sizes, shapes, fractal dimension (docs/clusters.md)");
  std::string clusters_file;
  ClusterOptions cluster_opt;
  clusters_cmd->add_option("trajectory", clusters_file, "Trajectory written by run")->required()->type_name("FILE.h5");
  clusters_cmd->add_option("--gap", cluster_opt.bond_gap, "Bond criterion: surface gap <= GAP [a]")
      ->type_name("GAP")
      ->default_str("0.1");
  clusters_cmd->add_option("--min-size", cluster_opt.min_size, "Smallest cluster size in the fractal-dimension fit")
      ->type_name("N")
      ->default_str("4");
  clusters_cmd->add_option("--every", cluster_opt.every, "Analyse every N-th frame")->type_name("N")->default_str("1");
  clusters_cmd->add_option("--out", cluster_opt.out, "HDF5 output (default: TRAJECTORY.clusters.h5 beside it)")
      ->type_name("FILE.h5");

  // A first word that is neither an option nor a command: name it (CLI11 would only say that a
  // command is required).
  const auto is_command = [&](const char* w) {
    for (const CLI::App* c : app.get_subcommands({}))
      if (c->get_name() == w) return true;
    return false;
  };
  if (argc > 1 && argv[1][0] != '-' && !is_command(argv[1])) {
    std::fprintf(stderr, "stokesian: unknown command \"%s\"; commands: run, solve, check, plot, sweep, average, clusters\n%s", argv[1],
                 "Run `stokesian --help` for usage.\n");
    return 1;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const std::string name = e.get_name();
    if (name == "CallForHelp" || name == "CallForAllHelp" || name == "CallForVersion") return app.exit(e);
    std::fprintf(stderr, "stokesian: %s\nRun `stokesian --help` or `stokesian COMMAND --help` for usage.\n", e.what());
    return 1;
  }
  if (!threads_text.empty()) threads = std::stoi(threads_text);  // validated above
  if (threads > 0) omp_set_num_threads(threads);

  if (plot_cmd->parsed()) {
    plot_req.input = traj;
    plot_req.png = out;
    plot_req.python = python;
    plot_req.frame = std::stol(frame_text);
    plot_req.projection = projection;
    return plot(plot_req);
  }
  if (average_cmd->parsed()) {
    AverageOptions opt;
    const int windows = !strain_text.empty() + !time_text.empty() + !window_text.empty();
    try {
      if (windows > 1) throw std::invalid_argument("give one of --strain, --time and --window");
      if (!strain_text.empty()) parse_window("--strain", strain_text, opt);
      if (!time_text.empty()) parse_window("--time", time_text, opt);
      if (!window_text.empty()) parse_window("--window", window_text, opt);
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "stokesian: average: %s\n", e.what());
      return 1;
    }
    for (std::size_t p = 0; !observables_text.empty() && p <= observables_text.size();) {
      const std::size_t q = std::min(observables_text.find(',', p), observables_text.size());
      if (q > p) opt.observables.push_back(observables_text.substr(p, q - p));
      p = q + 1;
    }
    Activity activity;
    activity.doing = "averaging";
    return guarded(activity, [&]() -> int { return app::average(average_file, opt, stdout); });
  }
  if (clusters_cmd->parsed()) {
    Activity activity;
    activity.doing = "analysing clusters";
    return guarded(activity, [&]() -> int { return app::clusters(clusters_file, cluster_opt, stdout); });
  }
  if (sweep_cmd->parsed()) {
    sweep_opt.jobs = std::stoi(jobs_text);
    sweep_opt.threads = std::stoi(sweep_threads_text);
    if (!run_text.empty()) sweep_opt.only_run = std::stol(run_text);
    Activity activity;
    activity.doing = "running a sweep";
    return guarded(activity, [&]() -> int { return app::sweep(sweep_file, sweep_opt); });
  }
  if (out.empty()) out = default_out(scene);

  Activity activity;
  return guarded(activity, [&]() -> int {
    // The resource estimate comes before anything large is allocated or any file is written; scene
    // loading checks the memory of generated particles itself before placing them.
    Scene loaded = io::load_scene(scene);
    activity.doing = "resolving the model";
    activity.estimate = estimate_resources(loaded, resolve_model(loaded));
    require_resources(loaded, *activity.estimate, memory_budget(), quiet && !check->parsed() ? nullptr : stderr);
    // A slow evaluation is announced with its estimate before it starts, even with --quiet (a long
    // silence must never look like a hang); check does not measure one (check.cpp).
    if (const double per_step = activity.estimate->seconds_per_step; !check->parsed() && per_step > kAnnounceSeconds)
      std::fprintf(stderr, "stokesian: note: %s: one evaluation is estimated at about %.3g s on one thread%s\n",
                   loaded.source.c_str(), per_step,
                   solve->parsed() ? "" : (" (" + std::to_string(loaded.time.steps) + " steps)").c_str());
    activity.doing = "building the simulation";
    Simulation sim(std::move(loaded));
    activity.doing = check->parsed() ? "checking the scene" : solve->parsed() ? "solving" : "running";
    if (check->parsed()) {
      CheckOptions opt;
      opt.out = out;
      opt.estimate = !no_estimate;
      opt.threads = threads;
      return app::check(sim, opt, stdout);
    }
    if (!quiet) std::fprintf(stderr, "%s\n", sim.model().describe().c_str());
    if (solve->parsed()) {
      app::solve(sim, out);
      if (!quiet) std::fprintf(stderr, "wrote %s\n", out.c_str());
      return 0;
    }
    if (progress_interval >= 0) progress::refresh_override() = progress_interval;
    RunOptions opt;
    opt.out = out;
    opt.resume = resume;
    opt.quiet = quiet;
    const long steps = app::run(sim, opt);
    if (!quiet) std::fprintf(stderr, "%ld steps, wrote %s\n", steps, out.c_str());
    return 0;
  });
}

}  // namespace stokesian::app
