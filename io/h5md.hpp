#pragma once
// Trajectory output in the H5MD 1.1 layout (de Buyl, Colberg & Hoefling 2014; h5md.nongnu.org),
// written so that the visible file is a complete, closed HDF5 file at every instant.
//
// Layout (docs/output.md has the full tree and h5py examples):
//   /h5md                      +version=[1,1]; author/+name; creator/+name,+version
//   /h5md/modules/units        +version=[1,0], +system: the reduced units a, mu, kT
//   /particles/all/box         +dimension=3, +boundary=3 x "none"|"periodic", edges (periodic:
//                              element [frames][3][3], rows = edge vectors)
//   /particles/all/<field>/{step,time,value}   every per-particle field of the RunHeader, in its
//                              order (position first: its step/time are shared by the others);
//                              `unit` attributes on value and time datasets (FieldSpec::unit);
//                              integer fields (image) as int64 datasets
//   /observables/<name>/{step,time,value}   every observable of the frames, shape of its first frame
//   /parameters/stokesian/{scene,model,model_key,version,git,compiler,build_type}
// The writer knows no quantity by name except position (the clock) and the box.
//
// Commit protocol (never-corrupt file). Let P be the visible file and S = P + ".shadow", a copy
// of P that lags exactly one commit behind. append() buffers frames in memory. commit():
//   1. append the previous segment and the pending one to S; close S; fsync S;
//   2. link(P, P.old); rename(S, P); rename(P.old, S); fsync the directory.
// rename() is atomic, so at every instant P names a closed file holding a whole number of
// segments; S never is P, so writing it cannot harm P. A kill during step 1 leaves S damaged,
// which resume() repairs from P.
#include "engine/core/errors.hpp"
#include "engine/core/frame.hpp"
#include "engine/core/output.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace stokesian::io {

class Trajectory {
 public:
  // Start a new trajectory at `path` (replacing any file there) with zero frames.
  static Trajectory create(const std::string& path, const RunHeader& header);
  // Continue an existing trajectory: keep exactly the frames with step <= last_step, which must
  // number `expected_frames` (the count stored in the checkpoint); refuse when the file
  // disagrees with `header` (particle number, box, recorded fields, scene, model key).
  static Trajectory resume(const std::string& path, const RunHeader& header,
                           std::int64_t last_step, std::int64_t expected_frames);

  // Buffer a frame; steps must increase strictly. When the buffer exceeds max_pending_bytes the
  // frames are committed early (safe: a later resume truncates to the checkpoint anyway), which
  // bounds memory for runs that checkpoint rarely.
  void append(Frame frame);
  void commit();  // make every buffered frame visible in the file (protocol above)
  // Commit, then delete the working copy S (a run that reached its end). A later commit or
  // resume rebuilds S from P.
  void finish();
  // Write a complete trajectory holding `frames` at `path` in one go (via path + ".tmp", fsync,
  // rename): no working copy is left behind (`stokesian solve`).
  static void write_frames(const std::string& path, const RunHeader& header, const std::vector<Frame>& frames);
  std::size_t max_pending_bytes = std::size_t(256) << 20;

  const std::string& path() const { return path_; }
  std::string shadow_path() const { return path_ + ".shadow"; }
  std::int64_t committed_frames() const { return committed_; }
  std::size_t pending_frames() const { return pending_.size(); }
  bool has_frames() const { return any_step_; }
  std::int64_t last_step() const { return last_step_; }  // of the last appended frame
  const RunHeader& header() const { return header_; }

 private:
  Trajectory(std::string path, RunHeader header) : path_(std::move(path)), header_(std::move(header)) {}
  void check_frame(const Frame& f) const;

  std::string path_;
  RunHeader header_;
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
  bool periodic = false;
  bool sheared_box = false;  // box edges stored per frame (every periodic box since 0.2; 0.1.0: sheared only)
  std::vector<FieldSpec> particle_fields;  // name and item shape of every per-particle field (by name)
  std::string scene_toml, model, version;
  std::string model_key;  // stored key, or the key read from a 0.1.0 model description
  std::vector<std::string> observables;
  bool records(const std::string& name) const {
    for (const auto& f : particle_fields)
      if (f.name == name) return true;
    return false;
  }
};
TrajectoryInfo inspect_trajectory(const std::string& path);

// Last frame of a previous run's trajectory, to start a new run from it.
struct Snapshot {
  std::int64_t step = 0;
  double time = 0.0;
  std::vector<Vec3> position;
  std::vector<double> radius;
  bool periodic = false;     // the run's box (last frame): edge lengths and Lees-Edwards strain
  Vec3 box = Vec3::Zero();
  double shear_strain = 0.0;
  std::vector<Vec3> velocity;     // read_frame: when the trajectory records velocity; else empty
  std::vector<std::int64_t> id;   // read_frame with present_only = false, open channels: slot ids (-1 empty)
};
Snapshot read_last_frame(const std::string& path);
// Frame `index` (0-based; negative counts from the end, -1 the last). present_only: open channels
// keep only the occupied slots (as read_last_frame); otherwise every slot is returned with its id
// (an empty slot's values are NaN), so wall particles stay the last entries of the frame.
Snapshot read_frame(const std::string& path, std::int64_t index, bool present_only);

// Every observable of a trajectory (/observables/<name>), whole: its times and values, each value
// flattened to `components` numbers (integer observables converted to double). For summaries.
struct ObservableSeries {
  std::string name, unit;
  std::vector<double> time;
  std::size_t components = 1;
  std::vector<double> value;  // time.size() x components, row-major
};
std::vector<ObservableSeries> read_observables(const std::string& path);

// A table of named columns (numbers or strings) written as HDF5: /table/<column> datasets in
// column order (the string dataset /table_columns lists them), plus string attributes on the root.
// Written to path + ".tmp" and renamed, so a reader never sees a partial file. '/' in a column
// name is stored as '|'.
struct TableColumn {
  std::string name;
  bool numeric = true;
  std::vector<double> num;
  std::vector<std::string> text;
};
void write_table_h5(const std::string& path, const std::vector<TableColumn>& columns,
                    const std::vector<std::pair<std::string, std::string>>& attributes);
// Several tables (group /<name>/<column>) and 2D datasets (/<name>, rows x cols, row-major) in one
// file, written through path + ".tmp" and renamed as write_table_h5.
struct TableGroup {
  std::string name;
  std::vector<TableColumn> columns;
};
struct Matrix2D {
  std::string name;
  std::size_t rows = 0, cols = 0;
  std::vector<double> data;
};
void write_tables_h5(const std::string& path, const std::vector<TableGroup>& groups, const std::vector<Matrix2D>& matrices,
                     const std::vector<std::pair<std::string, std::string>>& attributes);

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
