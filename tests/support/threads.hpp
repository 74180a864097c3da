#pragma once
// OpenMP thread count for a scope, restored when the scope ends (also on a failed REQUIRE): the
// suites that check a result is independent of the thread count run it on one and on several.
#include <omp.h>

#include <algorithm>

namespace stokesian::test {

class ThreadCount {
 public:
  static constexpr int kSeveral = 0;  // every thread, at least two
  explicit ThreadCount(int n) : saved_(omp_get_max_threads()) {
    omp_set_num_threads(n == kSeveral ? std::max(2, saved_) : n);
  }
  ~ThreadCount() { omp_set_num_threads(saved_); }
  ThreadCount(const ThreadCount&) = delete;
  ThreadCount& operator=(const ThreadCount&) = delete;

 private:
  int saved_;
};

}  // namespace stokesian::test
