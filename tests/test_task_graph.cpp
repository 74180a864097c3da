// The step's task graph: every node runs once, after the nodes it depends on, whether the graph
// runs as OpenMP tasks or serially; errors in a node reach the caller; and an evaluation gives
// bit-identical results either way (the graph changes timings only).
#include <doctest/doctest.h>

#include "engine/core/task_graph.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <omp.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

using namespace stokesian;

TEST_CASE("task graph: each node once, after its dependencies, in both modes") {
  omp_set_num_threads(2);
  for (TaskGraph::Mode mode : {TaskGraph::Mode::automatic, TaskGraph::Mode::serial}) {
    std::atomic<int> clock{0};
    std::vector<int> start(6, -1), end(6, -1), runs(6, 0);
    TaskGraph g;
    auto node = [&](int k) {
      return [&, k] {
        start[std::size_t(k)] = clock++;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        ++runs[std::size_t(k)];
        end[std::size_t(k)] = clock++;
      };
    };
    using K = TaskGraph::Kind;
    g.add("a", K::single, node(0));
    g.add("b", K::single, node(1));
    g.add("c", K::team, node(2), {0});
    g.add("d", K::single, node(3), {1});
    g.add("e", K::single, node(4), {2, 3});
    g.add("f", K::single, node(5), {0});
    g.run(mode);
    const std::vector<std::vector<int>> deps{{}, {}, {0}, {1}, {2, 3}, {0}};
    for (int k = 0; k < 6; ++k) {
      CAPTURE(k);
      CHECK(runs[std::size_t(k)] == 1);
      for (int d : deps[std::size_t(k)]) CHECK(end[std::size_t(d)] < start[std::size_t(k)]);
    }
    // The team node ran alone.
    for (int k = 0; k < 6; ++k)
      if (k != 2) CHECK((end[std::size_t(k)] < start[2] || start[std::size_t(k)] > end[2]));
  }
}

TEST_CASE("task graph: a failing node's exception reaches the caller; order is checked") {
  omp_set_num_threads(2);
  TaskGraph g;
  g.add("ok", TaskGraph::Kind::single, [] {});
  g.add("fails", TaskGraph::Kind::single, [] { throw std::runtime_error("node failed"); });
  CHECK_THROWS_WITH_AS(g.run(), "node failed", std::runtime_error);
  TaskGraph h;
  CHECK_THROWS_AS(h.add("x", TaskGraph::Kind::single, [] {}, {0}), std::logic_error);
}

TEST_CASE("an evaluation as tasks is bit-identical to its phases run serially") {
  omp_set_num_threads(2);
  const char* scenes[] = {
      // dense SD, pair forces
      "[particles]\ngenerate = \"random\"\ncount = 40\nvolume_fraction = 0.15\nseed = 3\n[forces]\n"
      "external_force = [0, 0, -1]\n[[forces.pair]]\nkind = \"morse\"\n[[forces.pair]]\nkind = \"hertz\"\n",
      // PME, sheared box, Brownian SD (pair forces: auto level stokesian; fixman integrator)
      "[domain]\nkind = \"periodic\"\nbox = [14, 14, 14]\n[fluid]\nkT = 1.0\n[particles]\ngenerate = \"random\"\n"
      "count = 150\nseed = 4\n[[forces.pair]]\nkind = \"hertz\"\n[flow]\nkind = \"simple_shear\"\nrate = 0.2\n"
      "[hydrodynamics]\nmoments = \"FT\"\ntolerance = 1e-5\n",
      // PME, sheared box, Brownian far field (midpoint)
      "[domain]\nkind = \"periodic\"\nbox = [14, 14, 14]\n[fluid]\nkT = 1.0\n[particles]\ngenerate = \"random\"\n"
      "count = 150\nseed = 4\n[[forces.pair]]\nkind = \"hertz\"\n[flow]\nkind = \"simple_shear\"\nrate = 0.2\n"
      "[hydrodynamics]\nmodel = \"far_field\"\nmoments = \"FT\"\ntolerance = 1e-5\n[time]\nintegrator = \"midpoint\"\n",
      // free draining, many pairs
      "[domain]\nkind = \"periodic\"\nbox = [40, 40, 40]\n[particles]\ngenerate = \"random\"\ncount = 5000\n"
      "seed = 5\n[[forces.pair]]\nkind = \"dlvo\"\n[hydrodynamics]\nmodel = \"free_draining\"\n"};
  for (const char* text : scenes) {
    Simulation a(io::parse_scene(text, "a.toml")), b(io::parse_scene(text, "b.toml"));
    a.set_task_mode(TaskGraph::Mode::automatic);
    b.set_task_mode(TaskGraph::Mode::serial);
    State sa = a.initial_state(), sb = b.initial_state();
    for (int step = 0; step < 3; ++step) {
      const Evaluation ea = a.evaluate(sa, sa.position, 0.0, true), eb = b.evaluate(sb, sb.position, 0.0, true);
      CHECK(ea.hydro.U == eb.hydro.U);
      CHECK(ea.force == eb.force);
      CHECK(ea.gaps->min_gap == eb.gaps->min_gap);
      a.advance(sa, ea);
      b.advance(sb, eb);
      CHECK(sa.position == sb.position);
    }
  }
}
