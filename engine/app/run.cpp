#include "engine/app/run.hpp"

#include "io/checkpoint.hpp"
#include "io/h5md.hpp"
#include "io/xyz.hpp"

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
    io::Checkpoint restored;
    out.emplace(io::RunOutput::resume(opt.out, header, restored));
    s = restored.state;
    control.frame_done = sim.frame_step(s.step);
  } else {
    s = sim.initial_state();
    out.emplace(io::RunOutput::start(opt.out, header));
  }
  std::optional<io::XyzWriter> xyz;
  if (const std::string path = xyz_path(scene, opt.out); !path.empty())
    xyz.emplace(path, s.domain, io::species_labels(s.radius, s.fixed),
                resume ? std::optional<std::int64_t>(s.step) : std::nullopt);
  RunFiles files(std::move(*out), std::move(xyz));
  const long taken = sim.run(s, files, control);
  if (s.step >= scene.time.last_step()) files.finish();
  return taken;
}

void solve(Simulation& sim, const std::string& path) {
  const State s = sim.initial_state();
  const Evaluation ev = sim.evaluate(s, s.position, 0.0, true);
  // A previous start's marker would let a later --resume replace this result: remove it first.
  io::detail::remove_if_exists(io::start_marker_path(path));
  io::Trajectory::write_frames(path, run_header(sim), {sim.frame(s, ev)});
  io::detail::remove_if_exists(io::checkpoint_path(path));  // a previous run's, now stale
}

}  // namespace stokesian::app
