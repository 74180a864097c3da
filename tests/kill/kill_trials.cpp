// kill_trials: kills `stokesian run` with SIGKILL at seeded random moments, continues it with
// --resume until it completes, and compares the result with an uninterrupted run.
//
//   kill_trials --scene FILE --stokesian PATH --work DIR [--trials 20] [--seed 1] [--threads 1]
//               [--first-trial 0] [--report out.json] [--keep]
//
// Trial t's kill moments depend only on (seed, t): --first-trial K --trials N runs trials K..K+N-1,
// so a long form can be split over several processes (each makes its own uninterrupted run).
//
// Once: `stokesian run FILE --out DIR/ref/k.h5` uninterrupted (timed: T). Then per trial t, in
// DIR/trial_t: a fresh `run` and then `run --resume` processes, each killed at a seeded moment,
// 1 to 4 kills per trial, until a process exits 0. Kill moments (per trial, from the seed):
//   * trials 0, 4, 8, ...: the first run is killed as soon as out.h5.shadow exists (the start has
//     created its files, long before the first checkpoint);
//   * trials 1, 5, ...: the first run is killed at a uniform moment before the first checkpoint is
//     due (checkpoint_every / steps of T);
//   * the other first runs, and every --resume, at a uniform moment in [0, 0.6 T], or with
//     probability 1/3 within the first 300 ms (the resume's rebuilding of its files).
// After every kill the visible files must be readable: out.h5 opens with HDF5 and every dataset is
// a prefix (first dimension) of the uninterrupted run's; the XYZ file is a byte prefix of the
// uninterrupted run's (a kill may cut its last frame; --resume removes that).
// At the end every dataset of the trajectory (found by visiting all links: values, steps, times,
// parameters) must equal the uninterrupted run's in shape and bytes, every attribute too, and the
// XYZ file (if the scene writes one) byte for byte.
// Exit status: 0 all trials identical, 1 some trial differs or failed, 2 usage or set-up error.
#include "../support/child_process.hpp"
#include "../support/h5_compare.hpp"

#include <hdf5.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using stokesian::test::ChildOutcome;
using stokesian::test::run_child;
using stokesian::test::Blob;
using stokesian::test::compare;
using stokesian::test::read_file;

namespace {

struct Options {
  std::string scene, stokesian, work, report;
  int trials = 20, threads = 1, first_trial = 0;
  std::uint64_t seed = 1;
  bool keep = false;
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "kill_trials: %s\nusage: kill_trials --scene FILE --stokesian PATH --work DIR [--trials N] [--seed S] "
               "[--threads T] [--first-trial K] [--report out.json] [--keep]\n",
               why.c_str());
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(a + " needs a value");
      return argv[++i];
    };
    auto number = [&](long lo, long hi) {
      const std::string v = value();
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (v.empty() || *end || n < lo || n > hi)
        usage(a + " = " + v + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
      return n;
    };
    if (a == "--scene") o.scene = value();
    else if (a == "--stokesian") o.stokesian = value();
    else if (a == "--work") o.work = value();
    else if (a == "--report") o.report = value();
    else if (a == "--trials") o.trials = int(number(1, 10000));
    else if (a == "--threads") o.threads = int(number(1, 256));
    else if (a == "--first-trial") o.first_trial = int(number(0, 1000000));
    else if (a == "--seed") o.seed = std::uint64_t(number(0, 2147483647));
    else if (a == "--keep") o.keep = true;
    else usage("unknown option " + a);
  }
  if (o.scene.empty() || o.stokesian.empty() || o.work.empty()) usage("--scene, --stokesian and --work are required");
  if (!fs::exists(o.scene)) usage("--scene " + o.scene + ": no such file");
  if (!fs::exists(o.stokesian)) usage("--stokesian " + o.stokesian + ": no such file");
  o.scene = fs::absolute(o.scene).string();
  o.stokesian = fs::absolute(o.stokesian).string();
  return o;
}

std::string bytes_of(const std::string& path) {
  std::ifstream is(path, std::ios::binary);
  std::ostringstream ss;
  ss << is.rdbuf();
  return ss.str();
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (c == '\n') o += "\\n";
    else if (static_cast<unsigned char>(c) < 0x20) o += ' ';
    else o += c;
  }
  return o;
}

struct Kill {
  double planned_ms = -1;     // < 0: killed when out.h5.shadow appeared
  double at_ms = 0;           // when it ended
  bool resume = false;        // a --resume process
  bool before_checkpoint = false;  // no checkpoint on disk after the kill
  std::vector<std::string> problems;  // unreadable or inconsistent visible files after the kill
};

struct Trial {
  int index = 0;
  std::vector<Kill> kills;
  int runs = 0;
  bool completed = false;
  bool identical = false;
  std::vector<std::string> problems;
};

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  std::error_code ec;
  fs::create_directories(opt.work, ec);
  if (ec) usage("--work " + opt.work + ": " + ec.message());
  const fs::path work = fs::absolute(opt.work);

  auto command = [&](const fs::path& dir, bool resume) {
    std::vector<std::string> a{opt.stokesian, "run", opt.scene, "--out", (dir / "k.h5").string(), "--quiet",
                               "--threads", std::to_string(opt.threads)};
    if (resume) a.push_back("--resume");
    return a;
  };

  // The uninterrupted run.
  const fs::path ref_dir = work / "ref";
  fs::remove_all(ref_dir);
  fs::create_directories(ref_dir);
  const ChildOutcome ref_run = run_child(command(ref_dir, false), -1, "", (ref_dir / "stderr.txt").string());
  if (ref_run.killed || ref_run.status != 0) {
    std::fprintf(stderr, "kill_trials: the uninterrupted run failed (status %d, signal %d): %s\n", ref_run.status,
                 ref_run.signal, bytes_of((ref_dir / "stderr.txt").string()).c_str());
    return 2;
  }
  const double T = ref_run.ms;
  std::map<std::string, Blob> ref_h5;
  std::string err;
  if (!read_file((ref_dir / "k.h5").string(), ref_h5, err)) {
    std::fprintf(stderr, "kill_trials: %s\n", err.c_str());
    return 2;
  }
  const bool has_xyz = fs::exists(ref_dir / "k.xyz");
  const std::string ref_xyz = has_xyz ? bytes_of((ref_dir / "k.xyz").string()) : "";
  // When the first checkpoint is due, as a share of the run: checkpoint_every / steps, found in the
  // scene text by a plain line search (0.2 if either key is absent).
  double first_ckpt_share = 0.2;
  {
    const std::string scene = bytes_of(opt.scene);
    auto key = [&](const std::string& k) -> double {
      std::istringstream is(scene);
      for (std::string line; std::getline(is, line);) {
        const auto p = line.find_first_not_of(" \t");
        if (p == std::string::npos || line.compare(p, k.size(), k) != 0) continue;
        const auto eq = line.find('=', p + k.size());
        if (eq == std::string::npos || line.find_first_not_of(" \t", p + k.size()) != eq) continue;
        return std::atof(line.c_str() + eq + 1);
      }
      return 0;
    };
    const double every = key("checkpoint_every"), steps = key("steps");
    if (every > 0 && steps > 0) first_ckpt_share = std::min(1.0, every / steps);
  }
  std::printf("uninterrupted run: %.0f ms; first checkpoint due at %.0f%% of it; %zu datasets and attributes%s\n", T,
              100 * first_ckpt_share, ref_h5.size(), has_xyz ? ", XYZ file" : "");
  std::fflush(stdout);

  std::vector<Trial> trials;
  int identical = 0, kills_total = 0, kills_before_ckpt = 0, kills_in_resume = 0;
  for (int t = opt.first_trial; t < opt.first_trial + opt.trials; ++t) {
    Trial tr;
    tr.index = t;
    std::seed_seq seq{std::uint32_t(opt.seed), std::uint32_t(opt.seed >> 32), std::uint32_t(t)};
    std::mt19937_64 rng(seq);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int planned_kills = 1 + int(rng() % 4);
    const fs::path dir = work / ("trial_" + std::to_string(t));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string out = (dir / "k.h5").string(), xyz = (dir / "k.xyz").string();
    const std::string err_file = (dir / "stderr.txt").string();
    for (int run = 0; run < planned_kills + 40; ++run) {
      const bool resume = run > 0;
      double kill_ms = -1;
      std::string kill_when;
      if (run < planned_kills) {
        if (run == 0 && t % 4 == 0) kill_when = out + ".shadow";
        else if (run == 0 && t % 4 == 1) kill_ms = u(rng) * first_ckpt_share * T;
        else if (u(rng) < 1.0 / 3.0) kill_ms = u(rng) * 300.0;
        else kill_ms = u(rng) * 0.6 * T;
      }
      ++tr.runs;
      const ChildOutcome c = run_child(command(dir, resume), kill_ms, kill_when, err_file, 10 * T + 60000);
      if (c.timed_out) {
        tr.problems.push_back("run " + std::to_string(run) + " hung (killed after " + std::to_string(int(c.ms)) + " ms)");
        break;
      }
      if (c.killed && c.signal != SIGKILL) {
        tr.problems.push_back("run " + std::to_string(run) + " crashed with signal " + std::to_string(c.signal));
        break;
      }
      if (!c.killed) {
        if (c.status == 0) {
          tr.completed = true;
          break;
        }
        tr.problems.push_back("run " + std::to_string(run) + (resume ? " (--resume)" : "") + " exited " +
                              std::to_string(c.status) + ": " + bytes_of(err_file));
        break;
      }
      Kill k;
      k.planned_ms = kill_when.empty() ? kill_ms : -1;
      k.at_ms = c.ms;
      k.resume = resume;
      k.before_checkpoint = !fs::exists(out + ".ckpt");
      // The visible files after the kill.
      if (fs::exists(out)) {
        std::map<std::string, Blob> got;
        if (!read_file(out, got, err)) k.problems.push_back("trajectory unreadable: " + err);
        else
          for (const std::string& d : compare(got, ref_h5, true)) k.problems.push_back("trajectory " + d);
      }
      if (has_xyz && fs::exists(xyz)) {
        const std::string b = bytes_of(xyz);
        if (b.size() > ref_xyz.size() || ref_xyz.compare(0, b.size(), b) != 0)
          k.problems.push_back("XYZ file (" + std::to_string(b.size()) + " bytes) is not a prefix of the uninterrupted run's");
      }
      for (const auto& p : k.problems) tr.problems.push_back("after kill " + std::to_string(tr.kills.size()) + ": " + p);
      ++kills_total;
      kills_before_ckpt += k.before_checkpoint;
      kills_in_resume += k.resume;
      tr.kills.push_back(std::move(k));
    }
    if (tr.completed) {
      std::map<std::string, Blob> got;
      if (!read_file(out, got, err)) tr.problems.push_back("final trajectory unreadable: " + err);
      else
        for (const std::string& d : compare(got, ref_h5, false)) tr.problems.push_back("final trajectory " + d);
      if (has_xyz && bytes_of(xyz) != ref_xyz) tr.problems.push_back("final XYZ file differs from the uninterrupted run's");
      if (fs::exists(out + ".shadow")) tr.problems.push_back("k.h5.shadow left after completion");
      if (fs::exists(out + ".starting")) tr.problems.push_back("k.h5.starting left after completion");
    } else if (tr.problems.empty()) {
      tr.problems.push_back("did not complete");
    }
    tr.identical = tr.completed && tr.problems.empty();
    identical += tr.identical;
    std::string phases;
    for (const Kill& k : tr.kills)
      phases += std::string(phases.empty() ? "" : ", ") + (k.resume ? "resume" : "start") + "@" +
                std::to_string(int(k.at_ms)) + "ms" + (k.before_checkpoint ? "(no ckpt)" : "");
    std::printf("trial %2d: %s; %zu kill(s): %s\n", t, tr.identical ? "identical" : "DIFFERENT", tr.kills.size(),
                phases.c_str());
    for (const auto& p : tr.problems) std::printf("    %s\n", p.c_str());
    std::fflush(stdout);
    if (tr.identical && !opt.keep) fs::remove_all(dir);
    trials.push_back(std::move(tr));
  }
  std::printf("%d of %d trials identical to the uninterrupted run; %d kills: %d before the first checkpoint, %d of "
              "--resume processes\n",
              identical, opt.trials, kills_total, kills_before_ckpt, kills_in_resume);

  if (!opt.report.empty()) {
    std::ofstream r(opt.report);
    r << "{\n  \"scene\": \"" << json_escape(opt.scene) << "\",\n  \"seed\": " << opt.seed
      << ",\n  \"first_trial\": " << opt.first_trial << ",\n  \"threads\": "
      << opt.threads << ",\n  \"uninterrupted_ms\": " << T << ",\n  \"trials\": " << opt.trials
      << ",\n  \"identical\": " << identical << ",\n  \"kills\": " << kills_total
      << ",\n  \"kills_before_first_checkpoint\": " << kills_before_ckpt << ",\n  \"kills_of_resumes\": "
      << kills_in_resume << ",\n  \"details\": [\n";
    for (std::size_t i = 0; i < trials.size(); ++i) {
      const Trial& tr = trials[i];
      r << "    {\"trial\": " << tr.index << ", \"identical\": " << (tr.identical ? "true" : "false")
        << ", \"runs\": " << tr.runs << ", \"kills\": [";
      for (std::size_t j = 0; j < tr.kills.size(); ++j) {
        const Kill& k = tr.kills[j];
        r << (j ? ", " : "") << "{\"resume\": " << (k.resume ? "true" : "false") << ", \"planned_ms\": " << k.planned_ms
          << ", \"at_ms\": " << k.at_ms << ", \"before_first_checkpoint\": " << (k.before_checkpoint ? "true" : "false")
          << "}";
      }
      r << "], \"problems\": [";
      for (std::size_t j = 0; j < tr.problems.size(); ++j) r << (j ? ", " : "") << '"' << json_escape(tr.problems[j]) << '"';
      r << "]}" << (i + 1 < trials.size() ? "," : "") << "\n";
    }
    r << "  ]\n}\n";
  }
  if (identical == opt.trials && !opt.keep) fs::remove_all(ref_dir);
  return identical == opt.trials ? 0 : 1;
}
