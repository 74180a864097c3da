#pragma once
// Trajectory output in the H5MD 1.1 layout (de Buyl, Colberg & Hoefling 2014; h5md.nongnu.org),
// written so that the visible file is a complete, closed HDF5 file at every instant.
//
// Layout (docs/output.md has the full tree and h5py examples):
//   /h5md                      +version=[1,1]; author/+name; creator/+name,+version
//   /particles/all/box         +dimension=3, +boundary=3 x "none"|"periodic", edges
//   /particles/all/<q>/{step,time,value}   q = position, velocity, angular_velocity, force,
//                              torque, stresslet (6 comps xx xy xz yy yz zz), radius
//   /observables/<name>/{step,time,value}
//   /parameters/stokesian/{scene,model,version,git,compiler,build_type}
//
// Commit protocol (never-corrupt file). Let P be the visible file and S = P + ".shadow", a copy
// of P that lags exactly one commit behind. append() buffers frames in memory. commit():
//   1. append the previous segment and the pending one to S; close S; fsync S;
//   2. link(P, P.old); rename(S, P); rename(P.old, S); fsync the directory.
// rename() is atomic, so at every instant P names a closed file holding a whole number of
// segments; S never is P, so writing it cannot harm P. A kill during step 1 leaves S damaged,
// which resume() repairs from P.
#include "engine/state.hpp"
#include "engine/sym_traceless.hpp"
#include "engine/types.hpp"

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace stokesian::io {

// Every failure of the io/ room: the message names the file and the problem.
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Symmetric 3x3 tensor as its 6 independent components xx, xy, xz, yy, yz, zz.
using Vec6 = Eigen::Matrix<double, 6, 1>;
inline Vec6 six_components(const Mat3& A) {
  Vec6 v;
  v << A(0, 0), 0.5 * (A(0, 1) + A(1, 0)), 0.5 * (A(0, 2) + A(2, 0)), A(1, 1),
      0.5 * (A(1, 2) + A(2, 1)), A(2, 2);
  return v;
}
inline Vec6 six_components(const Vec5& s) { return six_components(from_vec5(s)); }

// Which per-particle quantities a trajectory records (position and radius always).
struct Quantities {
  bool velocity = true, angular_velocity = true, force = true, torque = true, stresslet = true;
};

// What is fixed for the whole trajectory. Stored in /parameters and checked on resume.
struct TrajectoryHeader {
  std::size_t particles = 0;
  Domain domain;             // open -> boundary "none", no edges; periodic -> edges [Lx Ly Lz]
  bool sheared_box = false;  // periodic with Lees-Edwards: edges become a per-frame 3x3 matrix
  Quantities record;
  std::string scene_toml;    // resolved scene text
  std::string model;         // resolved model description (hydrodynamics, moments, method)
  std::string author = "unknown";
};

// One sample, filled by the caller. Vectors of recorded quantities must have `particles` entries;
// those not recorded are ignored and may stay empty.
struct Frame {
  std::int64_t step = 0;
  double time = 0.0;
  double shear_strain = 0.0;  // Lees-Edwards strain of the box at this frame (sheared_box only)
  std::vector<Vec3> position, velocity, angular_velocity, force, torque;
  std::vector<Vec6> stresslet;
  std::vector<double> radius;
  std::map<std::string, double> scalars;               // /observables/<name>, value [frames]
  std::map<std::string, std::vector<double>> vectors;  // /observables/<name>, value [frames][k]
};

class Trajectory {
 public:
  // Start a new trajectory at `path` (replacing any file there) with zero frames.
  static Trajectory create(const std::string& path, const TrajectoryHeader& header);
  // Continue an existing trajectory: keep exactly the frames with step <= last_step, which must
  // number `expected_frames` (the count stored in the checkpoint); refuse when the file
  // disagrees with `header` (particle number, scene, model, recorded quantities, box).
  static Trajectory resume(const std::string& path, const TrajectoryHeader& header,
                           std::int64_t last_step, std::int64_t expected_frames);

  // Buffer a frame; steps must increase strictly. When the buffer exceeds max_pending_bytes the
  // frames are committed early (safe: a later resume truncates to the checkpoint anyway), which
  // bounds memory for runs that checkpoint rarely.
  void append(Frame frame);
  void commit();  // make every buffered frame visible in the file (protocol above)
  std::size_t max_pending_bytes = std::size_t(256) << 20;

  const std::string& path() const { return path_; }
  std::string shadow_path() const { return path_ + ".shadow"; }
  std::int64_t committed_frames() const { return committed_; }
  std::size_t pending_frames() const { return pending_.size(); }
  bool has_frames() const { return any_step_; }
  std::int64_t last_step() const { return last_step_; }  // of the last appended frame
  const TrajectoryHeader& header() const { return header_; }

 private:
  Trajectory(std::string path, TrajectoryHeader header) : path_(std::move(path)), header_(std::move(header)) {}
  void check_frame(const Frame& f) const;

  std::string path_;
  TrajectoryHeader header_;
  std::vector<Frame> pending_;   // not yet in P
  std::size_t pending_bytes_ = 0;
  std::vector<Frame> previous_;  // in P but not yet in S
  std::int64_t committed_ = 0;   // frames in P
  std::int64_t last_step_ = 0;
  bool any_step_ = false;
  bool shadow_suspect_ = false;  // a write to S failed: rebuild it from P before the next append
};

// Summary of a trajectory file after a full consistency check (every element has matching
// step/time/value extents, steps increase, particle counts agree). Throws IoError otherwise.
struct TrajectoryInfo {
  std::size_t particles = 0;
  std::int64_t frames = 0;
  std::int64_t first_step = 0, last_step = 0;
  double last_time = 0.0;
  bool periodic = false, sheared_box = false;
  Quantities record;
  std::string scene_toml, model, version;
  std::vector<std::string> observables;
};
TrajectoryInfo inspect_trajectory(const std::string& path);

// Last frame of a previous run's trajectory, to start a new run from it.
struct Snapshot {
  std::int64_t step = 0;
  double time = 0.0;
  std::vector<Vec3> position;
  std::vector<double> radius;
};
Snapshot read_last_frame(const std::string& path);

namespace detail {
// Durable file operations shared by the trajectory and checkpoint writers.
void fsync_file(const std::string& path);
void fsync_parent_dir(const std::string& path);
void durable_copy(const std::string& from, const std::string& to);  // via to + ".tmp", then rename
void durable_rename(const std::string& from, const std::string& to);
bool exists(const std::string& path);
void remove_if_exists(const std::string& path);
}  // namespace detail

}  // namespace stokesian::io
