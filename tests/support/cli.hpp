#pragma once
// Running the `stokesian` binary from a test: a per-process scratch folder (removed at exit), the
// command's exit status and its stdout/stderr text. STOKESIAN_BINARY is defined for every suite
// (tests/CMakeLists.txt).
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace stokesian::test {

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// A scratch folder named after `prefix` and the process id, emptied when made and removed at exit.
struct ScratchDir {
  std::filesystem::path path;
  explicit ScratchDir(const std::string& prefix)
      : path(std::filesystem::temp_directory_path() / (prefix + std::to_string(getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

struct CliResult {
  int status;  // exit status; -1 when ended by a signal
  std::string out, err;
};

// Runs `env stokesian args` through the shell (arguments are not quoted: test paths have no spaces),
// in folder `cwd` when not empty; stdout and stderr are captured through files in `scratch`.
inline CliResult run_stokesian(const std::string& args, const std::filesystem::path& scratch, const std::string& env = "",
                               const std::filesystem::path& cwd = {}) {
  const std::filesystem::path o = scratch / "stdout.txt", e = scratch / "stderr.txt";
  std::string cmd = env + " " + std::string(STOKESIAN_BINARY) + " " + args + " > " + o.string() + " 2> " + e.string();
  if (!cwd.empty()) cmd = "cd " + cwd.string() + " && " + cmd;
  const int rc = std::system(cmd.c_str());
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, read_text(o), read_text(e)};
}

}  // namespace stokesian::test
