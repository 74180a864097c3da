#pragma once
// Starting a command line as a child process and killing it with SIGKILL at a chosen moment: after
// a delay, or as soon as a file exists. Used by the kill-and-resume tests (tests/test_resume.cpp,
// tests/kill/kill_trials.cpp). POSIX only.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace stokesian::test {

struct ChildOutcome {
  bool killed = false;  // ended by a signal (our SIGKILL, or a crash)
  int signal = 0;       // the signal when killed
  int status = 0;       // exit status otherwise
  bool timed_out = false;  // killed by the hang guard, not by the planned kill
  double ms = 0;        // wall time from start to end
};

// Runs args[0] with args (stdout to /dev/null when quiet_stdout, stderr to `err_file` when not
// empty). Kills it with SIGKILL `kill_ms` milliseconds after the start (< 0: never) or as soon as
// the file `kill_when` exists (when not empty), whichever comes first; `guard_ms` (> 0) kills a
// child that runs longer, reported as timed_out.
inline ChildOutcome run_child(const std::vector<std::string>& args, double kill_ms = -1, const std::string& kill_when = "",
                              const std::string& err_file = "", double guard_ms = -1, bool quiet_stdout = true) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<std::string> a(args);
    std::vector<char*> argv;
    for (auto& s : a) argv.push_back(s.data());
    argv.push_back(nullptr);
    if (!err_file.empty()) {
      const int fd = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd < 0 || dup2(fd, 2) < 0) _exit(126);
    }
    if (quiet_stdout) {
      const int fd = ::open("/dev/null", O_WRONLY);
      if (fd < 0 || dup2(fd, 1) < 0) _exit(126);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  ChildOutcome out;
  if (pid < 0) {
    out.status = 127;
    return out;
  }
  auto elapsed = [&] { return std::chrono::duration<double, std::milli>(clock::now() - t0).count(); };
  int status = 0;
  bool sent = false;
  const bool watch = kill_ms >= 0 || !kill_when.empty() || guard_ms > 0;
  while (watch) {
    if (waitpid(pid, &status, WNOHANG) == pid) break;
    const double t = elapsed();
    const bool planned = (kill_ms >= 0 && t >= kill_ms) || (!kill_when.empty() && std::filesystem::exists(kill_when));
    const bool guard = guard_ms > 0 && t >= guard_ms;
    if (planned || guard) {
      kill(pid, SIGKILL);
      out.timed_out = guard && !planned;
      sent = true;
      waitpid(pid, &status, 0);
      break;
    }
    // Short naps: precise enough for millisecond kill moments, without taking a core from the child.
    std::this_thread::sleep_for(std::chrono::microseconds(kill_when.empty() ? 200 : 50));
  }
  if (!watch || (!sent && !WIFEXITED(status) && !WIFSIGNALED(status))) waitpid(pid, &status, 0);
  out.ms = elapsed();
  out.killed = WIFSIGNALED(status);
  out.signal = out.killed ? WTERMSIG(status) : 0;
  out.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

}  // namespace stokesian::test
