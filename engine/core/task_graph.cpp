#include "engine/core/task_graph.hpp"

#include <omp.h>

#include <chrono>
#include <exception>
#include <stdexcept>

namespace stokesian {

int TaskGraph::add(std::string name, Kind kind, std::function<void()> body, std::vector<int> after) {
  const int id = int(nodes_.size());
  for (int a : after)
    if (a < 0 || a >= id) throw std::logic_error("TaskGraph: node \"" + name + "\" depends on a later node");
  nodes_.push_back(Node{std::move(name), kind, std::move(body), std::move(after), 0.0});
  return id;
}

void TaskGraph::execute(Node& n) {
  const auto t0 = std::chrono::steady_clock::now();
  n.body();
  n.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void TaskGraph::run(Mode mode) {
  const int n = int(nodes_.size());
  if (mode == Mode::serial || n < 2 || omp_get_max_threads() < 2 || omp_in_parallel()) {
    for (auto& node : nodes_) execute(node);
    return;
  }
  std::vector<char> done(std::size_t(n), 0);
  auto ready = [&](int k) {
    if (done[std::size_t(k)]) return false;
    for (int a : nodes_[std::size_t(k)].after)
      if (!done[std::size_t(a)]) return false;
    return true;
  };
  for (int remaining = n; remaining > 0;) {
    bool ran_team = false;
    for (int k = 0; k < n; ++k)
      if (nodes_[std::size_t(k)].kind == Kind::team && ready(k)) {
        execute(nodes_[std::size_t(k)]);
        done[std::size_t(k)] = 1;
        --remaining;
        ran_team = true;
      }
    if (ran_team) continue;
    // Wave of single nodes: every single node whose team-node ancestors have all run; `depend`
    // orders those that depend on each other.
    std::vector<int> wave;
    std::vector<char> in_wave(std::size_t(n), 0);
    for (int k = 0; k < n; ++k) {
      const Node& node = nodes_[std::size_t(k)];
      if (done[std::size_t(k)] || node.kind == Kind::team) continue;
      bool ok = true;
      for (int a : node.after) ok = ok && (done[std::size_t(a)] || in_wave[std::size_t(a)]);
      if (ok) {
        wave.push_back(k);
        in_wave[std::size_t(k)] = 1;
      }
    }
    if (wave.empty()) throw std::logic_error("TaskGraph: no node is ready");
    std::exception_ptr error;  // exceptions must not leave a task: the first is rethrown after the wave
    std::vector<char> token_store(std::size_t(n), 0);
    char* token = token_store.data();
    (void)token;  // used only in the depend clauses
#pragma omp parallel
#pragma omp single
    for (int k : wave) {
      const int nd = int(nodes_[std::size_t(k)].after.size());
      const int* dep = nodes_[std::size_t(k)].after.data();
#pragma omp task default(shared) firstprivate(k) depend(iterator(it = 0 : nd), in : token[dep[it]]) \
    depend(out : token[k])
      {
        try {
          execute(nodes_[std::size_t(k)]);
        } catch (...) {
#pragma omp critical(stokesian_task_graph_error)
          if (!error) error = std::current_exception();
        }
      }
    }
    if (error) std::rethrow_exception(error);
    for (int k : wave) done[std::size_t(k)] = 1;
    remaining -= int(wave.size());
  }
}

}  // namespace stokesian
