// The command line (docs/cli.md): help and usage errors, typed options, the progress line, what
// `check` reports (initial overlaps, particles outside the box, step-size criteria against the
// analytic stiffness of Hertz and Morse pairs), and `plot`.
#include <doctest/doctest.h>

#include "engine/app/check.hpp"
#include "engine/progress.hpp"
#include "io/scene_toml.hpp"

#include "support/cli.hpp"
#include "support/hdf5_read.hpp"

#include <hdf5.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace stokesian;

namespace {

const double kPiTest = std::acos(-1.0);

fs::path scratch() {
  static const test::ScratchDir dir("stokesian_cli_");
  return dir.path;
}

using test::contains;
using test::read_text;
using Result = test::CliResult;

Result cli(const std::string& args, const std::string& env = "") { return test::run_stokesian(args, scratch(), env); }

fs::path write_scene(const std::string& name, const std::string& text) {
  const fs::path p = scratch() / name;
  std::ofstream(p) << text;
  return p;
}

// The number after `label` in `text` (e.g. "stable dt < ").
double number_after(const std::string& text, const std::string& label) {
  const auto k = text.find(label);
  REQUIRE(k != std::string::npos);
  return std::stod(text.substr(k + label.size()));
}

// Two spheres of radius 1 on the x axis at centre distance r, free draining, pushed together by
// external forces +-f, with the given pair law; Euler steps of dt.
std::string two_spheres(double r, double f, const std::string& law, double dt) {
  std::ostringstream o;
  o << "[particles]\npositions = [[0.0, 0.0, 0.0], [" << r << ", 0.0, 0.0]]\nradius = 1.0\n"
    << "[forces]\nexternal_force = [[" << f << ", 0.0, 0.0], [" << -f << ", 0.0, 0.0]]\n"
    << "[[forces.pair]]\n" << law << "\n"
    << "[hydrodynamics]\nmodel = \"free_draining\"\n"
    << "[time]\ndt = " << dt << "\nsteps = 4\nintegrator = \"euler\"\n";
  return o.str();
}

const char* kPeriodicBad =
    "[domain]\nkind = \"periodic\"\nbox = [10.0, 10.0, 10.0]\n"
    "[particles]\npositions = [[1.0, 1.0, 1.0], [2.8, 1.0, 1.0], [12.5, 5.0, -1.0], [5.0, 5.0, 5.0]]\nradius = 1.0\n"
    "[time]\ndt = 0.01\nsteps = 2\n";

const char* kPeriodicOutside =
    "[domain]\nkind = \"periodic\"\nbox = [10.0, 10.0, 10.0]\n"
    "[particles]\npositions = [[1.0, 1.0, 1.0], [12.5, 5.0, -1.0], [5.0, 5.0, 5.0]]\nradius = 1.0\n"
    "[time]\ndt = 0.01\nsteps = 2\n";

}  // namespace

TEST_CASE("--help of the program and of each command exits 0 and lists every option with type and default") {
  const Result top = cli("--help");
  CHECK(top.status == 0);
  for (const char* c : {"run", "solve", "check", "plot", "--version", "Exit status"}) CHECK(contains(top.out, c));

  const Result run = cli("run --help");
  CHECK(run.status == 0);
  for (const char* o : {"--out FILE.h5", "--threads INT=OpenMP default", "--resume", "--quiet",
                        "--progress-interval SECONDS", "SCENE.toml REQUIRED"})
    CHECK_MESSAGE(contains(run.out, o), o);
  const Result check = cli("check --help");
  CHECK(check.status == 0);
  for (const char* o : {"--out", "--threads", "--no-estimate"}) CHECK(contains(check.out, o));
  const Result solve = cli("solve --help");
  CHECK(solve.status == 0);
  CHECK(contains(solve.out, "--out FILE.h5 REQUIRED"));
  const Result plot = cli("plot --help");
  CHECK(plot.status == 0);
  for (const char* o : {"--out FILE.png", "--frame INT=-1", "--projection PLANE:{xy,xz,yz}=xy", "--python PATH"})
    CHECK_MESSAGE(contains(plot.out, o), o);
  const Result version = cli("--version");
  CHECK(version.status == 0);
  CHECK(version.out.rfind("stokesian ", 0) == 0);
}

TEST_CASE("usage errors exit 1 and name the option, the value and what is allowed") {
  const fs::path scene = fs::path(STOKESIAN_SOURCE_DIR) / "configs" / "quickstart.toml";
  for (const std::string v : {"abc", "2x", "0", "-3", "100000"}) {
    CAPTURE(v);
    const Result r = cli("run " + scene.string() + " --threads " + v + " --out " + (scratch() / "never.h5").string());
    CHECK(r.status == 1);
    CHECK(contains(r.err, "--threads"));
    CHECK(contains(r.err, "\"" + v + "\""));
    CHECK(contains(r.err, "1 to 1024"));
    CHECK(!fs::exists(scratch() / "never.h5"));
  }
  CHECK(cli("frob").status == 1);
  CHECK(contains(cli("frob").err, "unknown command \"frob\""));
  CHECK(cli("").status == 1);
  CHECK(cli("run").status == 1);
  CHECK(cli("run " + scene.string() + " --bogus").status == 1);
  CHECK(cli("solve " + scene.string()).status == 1);  // --out is required
  const Result pi = cli("run " + scene.string() + " --progress-interval soon");
  CHECK(pi.status == 1);
  CHECK(contains(pi.err, "--progress-interval: \"soon\" is not a number >= 0"));
  const Result pr = cli("plot x.h5 --projection xw");
  CHECK(pr.status == 1);
  CHECK(contains(pr.err, "--projection"));
  // Scene and file errors keep their statuses.
  CHECK(cli("check " + (scratch() / "missing.toml").string()).status == 2);
  CHECK(cli("plot " + (scratch() / "missing.h5").string()).status == 4);
}

TEST_CASE("progress line fits the terminal width and drops whole fields first") {
  progress::Status s;
  s.step = 1234;
  s.last = 100000;
  s.time = 12.5;
  s.rate = 345.6;
  s.eta = 285;
  s.diagnostics = true;
  s.min_gap = 0.0123;
  s.overlaps = 2;
  const std::string full = progress::format_line(s, 1000);
  CHECK(full == "step 1234/100000  t=12.5  346 steps/s  ETA 285s  min_gap=0.0123 overlaps=2");
  for (int w : {120, 80, 73, 72, 60, 40, 20, 10, 2, 1, 0}) {
    CAPTURE(w);
    const std::string line = progress::format_line(s, w);
    CHECK(line.size() <= std::size_t(std::max(w - 1, 0)));
    if (w > 20) CHECK(line.rfind("step 1234/100000", 0) == 0);  // the step always leads
    CHECK(full.rfind(line, 0) == 0);                              // a prefix of whole fields (or the cut first field)
  }
  CHECK(progress::format_line(s, 80) == full);  // 73 characters fit in 79
  CHECK(progress::format_line(s, 60) == "step 1234/100000  t=12.5  346 steps/s  ETA 285s");
  CHECK(progress::format_line(s, 20) == "step 1234/100000");
  CHECK(progress::format_line(s, 10) == "step 1234");

  // Not a terminal: the width comes from COLUMNS.
  const fs::path f = scratch() / "not_a_tty.txt";
  std::FILE* fp = std::fopen(f.c_str(), "w");
  REQUIRE(fp);
  setenv("COLUMNS", "57", 1);
  CHECK(progress::terminal_width(fileno(fp)) == 57);
  unsetenv("COLUMNS");
  CHECK(progress::terminal_width(fileno(fp)) == 80);
  std::fclose(fp);
}

TEST_CASE("every progress line is printed once; the last one carries the last frame's diagnostics") {
  const fs::path scene = write_scene("progress.toml", two_spheres(2.6, 0.5, "kind = \"hertz\"\nstiffness = 100.0", 0.05) +
                                                          "[output]\nevery = 2\n");
  const fs::path out = scratch() / "progress.h5";
  const Result r = cli("run " + scene.string() + " --out " + out.string() + " --threads 1 --progress-interval 0");
  REQUIRE(r.status == 0);
  std::vector<std::string> lines;
  std::istringstream in(r.err);
  for (std::string l; std::getline(in, l);)
    if (l.rfind("step ", 0) == 0 && contains(l, "steps/s")) lines.push_back(l);
  REQUIRE(lines.size() == 4);  // steps 1..4, each once
  for (int k = 0; k < 4; ++k) CHECK(lines[std::size_t(k)].rfind("step " + std::to_string(k + 1) + "/4 ", 0) == 0);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const auto gap = stokesian::test::read_doubles(out.string(), "/observables/min_gap/value");
  REQUIRE(gap.size() == 3);  // frames at steps 0, 2, 4
  char want[64];
  std::snprintf(want, sizeof want, "min_gap=%.3g ", gap.back());
  CHECK_MESSAGE(contains(lines.back(), want), lines.back());
}

TEST_CASE("check reports each initial overlap and each particle outside a periodic box") {
  const Result bad = cli("check --no-estimate " + write_scene("bad.toml", kPeriodicBad).string());
  CHECK(bad.status == 2);
  CHECK(contains(bad.out, "ERROR overlap: particles 0 and 1, gap -0.2 a"));
  CHECK(contains(bad.out, "particle 2 at (12.5, 5, -1) is outside the box"));
  CHECK(contains(bad.out, "periodic image (2.5, 5, 9)"));
  CHECK(contains(bad.err, "1 overlapping pair(s)"));

  // Outside the box alone is a warning: the run wraps the particle.
  const Result outside = cli("check " + write_scene("outside.toml", kPeriodicOutside).string());
  CHECK(outside.status == 0);
  CHECK(contains(outside.out, "warning: particle 1 at (12.5, 5, -1) is outside the box"));
  CHECK(contains(outside.out, "no overlapping pairs"));

  const Scene s = io::load_scene(write_scene("bad2.toml", kPeriodicBad).string());
  const auto o = app::initial_overlaps(s);
  REQUIRE(o.size() == 1);
  CHECK(o[0].i == 0);
  CHECK(o[0].j == 1);
  CHECK(o[0].gap == doctest::Approx(-0.2).epsilon(1e-12));
  const auto b = app::outside_box(s);
  REQUIRE(b.size() == 1);
  CHECK(b[0].i == 2);
  CHECK((b[0].wrapped - Vec3(2.5, 5.0, 9.0)).norm() < 1e-12);
}

TEST_CASE("pair stiffness against the analytic second derivative (Hertz, Morse)") {
  PairForceParams hertz;
  hertz.kind = PairForceParams::Kind::hertz;
  hertz.hertz_stiffness = 1000.0;
  // U = (2/5) k_H delta^{5/2} -> d2U/dr2 = (3/2) k_H delta^{1/2}.
  for (double delta : {1e-3, 0.01, 0.1}) {
    CAPTURE(delta);
    CHECK(app::pair_stiffness({hertz}, 1.0, 2.0 - delta, 1.0, 1.0) ==
          doctest::Approx(1.5 * 1000.0 * std::sqrt(delta)).epsilon(1e-6));
  }
  CHECK(app::pair_stiffness({hertz}, 1.0, 2.5, 1.0, 1.0) == 0.0);

  PairForceParams morse;
  morse.kind = PairForceParams::Kind::morse;
  morse.morse_depth = 5.0;
  morse.morse_kappa = 4.0;
  // U = -V0 [2 e^{-k h} - e^{-2 k h}] -> d2U/dr2 = 2 k^2 V0 [2 e^{-2 k h} - e^{-k h}].
  for (double h : {-0.05, 0.0, 0.1, 0.5}) {
    CAPTURE(h);
    const double y = std::exp(-4.0 * h);
    CHECK(app::pair_stiffness({morse}, 1.0, 2.0 + h, 1.0, 1.0) ==
          doctest::Approx(2 * 16.0 * 5.0 * (2 * y * y - y)).epsilon(1e-6));
  }
}

TEST_CASE("stiffness criterion on two Hertz spheres pressed together: dt < 2 / (k m_rel)") {
  const double kH = 1000.0, f = 1.0;
  const fs::path p = write_scene("hertz.toml", two_spheres(2.5, f, "kind = \"hertz\"\nstiffness = 1000.0", 1.0));
  const Scene s = io::load_scene(p.string());
  // Balance k_H delta^{3/2} = f at delta = (f/k_H)^{2/3}; stiffness there (3/2) k_H^{2/3} f^{1/3};
  // relative Stokes mobility 2/(6 pi mu a).
  const double delta = std::pow(f / kH, 2.0 / 3.0);
  const double k = 1.5 * std::pow(kH, 2.0 / 3.0) * std::pow(f, 1.0 / 3.0);
  const double m = 2.0 / (6 * kPiTest);
  const double dt_max = 2.0 / (k * m);
  Simulation sim(s);
  const app::StiffnessBound b = app::stiffness_bound(s, sim.model());
  REQUIRE(b.applies);
  CHECK(b.h_lo == doctest::Approx(-delta).epsilon(1e-6));
  CHECK(b.gap == doctest::Approx(-delta).epsilon(1e-6));
  CHECK(b.k == doctest::Approx(k).epsilon(1e-5));
  CHECK(b.m_rel == doctest::Approx(m).epsilon(1e-12));
  CHECK(b.dt_max == doctest::Approx(dt_max).epsilon(1e-5));

  // The CLI warns (dt = 1 > 0.1257) and names the stable step.
  const Result r = cli("check " + p.string());
  CHECK(r.status == 0);
  CHECK(contains(r.out, "WARNING: dt = 1 exceeds the stability limit"));
  CHECK(number_after(r.out, "use dt < ") == doctest::Approx(dt_max).epsilon(1e-3));
  // A step below the bound passes.
  const Result ok = cli("check --no-estimate " +
                        write_scene("hertz_ok.toml", two_spheres(2.5, f, "kind = \"hertz\"\nstiffness = 1000.0", 0.1)).string());
  CHECK(contains(ok.out, "stiffness ok"));
}

TEST_CASE("stiffness criterion on two Morse spheres: attraction presses the pair to the balance gap") {
  // No external force; the largest Morse attraction, V0 kappa / 2 at e^{-kappa h} = 1/2, is balanced
  // by the repulsion 2 kappa V0 (y^2 - y) at y = e^{-kappa h} = (1 + sqrt 2)/2 < contact.
  const double V0 = 5.0, kappa = 4.0;
  const fs::path p = write_scene("morse.toml", two_spheres(3.0, 0.0, "kind = \"morse\"\ndepth = 5.0\nkappa = 4.0", 0.1));
  const Scene s = io::load_scene(p.string());
  const double y = (1 + std::sqrt(2.0)) / 2;
  const double h_lo = -std::log(y) / kappa;
  const double k = 2 * kappa * kappa * V0 * (2 * y * y - y);
  const double m = 2.0 / (6 * kPiTest);
  Simulation sim(s);
  const app::StiffnessBound b = app::stiffness_bound(s, sim.model());
  REQUIRE(b.applies);
  CHECK(b.h_lo == doctest::Approx(h_lo).epsilon(1e-6));
  CHECK(b.k == doctest::Approx(k).epsilon(1e-5));
  CHECK(b.dt_max == doctest::Approx(2.0 / (k * m)).epsilon(1e-5));
  const Result r = cli("check " + p.string());
  CHECK(r.status == 0);
  CHECK(contains(r.out, "WARNING: dt = 0.1 exceeds"));
  CHECK(number_after(r.out, "use dt < ") == doctest::Approx(2.0 / (k * m)).epsilon(1e-3));
  CHECK(contains(r.out, "pair: morse, depth 5 kT, kappa"));  // athermal: no second unit

  // With fluid.kT = 0.5 the depth is also given in the scene's own thermal energy: 5 / 0.5 = 10.
  const Result hot = cli("check " + write_scene("morse_hot.toml", "[fluid]\nkT = 0.5\n[brownian]\nseed = 3\n" +
                                                                      two_spheres(3.0, 0.0, "kind = \"morse\"\ndepth = 5.0\nkappa = 4.0", 0.01))
                                        .string());
  CHECK(contains(hot.out, "pair: morse, depth 5 kT (10 x fluid.kT), kappa"));
  CHECK(contains(hot.out, "Brownian: fluid.kT = 0.5 (in the reference kT)"));
}

TEST_CASE("check: wall contact in a channel flow, and the warning at the default lubrication floor") {
  // A slit 10 a high with plane Poiseuille flow (mean U = 1): fixed wall particles see
  // no flow, so check reports the speed U_c at which a touching sphere is carried against one and
  // the contact force 6 pi mu a_eff^2 U_c / h_f that stops it (unit radii: a_eff = 1/2, h_f = the
  // floor); docs/channels.md, "Contact with wall particles".
  auto scene = [](const char* floor_line) {
    return std::string("[domain]\nkind = \"periodic\"\nbox = [16.4, 14.05, 16.4]\n[walls]\nkind = \"slit\"\n"
                       "height = 10.0\nradius = 1.0\ngap = 0.05\n[particles]\ngenerate = \"random\"\ncount = 8\n"
                       "seed = 2\n[flow]\nkind = \"poiseuille\"\nmean_velocity = 1.0\n[hydrodynamics]\n"
                       "model = \"stokesian\"\ntolerance = 1e-3\n") +
           floor_line + "[time]\ndt = 0.001\nsteps = 2\n";
  };
  const Result def = cli("check --no-estimate " + write_scene("slit_floor_default.toml", scene("")).string());
  CHECK(def.status == 0);
  // Wall-particle centres lie r_w = 1 outside the boundary planes (docs/channels.md, "Geometry"), so
  // the point one contact distance (r_w + a = 2) above a lower-wall centre is a = 1 inside the fluid,
  // where plane Poiseuille gives u = 6 U s (H - s) / H^2 = 6 x 1 x 9 / 100 = 0.54; the points along
  // x and z stay outside the fluid (u = 0).
  const double u_c = number_after(def.out, "carried against it at up to ");
  CHECK(u_c == doctest::Approx(0.54).epsilon(1e-3));
  const double f = number_after(def.out, "stopping it takes a contact force of about ");
  CHECK(f == doctest::Approx(6 * kPiTest * 0.25 * u_c / 1e-6).epsilon(1e-3));
  CHECK(contains(def.out, "WARNING: with [hydrodynamics] lubrication_min_gap = 1e-06"));
  CHECK(number_after(def.out, "where the force is about ") == doctest::Approx(6 * kPiTest * 0.25 * u_c / 1e-2).epsilon(1e-3));

  const Result held = cli("check --no-estimate " +
                          write_scene("slit_floor_1e2.toml", scene("lubrication_min_gap = 1e-2\n")).string());
  CHECK(held.status == 0);
  CHECK(number_after(held.out, "carried against it at up to ") == doctest::Approx(u_c).epsilon(1e-3));
  CHECK_FALSE(contains(held.out, "WARNING: with [hydrodynamics] lubrication_min_gap"));

  // Far field only (no lubrication): nothing to report.
  std::string ff = scene("");
  ff.replace(ff.find("model = \"stokesian\""), 20, "model = \"far_field\"");
  CHECK_FALSE(contains(cli("check --no-estimate " + write_scene("slit_ff.toml", ff).string()).out, "wall contact"));
}

TEST_CASE("displacement criterion: a closing pair may close a tenth of its gap per step") {
  // Free draining: each sphere moves at f/(6 pi mu a); the pair closes at 2 f/(6 pi), gap 0.5.
  const double f = 1.0, gap = 0.5;
  const double dt_max = 0.1 * gap / (2 * f / (6 * kPiTest));
  const fs::path p = write_scene("disp.toml", two_spheres(2.5, f, "kind = \"hertz\"\nstiffness = 10.0", 1.0));
  const Result r = cli("check --threads 1 " + p.string());
  CHECK(r.status == 0);
  CHECK(contains(r.out, "displacement WARNING: particles 0 and 1 at gap 0.5 a"));
  CHECK(number_after(r.out, "close more than a tenth of their gap in one step; use dt < ") ==
        doctest::Approx(dt_max).epsilon(1e-3));
  // Cost lines (measured; not compared).
  CHECK(contains(r.out, "per step: "));
  CHECK(contains(r.out, "whole run: about "));
  CHECK(contains(r.out, "trajectory: disp.h5, a frame every 1 steps (5 frames)"));

  const Scene s = io::load_scene(p.string());
  const std::vector<Vec3> u{{0.3, 0.0, 0.0}, {-0.1, 0.0, 0.0}};
  const app::DisplacementBound d = app::displacement_bound(s, u);
  CHECK(d.pair_i == 0);
  CHECK(d.dt_max == doctest::Approx(0.1 * gap / 0.4).epsilon(1e-12));
  // Translation together closes nothing.
  CHECK(app::displacement_bound(s, {{0.3, 0.0, 0.0}, {0.3, 0.0, 0.0}}).pair_i == -1);
}

TEST_CASE("displacement criterion in a sheared box: images move with the flow (Lees-Edwards)") {
  // Two spheres across the y boundary of a sheared box of side 10 (separation r = x_0 - x_1' =
  // (0.5, 2.2, 0) through the boundary), both moving with the ambient flow u = (y, 0, 0) at their
  // own centres: the pair separates at r.(G r)/|r| = r_x r_y / |r|. Before the fix the criterion
  // used U_0 - U_1 = (0.1 - 7.9, 0, 0) and saw it closing at 1.7 a/time.
  const fs::path p = write_scene("le.toml", R"(
[domain]
kind = "periodic"
box = [10, 10, 10]
[particles]
positions = [[5.5, 0.1, 5.0], [5.0, 7.9, 5.0]]
[flow]
kind = "simple_shear"
rate = 1.0
)");
  const Scene s = io::load_scene(p.string());
  std::vector<Vec3> u;
  for (const Vec3& x : s.positions) u.push_back(Vec3(x.y(), 0.0, 0.0));
  CHECK(app::displacement_bound(s, u).pair_i == -1);
  // An approach on top of the flow is still seen: sphere 1 moving at +1 in y towards sphere 0.
  u[1].y() += 1.0;
  const app::DisplacementBound d = app::displacement_bound(s, u);
  CHECK(d.pair_i == 0);
  const Vec3 r = s.domain.minimum_image(s.positions[0] - s.positions[1]);
  CHECK(r.y() == doctest::Approx(2.2));
  CHECK(d.closing_speed == doctest::Approx((r.y() - r.x() * r.y()) / r.norm()).epsilon(1e-9));
}

// Runs `scene` to `traj`, plots it to `png` with `options` and checks a PNG was written.
static void run_and_plot(const fs::path& scene, const fs::path& traj, const fs::path& png, const std::string& options = "") {
  REQUIRE(cli("run " + scene.string() + " --quiet --threads 1 --out " + traj.string()).status == 0);
  const Result r = cli("plot " + traj.string() + " --out " + png.string() + options);
  CHECK_MESSAGE(r.status == 0, r.err);
  REQUIRE(fs::exists(png));
  CHECK(read_text(png).substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
}

TEST_CASE("plot writes one PNG of a short periodic run") {
  const fs::path scene = write_scene(
      "plot.toml",
      "[domain]\nkind = \"periodic\"\nbox = [12.0, 12.0, 12.0]\n"
      "[particles]\ngenerate = \"random\"\ncount = 20\nseed = 3\n"
      "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"
      "[hydrodynamics]\nmodel = \"free_draining\"\n"
      "[time]\ndt = 0.05\nsteps = 6\n[output]\nevery = 2\n");
  const fs::path traj = scratch() / "plot.h5", png = scratch() / "chart.png";
  run_and_plot(scene, traj, png, " --projection xz");
  // A frame the file does not have: a usage error naming the frames there are.
  const Result frame = cli("plot " + traj.string() + " --out " + png.string() + " --frame 4");
  CHECK(frame.status == 1);
  CHECK(contains(frame.err, "--frame 4: the file has 4 frames (0 to 3, or -1 to -4)"));
  // Not a trajectory: a file error.
  const Result bad = cli("plot " + scene.string() + " --out " + (scratch() / "bad.png").string());
  CHECK(bad.status == 4);
}

TEST_CASE("plot draws an open channel's trajectory, whose empty slots hold NaN") {
  // [inflow] keeps `capacity` slots per frame; the empty ones (id -1) are NaN and are left out (before
  // 2026-12-02 they made the snapshot's limits NaN and the plot failed).
  const fs::path scene = write_scene("open_plot.toml",
                                     "[walls]\nkind = \"outline\"\noutline = [[0, -5], [30, -5], [30, 5], [0, 5]]\n"
                                     "openings = [1, 3]\ninlet = 3\n"
                                     "[particles]\npositions = [[5.0, 0.0, 0.0], [15.0, 2.0, 0.0]]\n"
                                     "[inflow]\nareal_fraction = 0.05\ncapacity = 12\n"
                                     "[flow]\nkind = \"poiseuille\"\nmean_velocity = 1.0\n"
                                     "[hydrodynamics]\nmodel = \"free_draining\"\n"
                                     "[time]\ndt = 0.1\nsteps = 10\n[output]\nevery = 5\n");
  run_and_plot(scene, scratch() / "open_plot.h5", scratch() / "open_plot.png");
}

TEST_CASE("average: the window in strain, time or fractions selects the frames; the mean is theirs; errors") {
  // Two spheres in simple shear (rate 2) in a periodic box, far field FTS, 20 steps of 0.05, a
  // frame per step: strain 2 t, frames at t = 0, 0.05, ..., 1.
  const fs::path scene = write_scene("avg.toml", R"([domain]
kind = "periodic"
box = [10, 10, 10]
[particles]
positions = [[0.0, 0.0, 0.0], [2.6, 0.5, 0.0]]
[flow]
kind = "simple_shear"
rate = 2.0
[hydrodynamics]
model = "far_field"
moments = "FTS"
[time]
dt = 0.05
steps = 20
)");
  const std::string h5 = (scratch() / "avg.h5").string();
  REQUIRE(cli("run " + scene.string() + " --out " + h5 + " --quiet").status == 0);
  const std::vector<double> t = test::read_doubles(h5, "observables/relative_viscosity/time");
  const std::vector<double> eta = test::read_doubles(h5, "observables/relative_viscosity/value");
  REQUIRE(t.size() == 21);
  auto mean_where = [&](double lo, double hi) {
    double s = 0;
    int n = 0;
    for (std::size_t k = 0; k < t.size(); ++k)
      if (t[k] >= lo - 1e-12 && t[k] <= hi + 1e-12) {
        s += eta[k];
        ++n;
      }
    return std::make_pair(s / n, n);
  };
  auto row = [](const std::string& out, const std::string& name) {
    std::istringstream in(out);
    for (std::string line; std::getline(in, line);) {
      std::istringstream w(line);
      std::string first;
      w >> first;
      if (first == name) {
        double mean = 0, se = 0;
        long n = 0;
        w >> mean >> se >> n;
        return std::make_pair(mean, n);
      }
    }
    return std::make_pair(std::nan(""), -1L);
  };
  // Strain 0.5 ... 1.5 is t = 0.25 ... 0.75: frames 5 ... 15.
  const Result s = cli("average " + h5 + " --strain 0.5:1.5 --observables relative_viscosity,N1");
  REQUIRE(s.status == 0);
  const auto [m_strain, n_strain] = mean_where(0.25, 0.75);
  CHECK(row(s.out, "relative_viscosity").second == n_strain);
  CHECK(row(s.out, "relative_viscosity").first == doctest::Approx(m_strain).epsilon(1e-7));
  CHECK(row(s.out, "N1").second == n_strain);
  CHECK(!contains(s.out, "stress_fluid"));  // only the observables asked for
  const Result ti = cli("average " + h5 + " --time 0.25:0.75 --observables relative_viscosity");
  CHECK(row(ti.out, "relative_viscosity").first == doctest::Approx(m_strain).epsilon(1e-7));
  // Default: the second half of the recorded time.
  const Result d = cli("average " + h5);
  REQUIRE(d.status == 0);
  const auto [m_half, n_half] = mean_where(0.5, 1.0);
  CHECK(row(d.out, "relative_viscosity").second == n_half);
  CHECK(row(d.out, "relative_viscosity").first == doctest::Approx(m_half).epsilon(1e-7));
  CHECK(contains(d.out, "stress_hydrodynamic[1]"));
  // Errors: usage (1), an unknown observable or a strain window without shear (2), no file (4).
  CHECK(cli("average " + h5 + " --strain 2:1").status == 1);
  CHECK(contains(cli("average " + h5 + " --strain 1:x").err, "expected A:B"));
  CHECK(cli("average " + h5 + " --strain 0:1 --time 0:1").status == 1);
  CHECK(cli("average " + h5 + " --window 0.5:2").status == 1);
  const Result unknown = cli("average " + h5 + " --observables viscosity");
  CHECK(unknown.status == 2);
  CHECK(contains(unknown.err, "no observable \"viscosity\""));
  const fs::path still = write_scene("still.toml", "[particles]\npositions = [[0,0,0]]\n[time]\nsteps = 2\n");
  const std::string h5s = (scratch() / "still.h5").string();
  REQUIRE(cli("run " + still.string() + " --out " + h5s + " --quiet").status == 0);
  const Result ns = cli("average " + h5s + " --strain 0:1");
  CHECK(ns.status == 2);
  CHECK(contains(ns.err, "--strain needs a run in simple shear"));
  CHECK(cli("average " + (scratch() / "missing.h5").string()).status == 4);
}

TEST_CASE("clusters: counts, histogram, shapes and velocities of a known configuration; option errors") {
  // A doublet (gap 0.05), a straight triplet (gaps 0.05) pulled down by unit forces (free draining:
  // it translates rigidly at 1/(6 pi)), and two singlets; three frames.
  const fs::path scene = write_scene("cl.toml", R"([particles]
positions = [[0, 0, 0], [2.05, 0, 0], [0, 20, 0], [2.05, 20, 0], [4.1, 20, 0], [30, 0, 0], [-30, 0, 0]]
radius = 1.0
[forces]
external_force = [[0, 0, 0], [0, 0, 0], [0, 0, -1], [0, 0, -1], [0, 0, -1], [0, 0, 0], [0, 0, 0]]
[hydrodynamics]
model = "free_draining"
[time]
dt = 0.1
steps = 2
[output]
cluster_gap = 0.06
)");
  const std::string h5 = (scratch() / "cl.h5").string();
  REQUIRE(cli("run " + scene.string() + " --out " + h5 + " --quiet").status == 0);
  const std::string out = (scratch() / "cl_clusters.h5").string();
  const Result r = cli("clusters " + h5 + " --gap 0.06 --out " + out);
  REQUIRE(r.status == 0);
  CHECK(contains(r.out, "clusters by surface gap <= 0.06 a"));
  CHECK(test::read_doubles(out, "frames/clusters") == std::vector<double>{4, 4, 4});
  // The run's own counts ([output] cluster_gap) agree.
  CHECK(test::read_doubles(h5, "observables/clusters/value") == std::vector<double>{4, 4, 4});
  CHECK(test::read_doubles(h5, "observables/clusters_singlets/value") == std::vector<double>{2, 2, 2});
  CHECK(test::read_doubles(h5, "observables/clusters_doublets/value") == std::vector<double>{1, 1, 1});
  CHECK(test::read_doubles(h5, "observables/clusters_triplets/value") == std::vector<double>{1, 1, 1});
  CHECK(test::read_doubles(h5, "observables/clusters_largest/value") == std::vector<double>{3, 3, 3});
  CHECK(test::read_doubles(out, "frames/particles") == std::vector<double>{7, 7, 7});
  CHECK(test::read_doubles(out, "frames/largest") == std::vector<double>{3, 3, 3});
  // Histogram rows: 2 singlets, 1 doublet, 1 triplet; nothing changes, so every growth rate is 0.
  CHECK(test::read_doubles(out, "size_histogram") == std::vector<double>{2, 1, 1, 2, 1, 1, 2, 1, 1});
  for (double g : test::read_doubles(out, "growth_rate")) CHECK(g == 0.0);
  const auto size = test::read_doubles(out, "clusters/size"), rg = test::read_doubles(out, "clusters/radius_of_gyration");
  const auto feret = test::read_doubles(out, "clusters/feret_diameter"), vz = test::read_doubles(out, "clusters/velocity_z");
  REQUIRE(size.size() == 12);
  CHECK(size[0] == 3);  // largest first
  CHECK(rg[0] == doctest::Approx(std::sqrt(2.05 * 2.05 * 8.0 / 12.0 + 0.6)));
  CHECK(feret[0] == doctest::Approx(6.1));
  CHECK(vz[0] == doctest::Approx(-1.0 / (6.0 * kPiTest)));
  CHECK(vz[1] == doctest::Approx(0.0));
  CHECK(feret[1] == doctest::Approx(4.05));
  // A tighter gap dissolves both: 7 singlets.
  REQUIRE(cli("clusters " + h5 + " --gap 0.04 --every 2 --out " + out).status == 0);
  CHECK(test::read_doubles(out, "frames/clusters") == std::vector<double>{7, 7});
  // Bad options and files: named, nothing written.
  fs::remove(out);
  const Result bad = cli("clusters " + h5 + " --gap -1 --out " + out);
  CHECK(bad.status != 0);
  CHECK(contains(bad.err, "--gap"));
  CHECK(contains(cli("clusters " + h5 + " --every 0 --out " + out).err, "--every"));
  CHECK(!fs::exists(out));
  const Result missing = cli("clusters " + (scratch() / "none.h5").string());
  CHECK(missing.status == 4);
  CHECK(contains(missing.err, "none.h5"));
}
