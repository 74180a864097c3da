// Outputs that open in the tools users have: H5MD unit attributes and MDAnalysis, image counts
// (unwrapped trajectories of periodic runs), integer counts, the author, the extended-XYZ export
// beside the trajectory, the files a run leaves behind, resume messages that name the changed
// key, and docs/output.md listing exactly the observables and elements runs write.
//
// The Python checks (tests/check_outputs.py) run with /usr/bin/python3, which has h5py and
// MDAnalysis (scripts/install-deps.sh).
#include <doctest/doctest.h>

#include "engine/app/run.hpp"
#include "engine/core/errors.hpp"
#include "engine/core/state.hpp"
#include "io/checkpoint.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"
#include "io/xyz.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace stokesian;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() / ("stokesian_outputs_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

// Eight spheres in a periodic cube of side 6, free draining, Brownian (D = 1/(6 pi) per unit
// time), large steps so that particles cross the box faces many times.
std::string brownian_box(long steps, const std::string& extra_output = "") {
  return R"([domain]
kind = "periodic"
box = [6.0, 6.0, 6.0]
[fluid]
kT = 1.0
[particles]
positions = [[1,1,1],[4,1,1],[1,4,1],[1,1,4],[4,4,1],[4,1,4],[1,4,4],[4,4,4]]
radius = 1.0
[hydrodynamics]
model = "free_draining"
[brownian]
seed = 11
[time]
dt = 1.0
steps = )" + std::to_string(steps) +
         R"(
integrator = "euler"
[output]
every = 1
checkpoint_every = 50
)" + extra_output;
}

long run_scene(const std::string& text, const std::string& out, bool resume = false, long max_steps = -1) {
  Simulation sim(io::parse_scene(text, "test scene"));
  app::RunOptions opt;
  opt.out = out;
  opt.quiet = true;
  opt.resume = resume;
  opt.max_steps = max_steps;
  return app::run(sim, opt);
}

int python_check(const std::string& args) {
  const std::string cmd = std::string("/usr/bin/python3 ") + STOKESIAN_SOURCE_DIR + "/tests/check_outputs.py " + args;
  return std::system(cmd.c_str());
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Names in the first column of the markdown table that follows `heading` in docs/output.md.
std::set<std::string> documented(const std::string& heading) {
  std::istringstream doc(read_text(std::string(STOKESIAN_SOURCE_DIR) + "/docs/output.md"));
  std::set<std::string> names;
  bool inside = false;
  const std::regex row(R"(^\|\s*`([A-Za-z0-9_/]+)`\s*\|)");
  for (std::string line; std::getline(doc, line);) {
    if (line.rfind("#", 0) == 0) {
      if (inside) break;
      inside = line == heading;
      continue;
    }
    std::smatch m;
    if (inside && std::regex_search(line, m, row)) names.insert(m[1]);
  }
  return names;
}

}  // namespace

TEST_CASE("H5MD units and MDAnalysis: positions, box, time and units read back with h5py and MDAnalysis") {
  TempDir tmp;
  const std::string out = tmp / "run.h5";
  run_scene(brownian_box(20, "author = \"Jane Doe\"\n"), out);
  // Units on every value and time dataset; MDAnalysis (tools/stokesian_mda.py) and h5py agree.
  CHECK(python_check("mdanalysis " + out + " \"Jane Doe\"") == 0);
}

TEST_CASE("author: [output] author, default the login name") {
  TempDir tmp;
  const std::string out = tmp / "run.h5";
  run_scene(brownian_box(2), out);
  CHECK(app::default_author() != "");
  CHECK(python_check("author " + out + " \"" + app::default_author() + "\"") == 0);
  CHECK_THROWS_AS(io::parse_scene(brownian_box(2, "author = 3\n"), "s"), ConfigError);
}

TEST_CASE("periodic Brownian run: image counts give a continuous unwrapped trajectory with MSD = 6 D t") {
  TempDir tmp;
  const std::string out = tmp / "run.h5";
  run_scene(brownian_box(600), out);
  // D = kT / (6 pi mu a) for free-draining spheres of radius 1 (Stokes-Einstein).
  CHECK(python_check("msd " + out + " " + std::to_string(1.0 / (6.0 * M_PI))) == 0);
}

TEST_CASE("tools/stokesian_msd.py: free-draining Brownian spheres in a slit diffuse with D0 in every bin, walls left out") {
  TempDir tmp;
  const std::string out = tmp / "slit.h5";
  run_scene(R"([domain]
kind = "periodic"
box = [16.4, 10.05, 16.4]
[fluid]
kT = 1.0
[walls]
kind = "slit"
height = 6.0
[particles]
generate = "random"
volume_fraction = 0.1
seed = 3
[hydrodynamics]
model = "free_draining"
[brownian]
seed = 5
[time]
dt = 0.05
steps = 400
integrator = "euler"
[output]
every = 1
checkpoint_every = 400
)",
            out);
  CHECK(python_check("msd_tool " + out) == 0);
}

TEST_CASE("image counts: kept in checkpoints, resumed runs write the uninterrupted run's images") {
  TempDir tmp;
  const std::string whole = tmp / "whole.h5", parts = tmp / "parts.h5";
  run_scene(brownian_box(200), whole);
  run_scene(brownian_box(200), parts, false, 120);
  const io::Checkpoint c = io::read_checkpoint(io::checkpoint_path(parts));
  REQUIRE(c.state.image.size() == 8);
  long crossings = 0;
  for (const auto& n : c.state.image) crossings += std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]);
  CHECK(crossings > 0);
  run_scene(brownian_box(200), parts, true);
  CHECK(python_check("same " + whole + " " + parts + " particles/all/image/value particles/all/position/value") == 0);
}

TEST_CASE("Lees-Edwards: unwrapped positions follow the unbounded sheared trajectory through strain reductions") {
  // One particle with a constant peculiar velocity v in simple shear u = rate * y e_x, advanced
  // by explicit Euler in the box (velocity from the wrapped y, as the engine does). The unwrapped
  // position must follow Euler in the unbounded fluid: u_{n+1} = u_n + (rate u_y + v) dt.
  State s;
  s.domain.kind = Domain::Kind::periodic;
  s.domain.box = Vec3(4.0, 5.0, 6.0);
  s.position = {Vec3(1.0, 2.0, 3.0)};
  s.radius = {1.0};
  s.fixed = {0};
  const double rate = 0.7, dt = 0.05;
  const Vec3 v(0.3, 1.1, -0.4);
  Vec3 u = s.position[0];
  int reductions = 0;
  for (int n = 0; n < 2000; ++n) {
    const Vec3 step = (Vec3(rate * s.position[0].y(), 0, 0) + v) * dt;
    u += (Vec3(rate * u.y(), 0, 0) + v) * dt;
    s.position[0] += step;
    const double unreduced = s.domain.shear_strain + rate * dt;
    s.domain = s.domain.strained_by(rate * dt);
    reductions += std::abs(unreduced - s.domain.shear_strain) > 0.5;
    wrap_positions(s, unreduced);
    const Vec3 x = s.position[0];
    REQUIRE(x.y() >= 0.0);
    REQUIRE(x.y() < 5.0);
    REQUIRE((unwrapped(s, 0) - u).norm() < 1e-9 * (1.0 + u.norm()));
  }
  CHECK(reductions > 2);
  CHECK(std::abs(s.image[0][1]) > 5);
}

TEST_CASE("checkpoint: image counts round trip; checkpoints without them (0.1.0) still read") {
  TempDir tmp;
  io::Checkpoint c;
  c.state.position = {Vec3(1, 2, 3), Vec3(4, 5, 6)};
  c.state.radius = {1.0, 2.0};
  c.state.fixed = {0, 1};
  c.state.image = {{1, -2, 3}, {-2147483647, 0, 7}};
  io::write_checkpoint(tmp / "c.ckpt", c);
  CHECK(io::read_checkpoint(tmp / "c.ckpt").state.image == c.state.image);
  const auto legacy = io::read_checkpoint(std::string(STOKESIAN_SOURCE_DIR) + "/tests/data/legacy/legacy_sheared.h5.ckpt");
  CHECK(legacy.state.image.empty());
}

TEST_CASE("counts are integers in the file: overlaps, krylov_iterations, image") {
  TempDir tmp;
  const std::string out = tmp / "run.h5";
  run_scene(brownian_box(3), out);
  CHECK(python_check("integers " + out + " observables/overlaps/value observables/krylov_iterations/value "
                     "particles/all/image/value") == 0);
}

TEST_CASE("XYZ export: beside --out, species by mobility and size, columns OVITO maps") {
  TempDir tmp;
  fs::create_directories(tmp.path / "results");
  const std::string scene = R"([domain]
kind = "periodic"
box = [12.0, 12.0, 12.0]
[particles]
positions = [[2,2,2],[6,2,2],[2,6,2],[6,6,6]]
radii = [1.0, 1.5, 1.0, 1.0]
fixed = [false, false, false, true]
[forces]
external_force = [0.0, 0.0, -1.0]
[hydrodynamics]
model = "free_draining"
[time]
dt = 0.1
steps = 3
[output]
record = ["velocity", "force"]
)";
  const std::string out = tmp / "results/run.h5";
  SUBCASE("xyz = true: <out stem>.xyz beside the trajectory") {
    run_scene(scene + "xyz = true\n", out);
    REQUIRE(fs::exists(tmp / "results/run.xyz"));
    const auto frames = io::read_xyz(tmp / "results/run.xyz");
    REQUIRE(frames.size() == 4);
    CHECK(frames[0].species == std::vector<std::string>{"M1", "M2", "M1", "F1"});
    CHECK(frames[3].radius == std::vector<double>{1.0, 1.5, 1.0, 1.0});
    std::ifstream in(tmp / "results/run.xyz");
    std::string count, comment;
    std::getline(in, count);
    std::getline(in, comment);
    CHECK(comment.find("pbc=\"T T T\"") != std::string::npos);
    CHECK(comment.find("Lattice=\"12 0 0 0 12 0 0 0 12\"") != std::string::npos);
    CHECK(comment.find("Properties=species:S:1:pos:R:3:radius:R:1:velo:R:3:forces:R:3 ") != std::string::npos);
    CHECK(comment.find("Time=0 Step=0") != std::string::npos);
  }
  SUBCASE("xyz = \"path\": relative to the folder of --out, not the working directory") {
    fs::create_directories(tmp.path / "results/movie");
    run_scene(scene + "xyz = \"movie/frames.xyz\"\n", out);
    CHECK(fs::exists(tmp / "results/movie/frames.xyz"));
    CHECK(!fs::exists("movie/frames.xyz"));
  }
  SUBCASE("xyz = false / absent: no export") {
    run_scene(scene, out);
    CHECK(!fs::exists(tmp / "results/run.xyz"));
  }
  CHECK(app::xyz_path(io::parse_scene(scene + "xyz = \"a/b.xyz\"\n", "s"), "/data/x/run.h5") == "/data/x/a/b.xyz");
  CHECK(app::xyz_path(io::parse_scene(scene + "xyz = \"/abs/b.xyz\"\n", "s"), "/data/x/run.h5") == "/abs/b.xyz");
  CHECK(app::xyz_path(io::parse_scene(scene + "xyz = true\n", "s"), "run.h5") == "run.xyz");
  CHECK(app::xyz_path(io::parse_scene(scene, "s"), "run.h5").empty());
  CHECK(io::species_labels({1.0, 1.0}, {0, 1}) == std::vector<std::string>{"M", "F"});
}

TEST_CASE("files left behind: a finished run keeps trajectory and checkpoint only; solve writes one file") {
  TempDir tmp;
  const std::string out = tmp / "run.h5";
  run_scene(brownian_box(100), out, false, 60);  // interrupted: the working copy stays for --resume
  CHECK(fs::exists(out + ".shadow"));
  CHECK(fs::exists(out + ".ckpt"));
  run_scene(brownian_box(100), out, true);
  CHECK(!fs::exists(out + ".shadow"));
  CHECK(fs::exists(out + ".ckpt"));
  CHECK(io::inspect_trajectory(out).last_step == 100);
  std::set<std::string> left;
  for (const auto& e : fs::directory_iterator(tmp.path)) left.insert(e.path().filename().string());
  CHECK(left == std::set<std::string>{"run.h5", "run.h5.ckpt"});
  // Resuming the finished run again is a no-op that leaves the same files.
  run_scene(brownian_box(100), out, true);
  CHECK(!fs::exists(out + ".shadow"));

  const std::string s = tmp / "solve.h5";
  Simulation sim(io::parse_scene(brownian_box(1), "s"));
  app::solve(sim, s);
  CHECK(io::inspect_trajectory(s).frames == 1);
  CHECK(!fs::exists(s + ".shadow"));
  CHECK(!fs::exists(s + ".ckpt"));
  CHECK(!fs::exists(s + ".tmp"));
}

TEST_CASE("resume after editing the scene names the changed keys with both values") {
  TempDir tmp;
  const std::string out = tmp / "run.h5";
  run_scene(brownian_box(100), out, false, 60);
  std::string edited = brownian_box(100);
  edited.replace(edited.find("dt = 1.0"), 8, "dt = 0.5");
  edited.replace(edited.find("seed = 11"), 9, "seed = 12");
  try {
    run_scene(edited, out, true);
    FAIL("resume accepted an edited scene");
  } catch (const IoError& e) {
    const std::string msg = e.what();
    MESSAGE(msg);
    CHECK(msg.find("[time] dt: 1.0 -> 0.5") != std::string::npos);
    CHECK(msg.find("[brownian] seed: 11 -> 12") != std::string::npos);
    CHECK(msg.find("steps") == std::string::npos);
  }
  CHECK(io::scene_differences(brownian_box(100), brownian_box(100)).empty());
  CHECK(io::scene_differences(brownian_box(100), brownian_box(100) + "\n# a comment\n").empty());
  // Values as a user writes them: the shortest text that reads back as the same double.
  std::string tenth = brownian_box(100);
  tenth.replace(tenth.find("dt = 1.0"), 8, "dt = 0.1");
  const auto d = io::scene_differences(brownian_box(100), tenth);
  REQUIRE(d.size() == 1);
  CHECK(d[0] == "[time] dt: 1.0 -> 0.1");
}

TEST_CASE("docs/output.md lists exactly the observables and per-particle elements runs write") {
  TempDir tmp;
  // Two runs between them write every built-in output: a periodic Brownian F-level run
  // (image) and an FTS Stokesian-dynamics run (angular velocity, torque, stresslet,
  // stresslet_sum, regularised_pairs).
  const std::string fts = R"([particles]
positions = [[0,0,0],[2.5,0,0]]
radius = 1.0
[forces]
external_force = [0.0, 0.0, -1.0]
[hydrodynamics]
model = "stokesian"
moments = "FTS"
[time]
dt = 0.1
steps = 1
)";
  // A sheared Brownian periodic FTS run with a pair force and a fixed particle: every stress part.
  const std::string sheared = R"([fluid]
kT = 1.0
[domain]
kind = "periodic"
box = [10, 10, 10]
[particles]
positions = [[0,0,0],[2.3,0,0],[0,2.4,0.5]]
fixed = [false, false, true]
[[forces.pair]]
kind = "repulsion"
decay = 10.0
[flow]
kind = "simple_shear"
rate = 0.5
[hydrodynamics]
model = "stokesian"
moments = "FTS"
[time]
dt = 0.001
steps = 2
)";
  // A channel: wall_force and pressure_drop_particles; an outline channel with inflow:
  // areal_fraction_sections, the id element and the inflow counts.
  const std::string channel_run = R"([flow]
kind = "poiseuille"
mean_velocity = 1.0
[hydrodynamics]
model = "far_field"
[time]
dt = 0.01
steps = 1
)";
  const std::string channel = R"([domain]
kind = "periodic"
box = [8.2, 10.05, 8.2]
[walls]
kind = "slit"
height = 6.0
[particles]
positions = [[4.0, 5.0, 4.0]]
)" + channel_run;
  const std::string outline = R"([walls]
kind = "outline"
outline = [[0, -5], [30, -5], [30, 5], [0, 5]]
openings = [1, 3]
inlet = 3
[particles]
positions = [[10.0, 0.0, 0.0]]
[inflow]
areal_fraction = 0.1
)" + channel_run;
  // A settling cloud (open domain, gravity): the cloud observables.
  const std::string cloud = R"([particles]
positions = [[0,0,0],[2.5,0,0],[0,3,1],[1,1,4]]
[forces]
gravity = [0.0, 0.0, -1.0]
[hydrodynamics]
model = "far_field"
[time]
dt = 0.1
steps = 1
[output]
cluster_gap = 0.1
)";
  run_scene(cloud, tmp / "f.h5");
  run_scene(outline, tmp / "e.h5");
  run_scene(brownian_box(2), tmp / "a.h5");
  run_scene(fts, tmp / "b.h5");
  run_scene(sheared, tmp / "c.h5");
  run_scene(channel, tmp / "d.h5");
  std::set<std::string> observables, elements;
  for (const std::string& f : {tmp / "a.h5", tmp / "b.h5", tmp / "c.h5", tmp / "d.h5", tmp / "e.h5", tmp / "f.h5"}) {
    const auto info = io::inspect_trajectory(f);
    observables.insert(info.observables.begin(), info.observables.end());
    for (const auto& spec : info.particle_fields) elements.insert(spec.name);
  }
  CHECK(documented("### Observables") == observables);
  CHECK(documented("### Per-particle elements") == elements);
}

TEST_CASE("cloud observables: a uniform sphere, two clouds and stragglers, a torus") {
  TempDir tmp;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Points uniform in a ball of radius R about c (rejection sampling).
  auto ball = [&](std::vector<Vec3>& x, int n, double R, const Vec3& c) {
    while (n > 0) {
      const Vec3 p(u(rng), u(rng), u(rng));
      if (p.squaredNorm() > 1.0) continue;
      x.push_back(c + R * p);
      --n;
    }
  };
  // Tiny spheres (no overlaps), free draining, gravity: the cloud observables are on by default.
  auto observe = [&](const std::vector<Vec3>& x, const std::string& name) {
    std::ostringstream o;
    o.precision(17);
    o << "[particles]\nradius = 0.01\npositions = [";
    for (std::size_t i = 0; i < x.size(); ++i) o << (i ? ", " : "") << "[" << x[i].x() << ", " << x[i].y() << ", " << x[i].z() << "]";
    o << "]\n[forces]\ngravity = [0.0, 0.0, -1.0]\n[hydrodynamics]\nmodel = \"free_draining\"\n[time]\ndt = 0.001\nsteps = 1\n";
    run_scene(o.str(), tmp / name);
    std::map<std::string, std::vector<double>> first;  // each observable's first frame
    for (const auto& s : io::read_observables(tmp / name))
      first[s.name] = std::vector<double>(s.value.begin(), s.value.begin() + long(s.components));
    return first;
  };
  std::vector<Vec3> one;
  const double R = 30.0;
  ball(one, 2000, R, Vec3(5, -3, 100));
  auto ob = observe(one, "one.h5");
  CHECK(ob["cloud_particles"][0] == 2000);
  CHECK(ob["cloud_lost"][0] == 0);
  CHECK(ob["cloud_parts"][0] == 1);
  // Sampling errors for 2000 points: axis share binomial sd 0.0065; radius and gyration ~1 %.
  CHECK(ob["cloud_axis_fraction"][0] == doctest::Approx(1.0 - std::pow(15.0 / 16.0, 1.5)).epsilon(0.25));
  CHECK(ob["cloud_radius"][0] == doctest::Approx(R).epsilon(0.03));
  for (double g : ob["cloud_gyration"]) CHECK(g == doctest::Approx(R * R / 5.0).epsilon(0.08));
  CHECK(ob["cloud_centroid"][2] == doctest::Approx(100.0).epsilon(0.01));
  // Free draining: every sphere falls at g a^2 / (6 pi).
  CHECK(ob["cloud_velocity"][2] == doctest::Approx(-1e-4 / (6.0 * M_PI)).epsilon(1e-9));
  CHECK(ob["mean_velocity"][2] == doctest::Approx(-1e-4 / (6.0 * M_PI)).epsilon(1e-9));

  // Two clouds far apart and three stragglers: two parts, three lost.
  std::vector<Vec3> two;
  ball(two, 600, 20.0, Vec3(0, 0, 0));
  ball(two, 400, 20.0, Vec3(300, 0, 0));
  for (double z : {-200.0, -260.0, -320.0}) two.push_back(Vec3(0, 0, z));
  ob = observe(two, "two.h5");
  CHECK(ob["cloud_parts"][0] == 2);
  CHECK(ob["cloud_lost"][0] == 3);
  CHECK(ob["cloud_particles"][0] == 1000);
  CHECK(ob["cloud_centroid"][0] == doctest::Approx(120.0).epsilon(0.02));  // (600 * 0 + 400 * 300) / 1000

  // A torus (ring radius 20, tube radius 6, axis along gravity): no sphere near the axis.
  std::vector<Vec3> torus;
  std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI);
  while (torus.size() < 2000) {
    const double t = angle(rng);
    const Vec3 p(6.0 * u(rng), 6.0 * u(rng), 6.0 * u(rng));
    if (p.squaredNorm() > 36.0) continue;
    const double rho = 20.0 + p.x();
    torus.push_back(Vec3(rho * std::cos(t), rho * std::sin(t), p.z()));
  }
  ob = observe(torus, "torus.h5");
  CHECK(ob["cloud_parts"][0] == 1);
  CHECK(ob["cloud_axis_fraction"][0] == 0.0);
  const auto& g = ob["cloud_gyration"];  // flattened: two large in-plane values, one small
  CHECK(g[0] == doctest::Approx(g[1]).epsilon(0.1));
  CHECK(g[2] < 0.1 * g[0]);
}
