#pragma once
// Progress of a run on stderr: on a terminal one line rewritten in place ("\r") at most every
// 0.5 s, fitted to the terminal's width so that it never wraps (a wrapped line cannot be rewritten
// by "\r" and would scroll one new line per update); otherwise a plain log line every 10 s. The
// final line is printed once, by finish(), with the diagnostics of the last recorded frame.
// The line itself is a pure function of the status and the width (format_line), tested alone.
#include <sys/ioctl.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace stokesian::progress {

struct Status {
  long step = 0, last = 0;  // current and final step
  double time = 0.0;        // simulated time
  double rate = 0.0;        // steps per wall-clock second
  double eta = 0.0;         // seconds to the end
  bool diagnostics = false; // min_gap and overlaps below are those of the latest frame
  double min_gap = 0.0, overlaps = 0.0;
};

// The status as one line of at most width - 1 characters (the last column stays free: writing
// into it makes some terminals wrap). Whole fields are dropped from the end when they do not fit;
// the first field is cut as a last resort. width <= 1 gives an empty line.
inline std::string format_line(const Status& s, int width) {
  char buf[128];
  std::string fields[4];
  std::snprintf(buf, sizeof buf, "step %ld/%ld", s.step, s.last);
  fields[0] = buf;
  std::snprintf(buf, sizeof buf, "  t=%.4g", s.time);
  fields[1] = buf;
  std::snprintf(buf, sizeof buf, "  %.3g steps/s  ETA %.0fs", s.rate, s.eta);
  fields[2] = buf;
  if (s.diagnostics) {
    std::snprintf(buf, sizeof buf, "  min_gap=%.3g overlaps=%.0f", s.min_gap, s.overlaps);
    fields[3] = buf;
  }
  const std::size_t room = width > 1 ? std::size_t(width - 1) : 0;
  std::string line = fields[0].substr(0, room);
  for (int k = 1; k < 4; ++k) {
    if (line.size() + fields[k].size() > room) break;
    line += fields[k];
  }
  return line;
}

// Columns of the terminal on file descriptor fd: TIOCGWINSZ, else $COLUMNS, else 80.
inline int terminal_width(int fd) {
  winsize ws{};
  if (ioctl(fd, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) return ws.ws_col;
  if (const char* c = std::getenv("COLUMNS")) {
    const int n = std::atoi(c);
    if (n > 0) return n;
  }
  return 80;
}

// Refresh interval override [s] (stokesian run --progress-interval); negative = the defaults.
inline double& refresh_override() {
  static double seconds = -1.0;
  return seconds;
}

class Progress {
 public:
  Progress(long first, long last, bool quiet)
      : first_(first), last_(last), quiet_(quiet), tty_(isatty(fileno(stderr))), start_(clock::now()), shown_(start_) {}

  // A step has been reached; printed when the refresh interval has passed since the last line.
  void update(long step, double time, bool diagnostics, double min_gap, double overlaps) {
    if (quiet_) return;
    const auto now = clock::now();
    const double interval = refresh_override() >= 0 ? refresh_override() : tty_ ? kTerminalSeconds : kLogSeconds;
    if (std::chrono::duration<double>(now - shown_).count() < interval) return;
    show(now, step, time, diagnostics, min_gap, overlaps, false);
  }
  // The run has ended at `step`: the one final line (ends the terminal line).
  void finish(long step, double time, bool diagnostics, double min_gap, double overlaps) {
    if (quiet_) return;
    show(clock::now(), step, time, diagnostics, min_gap, overlaps, true);
  }

 private:
  static constexpr double kTerminalSeconds = 0.5, kLogSeconds = 10.0;  // refresh intervals
  using clock = std::chrono::steady_clock;
  void show(clock::time_point now, long step, double time, bool diagnostics, double min_gap, double overlaps,
            bool last) {
    shown_ = now;
    Status st;
    st.step = step;
    st.last = last_;
    st.time = time;
    const double el = std::chrono::duration<double>(now - start_).count();
    st.rate = el > 0 ? double(step - first_) / el : 0.0;
    st.eta = st.rate > 0 ? double(last_ - step) / st.rate : 0.0;
    st.diagnostics = diagnostics;
    st.min_gap = min_gap;
    st.overlaps = overlaps;
    if (tty_) {
      const int width = terminal_width(fileno(stderr));
      const std::string line = format_line(st, width);
      std::fprintf(stderr, "\r%-*s%s", width > 1 ? width - 1 : 0, line.c_str(), last ? "\n" : "");
    } else {
      std::fprintf(stderr, "%s\n", format_line(st, 1 << 20).c_str());
    }
    std::fflush(stderr);
  }
  long first_, last_;
  bool quiet_, tty_;
  clock::time_point start_, shown_;
};

}  // namespace stokesian::progress
