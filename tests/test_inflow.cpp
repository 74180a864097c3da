// Open channels: particles inserted at the inlet and removed at the outlets (issue 17;
// engine/inflow.hpp, docs/channels.md "Open channels").
//
// References, each independent of the code under test:
//   - the flux-weighted distribution along the inlet: the parabolic profile u(s) = 6 U s (1 - s)
//     restricted to the band the centres reach, CDF (F(s) - F(s0)) / (F(s1) - F(s0)), F = 3s^2 - 2s^3
//     (closed form), tested by Kolmogorov-Smirnov;
//   - kinematics of free-draining spheres in plane Poiseuille flow: each moves along its streamline,
//     so centres fed at the rate n_A u(y) dy fill the channel at the uniform number density n_A
//     (steady continuity, d(n u)/dx = 0 with u independent of x): the mean count in a window is n_A
//     times its band area, and half of it lies in the central half of the band;
//   - particle conservation: inserted - removed = present - initial, exactly.
#include <doctest/doctest.h>

#include "engine/app/run.hpp"
#include "engine/inflow.hpp"
#include "engine/model.hpp"
#include "engine/simulation.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"
#include "support/hdf5_read.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

using namespace stokesian;

namespace {

// Straight channel [0, 40] x [0, 10]; inlet at x = 0 (edge 3), outlet at x = 40 (edge 1).
const std::string kStraight = R"(
[walls]
kind = "outline"
outline = [[0, 0], [40, 0], [40, 10], [0, 10]]
openings = [1, 3]
inlet = 3
)";

std::string straight_scene(double phi, const std::string& extra = "") {
  return kStraight + R"([particles]
generate = "random"
count = 1
[inflow]
areal_fraction = )" + std::to_string(phi) + R"(
[flow]
kind = "poiseuille"
mean_velocity = 1.0
[hydrodynamics]
model = "free_draining"
[time]
dt = 0.05
steps = 1
)" + extra;
}

double F(double s) { return 3 * s * s - 2 * s * s * s; }

struct Collect final : OutputSink {
  std::vector<Frame> frames;
  void record(const Frame& f) override { frames.push_back(f); }
  void checkpoint(const State&) override {}
};

}  // namespace

TEST_CASE("inflow: positions along the inlet follow the flux (Kolmogorov-Smirnov, 10^5 draws)") {
  const Scene scene = io::parse_scene(straight_scene(0.2), "inflow.toml");
  const Inflow in(scene);
  const double s0 = 1.1 / 10.0, s1 = 1.0 - s0;  // (radius + min_gap) / width
  // Rate: n_A U w [F]_{s0}^{s1}, n_A = phi / pi (header of engine/inflow.hpp).
  CHECK(in.rate() == doctest::Approx(0.2 / kPi * 1.0 * 10.0 * (F(s1) - F(s0))).epsilon(1e-12));
  Rng rng = RandomStream::for_purpose(5, Purpose::test, 1);
  const int n = 100000;
  std::vector<double> s(n);
  for (double& v : s) v = in.sample_inlet_coordinate(rng);
  std::sort(s.begin(), s.end());
  CHECK(s.front() >= s0);
  CHECK(s.back() <= s1);
  auto cdf = [&](double x) { return (F(x) - F(s0)) / (F(s1) - F(s0)); };
  double d = 0;
  for (int i = 0; i < n; ++i) d = std::max({d, std::abs(cdf(s[i]) - double(i) / n), std::abs(cdf(s[i]) - double(i + 1) / n)});
  const double critical = 1.628 / std::sqrt(double(n));  // p = 0.01
  MESSAGE("KS distance " << d << ", critical " << critical);
  CHECK(d < critical);
  // The test has power: a uniform distribution on the band is 9 critical distances away.
  double du = 0;
  for (int k = 0; k <= 1000; ++k) {
    const double x = s0 + (s1 - s0) * k / 1000.0;
    du = std::max(du, std::abs(cdf(x) - (x - s0) / (s1 - s0)));
  }
  CHECK(du > 9 * critical);
}

TEST_CASE("inflow: free-draining spheres fill a straight channel at the incoming density; counts are conserved") {
  // phi_A = 0.2, 100 000 steps (t = 5000, about 250 transits of the window); frames every 20 steps.
  const double phi = 0.2;
  Scene scene = io::parse_scene(straight_scene(phi), "inflow.toml");
  scene.time.steps = 100000;
  scene.output.every = 20;
  Simulation sim(scene);
  State s = sim.initial_state();
  Collect out;
  RunControl rc;
  rc.quiet = true;
  sim.run(s, out, rc);
  REQUIRE(out.frames.size() > 1000);
  const double n_area = phi / kPi, band_lo = 1.1, band_hi = 8.9, x0 = 10, x1 = 30;
  const double expected = n_area * (x1 - x0) * (band_hi - band_lo);
  // Skip the filling transient (t < 100); block averages over 20 blocks give the standard errors.
  std::vector<double> count, central;
  for (const Frame& f : out.frames) {
    const auto& id = f.particles.at("id").values;
    const auto& x = f.particles.at("position").values;
    const std::int64_t present = std::int64_t(f.scalar("particles_present"));
    long n_present = 0;
    for (std::size_t i = 0; i < id.size(); ++i) n_present += id[i] >= 0 && std::isfinite(x[3 * i]) && i < std::size_t(scene.inflow.capacity);
    CHECK(n_present == present);
    CHECK(std::int64_t(f.scalar("inflow_inserted")) - std::int64_t(f.scalar("inflow_removed")) == present - 1);
    if (f.time < 100) continue;
    double c = 0, m = 0;
    for (std::size_t i = 0; i < std::size_t(scene.inflow.capacity); ++i) {
      if (id[i] < 0 || x[3 * i] < x0 || x[3 * i] >= x1) continue;
      c += 1;
      if (std::abs(x[3 * i + 1] - 5.0) < 0.25 * (band_hi - band_lo)) m += 1;
    }
    count.push_back(c);
    central.push_back(m);
  }
  auto block_mean = [](const std::vector<double>& v, double& se) {
    const int B = 20;
    const std::size_t len = v.size() / B;
    std::vector<double> b(B, 0.0);
    for (int k = 0; k < B; ++k) {
      for (std::size_t i = 0; i < len; ++i) b[std::size_t(k)] += v[std::size_t(k) * len + i];
      b[std::size_t(k)] /= double(len);
    }
    double m = 0, var = 0;
    for (double x : b) m += x / B;
    for (double x : b) var += (x - m) * (x - m) / (B - 1);
    se = std::sqrt(var / B);
    return m;
  };
  double se = 0, se_c = 0;
  const double mean = block_mean(count, se), mean_c = block_mean(central, se_c);
  MESSAGE("mean count in the window " << mean << " +- " << se << ", expected " << expected << "; central half "
                                      << mean_c << " +- " << se_c << ", expected " << expected / 2);
  CHECK(se < 0.03 * expected);  // the comparison has the resolution to see a few per cent
  CHECK(std::abs(mean - expected) < 3 * se);
  CHECK(std::abs(mean_c - expected / 2) < 3 * se_c);
  // A particle whose place is blocked waits a few steps; waiting steps stay a small fraction.
  MESSAGE("steps with a particle waiting: " << out.frames.back().scalar("inflow_deferred") << " of " << scene.time.steps);
  CHECK(out.frames.back().scalar("inflow_deferred") < 0.05 * double(scene.time.steps));
}

TEST_CASE("inflow: a sphere stuck at the inlet does not stop the inflow") {
  // A sphere stuck at the inlet's centre blocks the places |y - 5| < 2r + g, which carry
  // (F(0.71) - F(0.29)) / (F(s1) - F(s0)) = 62 % of the incoming flux. A due particle drawn there
  // waits (2r + g)/u(s) and then passes at a new place (engine/inflow.hpp), so the inflow goes on at
  // its rate. Kinematics by hand: the stuck sphere (slot 0) stays, every other sphere moves with
  // the plane Poiseuille profile; t = 100, about 60 particles due.
  std::string text = straight_scene(0.2);
  text.replace(text.find("generate = \"random\"\ncount = 1"), 29, "positions = [[1.2, 5.0, 0.0]]");
  const Scene scene = io::parse_scene(text, "stuck.toml");
  const Inflow in(scene);
  Simulation sim(scene);
  State st = sim.initial_state();
  const double dt = 0.05;
  for (int n = 0; n < 2000; ++n) {
    st.step = n;
    in.exchange(st, dt, 11);
    for (std::size_t i = 1; i < std::size_t(scene.inflow.capacity); ++i)
      if (st.id[i] >= 0) {
        const double eta = st.position[i].y() / 10.0;
        st.position[i].x() += 6.0 * eta * (1.0 - eta) * dt;
      }
    for (std::size_t i = 1; i < std::size_t(scene.inflow.capacity); ++i)  // nothing placed on the stuck one
      if (st.id[i] >= 0) CHECK((st.position[i] - st.position[0]).norm() >= 2.1 - 1e-9);
  }
  const double due = in.rate() * 2000 * dt;
  MESSAGE("inserted " << st.inflow.inserted << " of " << due << " due; redrawn " << st.inflow.redrawn
                      << ", steps waiting " << st.inflow.deferred);
  CHECK(double(st.inflow.inserted) > 0.85 * due);
  CHECK(double(st.inflow.inserted) <= due + 1.0);
  CHECK(st.inflow.redrawn > 0);
  CHECK(st.id[0] == 0);  // the stuck sphere is still there
}

TEST_CASE("inflow: scene errors name the key") {
  auto refused = [](const std::string& text, const std::string& what) {
    CAPTURE(what);
    try {
      io::parse_scene(text, "bad.toml");
      FAIL("accepted");
    } catch (const std::exception& e) {
      CHECK(std::string(e.what()).find(what) != std::string::npos);
    }
  };
  std::string t = straight_scene(0.2);
  refused(t.replace(t.find("areal_fraction = "), 17, "areal_fraction = 0.7 #"), "[inflow] areal_fraction");
  refused(straight_scene(0.2, "[inflow]\n"), "");  // a second [inflow] table is a TOML error
  std::string r = straight_scene(0.2);
  r.insert(r.find("[flow]"), "radius = 4.9\n");
  refused(r, "[inflow] radius");
  std::string c = straight_scene(0.2);
  c.replace(c.find("count = 1"), 9, "count = 5");
  c.insert(c.find("[flow]"), "capacity = 3\n");
  refused(c, "[inflow] capacity");
  std::string f = straight_scene(0.2);
  f.replace(f.find("mean_velocity = 1.0"), 19, "mean_velocity = 0.0");
  refused(f, "[inflow]");
}

TEST_CASE("inflow: the model is chosen for the most particles present, capacity + walls") {
  // One sphere and the straight channel's walls at the start; 200 slots. The auto solver takes dense
  // SD up to 120 particles in an open domain (engine/model.cpp), so the full channel needs the
  // accelerated solver although the start would fit the dense one; and inserted spheres come within
  // min_gap (0.1 a) of the others, so the level is Stokesian although the start has no close pair.
  std::string text = straight_scene(0.2);
  text.replace(text.find("model = \"free_draining\""), 23, "model = \"auto\"");
  text.insert(text.find("[flow]"), "capacity = 200\n");
  const Scene s = io::parse_scene(text, "open.toml");
  REQUIRE(s.positions.size() < 120);
  const ResolvedModel m = resolve_model(s);
  INFO(m.describe());
  CHECK(m.level == HydroModel::stokesian);
  CHECK(m.solver == "accelerated_sd");
  CHECK(m.describe().find("[inflow]: up to N = " + std::to_string(200 + s.wall_count)) != std::string::npos);
  // Without [inflow] the same start resolves to the far field (no close pair, no pair force).
  std::string closed = text.substr(0, text.find("[inflow]")) + text.substr(text.find("[flow]"));
  const ResolvedModel mc = resolve_model(io::parse_scene(closed, "closed.toml"));
  CHECK(mc.level == HydroModel::far_field);
}

TEST_CASE("inflow: the trajectory keeps every slot (id -1 and NaN when empty); the XYZ export lists the present ones") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("stokesian_inflow_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string text = straight_scene(0.3);
  text.replace(text.find("steps = 1\n"), 10, "steps = 1200\n[output]\nevery = 100\nxyz = true\n");
  Scene scene = io::parse_scene(text, (dir / "s.toml").string());
  Simulation sim(scene);
  app::RunOptions opt;
  opt.out = (dir / "s.h5").string();
  opt.quiet = true;
  app::run(sim, opt);
  const auto info = io::inspect_trajectory(opt.out);
  const std::size_t slots = std::size_t(scene.inflow.capacity) + scene.wall_count;
  CHECK(info.particles == slots);
  const auto id = test::read_doubles(opt.out, "particles/all/id/value");
  const auto x = test::read_doubles(opt.out, "particles/all/position/value");
  const auto present = test::read_doubles(opt.out, "observables/particles_present/value");
  const std::size_t frames = present.size();
  REQUIRE(frames == 13);
  REQUIRE(id.size() == frames * slots);
  std::vector<std::size_t> shown;
  for (std::size_t f = 0; f < frames; ++f) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < slots; ++i) {
      const double v = id[f * slots + i];
      CHECK((v >= 0) == std::isfinite(x[3 * (f * slots + i)]));
      n += v >= 0;
    }
    CHECK(double(n - scene.wall_count) == present[f]);
    shown.push_back(n);
  }
  CHECK(present.back() > 5);  // particles came in
  // Each XYZ frame: a count line, a comment line, then that many particle lines.
  std::ifstream xyz(dir / "s.xyz");
  std::size_t f = 0;
  std::string line;
  while (std::getline(xyz, line)) {
    REQUIRE(f < frames);
    CHECK(std::stoul(line) == shown[f]);
    std::getline(xyz, line);
    for (std::size_t k = 0; k < shown[f]; ++k) std::getline(xyz, line);
    ++f;
  }
  CHECK(f == frames);
  fs::remove_all(dir);
}

TEST_CASE("wall contact: a sphere pulled onto the wall particles in shear rests on them with the lubrication floor 1e-2") {
  // Morse (kappa a = 5, depth 37.7) pulls a sphere onto the wall of a straight outline carrying
  // Poiseuille flow; Hertz contact. The wall particles see no ambient flow, so at contact the sphere
  // is carried against them at ~ shear rate x a: the lubrication floor decides whether the contact
  // force can hold it (docs/channels.md, "Contact with wall particles").
  auto deepest = [](const std::string& floor) {
    std::string text = kStraight + R"(
[particles]
positions = [[20.5, 1.0, 0.0]]
[[forces.pair]]
kind = "morse"
depth = 37.7
kappa = 5.0
cutoff = 1.5
[[forces.pair]]
kind = "hertz"
stiffness = 20000.0
[flow]
kind = "poiseuille"
mean_velocity = 1.0
[hydrodynamics]
model = "stokesian"
solver = "accelerated"
tolerance = 1e-3
lubrication_min_gap = )" + floor + R"(
[time]
dt = 0.002
steps = 1500
[output]
every = 100
)";
    Simulation sim(io::parse_scene(text, "wall_contact.toml"));
    State s = sim.initial_state();
    Collect out;
    RunControl rc;
    rc.quiet = true;
    sim.run(s, out, rc);
    double worst = 0;
    for (const Frame& f : out.frames) worst = std::min(worst, f.scalar("min_gap"));
    return std::make_pair(worst, out.frames.back().scalar("min_gap"));
  };
  // (With the default floor 1e-6 the same sphere sinks: 0.15 a deep at t = 6 and deepening; the
  // measurement is in docs/channels.md.)
  const auto [worst, last] = deepest("1e-2");
  MESSAGE("floor 1e-2: deepest overlap " << -worst << " a, final gap " << last << " a");
  CHECK(last < 0.01);  // it reached the wall
  CHECK(-worst < 0.02);   // the impact
  CHECK(last > -2e-3);    // then at rest in the pocket, not sinking
}
