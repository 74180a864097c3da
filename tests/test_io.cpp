// io/: H5MD trajectory layout, commit/checkpoint/resume guarantees (including SIGKILL at random
// moments), bit-exact checkpoints, extended XYZ, and error messages.
#include "io/checkpoint.hpp"
#include "io/h5md.hpp"
#include "io/xyz.hpp"

#include <doctest/doctest.h>
#include <hdf5.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <random>
#include <signal.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

using namespace stokesian;
namespace fs = std::filesystem;

namespace {

// A fresh directory under /tmp, removed with its contents at scope exit.
struct TempDir {
  fs::path dir;
  TempDir() {
    char tmpl[] = "/tmp/stokesian_io_XXXXXX";
    const char* d = mkdtemp(tmpl);
    REQUIRE(d != nullptr);
    dir = d;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  std::string operator/(const std::string& name) const { return (dir / name).string(); }
};

// Deterministic per-particle data: every value is a known function of (step, particle, component),
// so a reader can tell whether any frame was torn or mixed with another.
double datum(std::int64_t step, std::size_t i, int quantity, int comp) {
  return 1000.0 * quantity + static_cast<double>(step) + 0.001 * static_cast<double>(i) + 1e-7 * comp;
}

// Per-particle fields of a trajectory: position, the optional kinematic quantities, radius.
std::vector<FieldSpec> fields_of(bool velocity = true, bool angular_velocity = true, bool force = true,
                                 bool torque = true, bool stresslet = true) {
  std::vector<FieldSpec> f{{"position", {3}, {}}};
  if (velocity) f.push_back({"velocity", {3}, {}});
  if (angular_velocity) f.push_back({"angular_velocity", {3}, {}});
  if (force) f.push_back({"force", {3}, {}});
  if (torque) f.push_back({"torque", {3}, {}});
  if (stresslet) f.push_back({"stresslet", {6}, {"xx", "xy", "xz", "yy", "yz", "zz"}});
  f.push_back({"radius", {}, {}});
  return f;
}

Frame make_frame(std::int64_t step, std::size_t n, const std::vector<FieldSpec>& fields) {
  static const std::vector<std::string> order{"position", "velocity", "angular_velocity", "force", "torque", "stresslet"};
  Frame f;
  f.step = step;
  f.time = 0.01 * static_cast<double>(step);
  f.shear_strain = 0.001 * static_cast<double>(step);
  for (const FieldSpec& spec : fields) {
    Field& field = f.particles[spec.name];
    field.shape = spec.shape;
    if (spec.name == "radius") {
      for (std::size_t i = 0; i < n; ++i) field.values.push_back(1.0 + 0.01 * static_cast<double>(i));
      continue;
    }
    const int quantity = int(std::find(order.begin(), order.end(), spec.name) - order.begin());
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < spec.item_size(); ++c) field.values.push_back(datum(step, i, quantity, c));
  }
  f.set_scalar("energy", 2.0 * static_cast<double>(step));
  return f;
}

RunHeader make_header(std::size_t n, bool periodic, bool sheared = false) {
  RunHeader h;
  h.particles = n;
  if (periodic) {
    h.domain.kind = Domain::Kind::periodic;
    h.domain.box = Vec3(10.0, 12.0, 14.0);
  }
  h.sheared_box = sheared;
  h.particle_fields = fields_of();
  h.scene_toml = "[time]\ndt = 0.01\nsteps = 100\n";
  h.model = "stokesian FTS, far field direct";
  h.author = "test";
  return h;
}

State make_state(std::size_t n, std::int64_t step) {
  State s;
  for (std::size_t i = 0; i < n; ++i) {
    s.position.push_back(Vec3(datum(step, i, 0, 0), datum(step, i, 0, 1), datum(step, i, 0, 2)));
    s.radius.push_back(1.0 + 0.01 * static_cast<double>(i));
    s.fixed.push_back(static_cast<char>(i % 3 == 0));
  }
  s.step = step;
  s.time = 0.01 * static_cast<double>(step);
  s.dt = 0.01;
  s.rng_state = "rng-at-" + std::to_string(step);
  return s;
}

// ---- HDF5 C API helpers for reading back, independently of io/ ---------------------------------

struct File {
  hid_t id;
  explicit File(const std::string& p) : id(H5Fopen(p.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)) { REQUIRE(id >= 0); }
  ~File() { H5Fclose(id); }
};

std::vector<hsize_t> shape(hid_t f, const char* name) {
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  REQUIRE_MESSAGE(d >= 0, std::string(name));
  hid_t s = H5Dget_space(d);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(s)));
  H5Sget_simple_extent_dims(s, dims.data(), nullptr);
  H5Sclose(s);
  H5Dclose(d);
  return dims;
}

template <typename T>
std::vector<T> read_all(hid_t f, const char* name, hid_t memtype) {
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  REQUIRE_MESSAGE(d >= 0, std::string(name));
  hid_t s = H5Dget_space(d);
  std::vector<T> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(s)));
  if (!v.empty()) REQUIRE(H5Dread(d, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
  H5Sclose(s);
  H5Dclose(d);
  return v;
}

std::vector<std::string> read_str_attr(hid_t f, const char* obj, const char* name) {
  hid_t a = H5Aopen_by_name(f, obj, name, H5P_DEFAULT, H5P_DEFAULT);
  REQUIRE_MESSAGE(a >= 0, (std::string(obj) + " @" + name));
  hid_t t = H5Aget_type(a);
  REQUIRE(H5Tget_class(t) == H5T_STRING);
  REQUIRE(H5Tis_variable_str(t) == 0);  // H5MD: fixed-length strings
  const std::size_t w = H5Tget_size(t);
  hid_t s = H5Aget_space(a);
  const auto n = static_cast<std::size_t>(H5Sget_simple_extent_npoints(s));
  std::vector<char> buf(w * n);
  REQUIRE(H5Aread(a, t, buf.data()) >= 0);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < n; ++i) out.emplace_back(buf.data() + i * w, strnlen(buf.data() + i * w, w));
  H5Sclose(s);
  H5Tclose(t);
  H5Aclose(a);
  return out;
}

std::string read_str_dataset(hid_t f, const char* name) {
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  REQUIRE_MESSAGE(d >= 0, std::string(name));
  hid_t t = H5Dget_type(d);
  std::vector<char> buf(H5Tget_size(t));
  REQUIRE(H5Dread(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) >= 0);
  H5Tclose(t);
  H5Dclose(d);
  return std::string(buf.data(), strnlen(buf.data(), buf.size()));
}

// Message matcher for CHECK_THROWS_WITH_AS (doctest::Contains copies the text).
doctest::Contains has(const std::string& s) { return doctest::Contains(s.c_str()); }

bool exists_link(hid_t f, const char* name) { return H5Lexists(f, name, H5P_DEFAULT) > 0; }

// Every frame in the trajectory carries exactly the data of its step (no torn or mixed frame),
// steps increase by `every`. Returns the steps.
std::vector<std::int64_t> verify_frames(const std::string& path, std::size_t n, std::int64_t every = 1) {
  File f(path);
  const auto steps = read_all<std::int64_t>(f.id, "/particles/all/position/step", H5T_NATIVE_INT64);
  if (steps.empty()) return steps;  // observables appear with the first frame
  const auto pos = read_all<double>(f.id, "/particles/all/position/value", H5T_NATIVE_DOUBLE);
  const auto vel = read_all<double>(f.id, "/particles/all/velocity/value", H5T_NATIVE_DOUBLE);
  const auto en = read_all<double>(f.id, "/observables/energy/value", H5T_NATIVE_DOUBLE);
  REQUIRE(pos.size() == steps.size() * n * 3);
  REQUIRE(vel.size() == steps.size() * n * 3);
  REQUIRE(en.size() == steps.size());
  std::size_t bad = 0;
  for (std::size_t j = 0; j < steps.size(); ++j) {
    if (j > 0 && steps[j] != steps[j - 1] + every) ++bad;
    if (en[j] != 2.0 * static_cast<double>(steps[j])) ++bad;
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) {
        if (pos[(j * n + i) * 3 + c] != datum(steps[j], i, 0, c)) ++bad;
        if (vel[(j * n + i) * 3 + c] != datum(steps[j], i, 1, c)) ++bad;
      }
  }
  CHECK(bad == 0);
  return steps;
}

}  // namespace

TEST_CASE("H5MD layout: names, shapes, attributes and values read back with the C API") {
  TempDir tmp;
  const std::string path = tmp / "out.h5";
  const std::size_t n = 5;
  auto h = make_header(n, true);
  auto t = io::Trajectory::create(path, h);
  for (std::int64_t s : {0, 10, 20}) {
    auto fr = make_frame(s, n, h.particle_fields);
    if (s != 10) fr.observables["stress"] = Field{{6}, {1.0 * s, 2.0, 3.0, 4.0, 5.0, 6.0}};
    t.append(fr);
  }
  CHECK(t.committed_frames() == 0);
  t.commit();
  CHECK(t.committed_frames() == 3);

  File f(path);
  {
    hid_t a = H5Aopen_by_name(f.id, "/h5md", "version", H5P_DEFAULT, H5P_DEFAULT);
    REQUIRE(a >= 0);
    int v[2] = {0, 0};
    REQUIRE(H5Aread(a, H5T_NATIVE_INT, v) >= 0);
    H5Aclose(a);
    CHECK(v[0] == 1);
    CHECK(v[1] == 1);
  }
  CHECK(read_str_attr(f.id, "/h5md/creator", "name") == std::vector<std::string>{"stokesian"});
  CHECK(read_str_attr(f.id, "/h5md/creator", "version").size() == 1);
  CHECK(read_str_attr(f.id, "/h5md/author", "name") == std::vector<std::string>{"test"});
  CHECK(read_str_attr(f.id, "/particles/all/box", "boundary") ==
        std::vector<std::string>{"periodic", "periodic", "periodic"});
  {  // periodic boxes: edges per frame (readers such as MDAnalysis need a time-dependent box)
    const std::vector<double> one{10, 0, 0, 0, 12, 0, 0, 0, 14};
    std::vector<double> three;
    for (int k = 0; k < 3; ++k) three.insert(three.end(), one.begin(), one.end());
    CHECK(read_all<double>(f.id, "/particles/all/box/edges/value", H5T_NATIVE_DOUBLE) == three);
  }
  CHECK(read_str_attr(f.id, "/particles/all/stresslet", "components") ==
        std::vector<std::string>{"xx", "xy", "xz", "yy", "yz", "zz"});

  for (const char* q : {"position", "velocity", "angular_velocity", "force", "torque"}) {
    const std::string base = std::string("/particles/all/") + q;
    CHECK(shape(f.id, (base + "/value").c_str()) == std::vector<hsize_t>{3, n, 3});
    CHECK(read_all<std::int64_t>(f.id, (base + "/step").c_str(), H5T_NATIVE_INT64) == std::vector<std::int64_t>{0, 10, 20});
    CHECK(read_all<double>(f.id, (base + "/time").c_str(), H5T_NATIVE_DOUBLE) == std::vector<double>{0.0, 0.1, 0.2});
  }
  CHECK(shape(f.id, "/particles/all/stresslet/value") == std::vector<hsize_t>{3, n, 6});
  CHECK(shape(f.id, "/particles/all/radius/value") == std::vector<hsize_t>{3, n});
  {
    const auto torque = read_all<double>(f.id, "/particles/all/torque/value", H5T_NATIVE_DOUBLE);
    const auto sl = read_all<double>(f.id, "/particles/all/stresslet/value", H5T_NATIVE_DOUBLE);
    const std::int64_t steps[3] = {0, 10, 20};
    std::size_t bad = 0;
    for (int j = 0; j < 3; ++j)
      for (std::size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) bad += torque[(j * n + i) * 3 + c] != datum(steps[j], i, 4, c);
        for (int c = 0; c < 6; ++c) bad += sl[(j * n + i) * 6 + c] != datum(steps[j], i, 5, c);
      }
    CHECK(bad == 0);
  }
  // Observables: scalar every frame, vector only where given.
  CHECK(shape(f.id, "/observables/energy/value") == std::vector<hsize_t>{3});
  CHECK(read_all<double>(f.id, "/observables/energy/value", H5T_NATIVE_DOUBLE) == std::vector<double>{0, 20, 40});
  CHECK(shape(f.id, "/observables/stress/value") == std::vector<hsize_t>{2, 6});
  CHECK(read_all<std::int64_t>(f.id, "/observables/stress/step", H5T_NATIVE_INT64) == std::vector<std::int64_t>{0, 20});
  // Parameters.
  CHECK(read_str_dataset(f.id, "/parameters/stokesian/scene") == h.scene_toml);
  CHECK(read_str_dataset(f.id, "/parameters/stokesian/model") == h.model);
  for (const char* k : {"version", "git", "compiler", "build_type"})
    CHECK(!read_str_dataset(f.id, (std::string("/parameters/stokesian/") + k).c_str()).empty());

  const auto info = io::inspect_trajectory(path);
  CHECK(info.particles == n);
  CHECK(info.frames == 3);
  CHECK(info.last_step == 20);
  CHECK(info.periodic);
  CHECK(info.observables == std::vector<std::string>{"energy", "stress"});

  const auto last = io::read_last_frame(path);
  CHECK(last.step == 20);
  CHECK(last.position[3] == Vec3(datum(20, 3, 0, 0), datum(20, 3, 0, 1), datum(20, 3, 0, 2)));
  CHECK(last.radius[4] == 1.04);
}

TEST_CASE("H5MD layout: open box without edges, absent quantities, sheared periodic box") {
  TempDir tmp;
  const std::size_t n = 3;
  SUBCASE("open box, positions and velocities only") {
    auto h = make_header(n, false);
    h.particle_fields = fields_of(true, false, false, false, false);
    auto t = io::Trajectory::create(tmp / "a.h5", h);
    t.append(make_frame(1, n, h.particle_fields));
    t.commit();
    File f(tmp / "a.h5");
    CHECK(read_str_attr(f.id, "/particles/all/box", "boundary") == std::vector<std::string>{"none", "none", "none"});
    CHECK(!exists_link(f.id, "/particles/all/box/edges"));
    CHECK(exists_link(f.id, "/particles/all/velocity"));
    for (const char* q : {"/particles/all/angular_velocity", "/particles/all/force", "/particles/all/torque",
                          "/particles/all/stresslet"})
      CHECK(!exists_link(f.id, q));
    const auto info = io::inspect_trajectory(tmp / "a.h5");
    CHECK(!info.records("force"));
    CHECK(info.records("velocity"));
  }
  SUBCASE("Lees-Edwards: triclinic edges per frame, clock shared with position") {
    auto h = make_header(n, true, true);
    auto t = io::Trajectory::create(tmp / "b.h5", h);
    t.append(make_frame(0, n, h.particle_fields));
    t.append(make_frame(50, n, h.particle_fields));
    t.commit();
    File f(tmp / "b.h5");
    CHECK(shape(f.id, "/particles/all/box/edges/value") == std::vector<hsize_t>{2, 3, 3});
    const auto e = read_all<double>(f.id, "/particles/all/box/edges/value", H5T_NATIVE_DOUBLE);
    CHECK(e[9 + 3] == doctest::Approx(0.05 * 12.0));  // frame 1, row b, x: strain * Ly
    CHECK(e[9 + 4] == 12.0);
    CHECK(read_all<std::int64_t>(f.id, "/particles/all/box/edges/step", H5T_NATIVE_INT64) ==
          std::vector<std::int64_t>{0, 50});
  }
}

TEST_CASE("commit and resume: the trajectory keeps exactly the frames up to the checkpoint") {
  TempDir tmp;
  const std::string path = tmp / "run.h5";
  const std::size_t n = 4;
  const auto h = make_header(n, false);
  {
    auto out = io::RunOutput::start(path, h);
    for (std::int64_t s = 0; s <= 20; s += 5) out.record(make_frame(s, n, h.particle_fields));
    out.checkpoint(make_state(n, 20), {{"accumulated_stress", 0.125}}, {{"note", "x"}});
    for (std::int64_t s = 25; s <= 30; s += 5) out.record(make_frame(s, n, h.particle_fields));
    out.trajectory().commit();  // frames beyond the checkpoint reach the file
    CHECK(io::inspect_trajectory(path).last_step == 30);
  }
  io::Checkpoint ck;
  auto out = io::RunOutput::resume(path, h, ck);
  CHECK(ck.state.step == 20);
  CHECK(ck.values.at("accumulated_stress") == 0.125);
  CHECK(ck.strings.at("note") == "x");
  CHECK(ck.trajectory_frames == 5);
  CHECK(verify_frames(path, n, 5) == std::vector<std::int64_t>{0, 5, 10, 15, 20});
  {
    File f(path);
    CHECK(read_all<double>(f.id, "/observables/energy/value", H5T_NATIVE_DOUBLE).size() == 5);
  }
  // The shadow was recreated: the run goes on appending through it.
  for (std::int64_t s = 25; s <= 40; s += 5) out.record(make_frame(s, n, h.particle_fields));
  out.checkpoint(make_state(n, 40));
  CHECK(verify_frames(path, n, 5) == std::vector<std::int64_t>{0, 5, 10, 15, 20, 25, 30, 35, 40});
  CHECK(io::inspect_trajectory(out.trajectory().shadow_path()).frames == 5);  // lags one commit

  SUBCASE("a frame after the checkpointed state is refused") {
    out.record(make_frame(45, n, h.particle_fields));
    CHECK_THROWS_AS(out.checkpoint(make_state(n, 44)), IoError);
  }
  SUBCASE("steps must increase") { CHECK_THROWS_AS(out.record(make_frame(40, n, h.particle_fields)), IoError); }
}

TEST_CASE("a full frame buffer is committed early; resume still truncates to the checkpoint") {
  TempDir tmp;
  const std::string path = tmp / "big.h5";
  const std::size_t n = 10;
  const auto h = make_header(n, false);
  auto out = io::RunOutput::start(path, h);
  // One frame: 10 x (5 x 3 + 6 + 1) doubles = 1760 bytes; a 4000-byte budget commits every 3rd.
  out.trajectory().max_pending_bytes = 4000;
  out.record(make_frame(1, n, h.particle_fields));
  out.checkpoint(make_state(n, 1));
  for (std::int64_t s = 2; s <= 7; ++s) out.record(make_frame(s, n, h.particle_fields));
  CHECK(out.trajectory().committed_frames() == 7);
  CHECK(out.trajectory().pending_frames() == 0);
  CHECK(verify_frames(path, n).size() == 7);
  io::Checkpoint ck;
  io::RunOutput::resume(path, h, ck);
  CHECK(verify_frames(path, n) == std::vector<std::int64_t>{1});
}

TEST_CASE("resume repairs a missing or damaged shadow and refuses inconsistent inputs") {
  TempDir tmp;
  const std::string path = tmp / "run.h5";
  const std::size_t n = 3;
  const auto h = make_header(n, true);
  {
    auto out = io::RunOutput::start(path, h);
    for (std::int64_t s = 1; s <= 6; ++s) {
      out.record(make_frame(s, n, h.particle_fields));
      if (s % 2 == 0) out.checkpoint(make_state(n, s));
    }
  }
  io::Checkpoint ck;
  SUBCASE("shadow overwritten with garbage, then the next commit rebuilds it") {
    { std::ofstream(path + ".shadow") << "not an HDF5 file"; }
    auto out = io::RunOutput::resume(path, h, ck);
    { std::ofstream(path + ".shadow") << "garbage again"; }
    out.record(make_frame(7, n, h.particle_fields));
    out.checkpoint(make_state(n, 7));
    CHECK(verify_frames(path, n).back() == 7);
    out.record(make_frame(8, n, h.particle_fields));
    out.checkpoint(make_state(n, 8));
    CHECK(verify_frames(path, n).size() == 8);
  }
  SUBCASE("trajectory missing: rebuilt from the shadow when it is complete") {
    { auto out = io::RunOutput::resume(path, h, ck); }  // afterwards shadow == trajectory
    fs::remove(path);
    auto out = io::RunOutput::resume(path, h, ck);
    CHECK(verify_frames(path, n).size() == 6);
  }
  SUBCASE("trajectory missing and shadow one segment behind: refused") {
    fs::remove(path);
    try {
      io::RunOutput::resume(path, h, ck);
      FAIL("resume should refuse");
    } catch (const IoError& e) {
      CHECK(std::string(e.what()).find("inconsistent") != std::string::npos);
      CHECK(std::string(e.what()).find(path) != std::string::npos);
    }
  }
  SUBCASE("different particle number") {
    auto h2 = make_header(n + 1, true);
    CHECK_THROWS_WITH_AS(io::RunOutput::resume(path, h2, ck), has("particles"), IoError);
  }
  SUBCASE("different scene") {
    auto h2 = h;
    h2.scene_toml += "# edited\n";
    CHECK_THROWS_WITH_AS(io::RunOutput::resume(path, h2, ck), has("scene"), IoError);
  }
  SUBCASE("checkpoint from another trajectory (frame count)") {
    auto c = io::read_checkpoint(io::checkpoint_path(path));
    c.trajectory_frames += 1;
    io::write_checkpoint(io::checkpoint_path(path), c);
    CHECK_THROWS_WITH_AS(io::RunOutput::resume(path, h, ck), has("inconsistent"), IoError);
    CHECK(verify_frames(path, n).size() == 6);  // the refused resume left the file alone
  }
  SUBCASE("no checkpoint") {
    fs::remove(io::checkpoint_path(path));
    CHECK_THROWS_WITH_AS(io::RunOutput::resume(path, h, ck), has("no checkpoint"), IoError);
  }
}

// The file-system states a kill can leave inside commit(), built by hand: resume must give back
// exactly the checkpointed frames from each of them.
TEST_CASE("resume from every intermediate state of the commit protocol") {
  TempDir tmp;
  const std::string P = tmp / "run.h5", S = P + ".shadow", old = P + ".old";
  const std::size_t n = 3;
  const auto h = make_header(n, false);
  {
    auto out = io::RunOutput::start(P, h);
    for (std::int64_t s = 1; s <= 9; ++s) {
      out.record(make_frame(s, n, h.particle_fields));
      if (s == 6) out.checkpoint(make_state(n, 6));
    }
    out.trajectory().commit();  // P: steps 1..9, S: 1..6, checkpoint: step 6
  }
  REQUIRE(io::inspect_trajectory(P).frames == 9);
  REQUIRE(io::inspect_trajectory(S).frames == 6);
  SUBCASE("killed after link(P, P.old): P old, P.old = P, S new and complete") {
    fs::rename(P, tmp / "new");
    fs::rename(S, P);
    fs::create_hard_link(P, old);
    fs::rename(tmp / "new", S);
  }
  SUBCASE("killed after rename(S, P): P new, P.old old, no shadow") { fs::rename(S, old); }
  SUBCASE("killed while appending to the shadow: S torn") { fs::resize_file(S, fs::file_size(S) / 2); }
  SUBCASE("killed while writing the checkpoint: temp checkpoint half written") {
    std::ofstream(io::checkpoint_path(P) + ".tmp") << "STKCKPT1 partial";
  }
  io::Checkpoint ck;
  auto out = io::RunOutput::resume(P, h, ck);
  CHECK(ck.state.step == 6);
  CHECK(verify_frames(P, n) == std::vector<std::int64_t>{1, 2, 3, 4, 5, 6});
  CHECK(!fs::exists(old));
  CHECK(io::inspect_trajectory(S).frames == 6);
  out.record(make_frame(7, n, h.particle_fields));
  out.checkpoint(make_state(n, 7));
  CHECK(verify_frames(P, n).back() == 7);
}

// A user peeking at the trajectory (another process holding it open, with HDF5's file lock) must
// not stop the run: after the swap that process holds the shadow's inode, so the writer replaces
// the shadow by a fresh copy instead of writing into it.
TEST_CASE("a reader holding the trajectory open does not block commits") {
  TempDir tmp;
  const std::string P = tmp / "peek.h5";
  const std::size_t n = 3;
  const auto h = make_header(n, false);
  auto out = io::RunOutput::start(P, h);
  out.record(make_frame(1, n, h.particle_fields));
  out.checkpoint(make_state(n, 1));
  int fds[2];
  REQUIRE(pipe(fds) == 0);
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const hid_t f = H5Fopen(P.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    const char ok = f >= 0 ? 'y' : 'n';
    if (write(fds[1], &ok, 1) != 1) _exit(2);
    pause();
    _exit(0);
  }
  char ok = 0;
  REQUIRE(read(fds[0], &ok, 1) == 1);
  CHECK(ok == 'y');
  for (std::int64_t s = 2; s <= 5; ++s) {
    out.record(make_frame(s, n, h.particle_fields));
    CHECK_NOTHROW(out.checkpoint(make_state(n, s)));
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  close(fds[0]);
  close(fds[1]);
  CHECK(verify_frames(P, n) == std::vector<std::int64_t>{1, 2, 3, 4, 5});
}

// A child process resumes, writes and checkpoints in a loop and is killed with SIGKILL after a
// random (seeded) delay; the next child resumes from whatever it left, so kills also land inside
// resume. After every kill the visible trajectory must open and pass the consistency check, and
// every frame must carry its own step's data. Where the kills land depends on timing; the
// invariants checked do not.
TEST_CASE("SIGKILL at random moments never corrupts the trajectory, and resume always works") {
  TempDir tmp;
  const std::string path = tmp / "kill.h5";
  const std::size_t n = 200;  // ~35 KB per frame: commits take long enough to be hit mid-way
  const auto h = make_header(n, true);
  std::mt19937_64 rng(20261121);
  std::uniform_int_distribution<int> delay_ms(2, 80);
  const int kills = 24;
  {
    // The run starts here, so that every child (however slowly it starts) has a checkpoint.
    auto out = io::RunOutput::start(path, h);
    out.record(make_frame(0, n, h.particle_fields));
    out.checkpoint(make_state(n, 0));
  }
  int with_checkpoint = 0, total_frames_seen = 0, left_old = 0, left_tmp = 0, left_ckpt_tmp = 0, shadow_damaged = 0;
  for (int round = 0; round < kills; ++round) {
    const pid_t pid = fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      try {
        io::Checkpoint ck;
        std::optional<io::RunOutput> out;
        out.emplace(io::RunOutput::resume(path, h, ck));
        std::int64_t step = ck.state.step;
        for (;;) {
          ++step;
          out->record(make_frame(step, n, h.particle_fields));
          if (step % 3 == 0) out->checkpoint(make_state(n, step));
        }
      } catch (const std::exception& e) {
        std::fprintf(stderr, "child: %s\n", e.what());
        _exit(3);
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    REQUIRE_MESSAGE(WIFSIGNALED(status), "child stopped by itself in round " << round);

    // Where the kill landed, from what it left behind (diagnostic only).
    if (fs::exists(path + ".old")) ++left_old;
    if (fs::exists(path + ".tmp") || fs::exists(path + ".shadow.tmp") || fs::exists(path + ".tmp.tmp")) ++left_tmp;
    if (fs::exists(io::checkpoint_path(path) + ".tmp")) ++left_ckpt_tmp;
    try {
      io::inspect_trajectory(path + ".shadow");
    } catch (const IoError&) {
      ++shadow_damaged;
    }
    if (fs::exists(path)) {
      io::TrajectoryInfo info;
      CHECK_NOTHROW(info = io::inspect_trajectory(path));
      const auto steps = verify_frames(path, n);
      total_frames_seen += static_cast<int>(steps.size());
      if (fs::exists(io::checkpoint_path(path))) {
        ++with_checkpoint;
        const auto ck = io::read_checkpoint(io::checkpoint_path(path));
        CHECK(ck.trajectory_frames <= info.frames);
        CHECK(ck.state.step % 3 == 0);
      }
    }
  }
  MESSAGE("kills: " << kills << ", with a checkpoint present: " << with_checkpoint
                    << ", frames seen in total: " << total_frames_seen << "; left behind: P.old " << left_old
                    << ", temp copies " << left_tmp << ", checkpoint temp " << left_ckpt_tmp
                    << ", shadow unreadable " << shadow_damaged);
  CHECK(with_checkpoint == kills);

  io::Checkpoint ck;
  auto out = io::RunOutput::resume(path, h, ck);
  const auto steps = verify_frames(path, n);
  REQUIRE(!steps.empty());
  CHECK(steps.front() == 0);
  CHECK(steps.back() == ck.state.step);
  CHECK(static_cast<std::int64_t>(steps.size()) == ck.trajectory_frames);
  CHECK(ck.state.position[7] == make_state(n, ck.state.step).position[7]);
  out.record(make_frame(ck.state.step + 1, n, h.particle_fields));
  out.checkpoint(make_state(n, ck.state.step + 1));
  CHECK(verify_frames(path, n).back() == ck.state.step + 1);
}

TEST_CASE("checkpoint round trip is bit-exact; damage is detected") {
  TempDir tmp;
  const std::string path = tmp / "c.ckpt";
  io::Checkpoint c;
  c.state = make_state(7, 123);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  for (auto& x : c.state.position) x = Vec3(u(rng), u(rng), u(rng));
  c.state.position[0].x() = 4.9e-324;  // denormal
  c.state.position[0].y() = -0.0;
  c.state.time = 0.1 + 0.2;
  c.state.dt = std::nextafter(1e-3, 1.0);
  c.state.domain.kind = Domain::Kind::periodic;
  c.state.domain.box = Vec3(u(rng), u(rng), u(rng));
  c.state.domain.shear_strain = u(rng);
  c.state.rng_state = std::string("mt 1 2 3\n\0binary", 16);
  c.scene_toml = "[x]\ny = 1\n";
  c.model = "far field";
  c.trajectory_frames = 42;
  c.values = {{"a", u(rng)}, {"b", std::numeric_limits<double>::infinity()}};
  c.strings = {{"k", "v w"}};
  io::write_checkpoint(path, c);
  const auto r = io::read_checkpoint(path);
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  std::size_t bad = 0;
  for (std::size_t i = 0; i < 7; ++i) {
    for (int k = 0; k < 3; ++k) bad += !same(r.state.position[i][k], c.state.position[i][k]);
    bad += !same(r.state.radius[i], c.state.radius[i]);
    bad += r.state.fixed[i] != c.state.fixed[i];
  }
  CHECK(bad == 0);
  CHECK(same(r.state.time, c.state.time));
  CHECK(same(r.state.dt, c.state.dt));
  CHECK(r.state.step == 123);
  CHECK(r.state.domain.kind == Domain::Kind::periodic);
  CHECK(r.state.domain.box == c.state.domain.box);
  CHECK(same(r.state.domain.shear_strain, c.state.domain.shear_strain));
  CHECK(r.state.rng_state == c.state.rng_state);
  CHECK(r.scene_toml == c.scene_toml);
  CHECK(r.model == c.model);
  CHECK(r.trajectory_frames == 42);
  CHECK(r.values.size() == 2);
  CHECK(same(r.values.at("a"), c.values.at("a")));
  CHECK(std::isinf(r.values.at("b")));
  CHECK(r.strings == c.strings);
  CHECK(!fs::exists(path + ".tmp"));

  std::string bytes;
  {
    std::ifstream is(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(is), {});
  }
  SUBCASE("one flipped bit") {
    bytes[bytes.size() / 2] ^= 0x10;
    std::ofstream(path, std::ios::binary) << bytes;
    CHECK_THROWS_WITH_AS(io::read_checkpoint(path), has("checksum"), IoError);
  }
  SUBCASE("truncated") {
    std::ofstream(path, std::ios::binary) << bytes.substr(0, bytes.size() - 5);
    CHECK_THROWS_WITH_AS(io::read_checkpoint(path), has(path), IoError);
  }
}

TEST_CASE("extended XYZ: write and read back, lattice with Lees-Edwards strain, resume truncation") {
  TempDir tmp;
  const std::string path = tmp / "t.xyz";
  Domain dom;
  dom.kind = Domain::Kind::periodic;
  dom.box = Vec3(10, 12, 14);
  const std::size_t n = 4;
  const auto q = fields_of();
  {
    io::XyzWriter w(path, dom, {"W", "P", "P", "P"});
    for (std::int64_t s : {0, 10, 20}) {
      auto f = make_frame(s, n, q);
      f.particles["position"].values[3] = 1.0 / 3.0;
      w.write(f);
    }
  }
  auto frames = io::read_xyz(path);
  REQUIRE(frames.size() == 3);
  CHECK(frames[2].step == 20);
  CHECK(frames[2].time == 0.2);
  CHECK(frames[0].species == std::vector<std::string>{"W", "P", "P", "P"});
  CHECK(frames[1].position[1].x() == 1.0 / 3.0);  // 17 digits: exact
  CHECK(frames[1].position[2] == Vec3(datum(10, 2, 0, 0), datum(10, 2, 0, 1), datum(10, 2, 0, 2)));
  CHECK(frames[1].radius[3] == 1.03);
  REQUIRE(frames[2].lattice.has_value());
  CHECK((*frames[2].lattice)(1, 0) == doctest::Approx(0.02 * 12.0));
  CHECK((*frames[2].lattice)(2, 2) == 14.0);

  // Resume after a checkpoint at step 10: frame 20 goes, new frames follow.
  {
    io::XyzWriter w(path, dom, {}, std::int64_t{10});
    w.write(make_frame(11, n, q));
  }
  frames = io::read_xyz(path);
  REQUIRE(frames.size() == 3);
  CHECK(frames[2].step == 11);

  // Plain XYZ (species x y z radius) is accepted too.
  { std::ofstream(tmp / "plain.xyz") << "2\nhello\nA 0 0 0 1.5\nB 1 2 3 2.5\n"; }
  const auto plain = io::read_xyz(tmp / "plain.xyz");
  CHECK(plain[0].radius == std::vector<double>{1.5, 2.5});
  CHECK(plain[0].position[1] == Vec3(1, 2, 3));
}

TEST_CASE("errors name the file and the problem") {
  TempDir tmp;
  const std::string missing = tmp / "nope.h5";
  CHECK_THROWS_WITH_AS(io::read_last_frame(missing), has(missing + ": file does not exist"), IoError);
  CHECK_THROWS_WITH_AS(io::read_checkpoint(missing), has(missing), IoError);
  CHECK_THROWS_WITH_AS(io::read_xyz(missing), has(missing), IoError);

  const std::string text = tmp / "text.h5";
  { std::ofstream(text) << "plain text"; }
  CHECK_THROWS_WITH_AS(io::read_last_frame(text), has("cannot open as HDF5"), IoError);

  // An HDF5 file with positions but no radius dataset.
  const std::string partial = tmp / "partial.h5";
  {
    auto h = make_header(2, false);
    auto t = io::Trajectory::create(partial, h);
    t.append(make_frame(3, 2, h.particle_fields));
    t.commit();
    hid_t f = H5Fopen(partial.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    REQUIRE(f >= 0);
    REQUIRE(H5Ldelete(f, "/particles/all/radius", H5P_DEFAULT) >= 0);
    H5Fclose(f);
  }
  CHECK_THROWS_WITH_AS(io::read_last_frame(partial),
                       has(partial + ": missing dataset /particles/all/radius/value"), IoError);
  CHECK_THROWS_WITH_AS(io::inspect_trajectory(partial), has("radius"), IoError);

  // An empty trajectory has no last frame.
  const std::string empty = tmp / "empty.h5";
  io::Trajectory::create(empty, make_header(2, false));
  CHECK_THROWS_WITH_AS(io::read_last_frame(empty), has("holds no frames"), IoError);

  // XYZ errors carry file:line.
  const std::string bad = tmp / "bad.xyz";
  { std::ofstream(bad) << "2\nProperties=species:S:1:pos:R:3:radius:R:1\nA 0 0 0 1\nB 1 x 3 1\n"; }
  CHECK_THROWS_WITH_AS(io::read_xyz(bad), has(bad + ":4: cannot read a coordinate"), IoError);
  { std::ofstream(bad) << "3\ncomment\nA 0 0 0\n"; }
  CHECK_THROWS_WITH_AS(io::read_xyz(bad), has(bad + ":4: file ends after 1 of 3"), IoError);
  { std::ofstream(bad) << "2\nProperties=species:S:1:radius:R:1\nA 1\nB 1\n"; }
  CHECK_THROWS_WITH_AS(io::read_xyz(bad), has("no pos:R:3"), IoError);

  // Frames with the wrong particle count are refused at append time.
  auto h = make_header(3, false);
  auto t = io::Trajectory::create(tmp / "x.h5", h);
  CHECK_THROWS_WITH_AS(t.append(make_frame(0, 2, h.particle_fields)), has("2 position entries for 3"), IoError);
}
