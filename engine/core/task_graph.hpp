#pragma once
// One step's phases as a task graph: OpenMP tasks with explicit dependencies.
//
// Nodes are added in a topological order (each lists only earlier nodes in `after`). A node is
//   single: runs on one thread and may overlap other single nodes (kernels inside that open their
//           own `omp parallel` region run on that one thread: nested parallelism is off);
//   team:   parallel inside (a kernel that uses every thread), so it runs alone.
// run() executes the graph in waves: the ready team nodes one at a time with the whole team,
// then all ready single nodes at once as OpenMP tasks of one team (`depend` clauses on one token
// per node order those that become ready inside the wave), until every node has run. With one
// thread, or inside a parallel region, nodes run serially in insertion order. Each node computes
// the same result whichever nodes run beside it, and kernels are deterministic for a given
// thread count, so the graph changes timings only. Per-node wall times are kept for benchmarks.
#include <functional>
#include <string>
#include <vector>

namespace stokesian {

class TaskGraph {
 public:
  enum class Kind { single, team };
  enum class Mode { automatic, serial };
  int add(std::string name, Kind kind, std::function<void()> body, std::vector<int> after = {});
  void run(Mode mode = Mode::automatic);
  std::size_t size() const { return nodes_.size(); }
  const std::string& name(std::size_t k) const { return nodes_[k].name; }
  double seconds(std::size_t k) const { return nodes_[k].seconds; }  // wall time in the last run

 private:
  struct Node {
    std::string name;
    Kind kind;
    std::function<void()> body;
    std::vector<int> after;
    double seconds = 0.0;
  };
  void execute(Node& n);
  std::vector<Node> nodes_;
};

}  // namespace stokesian
