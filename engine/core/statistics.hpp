#pragma once
// Time averages of correlated series with their standard errors, by blocking (Flyvbjerg &
// Petersen 1989, J. Chem. Phys. 91, 461): the series is halved into block means repeatedly; at
// level l the blocks of 2^l samples give se_l = sqrt(var(block means) / (n_b - 1)), which rises
// with l until the blocks are longer than the correlation time and then stays flat. The error
// reported is the largest se_l over the levels that keep at least kMinBlocks blocks (level 0, the
// naive error, always counts), which reaches the plateau when the series spans at least about
// kMinBlocks correlation times and is otherwise a lower bound; `blocks` says how many blocks the
// chosen level had.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace stokesian::stats {

inline constexpr std::size_t kMinBlocks = 16;

struct MeanError {
  double mean = std::nan("");
  double se = std::nan("");   // standard error of the mean; NaN with fewer than 2 samples
  std::size_t n = 0;          // samples
  std::size_t blocks = 0;     // blocks of the level that gave se
};

inline MeanError blocked_mean(std::vector<double> x) {
  MeanError r;
  r.n = x.size();
  if (x.empty()) return r;
  double m = 0.0;
  for (double v : x) m += v;
  m /= double(x.size());
  r.mean = m;
  if (x.size() < 2) return r;
  double best = -1.0;
  std::size_t best_blocks = 0;
  for (bool first = true; x.size() >= 2 && (first || x.size() >= kMinBlocks); first = false) {
    double s2 = 0.0, mb = 0.0;
    for (double v : x) mb += v;
    mb /= double(x.size());
    for (double v : x) s2 += (v - mb) * (v - mb);
    const double se = std::sqrt(s2 / (double(x.size()) * double(x.size() - 1)));
    if (se > best) {
      best = se;
      best_blocks = x.size();
    }
    std::vector<double> y(x.size() / 2);
    for (std::size_t i = 0; i < y.size(); ++i) y[i] = 0.5 * (x[2 * i] + x[2 * i + 1]);
    x.swap(y);
  }
  r.se = best;
  r.blocks = best_blocks;
  return r;
}

}  // namespace stokesian::stats
