#include "engine/app/run.hpp"

#include "io/checkpoint.hpp"
#include "io/h5md.hpp"
#include "io/xyz.hpp"

#include <optional>

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

 private:
  io::RunOutput out_;
  std::optional<io::XyzWriter> xyz_;
};

}  // namespace

long run(Simulation& sim, const RunOptions& opt) {
  const Scene& scene = sim.scene();
  State s;
  RunControl control;
  control.quiet = opt.quiet;
  control.max_steps = opt.max_steps;
  std::optional<io::RunOutput> out;
  if (opt.resume) {
    io::Checkpoint restored;
    out.emplace(io::RunOutput::resume(opt.out, sim.header(), restored));
    s = restored.state;
    control.frame_done = s.step % scene.output.every == 0;
  } else {
    s = sim.initial_state();
    out.emplace(io::RunOutput::start(opt.out, sim.header()));
  }
  std::optional<io::XyzWriter> xyz;
  if (!scene.output.xyz.empty())
    xyz.emplace(scene.output.xyz, s.domain, std::vector<std::string>{},
                opt.resume ? std::optional<std::int64_t>(s.step) : std::nullopt);
  RunFiles files(std::move(*out), std::move(xyz));
  return sim.run(s, files, control);
}

void solve(Simulation& sim, const std::string& path) {
  const State s = sim.initial_state();
  const Evaluation ev = sim.evaluate(s, s.position, 0.0, true);
  io::Trajectory t = io::Trajectory::create(path, sim.header());
  t.append(sim.frame(s, ev));
  t.commit();
}

}  // namespace stokesian::app
