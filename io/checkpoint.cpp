#include "io/checkpoint.hpp"

#include "io/scene_toml.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace stokesian::io {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'K', 'C', 'K', 'P', 'T', '1'};

std::uint64_t fnv1a64(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// Little-endian encoder/decoder, independent of the host byte order.
struct Writer {
  std::string out;
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, 8);
    u64(b);
  }
  void str(const std::string& s) {
    u64(s.size());
    out += s;
  }
};

struct Reader {
  const std::string& in;
  std::size_t pos = 0;
  std::string file;
  void need(std::size_t n) const {
    if (in.size() - pos < n) throw IoError(file + ": checkpoint payload ends early (corrupt)");
  }
  std::uint64_t u64() {
    need(8);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(in[pos + i])) << (8 * i);
    pos += 8;
    return v;
  }
  std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
  double f64() {
    const std::uint64_t b = u64();
    double v;
    std::memcpy(&v, &b, 8);
    return v;
  }
  std::string str() {
    const std::uint64_t n = u64();
    need(n);
    std::string s = in.substr(pos, n);
    pos += n;
    return s;
  }
  std::size_t count(std::size_t bytes_each) {
    const std::uint64_t n = u64();
    if (bytes_each && n > (in.size() - pos) / bytes_each) throw IoError(file + ": checkpoint count out of range (corrupt)");
    return n;
  }
};

// 1: stokesian 0.1.0 (no image counts); 2: image counts after the fixed flags.
constexpr std::uint64_t kFormatVersion = 2;

}  // namespace

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  const State& s = c.state;
  if (s.radius.size() != s.size() || s.fixed.size() != s.size() || (!s.image.empty() && s.image.size() != s.size()))
    throw IoError(path + ": state has inconsistent sizes (positions, radii, fixed flags, images)");
  Writer w;
  w.u64(kFormatVersion);
  w.i64(s.step);
  w.f64(s.time);
  w.f64(s.dt);
  w.u64(s.domain.kind == Domain::Kind::periodic ? 1 : 0);
  for (int k = 0; k < 3; ++k) w.f64(s.domain.box[k]);
  w.f64(s.domain.shear_strain);
  w.u64(s.size());
  for (const auto& x : s.position)
    for (int k = 0; k < 3; ++k) w.f64(x[k]);
  for (double r : s.radius) w.f64(r);
  for (char f : s.fixed) w.out.push_back(f ? 1 : 0);
  w.u64(s.image.size());
  for (const auto& n : s.image)
    for (int k = 0; k < 3; ++k) w.i64(n[std::size_t(k)]);
  w.str(s.rng_state);
  w.str(c.scene_toml);
  w.str(c.model);
  w.i64(c.trajectory_frames);
  // The state's window sums travel as values "state.*" (format unchanged; read back below).
  std::map<std::string, double> values = c.values;
  if (s.brownian_samples != 0) values["state.brownian_samples"] = double(s.brownian_samples);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (s.brownian_stresslet_sum(i, j) != 0.0)
        values["state.brownian_stresslet_sum." + std::to_string(3 * i + j)] = s.brownian_stresslet_sum(i, j);
  std::map<std::string, std::string> strings = c.strings;
  if (!s.id.empty()) {  // open channels (engine/inflow.hpp): slots and the inflow's tally
    if (s.id.size() != s.size()) throw IoError(path + ": state has " + std::to_string(s.id.size()) + " ids for " +
                                               std::to_string(s.size()) + " slots");
    std::ostringstream ids;
    for (std::size_t i = 0; i < s.id.size(); ++i) ids << (i ? " " : "") << s.id[i];
    strings["state.id"] = ids.str();
    values["state.inflow.credit"] = s.inflow.credit;
    values["state.inflow.pending"] = s.inflow.pending;
    values["state.inflow.next_id"] = double(s.inflow.next_id);
    values["state.inflow.inserted"] = double(s.inflow.inserted);
    values["state.inflow.removed"] = double(s.inflow.removed);
    values["state.inflow.deferred"] = double(s.inflow.deferred);
    values["state.inflow.waited"] = s.inflow.waited;
    values["state.inflow.redrawn"] = double(s.inflow.redrawn);
  }
  w.u64(values.size());
  for (const auto& [k, v] : values) {
    w.str(k);
    w.f64(v);
  }
  w.u64(strings.size());
  for (const auto& [k, v] : strings) {
    w.str(k);
    w.str(v);
  }

  Writer file;
  file.out.assign(kMagic, 8);
  file.u64(w.out.size());
  file.out += w.out;
  file.u64(fnv1a64(w.out));

  const std::string tmp = path + ".tmp";
  {
    std::ofstream os(tmp, std::ios::binary | std::ios::trunc);
    if (!os) throw IoError(tmp + ": cannot create checkpoint (" + std::strerror(errno) + ")");
    os.write(file.out.data(), static_cast<std::streamsize>(file.out.size()));
    os.close();
    if (!os) throw IoError(tmp + ": writing the checkpoint failed");
  }
  detail::fsync_file(tmp);
  detail::durable_rename(tmp, path);
}

Checkpoint read_checkpoint(const std::string& path) {
  std::ifstream is(path, std::ios::binary);
  if (!is) throw IoError(path + ": cannot open checkpoint (" + std::strerror(errno) + ")");
  std::ostringstream ss;
  ss << is.rdbuf();
  const std::string bytes = ss.str();
  if (bytes.size() < 24 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw IoError(path + ": not a stokesian checkpoint (bad header)");
  Reader head{bytes, 8, path};
  const std::uint64_t len = head.u64();
  if (len != bytes.size() - 24) throw IoError(path + ": checkpoint has the wrong length (truncated or corrupt)");
  const std::string payload = bytes.substr(16, len);
  Reader tail{bytes, 16 + len, path};
  if (tail.u64() != fnv1a64(payload)) throw IoError(path + ": checkpoint checksum mismatch (corrupt)");

  Reader r{payload, 0, path};
  const std::uint64_t version = r.u64();
  if (version < 1 || version > kFormatVersion)
    throw IoError(path + ": unsupported checkpoint format version " + std::to_string(version) + " (this build reads 1 to " +
                  std::to_string(kFormatVersion) + ")");
  Checkpoint c;
  State& s = c.state;
  s.step = r.i64();
  s.time = r.f64();
  s.dt = r.f64();
  s.domain.kind = r.u64() ? Domain::Kind::periodic : Domain::Kind::open;
  for (int k = 0; k < 3; ++k) s.domain.box[k] = r.f64();
  s.domain.shear_strain = r.f64();
  const std::size_t n = r.count(3 * 8 + 8 + 1);
  s.position.resize(n);
  for (auto& x : s.position)
    for (int k = 0; k < 3; ++k) x[k] = r.f64();
  s.radius.resize(n);
  for (auto& a : s.radius) a = r.f64();
  r.need(n);
  s.fixed.assign(payload.begin() + static_cast<std::ptrdiff_t>(r.pos),
                 payload.begin() + static_cast<std::ptrdiff_t>(r.pos + n));
  r.pos += n;
  if (version >= 2) {
    const std::size_t m = r.count(3 * 8);
    if (m != 0 && m != n) throw IoError(path + ": checkpoint holds image counts for " + std::to_string(m) + " of " +
                                        std::to_string(n) + " particles (corrupt)");
    s.image.resize(m);
    for (auto& im : s.image)
      for (int k = 0; k < 3; ++k) im[std::size_t(k)] = static_cast<std::int32_t>(r.i64());
  }
  s.rng_state = r.str();
  c.scene_toml = r.str();
  c.model = r.str();
  c.trajectory_frames = r.i64();
  for (std::size_t i = 0, m = r.count(16); i < m; ++i) {
    std::string k = r.str();
    c.values[k] = r.f64();
  }
  for (std::size_t i = 0, m = r.count(16); i < m; ++i) {
    std::string k = r.str();
    c.strings[k] = r.str();
  }
  if (r.pos != payload.size()) throw IoError(path + ": checkpoint has trailing bytes (corrupt)");
  for (auto it = c.values.begin(); it != c.values.end();) {
    const std::string& k = it->first;
    if (k.rfind("state.", 0) != 0) {
      ++it;
      continue;
    }
    if (k == "state.brownian_samples") {
      s.brownian_samples = std::int64_t(it->second);
    } else if (k.rfind("state.brownian_stresslet_sum.", 0) == 0) {
      const int e = std::atoi(k.c_str() + std::strlen("state.brownian_stresslet_sum."));
      if (e < 0 || e > 8) throw IoError(path + ": checkpoint value " + k + " is not a stresslet entry (corrupt)");
      s.brownian_stresslet_sum(e / 3, e % 3) = it->second;
    } else if (k == "state.inflow.credit") {
      s.inflow.credit = it->second;
    } else if (k == "state.inflow.pending") {
      s.inflow.pending = it->second;
    } else if (k == "state.inflow.next_id") {
      s.inflow.next_id = std::int64_t(it->second);
    } else if (k == "state.inflow.inserted") {
      s.inflow.inserted = std::int64_t(it->second);
    } else if (k == "state.inflow.removed") {
      s.inflow.removed = std::int64_t(it->second);
    } else if (k == "state.inflow.deferred") {
      s.inflow.deferred = std::int64_t(it->second);
    } else if (k == "state.inflow.waited") {  // absent in checkpoints before 2026-11-28: 0
      s.inflow.waited = it->second;
    } else if (k == "state.inflow.redrawn") {
      s.inflow.redrawn = std::int64_t(it->second);
    } else {
      throw IoError(path + ": checkpoint holds an unknown state value " + k + " (written by a newer version?)");
    }
    it = c.values.erase(it);
  }
  if (auto it = c.strings.find("state.id"); it != c.strings.end()) {
    std::istringstream in(it->second);
    std::int64_t v;
    while (in >> v) s.id.push_back(v);
    if (!in.eof() || s.id.size() != s.size())
      throw IoError(path + ": checkpoint holds " + std::to_string(s.id.size()) + " particle ids for " +
                    std::to_string(s.size()) + " slots (corrupt)");
    c.strings.erase(it);
  }
  return c;
}

std::string join_differences(const std::vector<std::string>& diff) {
  std::string out;
  for (std::size_t i = 0; i < diff.size(); ++i) out += (i ? "; " : "") + diff[i];
  return out;
}

RunOutput RunOutput::start(const std::string& path, const RunHeader& header) {
  // 1. The start marker, durably: from here on a missing checkpoint means "this start was
  //    interrupted", so a --resume may replace whatever P holds (the user asked to replace it).
  const std::string marker = start_marker_path(path);
  {
    std::ofstream os(marker, std::ios::trunc);
    if (!os) throw IoError(marker + ": cannot create the start marker (" + std::strerror(errno) + ")");
    os << "stokesian: run started, no checkpoint yet; " << path << " may be replaced by --resume\n";
    os.close();
    if (!os) throw IoError(marker + ": writing the start marker failed");
  }
  detail::fsync_file(marker);
  detail::fsync_parent_dir(marker);
  // 2. Remove the old checkpoint before the trajectory is replaced: a kill between the steps
  //    leaves no checkpoint, never a checkpoint that points into the new trajectory.
  detail::remove_if_exists(checkpoint_path(path));
  detail::remove_if_exists(checkpoint_path(path) + ".tmp");
  return RunOutput(Trajectory::create(path, header), true);
}

std::optional<std::string> RunOutput::nothing_to_resume(const std::string& path) {
  const std::string cp = checkpoint_path(path), shadow = path + ".shadow";
  if (detail::exists(cp)) return std::nullopt;
  const std::string head = "no checkpoint " + cp + ": nothing to resume, starting afresh ";
  if (detail::exists(start_marker_path(path)))
    return head + "(the partial " + path + " of an interrupted start is replaced)";
  if (!detail::exists(path) && !detail::exists(shadow)) return head + "(" + path + " does not exist yet)";
  // No marker: replace only files that hold no frames at all.
  for (const std::string& f : {path, shadow}) {
    if (!detail::exists(f)) continue;
    std::int64_t frames = -1;
    std::string problem;
    try {
      frames = inspect_trajectory(f).frames;
    } catch (const IoError& e) {
      problem = e.what();
    }
    if (frames != 0)
      throw IoError(cp + ": no checkpoint to resume from, and " + f +
                    (frames > 0 ? " holds " + std::to_string(frames) + " frame(s)" : " is not a readable trajectory (" + problem + ")") +
                    " that may belong to another run (a finished run whose checkpoint was removed, a `stokesian solve` "
                    "result, ...); refusing to replace it: run without --resume to start afresh and overwrite it, "
                    "or move it away");
  }
  return head + "(" + path + " holds no frames and is replaced)";
}

RunOutput RunOutput::resume(const std::string& path, const RunHeader& header, Checkpoint& restored) {
  const std::string cp = checkpoint_path(path);
  if (!detail::exists(cp)) throw IoError(cp + ": no checkpoint to resume from");
  Checkpoint c = read_checkpoint(cp);
  auto refuse = [&](const std::string& why) { throw IoError(cp + ": cannot resume: " + why); };
  if (c.state.size() != header.particles)
    refuse("the checkpoint holds " + std::to_string(c.state.size()) + " particles, the run has " +
           std::to_string(header.particles));
  if (const auto diff = scene_differences(c.scene_toml, header.scene_toml); !diff.empty())
    refuse("the scene differs from the one the checkpoint was written with (checkpoint -> this scene): " +
           join_differences(diff));
  const ModelKey stored = ModelKey::from_stored(c.model), run = ModelKey::from_stored(header.model_key);
  if (stored != run || (stored.empty() && c.model != header.model))
    refuse("the model differs (checkpoint: \"" + (stored.empty() ? c.model : stored.text()) + "\", run: \"" +
           (run.empty() ? header.model : run.text()) + "\")");
  RunOutput out(Trajectory::resume(path, header, c.state.step, c.trajectory_frames));
  // A start marker beside a valid checkpoint is stale (killed between the first checkpoint and
  // the marker's removal, or before the start removed an older checkpoint): the checkpoint rules.
  detail::remove_if_exists(start_marker_path(path));
  restored = std::move(c);
  return out;
}

void RunOutput::checkpoint(const State& state, const std::map<std::string, double>& values,
                           const std::map<std::string, std::string>& strings) {
  if (state.size() != traj_.header().particles)
    throw IoError(checkpoint_file() + ": state has " + std::to_string(state.size()) + " particles, trajectory " +
                  std::to_string(traj_.header().particles));
  if (traj_.has_frames() && traj_.last_step() > state.step)
    throw IoError(checkpoint_file() + ": a frame at step " + std::to_string(traj_.last_step()) +
                  " lies after the checkpointed state (step " + std::to_string(state.step) + ")");
  traj_.commit();
  Checkpoint c;
  c.state = state;
  c.values = values;
  c.strings = strings;
  c.scene_toml = traj_.header().scene_toml;
  c.model = traj_.header().model_key.empty() ? traj_.header().model : traj_.header().model_key;
  c.trajectory_frames = traj_.committed_frames();
  write_checkpoint(checkpoint_file(), c);
  if (marked_) {  // the first checkpoint is durable: P now holds frames a resume must keep
    detail::remove_if_exists(start_marker_path(traj_.path()));
    detail::fsync_parent_dir(traj_.path());
    marked_ = false;
  }
}

}  // namespace stokesian::io
