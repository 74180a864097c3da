#include "engine/app/run.hpp"

#include "io/checkpoint.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"
#include "io/xyz.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <pwd.h>
#include <unistd.h>

namespace stokesian::app {

namespace {

// Trajectory + checkpoint, and the optional XYZ export flushed at each checkpoint.
class RunFiles final : public OutputSink {
 public:
  RunFiles(io::RunOutput out, std::optional<io::XyzWriter> xyz) : out_(std::move(out)), xyz_(std::move(xyz)) {}
  void record(const Frame& f) override {
    if (xyz_) xyz_->write(f);
    out_.record(f);
  }
  void checkpoint(const State& s) override {
    out_.checkpoint(s);
    if (xyz_) xyz_->flush();
  }
  // The run reached its last step: the trajectory's working copy is no longer needed.
  void finish() { out_.trajectory().finish(); }

 private:
  io::RunOutput out_;
  std::optional<io::XyzWriter> xyz_;
};

// The scene changes a resume accepts: [time] dt and [run] keys (failure policy).
struct ResumableChanges {
  std::string stored_scene;  // the checkpoint's scene text
  std::string changes;       // "[time] dt: 0.1 -> 0.05; ..."
  bool dt_changed = false;
};
std::optional<ResumableChanges> resumable_changes(const std::string& checkpoint, const Scene& scene,
                                                  const std::string& scene_toml) {
  const io::Checkpoint c = io::read_checkpoint(checkpoint);
  const auto diff = io::scene_differences(c.scene_toml, scene_toml);
  if (diff.empty()) return std::nullopt;
  for (const auto& d : diff)
    if (d.rfind("[time] dt: ", 0) != 0 && d.rfind("[run] ", 0) != 0)
      return std::nullopt;  // RunOutput::resume refuses, naming every changed key
  // The changed values as written (%g), not at full precision.
  const Scene stored = io::parse_scene(c.scene_toml, "stored scene");
  ResumableChanges r;
  r.stored_scene = c.scene_toml;
  char buf[96];
  auto change = [&](const char* key, double from, double to) {
    if (from == to) return;
    std::snprintf(buf, sizeof buf, "%s%s: %g -> %g", r.changes.empty() ? "" : "; ", key, from, to);
    r.changes += buf;
  };
  change("[run] max_overlap", stored.run.max_overlap, scene.run.max_overlap);
  change("[time] dt", stored.time.dt, scene.time.dt);
  r.dt_changed = stored.time.dt != scene.time.dt;
  return r;
}

// The message of a run stopped by a physics failure: what failed (from the engine), then what was
// kept or removed and what to do.
std::string stopped_message(const RunStopped& e, const Scene& scene, const RunOptions& opt, bool resumed,
                            std::optional<RunFiles>& files) {
  std::string m = e.what();
  const std::string cmd = "stokesian run " + scene.source + " --out " + opt.out + " --resume";
  if (e.checkpoint_step >= 0) {
    m += "\n  checkpoint: " + io::checkpoint_path(opt.out) + " (step " + std::to_string(e.checkpoint_step) + "); " +
         opt.out + " holds the frames up to that step";
    char half[32];
    std::snprintf(half, sizeof half, "%g", 0.5 * scene.time.dt);
    m += "\n  to continue: reduce [time] dt in " + scene.source + " (e.g. to " + half + ") and run `" + cmd +
         "` (a resume accepts a changed [time] dt and [run] keys)";
  } else if (!resumed) {
    // The scene's initial state fails: nothing worth resuming. Remove what the start created.
    const std::string xyz = xyz_path(scene, opt.out);
    files.reset();
    for (const std::string& f : {opt.out, opt.out + ".shadow", io::checkpoint_path(opt.out),
                                 io::start_marker_path(opt.out), xyz})
      if (!f.empty()) io::detail::remove_if_exists(f);
    m += "\n  no step was taken: removed " + opt.out + " and its working files; change the initial state or the "
         "model in " + scene.source + " and run again";
  } else {
    m += "\n  the resumed state (the checkpoint " + io::checkpoint_path(opt.out) +
         ") itself fails: it is kept unchanged; a smaller [time] dt cannot help here";
  }
  return m;
}

}  // namespace

std::string default_author() {
  if (const passwd* pw = ::getpwuid(::getuid()); pw && pw->pw_name && *pw->pw_name) return pw->pw_name;
  for (const char* var : {"USER", "LOGNAME"})
    if (const char* v = std::getenv(var); v && *v) return v;
  return "unknown";
}

std::string xyz_path(const Scene& scene, const std::string& out) {
  if (!scene.output.xyz) return "";
  namespace fs = std::filesystem;
  const fs::path o(out);
  if (scene.output.xyz_path.empty()) return (o.parent_path() / o.stem()).string() + ".xyz";
  const fs::path p(scene.output.xyz_path);
  return p.is_absolute() ? p.string() : (o.parent_path() / p).string();
}

RunHeader run_header(const Simulation& sim) {
  RunHeader h = sim.header();
  h.author = sim.scene().output.author.empty() ? default_author() : sim.scene().output.author;
  return h;
}

long run(Simulation& sim, const RunOptions& opt) {
  const Scene& scene = sim.scene();
  const RunHeader header = run_header(sim);
  State s;
  RunControl control;
  control.quiet = opt.quiet;
  control.max_steps = opt.max_steps;
  std::optional<io::RunOutput> out;
  bool resume = opt.resume;
  if (resume) {
    // Nothing to resume from (no checkpoint): start afresh when no other run's frames can be lost
    // (RunOutput::nothing_to_resume refuses otherwise). Said even with --quiet: files are replaced.
    if (const auto notice = io::RunOutput::nothing_to_resume(opt.out)) {
      std::fprintf(stderr, "stokesian: %s\n", notice->c_str());
      resume = false;
    }
  }
  if (resume) {
    // A failed run is continued with a smaller [time] dt (docs/reliability.md): the scene may differ
    // from the checkpoint's in [time] dt and [run] keys only. The files keep the scene the run
    // started with (io compares against it); the state takes this scene's dt.
    RunHeader stored_header = header;
    bool dt_changed = false;
    if (const auto allowed = resumable_changes(io::checkpoint_path(opt.out), scene, header.scene_toml)) {
      stored_header.scene_toml = allowed->stored_scene;
      dt_changed = allowed->dt_changed;
      std::fprintf(stderr, "stokesian: resuming with changed %s (allowed on resume; %s keeps the scene it was started "
                   "with, the dt observable records the step used)\n", allowed->changes.c_str(), opt.out.c_str());
    }
    io::Checkpoint restored;
    out.emplace(io::RunOutput::resume(opt.out, stored_header, restored));
    s = restored.state;
    // Fixed-step integrators step by the scene's dt; rkf45 adapts its own and takes a changed one
    // as its next trial step.
    if (dt_changed || sim.model().integrator != "rkf45") s.dt = scene.time.dt;
    // The frame of the checkpoint's step is recorded unless the run stopped before recording it.
    control.frame_done = out->trajectory().has_frames() && out->trajectory().last_step() == s.step;
  } else {
    s = sim.initial_state();
    out.emplace(io::RunOutput::start(opt.out, header));
  }
  std::optional<io::XyzWriter> xyz;
  if (const std::string path = xyz_path(scene, opt.out); !path.empty())
    xyz.emplace(path, s.domain, io::species_labels(s.radius, s.fixed),
                resume ? std::optional<std::int64_t>(s.step) : std::nullopt);
  std::optional<RunFiles> files(std::in_place, std::move(*out), std::move(xyz));
  long taken = 0;
  try {
    taken = sim.run(s, *files, control);
  } catch (const RunStopped& e) {
    throw RunStopped(stopped_message(e, scene, opt, resume, files), e.failed_step, e.checkpoint_step);
  }
  if (s.step >= scene.time.last_step()) files->finish();
  return taken;
}

std::size_t report_close_pairs(const Scene& scene, const ResolvedModel& model, std::FILE* to) {
  const auto& x = scene.positions;
  const auto& a = scene.radii;
  if (x.size() < 2) return 0;
  // Pairs whose symmetric gap xi = 2r/(a_i + a_j) - 2 is below the lubrication floor: their gap
  // h = xi (a_i + a_j)/2 is below min_gap * max(a).
  const double amax = *std::max_element(a.begin(), a.end());
  const double floor_xi = scene.hydro.lubrication_min_gap;
  const bool near_field = model.level == HydroModel::stokesian;
  const GapSurvey g = survey_gaps(x, a, scene.domain, near_field ? floor_xi * amax : 0.0, x.size() * 8);
  std::vector<PairGap> overlapping, regularised;
  for (const PairGap& p : g.worst) {
    const double xi = 2.0 * p.gap / (a[std::size_t(p.i)] + a[std::size_t(p.j)]);
    if (p.gap < 0) overlapping.push_back(p);
    else if (near_field && xi < floor_xi) regularised.push_back(p);
  }
  constexpr std::size_t kShown = 10;
  auto listed = [&](std::vector<PairGap> v) {
    const std::size_t n = v.size();
    if (n > kShown) v.resize(kShown);
    return describe_pairs(v) + (n > kShown ? ", ... (" + std::to_string(n - kShown) + " more)" : "");
  };
  if (!overlapping.empty())
    std::fprintf(to, "stokesian: warning: %zu overlapping pair(s): %s; %s\n", overlapping.size(),
                 listed(overlapping).c_str(),
                 near_field ? "their lubrication is evaluated at the lubrication minimum gap (it does not depend on "
                              "how deep they overlap) and the far field uses the overlap-regularised mobility"
                 : model.level == HydroModel::far_field ? "the far field uses the overlap-regularised mobility"
                                                        : "free-draining spheres do not interact hydrodynamically");
  if (!regularised.empty())
    std::fprintf(to,
                 "stokesian: warning: %zu pair(s) closer than [hydrodynamics] lubrication_min_gap = %g (symmetric "
                 "gap 2r/(a_i+a_j) - 2): %s; their lubrication is evaluated at that gap (regularised), so the result "
                 "does not change as they come closer\n",
                 regularised.size(), floor_xi, listed(regularised).c_str());
  return overlapping.size() + regularised.size();
}

void solve(Simulation& sim, const std::string& path) {
  const State s = sim.initial_state();
  report_close_pairs(sim.scene(), sim.model(), stderr);
  const State p = sim.present(s);
  const Evaluation ev = sim.evaluate(p, p.position, 0.0, true);
  // A previous start's marker would let a later --resume replace this result: remove it first.
  io::detail::remove_if_exists(io::start_marker_path(path));
  io::Trajectory::write_frames(path, run_header(sim), {sim.frame_of_present(s, ev)});
  io::detail::remove_if_exists(io::checkpoint_path(path));  // a previous run's, now stale
}

}  // namespace stokesian::app
