// `stokesian sweep` (sweep.hpp, docs/sweeps.md).
#include "engine/app/sweep.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/statistics.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"
#include "io/sweep.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace stokesian::app {
namespace {

// Exit status of a child that found its run locked by another sweep process.
constexpr int kBusy = 75;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Writes `text` to `p` through a temporary file, fsync and rename.
void write_atomic(const fs::path& p, const std::string& text) {
  const std::string tmp = p.string() + ".tmp." + std::to_string(getpid());
  {
    std::ofstream o(tmp, std::ios::trunc);
    o << text;
    o.flush();
    if (!o) throw IoError(tmp + ": cannot write");
  }
  io::detail::fsync_file(tmp);
  io::detail::durable_rename(tmp, p.string());
}

struct Status {
  std::string state;  // "", "done", "failed"
  int exit_code = 0;
  double wall_seconds = 0.0;  // summed over the attempts that ended
  int attempts = 0;
  std::string message;
};

Status read_status(const fs::path& dir) {
  Status s;
  std::ifstream in(dir / "status");
  std::string line;
  while (std::getline(in, line)) {
    const auto eq = line.find(" = ");
    if (eq == std::string::npos) continue;
    const std::string k = line.substr(0, eq), v = line.substr(eq + 3);
    if (k == "status") s.state = v;
    else if (k == "exit_code") s.exit_code = std::atoi(v.c_str());
    else if (k == "wall_seconds") s.wall_seconds = std::atof(v.c_str());
    else if (k == "attempts") s.attempts = std::atoi(v.c_str());
    else if (k == "message") s.message = v;
  }
  return s;
}

// Wall time of the attempts that ended (one line each in dir/attempts; an attempt killed with the
// sweep is not counted).
double read_partial(const fs::path& dir, int& attempts) {
  std::ifstream in(dir / "attempts");
  double t = 0.0, x = 0.0;
  attempts = 0;
  while (in >> x) {
    t += x;
    ++attempts;
  }
  return t;
}

void write_status(const fs::path& dir, const Status& s) {
  std::ostringstream o;
  o << "status = " << s.state << "\nexit_code = " << s.exit_code << "\nwall_seconds = " << s.wall_seconds
    << "\nattempts = " << s.attempts << "\nmessage = " << s.message << "\n";
  write_atomic(dir / "status", o.str());
}

// The last "stokesian: ..." line written to the log from byte `from` on (the failure's message).
std::string last_message(const fs::path& log, std::streamoff from) {
  std::ifstream in(log);
  in.seekg(from);
  std::string line, msg;
  while (std::getline(in, line))
    if (line.rfind("stokesian:", 0) == 0) msg = line;
  for (char& c : msg)
    if (c == '\n' || c == '\r') c = ' ';
  return msg;
}

std::string self_exe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw IoError("/proc/self/exe: cannot find the stokesian executable to start runs");
  return p.string();
}

// Starts `stokesian run scene.toml --out trajectory.h5 --resume --quiet` in `dir`. The child dies
// with the sweep (PR_SET_PDEATHSIG), so a killed sweep leaves no run writing behind it, and holds
// an exclusive lock on dir/lock for its lifetime, so two sweep processes never run one run twice.
pid_t launch(const std::string& exe, const fs::path& dir, int threads) {
  const pid_t parent = getpid();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw IoError(std::string("fork: ") + std::strerror(errno));
  if (pid > 0) return pid;
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(kBusy);
  if (chdir(dir.c_str()) != 0) _exit(127);
  const int lock = open("lock", O_WRONLY | O_CREAT, 0644);
  if (lock < 0 || flock(lock, LOCK_EX | LOCK_NB) != 0) _exit(kBusy);
  const int log = open("log.txt", O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (log < 0) _exit(127);
  dup2(log, 1);
  dup2(log, 2);
  const std::string t = std::to_string(threads);
  setenv("OMP_NUM_THREADS", t.c_str(), 1);
  execl(exe.c_str(), "stokesian", "run", "scene.toml", "--out", "trajectory.h5", "--resume", "--quiet", "--threads",
        t.c_str(), static_cast<char*>(nullptr));
  std::fprintf(stderr, "stokesian: error: cannot start %s: %s\n", exe.c_str(), std::strerror(errno));
  _exit(127);
}

// Folders and scenes: created, or checked against what an earlier call of this sweep wrote.
void prepare(const io::Sweep& sw, const fs::path& out, const std::string& sweep_text) {
  fs::create_directories(out);
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string n = e.path().filename().string();
    if (e.is_directory() && n.rfind("run_", 0) == 0) {
      bool known = false;
      for (const auto& r : sw.runs) known = known || r.name == n;
      if (!known)
        throw ConfigError(sw.path + ": " + (out / n).string() + " exists but this sweep expands to " +
                          std::to_string(sw.runs.size()) + " runs: the folder belongs to another sweep (use another --out)");
    }
  }
  for (const auto& r : sw.runs) {
    const fs::path dir = out / r.name;
    fs::create_directories(dir);
    const fs::path scene = dir / "scene.toml";
    if (fs::exists(scene)) {
      const std::string old = slurp(scene);
      if (!io::same_scene(old, r.scene)) {
        const auto diff = io::scene_differences(old, r.scene);
        throw ConfigError(sw.path + ": " + scene.string() + " was written by a different sweep (" +
                          (diff.empty() ? std::string("scenes differ") : diff.front()) +
                          "); use another --out, or remove the folder to start again");
      }
    } else {
      write_atomic(scene, r.scene);
    }
  }
  write_atomic(out / "sweep.toml", sweep_text);
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// Shortest text that reads back to the same double; empty for NaN.
std::string number_text(double v) {
  if (std::isnan(v)) return "";
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// Writes DIR/summary.csv and DIR/summary.h5 from the runs' status files and trajectories.
void write_summary(const io::Sweep& sw, const fs::path& out, bool quiet) {
  struct Cell {
    stats::MeanError me;
  };
  // Observable columns: the sweep's list, else every observable of the finished runs (first seen order).
  std::vector<std::pair<std::string, std::size_t>> obs;  // name, components
  std::vector<std::map<std::string, std::vector<stats::MeanError>>> per_run(sw.runs.size());
  std::vector<Status> status(sw.runs.size());
  for (std::size_t i = 0; i < sw.runs.size(); ++i) {
    const fs::path dir = out / sw.runs[i].name;
    status[i] = read_status(dir);
    if (status[i].state != "done") continue;
    for (const auto& o : io::read_observables((dir / "trajectory.h5").string())) {
      if (!sw.summary.observables.empty() &&
          std::find(sw.summary.observables.begin(), sw.summary.observables.end(), o.name) == sw.summary.observables.end())
        continue;
      if (std::none_of(obs.begin(), obs.end(), [&](const auto& p) { return p.first == o.name; }))
        obs.emplace_back(o.name, o.components);
      // The window in fractions of the observable's recorded time span.
      std::vector<stats::MeanError> comps;
      const double t0 = o.time.empty() ? 0.0 : o.time.front(), t1 = o.time.empty() ? 0.0 : o.time.back();
      const double lo = t0 + sw.summary.window_begin * (t1 - t0), hi = t0 + sw.summary.window_end * (t1 - t0);
      for (std::size_t c = 0; c < o.components; ++c) {
        std::vector<double> x;
        for (std::size_t k = 0; k < o.time.size(); ++k)
          if (o.time[k] >= lo && o.time[k] <= hi && std::isfinite(o.value[k * o.components + c]))
            x.push_back(o.value[k * o.components + c]);
        comps.push_back(stats::blocked_mean(std::move(x)));
      }
      per_run[i][o.name] = std::move(comps);
    }
  }
  if (!sw.summary.observables.empty()) {
    for (const auto& name : sw.summary.observables)
      if (std::none_of(obs.begin(), obs.end(), [&](const auto& p) { return p.first == name; })) {
        if (!quiet && std::any_of(status.begin(), status.end(), [](const Status& s) { return s.state == "done"; }))
          std::fprintf(stderr, "stokesian: warning: %s: [summary] observable \"%s\" is written by no finished run\n",
                       sw.path.c_str(), name.c_str());
        obs.emplace_back(name, 1);
      }
    // The sweep's order.
    std::vector<std::pair<std::string, std::size_t>> ordered;
    for (const auto& name : sw.summary.observables)
      for (const auto& p : obs)
        if (p.first == name) ordered.push_back(p);
    obs = ordered;
  }

  std::vector<io::TableColumn> cols;
  auto text_col = [&](const std::string& name) -> io::TableColumn& {
    cols.push_back({name, false, {}, {}});
    return cols.back();
  };
  auto num_col = [&](const std::string& name) -> io::TableColumn& {
    cols.push_back({name, true, {}, {}});
    return cols.back();
  };
  {
    auto& c = text_col("run");
    for (const auto& r : sw.runs) c.text.push_back(r.name);
  }
  for (std::size_t k = 0; k < sw.columns.size(); ++k) {
    // Numbers as numbers, anything else as its TOML text.
    bool numeric = true;
    std::vector<double> v;
    for (const auto& r : sw.runs) {
      char* end = nullptr;
      const double x = std::strtod(r.values[k].c_str(), &end);
      numeric = numeric && !r.values[k].empty() && end == r.values[k].c_str() + r.values[k].size();
      v.push_back(x);
    }
    if (numeric) num_col(sw.columns[k]).num = v;
    else {
      auto& c = text_col(sw.columns[k]);
      for (const auto& r : sw.runs) c.text.push_back(r.values[k]);
    }
  }
  {
    auto& c = text_col("status");
    for (const auto& s : status) c.text.push_back(s.state.empty() ? "pending" : s.state);
  }
  {
    auto& c = num_col("exit_code");
    for (const auto& s : status) c.num.push_back(s.state.empty() ? std::nan("") : double(s.exit_code));
  }
  {
    auto& c = num_col("wall_seconds");
    for (const auto& s : status) c.num.push_back(s.state.empty() ? std::nan("") : s.wall_seconds);
  }
  {
    auto& c = num_col("attempts");
    for (const auto& s : status) c.num.push_back(double(s.attempts));
  }
  {
    auto& c = text_col("message");
    for (const auto& s : status) c.text.push_back(s.message);
  }
  for (const auto& [name, comps] : obs)
    for (std::size_t c = 0; c < comps; ++c) {
      const std::string base = comps > 1 ? name + "[" + std::to_string(c) + "]" : name;
      std::vector<double> mean, se, n;
      for (std::size_t i = 0; i < sw.runs.size(); ++i) {
        const auto it = per_run[i].find(name);
        const stats::MeanError me = it != per_run[i].end() && c < it->second.size() ? it->second[c] : stats::MeanError{};
        mean.push_back(me.mean);
        se.push_back(me.se);
        n.push_back(double(me.n));
      }
      num_col(base + "_mean").num = mean;
      num_col(base + "_se").num = se;
      num_col(base + "_n").num = n;
    }

  std::ostringstream csv;
  for (std::size_t k = 0; k < cols.size(); ++k) csv << (k ? "," : "") << csv_field(cols[k].name);
  csv << "\n";
  for (std::size_t i = 0; i < sw.runs.size(); ++i) {
    for (std::size_t k = 0; k < cols.size(); ++k)
      csv << (k ? "," : "") << csv_field(cols[k].numeric ? number_text(cols[k].num[i]) : cols[k].text[i]);
    csv << "\n";
  }
  write_atomic(out / "summary.csv", csv.str());
  char window[64];
  std::snprintf(window, sizeof window, "[%g, %g]", sw.summary.window_begin, sw.summary.window_end);
  io::write_table_h5((out / "summary.h5").string(), cols,
                     {{"sweep", sw.path}, {"base", sw.base}, {"window", window},
                      {"error", "standard error of the window mean by blocking (Flyvbjerg & Petersen 1989)"}});
}

std::string slurm_script(const io::Sweep& sw, const fs::path& out, const SweepOptions& opt, const std::string& exe) {
  std::ostringstream o;
  const int threads = sw.slurm.cpus_per_task;
  o << "#!/bin/bash\n"
    << "# Slurm job array of the sweep " << sw.path << ": one array task per run (written by stokesian sweep --slurm).\n"
    << "# Submit: sbatch " << (out / "sweep.sbatch").string() << "\n"
    << "#SBATCH --job-name=" << fs::path(sw.path).stem().string() << "\n"
    << "#SBATCH --array=0-" << (sw.runs.size() - 1) << (opt.jobs > 1 ? "%" + std::to_string(opt.jobs) : std::string()) << "\n"
    << "#SBATCH --cpus-per-task=" << threads << "\n"
    << "#SBATCH --time=" << sw.slurm.time << "\n"
    << "#SBATCH --mem=" << sw.slurm.mem << "\n"
    << "#SBATCH --output=" << (fs::absolute(out) / "slurm-%A_%a.out").string() << "\n";
  if (!sw.slurm.partition.empty()) o << "#SBATCH --partition=" << sw.slurm.partition << "\n";
  if (!sw.slurm.account.empty()) o << "#SBATCH --account=" << sw.slurm.account << "\n";
  for (const auto& e : sw.slurm.extra) o << "#SBATCH " << e << "\n";
  o << "set -eu\n"
    << "exec " << exe << " sweep " << fs::absolute(sw.path).string() << " --out " << fs::absolute(out).string()
    << " --run \"$SLURM_ARRAY_TASK_ID\" --threads " << threads << " --quiet\n";
  return o.str();
}

}  // namespace

int sweep(const std::string& sweep_file, const SweepOptions& opt) {
  const io::Sweep sw = io::load_sweep(sweep_file);  // every expanded scene validated: nothing written before
  if (opt.only_run >= long(sw.runs.size()))
    throw ConfigError("--run " + std::to_string(opt.only_run) + ": the sweep has runs 0 to " + std::to_string(sw.runs.size() - 1));
  const fs::path out = opt.out;
  const std::string exe = self_exe();
  prepare(sw, out, slurp(sweep_file));
  if (opt.slurm) {
    write_atomic(out / "sweep.sbatch", slurm_script(sw, out, opt, exe));
    if (!opt.quiet)
      std::fprintf(stderr, "wrote %s: %zu array tasks; submit with `sbatch %s`, then `stokesian sweep %s --out %s --summary`\n",
                   (out / "sweep.sbatch").c_str(), sw.runs.size(), (out / "sweep.sbatch").c_str(), sweep_file.c_str(),
                   out.c_str());
    return 0;
  }

  std::vector<std::size_t> todo;
  std::size_t done_before = 0;
  for (std::size_t i = 0; i < sw.runs.size(); ++i) {
    if (opt.only_run >= 0 && long(i) != opt.only_run) continue;
    const Status s = read_status(out / sw.runs[i].name);
    if (s.state == "done") ++done_before;
    else if (opt.summary_only || (s.state == "failed" && !opt.retry_failed)) continue;
    else todo.push_back(i);
  }
  if (!opt.quiet && !opt.summary_only)
    std::fprintf(stderr, "sweep %s: %zu runs, %zu finished before, %zu to run, %d at a time\n", sweep_file.c_str(),
                 opt.only_run >= 0 ? std::size_t(1) : sw.runs.size(), done_before, todo.size(), opt.jobs);

  struct Active {
    std::size_t run;
    std::chrono::steady_clock::time_point start;
    std::streamoff log_from;
  };
  std::map<pid_t, Active> active;
  std::size_t next = 0, finished = 0;
  int busy = 0;
  while (next < todo.size() || !active.empty()) {
    while (int(active.size()) < opt.jobs && next < todo.size()) {
      const std::size_t i = todo[next++];
      const fs::path dir = out / sw.runs[i].name;
      std::error_code ec;
      const auto size = fs::exists(dir / "log.txt") ? std::streamoff(fs::file_size(dir / "log.txt", ec)) : 0;
      active[launch(exe, dir, opt.threads)] = {i, std::chrono::steady_clock::now(), size};
    }
    int st = 0;
    const pid_t pid = waitpid(-1, &st, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw IoError(std::string("waitpid: ") + std::strerror(errno));
    }
    const auto it = active.find(pid);
    if (it == active.end()) continue;
    const Active a = it->second;
    active.erase(it);
    const io::SweepRun& r = sw.runs[a.run];
    const fs::path dir = out / r.name;
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - a.start).count();
    const int code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
    if (code == kBusy) {
      ++busy;
      if (!opt.quiet) std::fprintf(stderr, "  %s: running in another sweep process, skipped\n", r.name.c_str());
      continue;
    }
    {
      std::ofstream log(dir / "attempts", std::ios::app);
      log << number_text(secs) << "\n";
    }
    Status s;
    s.wall_seconds = read_partial(dir, s.attempts);
    s.exit_code = code;
    if (code == 0) {
      s.state = "done";
    } else {
      s.state = "failed";
      s.message = last_message(dir / "log.txt", a.log_from);
      if (s.message.empty()) s.message = "exit status " + std::to_string(code) + " (see log.txt)";
    }
    write_status(dir, s);
    ++finished;
    if (!opt.quiet)
      std::fprintf(stderr, "  [%zu/%zu] %s %s (%.1f s)%s%s\n", finished, todo.size(), r.name.c_str(), s.state.c_str(), secs,
                   s.message.empty() ? "" : ": ", s.message.c_str());
  }

  // An array task (--run) leaves the summary to `--summary` after the array: concurrent tasks
  // would only rewrite it over each other.
  if (opt.only_run < 0) write_summary(sw, out, opt.quiet);
  std::size_t failed = 0, pending = 0;
  for (std::size_t i = 0; i < sw.runs.size(); ++i) {
    if (opt.only_run >= 0 && long(i) != opt.only_run) continue;
    const Status s = read_status(out / sw.runs[i].name);
    failed += s.state == "failed";
    pending += s.state.empty();
  }
  if (!opt.quiet && opt.only_run < 0)
    std::fprintf(stderr, "wrote %s and %s: %zu failed, %zu unfinished\n", (out / "summary.csv").c_str(),
                 (out / "summary.h5").c_str(), failed, pending);
  if (failed) return 6;
  if (pending && !opt.summary_only) return 6;  // runs held by another process (busy) are unfinished here
  (void)busy;
  return 0;
}

}  // namespace stokesian::app
