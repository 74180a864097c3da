// The XYZ export of a run killed with SIGKILL: every frame recorded before a checkpoint must be in
// the file when the checkpoint is written (the writer must not hold frames in a buffer), and a
// resume must drop the frames after the checkpoint even when the kill cut the last one anywhere
// (inside a number, between lines, inside the comment or the count line). Found by
// tests/kill/kill_trials.cpp on configs/brownian_aggregation.toml: a resume exited 4 with
// "k.xyz:390: expected 17 columns, found 3".
#include <doctest/doctest.h>

#include "engine/core/domain.hpp"
#include "engine/core/frame.hpp"
#include "io/xyz.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace stokesian;

namespace {

std::string bytes_of(const fs::path& p) {
  std::ifstream is(p, std::ios::binary);
  std::ostringstream ss;
  ss << is.rdbuf();
  return ss.str();
}

// A frame of n particles with position, radius and velocity; values with 17 significant digits.
Frame frame_at(std::int64_t step, std::size_t n) {
  Frame f;
  f.step = step;
  f.time = 0.001 * double(step);
  std::vector<Vec3> x(n), v(n);
  std::vector<double> a(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = Vec3(double(i) / 3.0 + 1e-3 * double(step), -double(i) / 7.0, 2.0 / (double(i) + 1.0));
    v[i] = Vec3(1.0 / (1.0 + double(step)), 0.1 * double(i), -1.0 / 9.0);
    a[i] = 1.0 + 0.01 * double(i);
  }
  f.set_particles("position", x);
  f.set_particles("velocity", v);
  f.set_particles("radius", a);
  return f;
}

struct TempDir {
  fs::path path;
  TempDir() : path(fs::temp_directory_path() / ("stokesian_xyz_resume_" + std::to_string(getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

}  // namespace

TEST_CASE("XyzWriter: a frame is in the file as soon as it is written, without flush()") {
  // A SIGKILL loses what the process still buffers. The run writes its checkpoint after recording
  // the frames up to it; if those frames were still buffered, a kill just after the checkpoint
  // would lose them for good (the resume continues after the checkpoint).
  TempDir tmp;
  const fs::path p = tmp.path / "t.xyz";
  Domain open;
  io::XyzWriter w(p.string(), open);
  for (std::int64_t s : {0, 10}) {
    w.write(frame_at(s, 5));
    const auto frames = io::read_xyz(p.string());  // another reader, the writer still open
    REQUIRE(frames.size() == std::size_t(s / 10 + 1));
    CHECK(frames.back().step == s);
  }
}

TEST_CASE("XyzWriter resume: frames after the checkpoint and a frame cut anywhere by a kill are dropped") {
  TempDir tmp;
  const fs::path p = tmp.path / "t.xyz";
  Domain box;
  box.kind = Domain::Kind::periodic;
  box.box = Vec3(10, 12, 14);
  const std::size_t n = 3;
  // The uninterrupted export: frames 0, 10, 20, 30, 40; checkpoint at 20.
  std::string full, upto20;
  {
    io::XyzWriter w(p.string(), box);
    for (std::int64_t s = 0; s <= 40; s += 10) {
      w.write(frame_at(s, n));
      if (s == 20) {
        w.flush();
        upto20 = bytes_of(p);
      }
    }
  }
  full = bytes_of(p);
  REQUIRE(full.size() > upto20.size());
  // Every cut at or after the end of frame 20 (every byte of frames 30 and 40, so inside numbers,
  // at line ends, inside the count and comment lines): resume at 20 and write 30 and 40 again.
  for (std::size_t cut = upto20.size(); cut <= full.size(); ++cut) {
    CAPTURE(cut);
    std::ofstream(p, std::ios::binary | std::ios::trunc) << full.substr(0, cut);
    {
      io::XyzWriter w(p.string(), box, {}, std::int64_t{20});
      REQUIRE(bytes_of(p) == upto20);
      w.write(frame_at(30, n));
      w.write(frame_at(40, n));
    }
    REQUIRE(bytes_of(p) == full);
  }
  // A file that is not an export of a run is refused, naming the file and the line.
  std::ofstream(p, std::ios::binary | std::ios::trunc) << "3\nno step here\n";
  CHECK_THROWS_WITH(io::XyzWriter(p.string(), box, {}, std::int64_t{20}),
                    doctest::Contains((p.string() + ":2: the comment line has no Step=").c_str()));
}
