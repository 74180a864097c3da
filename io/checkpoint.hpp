#pragma once
// Kill-safe checkpoints, and RunOutput, which ties them to the trajectory so that a checkpoint
// is only ever written after the frames it accounts for are committed.
//
// Checkpoint file (P + ".ckpt"), little-endian binary:
//   "STKCKPT1" | u64 payload length | payload | u64 FNV-1a-64 checksum of the payload
// Doubles are stored as their IEEE-754 bit patterns, so a round trip is bit-exact. The file is
// written to P.ckpt.tmp, fsync'ed, then renamed over P.ckpt: a reader sees the old or the new
// checkpoint, never a mixture; a damaged file fails the length or checksum test.
//
// Resume guarantee: after RunOutput::resume the trajectory holds exactly the frames with
// step <= checkpoint step, and their number equals the count the checkpoint recorded.
#include "engine/core/output.hpp"
#include "engine/core/state.hpp"
#include "io/h5md.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace stokesian::io {

struct Checkpoint {
  State state;                                  // full dynamic state (positions ... rng)
  std::map<std::string, double> values;         // opaque driver data (accumulators, counters)
  std::map<std::string, std::string> strings;   // opaque driver data (text)
  std::string scene_toml;                       // resolved scene the run was started with
  std::string model;                            // model key (ModelKey::text); 0.1.0 wrote the description
  std::int64_t trajectory_frames = 0;           // frames committed to the trajectory when written
};

void write_checkpoint(const std::string& path, const Checkpoint& c);  // atomic replace
Checkpoint read_checkpoint(const std::string& path);                  // IoError if damaged

// "a; b; c" of scene_differences() entries, for resume messages.
std::string join_differences(const std::vector<std::string>& diff);

inline std::string checkpoint_path(const std::string& trajectory_path) { return trajectory_path + ".ckpt"; }
// Start marker (P + ".starting"): written by RunOutput::start before anything else, removed once the
// run's first checkpoint is durable. While it exists, P holds only frames of a run that has no
// checkpoint yet, so a --resume may replace P (RunOutput::nothing_to_resume).
inline std::string start_marker_path(const std::string& trajectory_path) { return trajectory_path + ".starting"; }

// The trajectory + checkpoint pair of one run.
class RunOutput final : public OutputSink {
 public:
  // Fresh run: writes the start marker, removes a stale checkpoint, then creates the trajectory
  // with zero frames.
  static RunOutput start(const std::string& path, const RunHeader& header);
  // Before a resume of `path`: std::nullopt when path.ckpt exists (resume from it). Otherwise
  // there is nothing to resume from, and the result is the one-line notice to print before
  // starting afresh, allowed only when no committed frame of another run can be lost:
  //   the start marker exists (P is the leftover of a start that never reached its first
  //   checkpoint), or P and its shadow are absent, or each of them that exists holds zero frames.
  // Anything else (P with frames and no checkpoint: a finished run whose checkpoint was
  // deleted, a `stokesian solve` result, ...) is refused with an IoError saying what to do.
  static std::optional<std::string> nothing_to_resume(const std::string& path);
  // Continue from path.ckpt: returns the restored checkpoint through `restored`. Refuses
  // (IoError) when checkpoint, trajectory and header disagree (N, scene, model key, frame count).
  static RunOutput resume(const std::string& path, const RunHeader& header, Checkpoint& restored);

  void record(const Frame& frame) override { traj_.append(frame); }
  void record(Frame&& frame) { traj_.append(std::move(frame)); }
  // Commit buffered frames, then write the checkpoint of `state` (in that order).
  void checkpoint(const State& state) override { checkpoint(state, {}, {}); }
  void checkpoint(const State& state, const std::map<std::string, double>& values,
                  const std::map<std::string, std::string>& strings = {});

  Trajectory& trajectory() { return traj_; }
  std::string checkpoint_file() const { return checkpoint_path(traj_.path()); }

 private:
  explicit RunOutput(Trajectory t, bool marked = false) : traj_(std::move(t)), marked_(marked) {}
  Trajectory traj_;
  bool marked_ = false;  // the start marker exists: remove it after the first checkpoint
};

}  // namespace stokesian::io
