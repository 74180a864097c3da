// Scene files: defaults, generation, and clear errors for bad input (file, line, key, allowed
// values), through the library and through the command line (non-zero exit, nothing written).
#include <doctest/doctest.h>

#include "engine/core/errors.hpp"
#include "engine/model.hpp"
#include "engine/observers.hpp"
#include "io/scene_toml.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

using namespace stokesian;

namespace {

// The ConfigError message for `text`, or "" if it parses.
std::string error_of(const std::string& text) {
  try {
    const Scene s = io::parse_scene(text, "bad.toml");
    resolve_model(s);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

const std::string kTwo = "[particles]\npositions = [[0,0,0],[3,0,0]]\n";

}  // namespace

TEST_CASE("a minimal scene gets the documented defaults") {
  const Scene s = io::parse_scene(kTwo, "min.toml");
  CHECK(s.positions.size() == 2);
  CHECK(s.radii == std::vector<double>{1.0, 1.0});
  CHECK(s.fluid.viscosity == 1.0);
  CHECK(s.fluid.kT == 0.0);
  CHECK(s.time.dt == 1e-3);
  CHECK(s.hydro.tolerance == 1e-6);
  CHECK(!s.domain.periodic());
  const ResolvedModel m = resolve_model(s);
  CHECK(m.level == HydroModel::far_field);
  CHECK(m.moments == Moments::F);
  CHECK(!m.brownian);
}

TEST_CASE("model resolution: cheapest adequate level and moments, recorded with reasons") {
  auto model = [](const std::string& extra) { return resolve_model(io::parse_scene(kTwo + extra, "m.toml")); };
  CHECK(model("[flow]\nkind = \"simple_shear\"\nrate = 1.0\n").moments == Moments::FTS);
  CHECK(model("[forces]\nexternal_torque = [0, 0, 1]\n").moments == Moments::FT);
  CHECK(model("[hydrodynamics]\nmodel = \"free_draining\"\n").level == HydroModel::free_draining);
  CHECK(model("[hydrodynamics]\nmoments = \"FTS\"\n").moments == Moments::FTS);
  // Close pairs resolve to Stokesian dynamics, athermal or Brownian (then with the Fixman midpoint
  // integrator, which gives the thermal drift; an explicit driftless integrator is refused).
  const std::string close = "[particles]\npositions = [[0,0,0],[2.1,0,0]]\n";
  CHECK(resolve_model(io::parse_scene(close, "c.toml")).level == HydroModel::stokesian);
  const ResolvedModel bsd = resolve_model(io::parse_scene(close + "[fluid]\nkT = 1.0\n", "c.toml"));
  CHECK(bsd.level == HydroModel::stokesian);
  CHECK(bsd.integrator == "fixman");
  CHECK(bsd.drift);
  CHECK(contains(bsd.describe(), "auto integrator"));
  const std::string e_euler = error_of(close + "[fluid]\nkT = 1.0\n[time]\nintegrator = \"euler\"\n");
  CHECK(contains(e_euler, "[time] integrator"));
  CHECK(contains(e_euler, "thermal drift"));
  CHECK(contains(e_euler, "fixman"));
  // The far field alone needs no drift at F/FT: the integrator stays Euler-Maruyama.
  const ResolvedModel ff = resolve_model(io::parse_scene(kTwo + "[fluid]\nkT = 1.0\n", "f.toml"));
  CHECK(ff.integrator == "euler");
  CHECK_FALSE(ff.drift);
  // Periodic boxes: PME far field by default, dense Ewald under Stokesian dynamics.
  const std::string box = "[domain]\nkind = \"periodic\"\nbox = [12, 12, 12]\n";
  const ResolvedModel pm = resolve_model(io::parse_scene(box + kTwo + "[fluid]\nkT = 1.0\n", "p.toml"));
  CHECK(pm.level == HydroModel::far_field);
  CHECK(pm.far_field == "pme");
  CHECK(resolve_model(io::parse_scene(box + close, "p.toml")).far_field == "ewald");
  CHECK(resolve_model(io::parse_scene("[particles]\npositions = [[0,0,0]]\n", "one.toml")).level ==
        HydroModel::free_draining);
  CHECK(contains(model("").describe(), "auto level"));
}

TEST_CASE("generated configurations honour count, volume fraction and non-overlap") {
  const Scene s = io::parse_scene(
      "[domain]\nkind = \"periodic\"\nbox = [30, 30, 30]\n[particles]\ngenerate = \"random\"\ncount = 200\n"
      "size_distribution = \"bidisperse\"\nradius_ratio = 2.0\nseed = 3\n",
      "gen.toml");
  REQUIRE(s.positions.size() == 200);
  for (std::size_t i = 0; i < 200; ++i)
    for (std::size_t j = i + 1; j < 200; ++j)
      CHECK(s.domain.minimum_image(s.positions[i] - s.positions[j]).norm() >= s.radii[i] + s.radii[j]);
  // In a periodic box the volume fraction fixes the count (bidisperse 1:2, half large: mean a^3 = 4.5).
  const Scene phi = io::parse_scene(
      "[domain]\nkind = \"periodic\"\nbox = [30, 30, 30]\n[particles]\ngenerate = \"random\"\nvolume_fraction = 0.2\n"
      "size_distribution = \"bidisperse\"\nradius_ratio = 2.0\n",
      "phi.toml");
  CHECK(phi.positions.size() == std::size_t(std::lround(0.2 * 27000 / (4.0 / 3.0 * M_PI * 4.5))));
  CHECK(error_of("[domain]\nkind = \"periodic\"\nbox = [30, 30, 30]\n[particles]\ngenerate = \"random\"\ncount = 5\n"
                 "volume_fraction = 0.2\n").find("exactly one of count and volume_fraction") != std::string::npos);
  const Scene open = io::parse_scene(
      "[particles]\ngenerate = \"lattice\"\ncount = 27\nvolume_fraction = 0.2\n", "lat.toml");
  double vol = 0;
  for (double a : open.radii) vol += 4.0 / 3.0 * M_PI * a * a * a;
  CHECK(open.positions.size() == 27);
  CHECK(vol == doctest::Approx(27 * 4.0 / 3.0 * M_PI));
}

TEST_CASE("bad input names the file, line, key and allowed values") {
  std::string e = error_of(kTwo + "[time]\ndt = -1.0\n");
  CHECK(contains(e, "bad.toml:4"));
  CHECK(contains(e, "[time] dt"));
  CHECK(contains(e, "out of range"));

  e = error_of(kTwo + "[fluid]\nviscosty = 2.0\n");
  CHECK(contains(e, "[fluid] viscosty"));
  CHECK(contains(e, "unknown key"));
  CHECK(contains(e, "viscosity"));

  e = error_of(kTwo + "[hydrodynamics]\nmodel = \"lattice_boltzmann\"\n");
  CHECK(contains(e, "\"free_draining\""));

  e = error_of(kTwo + "[time]\nsteps = \"ten\"\n");
  CHECK(contains(e, "expected an integer"));

  e = error_of("[particles]\npositions = [[0,0,0],[3,0,0]]\nradii = [1.0]\n");
  CHECK(contains(e, "radii"));
  CHECK(contains(e, "1 entries for 2 positions"));

  e = error_of("[particles]\npositions = [[0,0,0]]\ngenerate = \"random\"\ncount = 3\n");
  CHECK(contains(e, "exactly one of"));

  e = error_of(kTwo + "[output]\nevery = 3\ncheckpoint_every = 10\n");
  CHECK(contains(e, "multiple"));

  e = error_of(kTwo + "[time\ndt = 1\n");
  CHECK(contains(e, "TOML syntax error"));

  e = error_of(kTwo + "[forces]\nexternal_force = [[0,0,1],[0,0,1],[0,0,1]]\n");
  CHECK(contains(e, "3 vectors for 2 particles"));

  e = error_of(kTwo + "[[forces.pair]]\nkind = \"morse\"\nstiffness = 3\n");
  CHECK(contains(e, "unknown key"));
}

TEST_CASE("asking for a model the engine lacks is an error, not a fallback") {
  CHECK(contains(error_of("[domain]\nkind = \"periodic\"\nbox = [10, 10, 10]\n" + kTwo +
                          "[hydrodynamics]\nfar_field = \"direct\"\n"), "no periodic images"));
  CHECK(contains(error_of(kTwo + "[hydrodynamics]\nfar_field = \"pme\"\n"), "needs a periodic domain"));
  CHECK(contains(error_of(kTwo + "[hydrodynamics]\nfar_field = \"octree\"\n"), "not in this version"));
  CHECK(contains(error_of("[domain]\nkind = \"periodic\"\nbox = [10, 10, 10]\n" + kTwo +
                          "[hydrodynamics]\nfar_field = \"tree\"\n"), "no periodic images"));
  CHECK(contains(error_of(kTwo + "[fluid]\nkT = 1.0\n[time]\nintegrator = \"rkf45\"\n"), "rkf45"));
  CHECK(contains(error_of(kTwo + "[forces]\nexternal_torque = [0,0,1]\n[hydrodynamics]\nmoments = \"F\"\n"), "torques"));
}

TEST_CASE("command line: a bad scene exits non-zero and writes nothing") {
  const auto dir = std::filesystem::temp_directory_path() / "stokesian_test_scene";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto scene = dir / "bad.toml";
  std::ofstream(scene) << kTwo << "[time]\ndt = 0\n";
  const auto out = dir / "out.h5";
  const std::string cmd = std::string(STOKESIAN_BINARY) + " run " + scene.string() + " --out " + out.string() +
                          " --quiet 2> " + (dir / "err.txt").string();
  const int status = std::system(cmd.c_str());
  CHECK(WEXITSTATUS(status) == 2);
  CHECK(!std::filesystem::exists(out));
  CHECK(!std::filesystem::exists(out.string() + ".ckpt"));
  std::ifstream err(dir / "err.txt");
  const std::string msg((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
  CHECK(contains(msg, "bad.toml:4: [time] dt"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("the resolved scene is complete: re-parsing it gives the same scene, bit for bit") {
  const Scene a = io::parse_scene(
      "[particles]\ngenerate = \"random\"\ncount = 20\nsize_distribution = \"lognormal\"\n[forces]\n"
      "external_force = [0, 0, -1]\n[[forces.pair]]\nkind = \"dlvo\"\n[[forces.pair]]\nkind = \"hertz\"\n"
      "[flow]\nkind = \"simple_shear\"\nrate = 0.3\n[time]\ndt = 0.1\nsteps = 7\nintegrator = \"midpoint\"\n",
      "gen.toml");
  const Scene b = io::parse_scene(a.toml, "resolved.toml");
  CHECK(b.toml == a.toml);
  REQUIRE(b.positions.size() == a.positions.size());
  for (std::size_t i = 0; i < a.positions.size(); ++i) {
    CHECK(b.positions[i] == a.positions[i]);
    CHECK(b.radii[i] == a.radii[i]);
  }
  CHECK(b.forces.pair.size() == 2);
  CHECK(b.time.integrator == "midpoint");
  CHECK(b.flow.rate == 0.3);
}

TEST_CASE("a recorded quantity the model does not compute is refused, naming the moments it needs") {
  const std::string sheared = "[domain]\nkind = \"periodic\"\nbox = [10, 10, 10]\n[fluid]\nkT = 1.0\n" + kTwo +
                              "[flow]\nkind = \"simple_shear\"\nrate = 0.1\n[hydrodynamics]\nmodel = \"far_field\"\n"
                              "moments = \"FT\"\n";
  auto observers_error = [](const std::string& text) -> std::string {
    try {
      const Scene s = io::parse_scene(text, "rec.toml");
      make_observers(s, resolve_model(s));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  // Earlier versions ran this scene and silently wrote no stresslet.
  const std::string e = observers_error(sheared + "[output]\nrecord = [\"stresslet\"]\n");
  CHECK(contains(e, "[output] record"));
  CHECK(contains(e, "\"stresslet\" needs moments = \"FTS\""));
  CHECK(contains(e, "resolves to moments = \"FT\""));
  CHECK(contains(observers_error(kTwo + "[hydrodynamics]\nmoments = \"F\"\n[output]\nrecord = [\"torque\"]\n"),
                 "\"torque\" needs moments = \"FT\" or \"FTS\""));
  // What the model computes is accepted; "all" (the default) takes whatever the model computes.
  CHECK(observers_error(sheared + "[output]\nrecord = [\"velocity\", \"angular_velocity\"]\n").empty());
  CHECK(observers_error(sheared).empty());
  CHECK(io::parse_scene(kTwo, "a.toml").output.record == std::vector<std::string>{"all"});
  CHECK(contains(error_of(kTwo + "[output]\nrecord = [\"all\", \"force\"]\n"), "\"all\" stands alone"));
  // 0.1.0 wrote its default as the full list: read back as "all", so its runs resume unchanged.
  const Scene old = io::parse_scene(kTwo + "[output]\nrecord = [\"velocity\", \"torque\", \"stresslet\", \"force\", "
                                           "\"angular_velocity\"]\n", "old.toml");
  CHECK(old.output.record == std::vector<std::string>{"all"});
}

TEST_CASE("Brownian motion with fixed particles, with stresslets, or with Stokesian dynamics resolves to fixman") {
  const std::string fixed = "[particles]\npositions = [[0,0,0],[3,0,0],[6,0,0]]\nfixed = [true, false, false]\n";
  const ResolvedModel m = resolve_model(io::parse_scene(fixed + "[fluid]\nkT = 1.0\n", "w.toml"));
  CHECK(m.integrator == "fixman");
  CHECK(contains(m.describe(), "fixed particles"));
  const ResolvedModel sh = resolve_model(io::parse_scene(kTwo + "[fluid]\nkT = 1.0\n[flow]\nkind = \"simple_shear\"\nrate = 1.0\n", "s.toml"));
  CHECK(sh.moments == Moments::FTS);
  CHECK(sh.integrator == "fixman");
  CHECK(error_of(kTwo + "[fluid]\nkT = 1.0\n[hydrodynamics]\nmodel = \"stokesian\"\n").empty());
  // A periodic box too small for the near-field pair search is a scene error naming the box.
  const std::string small = error_of("[domain]\nkind = \"periodic\"\nbox = [7, 7, 7]\n[particles]\npositions = "
                                     "[[0,0,0],[2.1,0,0]]\n[hydrodynamics]\nmodel = \"stokesian\"\n");
  CHECK(contains(small, "[domain] box"));
  CHECK(contains(small, "lubrication pairs reach centre distance 4 a"));
  CHECK(error_of(fixed + "[fluid]\nkT = 0.0\n").empty());
  CHECK(error_of(fixed + "[fluid]\nkT = 0.0\n[hydrodynamics]\nmodel = \"stokesian\"\n").empty());
  CHECK(error_of(fixed + "[fluid]\nkT = 1.0\n[hydrodynamics]\nmodel = \"free_draining\"\n").empty());
  CHECK(error_of("[particles]\npositions = [[0,0,0],[3,0,0],[6,0,0]]\n[fluid]\nkT = 1.0\n").empty());
}

TEST_CASE("pathological TOML texts are refused before parsing, naming the line and the limit") {
  // 200 000 dotted parts in a header or a key, or deep nesting, used to overflow the stack of the
  // TOML parser (SIGSEGV); the scan before parsing refuses them with a ConfigError.
  std::string parts;
  for (int i = 0; i < 200000; ++i) parts += "a.";
  std::string e = error_of(kTwo + "[" + parts + "a]\n");
  CHECK(contains(e, "bad.toml:3"));
  CHECK(contains(e, "dotted parts"));
  CHECK(contains(e, "allowed 1 to 64"));
  e = error_of(kTwo + "[output]\n" + parts + "a = 1\n");
  CHECK(contains(e, "bad.toml:4"));
  CHECK(contains(e, "allowed 1 to 64"));
  e = error_of(kTwo + "[output]\nx = {" + parts + "a = 1}\n");
  CHECK(contains(e, "allowed 1 to 64"));
  e = error_of(kTwo + "[output]\nx = " + std::string(100000, '[') + std::string(100000, ']') + "\n");
  CHECK(contains(e, "bad.toml:4"));
  CHECK(contains(e, "allowed at most 64 levels"));
  std::string inl;
  for (int i = 0; i < 100000; ++i) inl += "{a=";
  e = error_of(kTwo + "[output]\nx = " + inl + "1" + std::string(100000, '}') + "\n");
  CHECK(contains(e, "allowed at most 64 levels"));
  e = error_of(kTwo + "# " + std::string(17u << 20, 'x') + "\n");
  CHECK(contains(e, "allowed at most 16777216 bytes"));
  // Dots and brackets inside strings, comments and numbers are not structure.
  // (Strings are at most 4096 bytes: 2000 dotted parts.)
  const std::string ok = kTwo + "[output]\n# a.b.c [[[[ {{{\nauthor = \"" + parts.substr(0, 4000) + "[[[{{{\"\n";
  CHECK(error_of(ok) == "");
  CHECK(error_of(kTwo + "[forces]\nexternal_force = [[0.5, 0.25, 1.5], [0.5, 0.25, 1.5]]\n"
                        "[[forces.pair]]\nkind = 'hertz'\n[output]\nauthor = '''x.y\n\"z]'''\n") == "");
}

TEST_CASE("a misspelt key is reported as unknown before a required key is reported missing") {
  const std::string e = error_of(kTwo + "[[forces.pair]]\nkinds = \"hertz\"\n");
  CHECK(contains(e, "kinds"));
  CHECK(contains(e, "unknown key"));
  CHECK(contains(e, "allowed: "));
  CHECK(contains(e, "kind,"));
  CHECK(!contains(e, "required"));
}

TEST_CASE("generator keys with positions or file are refused, naming the key") {
  for (const std::string kv : {"count = \"x\"", "volume_fraction = nan", "size_distribution = \"bogus\"", "seed = -3",
                               "radius_ratio = 2", "large_fraction = 0.5", "sigma = 0.1"}) {
    const std::string key = kv.substr(0, kv.find(' '));
    const std::string e = error_of(kTwo + kv + "\n");
    CHECK_MESSAGE(contains(e, "[particles] " + key), kv);
    CHECK_MESSAGE(contains(e, "only meaningful with generate"), kv);
  }
  CHECK(error_of(kTwo + "radius = 0.5\n") == "");  // radius sizes given positions
}

TEST_CASE("radii, positions and overlaps are checked against documented ranges") {
  std::string e = error_of("[particles]\npositions = [[0,0,0],[3,0,0]]\nradii = [1.0, 1e-130]\n");
  CHECK(contains(e, "[particles] radii"));
  CHECK(contains(e, "allowed [0.001, 1000] a"));
  e = error_of("[particles]\npositions = [[0,0,0],[3,0,0]]\nradii = [1.0, inf]\n");
  CHECK(contains(e, "allowed [0.001, 1000] a"));
  e = error_of("[particles]\npositions = [[0,0,0]]\nradius = 1e-130\n");
  CHECK(contains(e, "[particles] radius"));
  CHECK(contains(e, "allowed [0.001, 1000]"));
  e = error_of("[particles]\npositions = [[0,0,0],[300,0,0]]\nradii = [0.5, 60.0]\n");
  CHECK(contains(e, "[particles] positions"));
  CHECK(contains(e, "allowed at most 100"));
  e = error_of("[particles]\ngenerate = \"random\"\ncount = 3\nradius_ratio = 500\nsize_distribution = \"bidisperse\"\n");
  CHECK(contains(e, "[particles] radius_ratio"));
  CHECK(contains(e, "allowed [0.01, 100]"));
  // Coincident or deeply overlapping centres: both indices named (also across a periodic boundary).
  e = error_of("[particles]\npositions = [[0,0,0],[5,0,0],[5,0,0]]\n");
  CHECK(contains(e, "[particles] positions"));
  CHECK(contains(e, "particles 1 and 2"));
  CHECK(contains(e, "half the smaller radius"));
  e = error_of("[domain]\nkind = \"periodic\"\nbox = [10, 10, 10]\n[particles]\npositions = [[0.2,0,0],[9.5,0,0]]\n");
  CHECK(contains(e, "particles 0 and 1"));
  CHECK(error_of("[particles]\npositions = [[0,0,0],[1.6,0,0]]\n") == "");  // overlap 0.4 a: allowed
  // Non-finite coordinates in an XYZ file: the particle index and the file are named.
  const auto dir = std::filesystem::temp_directory_path() / "stokesian_test_scene_nan";
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir / "nan.xyz");
    f << "2\nProperties=species:S:1:pos:R:3:radius:R:1\nA 0 0 0 1.0\nA nan 4 0 1.0\n";
  }
  {
    std::ofstream f(dir / "s.toml");
    f << "[particles]\nfile = \"nan.xyz\"\n";
  }
  try {
    io::load_scene((dir / "s.toml").string());
    FAIL("no error");
  } catch (const ConfigError& err) {
    e = err.what();
  }
  CHECK(contains(e, "[particles] file"));
  CHECK(contains(e, "particle 1"));
  CHECK(contains(e, "nan.xyz"));
  CHECK(contains(e, "finite"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("periodic box edges and the count implied by volume_fraction are bounded") {
  std::string e = error_of("[domain]\nkind = \"periodic\"\nbox = [1e7, 10, 10]\n" + kTwo);
  CHECK(contains(e, "[domain] box"));
  CHECK(contains(e, "(0, 1e+06] a"));
  e = error_of("[domain]\nkind = \"periodic\"\nbox = [1e5, 1e5, 1e5]\n[particles]\ngenerate = \"lattice\"\n"
               "volume_fraction = 0.5\n");
  CHECK(contains(e, "[particles] volume_fraction"));
  CHECK(contains(e, "allowed count 1 to 10000000"));
  CHECK(contains(e, "1.19"));  // round(0.5e15 / (4 pi / 3)) = 1.19e14 particles
  e = error_of("[domain]\nkind = \"periodic\"\nbox = [3, 3, 3]\n[particles]\ngenerate = \"lattice\"\n"
               "volume_fraction = 0.001\n");
  CHECK(contains(e, "= 0 in this box"));
}

namespace {

// The ConfigError of the scene `text` written as s.toml beside the files `files` (name, content).
std::string file_error_of(const std::string& text, const std::vector<std::pair<std::string, std::string>>& files) {
  const auto dir = std::filesystem::temp_directory_path() / "stokesian_test_scene_files";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  for (const auto& [name, body] : files) std::ofstream(dir / name) << body;
  std::ofstream(dir / "s.toml") << text;
  std::string e;
  try {
    io::load_scene((dir / "s.toml").string());
  } catch (const ConfigError& err) {
    e = err.what();
  }
  std::filesystem::remove_all(dir);
  return e;
}

const std::string kXyzWithRadii = "2\nProperties=species:S:1:pos:R:3:radius:R:1\nA 0 0 0 1.0\nA 4 0 0 1.5\n";

}  // namespace

// Fuzz finding (issue 10): `radius` beside a file with a radius column was ignored without a word,
// and its value was never checked (radius = inf passed).
TEST_CASE("radius beside a particle file that has radii is refused; beside one without, it is checked") {
  std::string e = file_error_of("[particles]\nfile = \"p.xyz\"\nradius = 2.0\n", {{"p.xyz", kXyzWithRadii}});
  CHECK(contains(e, "s.toml:3: [particles] radius"));
  CHECK(contains(e, "p.xyz gives a radius per particle"));
  CHECK(contains(e, "allowed"));
  e = file_error_of("[particles]\nfile = \"p.xyz\"\nradius = inf\n", {{"p.xyz", kXyzWithRadii}});
  CHECK(contains(e, "[particles] radius"));
  CHECK(contains(e, "allowed [0.001, 1000]"));
  const std::string plain = "2\ncomment\nA 0 0 0\nA 4 0 0\n";
  e = file_error_of("[particles]\nfile = \"p.xyz\"\nradius = nan\n", {{"p.xyz", plain}});
  CHECK(contains(e, "[particles] radius"));
  CHECK(contains(e, "allowed [0.001, 1000]"));
  CHECK(file_error_of("[particles]\nfile = \"p.xyz\"\nradius = 1.5\n", {{"p.xyz", plain}}) == "");
  CHECK(file_error_of("[particles]\nfile = \"p.xyz\"\n", {{"p.xyz", kXyzWithRadii}}) == "");
}

// Fuzz finding: a non-positive or non-finite radius in an XYZ file said "radius must be positive"
// without the value, the particle or what is allowed.
TEST_CASE("a bad radius in an XYZ file names the file, line, particle, value and what is allowed") {
  const std::string e = file_error_of("[particles]\nfile = \"p.xyz\"\n",
                                      {{"p.xyz", "2\nProperties=species:S:1:pos:R:3:radius:R:1\nA 0 0 0 1\nA 4 0 0 -2\n"}});
  CHECK(contains(e, "s.toml:2: [particles] file"));
  CHECK(contains(e, "p.xyz:4"));
  CHECK(contains(e, "radius -2 of particle 1"));
  CHECK(contains(e, "allowed: a finite number > 0"));
}

// Fuzz finding: a volume fraction beyond what the generator reaches was reported against
// `generate` (not the key that sets it) and without the allowed limit; a periodic count far beyond
// it ran the placement first.
TEST_CASE("volume fractions beyond what a generator reaches are refused naming the key and the limit") {
  std::string e = error_of("[particles]\ngenerate = \"random\"\ncount = 20\nvolume_fraction = 0.7\n");
  CHECK(contains(e, "bad.toml:4: [particles] volume_fraction"));
  CHECK(contains(e, "allowed: generate = \"random\" up to volume fraction 0.6"));
  e = error_of("[particles]\ngenerate = \"random\"\ncount = 20\nvolume_fraction = 0.4\nequilibration_sweeps = 0\n");
  CHECK(contains(e, "[particles] volume_fraction"));
  CHECK(contains(e, "0.35 with equilibration_sweeps = 0"));
  // A periodic box given by count: the count implies the fraction (here 10^6 spheres in 10^3 a^3).
  e = error_of("[domain]\nkind = \"periodic\"\nbox = [10, 10, 10]\n[particles]\ngenerate = \"random\"\ncount = 1000000\n");
  CHECK(contains(e, "bad.toml:6: [particles] count"));
  CHECK(contains(e, "(from count)"));
  CHECK(contains(e, "allowed"));
  // Lattice: simple cubic spacing below 2 a + min_gap.
  e = error_of("[particles]\ngenerate = \"lattice\"\ncount = 27\nvolume_fraction = 0.6\n");
  CHECK(contains(e, "bad.toml:4: [particles] volume_fraction (generate = \"lattice\")"));
  CHECK(contains(e, "lattice spacing"));
  CHECK(contains(e, "pi/6"));
  e = error_of("[domain]\nkind = \"periodic\"\nbox = [12, 12, 12]\n[particles]\ngenerate = \"lattice\"\nvolume_fraction = 0.5\n");
  CHECK(contains(e, "[particles] volume_fraction"));
  CHECK(contains(e, "allowed"));
  CHECK(error_of("[particles]\ngenerate = \"lattice\"\ncount = 27\nvolume_fraction = 0.5\n") == "");
}

// Fuzz findings: a TOML syntax error (e.g. an integer beyond 64 bits) named the line but not the
// key; strings had no length limit (a 1 MiB author made solve fail writing its HDF5 attribute); type
// errors did not say what is allowed.
TEST_CASE("syntax errors quote the line, strings are bounded, type errors give the allowed range") {
  std::string e = error_of(kTwo + "[time]\nsteps = 99999999999999999999\n");
  CHECK(contains(e, "bad.toml:4: TOML syntax error"));
  CHECK(contains(e, "(in the line: steps = 99999999999999999999)"));
  e = error_of(kTwo + "[time]\ndt = 1\ndt = 2\n");
  CHECK(contains(e, "bad.toml:5"));
  CHECK(contains(e, "dt = 2"));
  e = error_of(kTwo + "[output]\nauthor = \"a\x01\"\n");  // a control byte: quoted as \x01
  CHECK(contains(e, "\\x01"));
  e = error_of(kTwo + "[output]\nauthor = \"" + std::string(5000, 'A') + "\"\n");
  CHECK(contains(e, "bad.toml:4: [output] author"));
  CHECK(contains(e, "a string of 5000 bytes (allowed at most 4096 bytes)"));
  CHECK(error_of(kTwo + "[output]\nauthor = \"" + std::string(4096, 'A') + "\"\n") == "");
  e = error_of(kTwo + "[output]\nxyz = \"" + std::string(5000, 'x') + "\"\n");
  CHECK(contains(e, "[output] xyz"));
  e = error_of(kTwo + "[brownian]\nseed = nan\n");
  CHECK(contains(e, "[brownian] seed: expected an integer, got a float (allowed an integer in [0, "));
  e = error_of(kTwo + "[brownian]\nstress_every = -1\n");
  CHECK(contains(e, "[brownian] stress_every"));
  CHECK(contains(e, "[0, 1000000000]"));
  e = error_of(kTwo + "[brownian]\nstress_every = \"often\"\n");
  CHECK(contains(e, "[brownian] stress_every: \"often\" is not \"auto\" or an integer"));
  CHECK(io::parse_scene(kTwo, "two.toml").brownian_stress_every == -1);  // "auto"
  CHECK(io::parse_scene(kTwo + "[brownian]\nstress_every = \"auto\"\n", "two.toml").brownian_stress_every == -1);
  for (const char* v : {"7", "\"auto\""}) {
    const Scene a = io::parse_scene(kTwo + "[brownian]\nstress_every = " + v + "\n", "b.toml");
    CHECK(io::parse_scene(io::resolved_toml(a), "r.toml").brownian_stress_every == a.brownian_stress_every);
  }
  e = error_of(kTwo + "[time]\ndt = \"x\"\n");
  CHECK(contains(e, "[time] dt: expected a number, got a string (allowed (0, 1e+12])"));
}

// Fuzz finding: a pair law reaching beyond half a small periodic box (e.g. DLVO's default range in a
// box of 10 a) passed check's validation and stopped the first force evaluation with exit 4 and
// "neighbor_pairs: interaction range ... exceeds half the smallest box edge", naming no key; a
// non-finite box edge did not say what is allowed.
TEST_CASE("a pair law longer than half the periodic box is a scene error naming the law, key and limit") {
  const std::string box = "[domain]\nkind = \"periodic\"\nbox = [10, 10, 10]\n[particles]\ngenerate = \"lattice\"\ncount = 8\n";
  std::string e = error_of(box + "[[forces.pair]]\nkind = \"dlvo\"\n");
  CHECK(contains(e, "bad.toml:8: [forces.pair.0] kind"));
  CHECK(contains(e, "the law's default"));
  CHECK(contains(e, "allowed: gap cut-off at most 3 a in this box"));
  e = error_of(box + "[[forces.pair]]\nkind = \"hertz\"\n[[forces.pair]]\nkind = \"morse\"\ncutoff = 3.5\n");
  CHECK(contains(e, "bad.toml:11: [forces.pair.1] cutoff"));
  CHECK(error_of(box + "[[forces.pair]]\nkind = \"morse\"\ncutoff = 3.0\n") == "");
  e = error_of("[domain]\nkind = \"periodic\"\nbox = [nan, 10, 10]\n" + kTwo);
  CHECK(contains(e, "bad.toml:3: [domain] box: component 0 is not a finite number (allowed: finite numbers)"));
}

// Fuzz finding: model resolution measured the smallest gap by a double loop over all pairs, so
// `check` of a 3e5-particle lattice spent minutes there (a hang in the fuzz test). Beyond the N
// where Stokesian dynamics can apply, only whether a gap lies below 0.5 a matters, found by the
// cell list; the outcome must be the same as the definition's.
TEST_CASE("auto level for large N: a close pair is still found (cell list), and no false one") {
  std::string pos;
  for (int i = 0; i < 3000; ++i) pos += (i ? ", [" : "[") + std::to_string(3.0 * (i % 15)) + ", " +
                                        std::to_string(3.0 * ((i / 15) % 15)) + ", " + std::to_string(3.0 * (i / 225)) + "]";
  const std::string far = "[particles]\npositions = [" + pos + "]\n";
  const ResolvedModel m = resolve_model(io::parse_scene(far, "far.toml"));
  CHECK(m.level == HydroModel::far_field);
  CHECK(!contains(m.describe(), "lubrication would be more accurate"));
  // The last particle moved to gap 0.2 a of its neighbour (centres 2.2 a apart).
  const std::string close = "[particles]\npositions = [" + pos.substr(0, pos.rfind(", [")) + ", [" +
                            std::to_string(3.0 * (2999 % 15) - 0.8) + ", " + std::to_string(3.0 * ((2999 / 15) % 15)) +
                            ", " + std::to_string(3.0 * (2999 / 225)) + "]]\n";
  const ResolvedModel c = resolve_model(io::parse_scene(close, "close.toml"));
  CHECK(c.level == HydroModel::stokesian);  // N > 2000: accelerated SD (dense SD would not apply)
  CHECK(c.solver == "accelerated_sd");
  CHECK(contains(c.describe(), "close pairs (smallest gap"));
}

TEST_CASE("[hydrodynamics] solver: auto picks dense below the crossover and accelerated above; explicit choices; bad values") {
  auto model = [](const std::string& text) { return resolve_model(io::parse_scene(text, "s.toml")); };
  const std::string close = "[particles]\npositions = [[0,0,0],[2.1,0,0]]\n[hydrodynamics]\nmodel = \"stokesian\"\n";
  CHECK(model(close).solver == "dense_sd");
  CHECK(model(close + "solver = \"accelerated\"\n").solver == "accelerated_sd");
  CHECK(model(close + "solver = \"dense\"\n").solver == "dense_sd");
  const std::string many = "[particles]\ngenerate = \"lattice\"\ncount = 1000\nvolume_fraction = 0.2\n"
                           "[hydrodynamics]\nmodel = \"stokesian\"\n";
  const ResolvedModel big = model(many);
  CHECK(big.solver == "accelerated_sd");
  bool said = false;
  for (const auto& r : big.reasons) said |= contains(r, "auto solver: N = 1000 > 50 -> accelerated_sd");
  CHECK(said);
  CHECK(model(many + "solver = \"dense\"\n").solver == "dense_sd");
  // dense beyond its limit is refused with the reason.
  const std::string e = error_of("[particles]\ngenerate = \"lattice\"\ncount = 2500\nvolume_fraction = 0.2\n"
                                 "[hydrodynamics]\nmodel = \"stokesian\"\nsolver = \"dense\"\n");
  CHECK(contains(e, "N <= 2000"));
  const std::string bad = error_of(kTwo + "[hydrodynamics]\nsolver = \"fast\"\n");
  CHECK(contains(bad, "bad.toml"));
  CHECK(contains(bad, "solver"));
  CHECK(contains(bad, "accelerated"));
  // On another level the key is noted, not silently dropped.
  const ResolvedModel ff = model(kTwo + "[hydrodynamics]\nmodel = \"far_field\"\nsolver = \"accelerated\"\n");
  bool noted = false;
  for (const auto& r : ff.reasons) noted |= contains(r, "applies to the stokesian level only");
  CHECK(noted);
}

TEST_CASE("far_field auto in open domains: direct below the octree's crossover, the tree from it") {
  // trees::tree_auto_from: the measured crossover with the vectorised direct sum (docs/tree.md).
  auto model = [](long n, const char* moments) {
    return resolve_model(io::parse_scene("[particles]\ngenerate = \"lattice\"\ncount = " + std::to_string(n) +
                                             "\nvolume_fraction = 0.1\n[hydrodynamics]\nmodel = \"far_field\"\n"
                                             "moments = \"" + moments + "\"\ntolerance = 1e-3\n",
                                         "s.toml"));
  };
  auto said = [](const ResolvedModel& r, const std::string& what) {
    bool yes = false;
    for (const auto& line : r.reasons) yes |= contains(line, what);
    return yes;
  };
  for (const char* m : {"F", "FTS"}) {
    CAPTURE(m);
    const ResolvedModel small = model(2000, m), large = model(40000, m);
    CHECK(small.far_field == "direct");
    CHECK(said(small, "the octree's measured crossover"));
    CHECK(large.far_field == "tree");
    CHECK(said(large, "the measured crossover with direct"));
  }
}

TEST_CASE("[flow] peclet sets rate = Pe kT / (6 pi mu); refused with rate, without kT or without a flow") {
  const std::string base = "[particles]\npositions = [[0,0,0]]\n[fluid]\nkT = 2.0\nviscosity = 1.5\n";
  const Scene s = io::parse_scene(base + "[flow]\nkind = \"simple_shear\"\npeclet = 10.0\n", "pe.toml");
  CHECK(s.flow.peclet == 10.0);
  CHECK(s.flow.rate == doctest::Approx(10.0 * 2.0 / (6.0 * kPi * 1.5)).epsilon(1e-15));
  // The resolved scene keeps the Peclet number and gives the same rate.
  const Scene r = io::parse_scene(io::resolved_toml(s), "pe2.toml");
  CHECK(r.flow.peclet == 10.0);
  CHECK(r.flow.rate == s.flow.rate);
  auto has = [](const std::string& e, const std::string& part) { return e.find(part) != std::string::npos; };
  std::string e = error_of(base + "[flow]\nkind = \"simple_shear\"\npeclet = 10.0\nrate = 1.0\n");
  CHECK(has(e, "[flow] peclet"));
  CHECK(has(e, "either rate or peclet"));
  e = error_of("[particles]\npositions = [[0,0,0]]\n[flow]\nkind = \"simple_shear\"\npeclet = 10.0\n");
  CHECK(has(e, "needs [fluid] kT > 0"));
  e = error_of(base + "[flow]\npeclet = 10.0\n");
  CHECK(has(e, "needs a flow"));
}

TEST_CASE("[brownian] stress_every = \"auto\": the Brownian stress is sampled every step with an ambient flow, else not") {
  const std::string box = "[fluid]\nkT = 1.0\n[domain]\nkind = \"periodic\"\nbox = [8, 8, 8]\n"
                          "[particles]\npositions = [[0,0,0],[2.5,0,0]]\n[hydrodynamics]\nmodel = \"stokesian\"\n"
                          "moments = \"FTS\"\n";
  auto every = [](const std::string& text) { return resolve_model(io::parse_scene(text, "s.toml")).brownian_stress_every; };
  CHECK(every(box) == 0);
  CHECK(every(box + "[flow]\nkind = \"simple_shear\"\nrate = 0.1\n") == 1);
  CHECK(every(box + "[flow]\nkind = \"simple_shear\"\nrate = 0.1\n[brownian]\nstress_every = 0\n") == 0);
  CHECK(every(box + "[brownian]\nstress_every = 5\n") == 5);
  // Where no stress is recorded (open domain) nothing is sampled, whatever the key says.
  CHECK(every("[fluid]\nkT = 1.0\n[particles]\npositions = [[0,0,0],[2.5,0,0]]\n[hydrodynamics]\nmodel = \"stokesian\"\n"
              "moments = \"FTS\"\n[brownian]\nstress_every = 1\n") == 0);
  const std::string why = resolve_model(io::parse_scene(box + "[flow]\nkind = \"simple_shear\"\nrate = 0.1\n", "s.toml")).describe();
  CHECK(why.find("auto Brownian stress: linear ambient flow -> sampled every step") != std::string::npos);
}

TEST_CASE("resume compatibility: a stored [brownian] stress_every = 1 equals \"auto\" where auto samples every step or nothing is sampled") {
  const std::string base = "[particles]\npositions = [[0,0,0],[3,0,0]]\n[domain]\nkind = \"periodic\"\nbox = [9, 9, 9]\n";
  const std::string shear = "[flow]\nkind = \"simple_shear\"\nrate = 0.1\n";
  auto resolved = [](const std::string& text) { return io::resolved_toml(io::parse_scene(text, "s.toml")); };
  const std::string one = "[brownian]\nstress_every = 1\n";
  // With a flow (auto = every step) and athermal (never sampled): the same run.
  CHECK(io::scene_differences(resolved("[fluid]\nkT = 1.0\n" + base + shear + one), resolved("[fluid]\nkT = 1.0\n" + base + shear)).empty());
  CHECK(io::scene_differences(resolved(base + shear + one), resolved(base + shear)).empty());
  CHECK(io::scene_differences(resolved(base + one), resolved(base)).empty());
  // Brownian without a flow: auto samples nothing, 1 every step: different runs.
  const auto d = io::scene_differences(resolved("[fluid]\nkT = 1.0\n" + base + one), resolved("[fluid]\nkT = 1.0\n" + base));
  REQUIRE(d.size() == 1);
  CHECK(d[0].find("stress_every") != std::string::npos);
  // Other values always count.
  CHECK(io::scene_differences(resolved("[fluid]\nkT = 1.0\n" + base + shear + "[brownian]\nstress_every = 2\n"),
                              resolved("[fluid]\nkT = 1.0\n" + base + shear)).size() == 1);
}
