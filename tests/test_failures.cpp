// Failure policies during a run (docs/reliability.md, "Failure policies during a run"): each failure
// mode is forced, and the report (step, particles, what failed, what to do) and the policy (stop
// with a checkpoint of the state before the failed step, exit 3, --resume after a smaller [time] dt
// continues; nothing left behind when the first evaluation fails) are checked.
#include <doctest/doctest.h>

#include "engine/app/run.hpp"
#include "engine/core/errors.hpp"
#include "engine/core/krylov.hpp"
#include "engine/core/random.hpp"
#include "engine/integrators.hpp"
#include "engine/kernels/far_field.hpp"
#include "engine/mobility_solver.hpp"
#include "engine/observers.hpp"
#include "engine/simulation.hpp"
#include "io/checkpoint.hpp"
#include "io/scene_toml.hpp"

#include "support/cli.hpp"
#include "support/hdf5_read.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace stokesian;

namespace {

fs::path scratch() {
  static const test::ScratchDir dir("stokesian_failures_");
  return dir.path;
}

using test::contains;
using test::read_text;
using Result = test::CliResult;

// `stokesian ARGS` run in the scratch folder (paths relative to it).
Result cli(const std::string& args) { return test::run_stokesian(args, scratch(), "", scratch()); }

void write_scene(const std::string& name, const std::string& text) { std::ofstream(scratch() / name) << text; }

std::vector<double> steps_of(const std::string& file) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  return test::read_doubles((scratch() / file).string(), "/particles/all/position/step");
}

// Frames and checkpoints in memory.
struct MemorySink final : OutputSink {
  std::vector<std::int64_t> frames, checkpoints;
  void record(const Frame& f) override { frames.push_back(f.step); }
  void checkpoint(const State& s) override { checkpoints.push_back(s.step); }
};

// A well-conditioned SPD matrix with a known spectrum in [1, 10].
MatX spd(int n, unsigned seed) {
  std::srand(seed);
  MatX Q = MatX::Random(n, n);
  Eigen::HouseholderQR<MatX> qr(Q);
  const MatX U = qr.householderQ();
  VecX lam(n);
  for (int i = 0; i < n; ++i) lam[i] = 1.0 + 9.0 * i / (n - 1);
  return U * lam.asDiagonal() * U.transpose();
}

LinearOperator product(const MatX& A) {
  return [A](const VecX& in, VecX& out) { out = A * in; };
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Krylov stagnation and breakdown

TEST_CASE("CG: a tolerance below round-off stagnates and is reported long before the iteration cap") {
  const int n = 40;
  const MatX A = spd(n, 3);
  const VecX b = VecX::LinSpaced(n, -1.0, 2.0);
  VecX x;
  const int cap = 10 * n + 100000;
  const KrylovResult r = conjugate_gradient(product(A), b, x, 1e-30, cap);
  CHECK(r.status == KrylovStatus::round_off);
  CHECK_FALSE(r.converged);
  // Stopped one stagnation window after the last halving, far below the cap.
  CHECK(r.iterations < 2 * n + 2 * kStagnationWindow);
  // The residual it reports is at round-off, and the iterate is the solution (direct reference).
  CHECK(r.relative_residual < 1e-12);
  const VecX ref = A.llt().solve(b);
  CHECK((x - ref).norm() < 1e-12 * ref.norm());
  CHECK(contains(describe(r), "stagnated at round-off"));

  // An operator that is not symmetric (SPD + a strong skew part: p.Ap > 0 for every p) makes the
  // residual stall: stopped one window after its last halving, not at the cap.
  std::srand(11);
  const MatX R = MatX::Random(n, n);
  const MatX K = A + 20.0 * (R - R.transpose());
  VecX z;
  const KrylovResult st = conjugate_gradient(product(K), b, z, 1e-10, cap);
  MESSAGE("non-symmetric operator: " << describe(st) << " after " << st.iterations << " iterations, residual "
                                     << st.relative_residual);
  CHECK(st.status == KrylovStatus::stagnated);
  CHECK(st.iterations >= kStagnationWindow);
  CHECK(st.iterations < 20 * kStagnationWindow);
  CHECK(contains(describe(st), "did not halve in 200 iterations"));

  // A reachable tolerance converges as before.
  VecX y;
  const KrylovResult ok = conjugate_gradient(product(A), b, y, 1e-10, cap);
  CHECK(ok.status == KrylovStatus::converged);
  CHECK(ok.converged);
  CHECK((A * y - b).norm() <= 1e-10 * b.norm());
}

TEST_CASE("CG: an indefinite or non-finite operator is detected at once") {
  const int n = 20;
  MatX A = spd(n, 5);
  A -= 5.0 * MatX::Identity(n, n);  // eigenvalues in [-4, 5]
  const VecX b = VecX::Ones(n);
  VecX x;
  const KrylovResult r = conjugate_gradient(product(A), b, x, 1e-10, 10 * n + 100);
  // Either a direction of non-positive curvature is met, or CG cannot converge; with this
  // spectrum it meets one within n iterations.
  CHECK(r.status == KrylovStatus::indefinite);
  CHECK(r.curvature <= 0.0);
  CHECK(r.iterations <= n);
  CHECK(contains(describe(r), "not positive definite"));

  MatX B = spd(n, 6);
  B(3, 3) = std::numeric_limits<double>::quiet_NaN();
  VecX y;
  const KrylovResult nf = conjugate_gradient(product(B), b, y, 1e-10, 10 * n + 100);
  CHECK(nf.status == KrylovStatus::non_finite);
  CHECK(nf.iterations <= 1);
}

TEST_CASE("GMRES: a singular operator stagnates long before the cap; a non-finite one is detected") {
  // The accelerated SD solve (engine/sd_accelerated.cpp) turns these into a physics error.
  const int n = 20;
  MatX A = spd(n, 7);
  A.col(4).setZero();  // singular: b has a part outside the range
  const VecX b = VecX::Ones(n);
  VecX x;
  const KrylovResult r = gmres(product(A), b, x, 1e-10, 2000, 10);
  CHECK(r.status == KrylovStatus::stagnated);
  CHECK_FALSE(r.converged);
  CHECK(r.iterations <= 4 * n);
  MatX B = spd(n, 8);
  B(2, 5) = std::numeric_limits<double>::quiet_NaN();
  VecX y;
  const KrylovResult nf = gmres(product(B), b, y, 1e-10, 2000, 10);
  CHECK(nf.status == KrylovStatus::non_finite);
  CHECK(nf.iterations <= 1);
}

TEST_CASE("Lanczos: an indefinite operator is detected; a happy breakdown is exact convergence") {
  const int n = 30;
  MatX A = spd(n, 7);
  A -= 4.0 * MatX::Identity(n, n);  // eigenvalues in [-3, 6]
  const VecX z = VecX::LinSpaced(n, 1.0, 2.0);
  VecX y;
  const KrylovResult r = lanczos_sqrt(product(A), z, y, 1e-8, 200);
  CHECK(r.status == KrylovStatus::indefinite);
  CHECK_FALSE(r.converged);
  CHECK(r.curvature < 0.0);
  CHECK(r.curvature >= -3.0 - 1e-9);  // a Ritz value lies inside the spectrum's hull

  // z an eigenvector of an SPD matrix: the Krylov space is invariant after one step (beta = 0).
  const MatX D = VecX::LinSpaced(n, 1.0, 4.0).asDiagonal();
  VecX e = VecX::Zero(n);
  e[5] = 3.0;
  const KrylovResult h = lanczos_sqrt(product(D), e, y, 1e-12, 200);
  CHECK(h.status == KrylovStatus::converged);
  CHECK(h.iterations == 1);
  CHECK((y - std::sqrt(D(5, 5)) * e).norm() < 1e-14 * e.norm());

  // SPD: converges to the exact square root (eigendecomposition reference).
  const MatX S = spd(n, 8);
  Eigen::SelfAdjointEigenSolver<MatX> eig(S);
  const VecX ref = eig.eigenvectors() * eig.eigenvalues().cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose() * z;
  const KrylovResult ok = lanczos_sqrt(product(S), z, y, 1e-10, 200);
  CHECK(ok.status == KrylovStatus::converged);
  CHECK((y - ref).norm() < 1e-8 * ref.norm());
}

namespace {
// The direct far field with entry (0, 0) lowered by 2/(6 pi a): no longer positive definite.
struct IndefiniteMobility final : MobilityOperator {
  DirectFarField M{MobilitySpec{Moments::F, 1.0, 1e-6}};
  const char* name() const override { return "indefinite test operator"; }
  Moments moments() const override { return Moments::F; }
  Eigen::Index size() const override { return M.size(); }
  void set_configuration(const Configuration& c) override { M.set_configuration(c); }
  void apply(const VecX& in, VecX& out) const override {
    M.apply(in, out);
    out[0] -= 2.0 / (6.0 * kPi) * in[0];
  }
};
}  // namespace

TEST_CASE("far-field Brownian displacement: an indefinite mobility is reported by the Lanczos square root") {
  MobilitySolver solver(std::make_unique<IndefiniteMobility>(), 1e-6);
  const std::vector<Vec3> x{{0, 0, 0}, {4, 0, 0}, {0, 5, 0}};
  const std::vector<double> a{1, 1, 1};
  const Domain open;
  solver.prepare({x, a, open});
  Rng rng = RandomStream::for_purpose(1, Purpose::brownian, 0);
  try {
    (void)solver.brownian_displacement(1.0, 0.01, rng);
    FAIL("no error");
  } catch (const PhysicsError& e) {
    const std::string m = e.what();
    MESSAGE(m);
    CHECK(contains(m, "Lanczos"));
    CHECK(contains(m, "not positive definite"));
    CHECK(contains(m, "iterations"));
  }
}

TEST_CASE("far-field Brownian force: an indefinite mobility is reported by the Lanczos inverse square root") {
  MobilitySolver solver(std::make_unique<IndefiniteMobility>(), 1e-6);
  const std::vector<Vec3> x{{0, 0, 0}, {4, 0, 0}, {0, 5, 0}};
  const std::vector<double> a{1, 1, 1};
  solver.prepare({x, a, Domain{}});
  Rng rng = RandomStream::for_purpose(1, Purpose::brownian, 0);
  try {
    (void)solver.brownian_force(1.0, 0.01, {}, rng);
    FAIL("no error");
  } catch (const PhysicsError& e) {
    const std::string m = e.what();
    MESSAGE(m);
    CHECK(contains(m, "M^(-1/2)"));
    CHECK(contains(m, "not positive definite"));
    CHECK(contains(m, "iterations"));
  }
}

TEST_CASE("far-field FTS solve: CG stagnation names step, iterations, residual and the closest pairs; "
          "at the first evaluation the run stops without a checkpoint") {
  Scene scene = io::parse_scene(R"(
[particles]
positions = [[0, 0, 0], [2.3, 0, 0], [0, 4, 0], [5, 5, 5]]
[forces]
external_force = [0, 0, -1]
[hydrodynamics]
model = "far_field"
moments = "FTS"
[time]
steps = 3
)", "stagnation.toml");
  scene.hydro.tolerance = 1e-30;  // below what double precision reaches (the scene file allows >= 1e-14)
  Simulation sim(scene);
  State s = sim.initial_state();
  MemorySink sink;
  try {
    sim.run(s, sink, RunControl{true});
    FAIL("no error");
  } catch (const RunStopped& e) {
    const std::string m = e.what();
    MESSAGE(m);
    CHECK(contains(m, "step 0:"));
    CHECK(contains(m, "conjugate gradients stagnated at round-off"));
    CHECK(contains(m, "iterations, relative residual"));
    CHECK(contains(m, "closest pairs: (0, 1) gap 0.3 a"));
    CHECK(contains(m, "first evaluation"));
    CHECK(e.checkpoint_step == -1);
  }
  CHECK(sink.checkpoints.empty());
  CHECK(sink.frames.empty());
}

// ------------------------------------------------------------------------------------------------
// Factorisation failure and non-finite states (engine level)

TEST_CASE("dense SD: coincident particles make the factorisation fail, naming the pair") {
  Scene scene = io::parse_scene(R"(
[particles]
positions = [[0, 0, 0], [6, 0, 0], [0, 0, 2.5]]
[forces]
external_force = [0, 0, -1]
[hydrodynamics]
model = "stokesian"
[time]
steps = 2
)", "coincident.toml");
  scene.positions[2] = scene.positions[0];  // input validation refuses this; a run state can reach it
  Simulation sim(scene);
  State s = sim.initial_state();
  try {
    (void)sim.evaluate(s, s.position);
    FAIL("no error");
  } catch (const PhysicsError& e) {
    const std::string m = e.what();
    MESSAGE(m);
    CHECK(contains(m, "step 0:"));
    CHECK(contains(m, "not positive definite"));
    CHECK(contains(m, "particle 2"));
    CHECK(contains(m, "pair (0, 2)"));
  }
  MemorySink sink;
  CHECK_THROWS_AS(sim.run(s, sink, RunControl{true}), RunStopped);
  CHECK(sink.checkpoints.empty());
}

TEST_CASE("non-finite positions, forces and velocities are named with particle and step") {
  const std::string toml = R"(
[particles]
positions = [[0, 0, 0], [3, 0, 0], [0, 3, 0]]
[hydrodynamics]
model = "far_field"
moments = "FT"
[time]
steps = 2
)";
  {
    Scene scene = io::parse_scene(toml, "nan_position.toml");
    scene.positions[1].y() = std::numeric_limits<double>::quiet_NaN();
    Simulation sim(scene);
    const State s = sim.initial_state();
    try {
      (void)sim.evaluate(s, s.position);
      FAIL("no error");
    } catch (const PhysicsError& e) {
      CHECK(contains(e.what(), "step 0: particle 1 has a non-finite position"));
    }
  }
  {
    Scene scene = io::parse_scene(toml, "nan_force.toml");
    scene.forces.external_force = {Vec3::Zero(), Vec3::Zero(), Vec3(0, std::numeric_limits<double>::infinity(), 0)};
    Simulation sim(scene);
    State s = sim.initial_state();
    s.step = 7;
    try {
      (void)sim.evaluate(s, s.position);
      FAIL("no error");
    } catch (const PhysicsError& e) {
      CHECK(contains(e.what(), "step 7: particle 2 has a non-finite force"));
    }
  }
}

TEST_CASE("rkf45: a step size below its minimum and a non-finite error estimate name the particle") {
  // Particle 1 relaxes with rate 1e6 (stiff): with dt_min = 1e-3 no step meets the tolerance.
  const VelocityField stiff = [](const std::vector<Vec3>& x, double) {
    return std::vector<Vec3>{Vec3::Zero(), -1e6 * x[1], Vec3::Zero()};
  };
  const std::vector<Vec3> x0{{0, 0, 0}, {1, 0, 0}, {0, 5, 0}};
  try {
    (void)rkf45_step(stiff, x0, stiff(x0, 0.0), 0.1, 1e-9, 1e-3);
    FAIL("no error");
  } catch (const PhysicsError& e) {
    CHECK(contains(e.what(), "step size fell below 0.001"));
    CHECK(contains(e.what(), "at particle 1"));
  }
  const VelocityField nan = [](const std::vector<Vec3>& x, double) {
    return std::vector<Vec3>{Vec3::Zero(), Vec3::Zero(), x[2] * std::numeric_limits<double>::quiet_NaN()};
  };
  try {
    (void)rkf45_step(nan, x0, std::vector<Vec3>(3, Vec3::Zero()), 0.1, 1e-9, 1e-3);
    FAIL("no error");
  } catch (const PhysicsError& e) {
    CHECK(contains(e.what(), "non-finite error estimate at particle 2"));
  }
}

TEST_CASE("min_gap is the true smallest surface gap, not capped at 1 a") {
  const Domain open;
  CHECK(gap_statistics({{0, 0, 0}, {10, 0, 0}}, {1.0, 1.5}, open).min_gap == doctest::Approx(7.5).epsilon(1e-14));
  CHECK(gap_statistics({{0, 0, 0}, {100, 0, 0}, {0, 40, 0}}, {1, 1, 1}, open).min_gap ==
        doctest::Approx(38.0).epsilon(1e-14));
  CHECK(gap_statistics({{0, 0, 0}, {2.5, 0, 0}}, {1, 1}, open).min_gap == doctest::Approx(0.5).epsilon(1e-14));
  CHECK(std::isinf(gap_statistics({{0, 0, 0}}, {1}, open).min_gap));
  // Periodic: the nearest image (edge 20: centres 18 apart along x are 2 apart through the boundary).
  Domain box;
  box.kind = Domain::Kind::periodic;
  box.box = Vec3(20, 20, 20);
  CHECK(gap_statistics({{1, 10, 10}, {19, 10, 10}}, {0.5, 0.5}, box).min_gap == doctest::Approx(1.0).epsilon(1e-14));
  CHECK(gap_statistics({{0, 0, 0}, {9, 0, 0}}, {1, 1}, box).min_gap == doctest::Approx(7.0).epsilon(1e-14));
}

TEST_CASE("survey_overlaps (one pair search on output steps) agrees with the all-pairs definition") {
  // Reference: every pair by its minimum image (cubic box: componentwise rounding), the overlapping
  // pairs ranked by depth -h / min(a_i, a_j), and the smallest gap over all pairs.
  for (const bool periodic : {false, true})
    for (const int n : {1, 2, 30, 200}) {
      CAPTURE(periodic);
      CAPTURE(n);
      Domain d;
      const double L = std::cbrt(double(n) * 4.19 / 0.3);  // volume fraction ~0.3 of unit spheres
      if (periodic) {
        d.kind = Domain::Kind::periodic;
        d.box = Vec3(L, L, L);
      }
      RandomStream rng = RandomStream::for_purpose(7, Purpose::test, std::uint64_t(n), periodic);
      std::vector<Vec3> x(static_cast<std::size_t>(n));
      std::vector<double> a(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        x[std::size_t(i)] = Vec3(rng.uniform(), rng.uniform(), rng.uniform()) * L;
        a[std::size_t(i)] = 0.8 + 0.4 * rng.uniform();
      }
      double min_gap = INFINITY;
      std::vector<PairGap> over;
      for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
          Vec3 r = x[std::size_t(j)] - x[std::size_t(i)];
          if (periodic) r -= L * (r / L).array().round().matrix();
          const double h = r.norm() - a[std::size_t(i)] - a[std::size_t(j)];
          min_gap = std::min(min_gap, h);
          if (h < 0) over.push_back({i, j, h, -h / std::min(a[std::size_t(i)], a[std::size_t(j)])});
        }
      std::sort(over.begin(), over.end(), [](const PairGap& u, const PairGap& v) { return u.depth > v.depth; });
      const std::size_t keep = 5;
      GapStats stats;
      const GapSurvey got = survey_overlaps(x, a, d, keep, stats);
      CHECK(stats.overlaps == long(over.size()));
      CHECK(got.stats.overlaps == long(over.size()));
      if (n < 2) CHECK(std::isinf(stats.min_gap));
      else CHECK(stats.min_gap == doctest::Approx(min_gap).epsilon(1e-12));
      REQUIRE(got.worst.size() == std::min(keep, over.size()));
      for (std::size_t k = 0; k < got.worst.size(); ++k) {
        CHECK(got.worst[k].i == over[k].i);
        CHECK(got.worst[k].j == over[k].j);
        CHECK(got.worst[k].gap == doctest::Approx(over[k].gap).epsilon(1e-12));
      }
    }
}

// ------------------------------------------------------------------------------------------------
// The policy through the command line

namespace {
// Two spheres pushed together by opposite forces of 60 kT/a against a Hertz contact of stiffness
// 300: the contact settles at an overlap of (60/300)^(2/3) = 0.34 a, stable for Euler steps below
// ~0.07; with dt = 0.1 the approach overshoots to an overlap of 0.63 a at step 5.
std::string squeezed(double dt) {
  std::ostringstream o;
  o << R"([particles]
positions = [[0, 0, 0], [3, 0, 0]]
[forces]
external_force = [[60, 0, 0], [-60, 0, 0]]
[[forces.pair]]
kind = "hertz"
stiffness = 300.0
[hydrodynamics]
model = "free_draining"
[time]
steps = 30
dt = )" << dt << R"(
[output]
every = 2
checkpoint_every = 4
)";
  return o.str();
}
}  // namespace

TEST_CASE("CLI: an overlap beyond [run] max_overlap stops the run at the step before, exit 3; --resume with a "
          "smaller dt continues to the end") {
  write_scene("squeeze.toml", squeezed(0.1));
  const Result r = cli("run squeeze.toml --out sq.h5 --quiet");
  MESSAGE(r.err);
  CHECK(r.status == 3);
  CHECK(contains(r.err, "physics error: the step from 4 to 5 (t = 0.4, dt = 0.1) failed: step 5: 1 overlapping pair(s)"));
  CHECK(contains(r.err, "(0, 1) gap -0.628 a (overlap 0.628 of the smaller radius)"));
  CHECK(contains(r.err, "[run] max_overlap = 0.5"));
  CHECK(contains(r.err, "checkpoint: sq.h5.ckpt (step 4)"));
  CHECK(contains(r.err, "reduce [time] dt in squeeze.toml (e.g. to 0.05)"));
  CHECK(contains(r.err, "stokesian run squeeze.toml --out sq.h5 --resume"));
  CHECK(io::read_checkpoint((scratch() / "sq.h5.ckpt").string()).state.step == 4);
  CHECK(steps_of("sq.h5") == std::vector<double>{0, 2, 4});

  // The same dt fails the same way (the policy is deterministic).
  const Result again = cli("run squeeze.toml --out sq.h5 --resume --quiet");
  CHECK(again.status == 3);
  CHECK(contains(again.err, "the step from 4 to 5"));

  // A change beyond dt and [run] is still refused.
  write_scene("squeeze.toml", squeezed(0.02) + "[brownian]\nseed = 9\n");
  const Result other = cli("run squeeze.toml --out sq.h5 --resume --quiet");
  CHECK(other.status == 4);
  CHECK(contains(other.err, "[brownian] seed"));

  // A stricter [run] max_overlap (a change a resume accepts) that the checkpointed state itself
  // violates: the resumed run fails at its first evaluation and keeps its files unchanged.
  write_scene("squeeze.toml", squeezed(0.02) + "[run]\nmax_overlap = 0.05\n");
  const Result strict = cli("run squeeze.toml --out sq.h5 --resume --quiet");
  MESSAGE(strict.err);
  CHECK(strict.status == 3);
  CHECK(contains(strict.err, "resuming with changed [run] max_overlap: 0.5 -> 0.05; [time] dt"));
  CHECK(contains(strict.err, "step 4: 1 overlapping pair(s), the deepest beyond [run] max_overlap = 0.05"));
  CHECK(contains(strict.err, "the resumed state (the checkpoint sq.h5.ckpt) itself fails: it is kept unchanged"));
  CHECK(io::read_checkpoint((scratch() / "sq.h5.ckpt").string()).state.step == 4);
  CHECK(steps_of("sq.h5") == std::vector<double>{0, 2, 4});

  // A smaller dt continues from step 4 to the end; the warning names the overlapping pair.
  write_scene("squeeze.toml", squeezed(0.02));
  const Result ok = cli("run squeeze.toml --out sq.h5 --resume --progress-interval 1000");
  MESSAGE(ok.err);
  CHECK(ok.status == 0);
  CHECK(contains(ok.err, "resuming with changed [time] dt"));
  CHECK(contains(ok.err, "step 4: 1 overlapping pair(s), deepest (0, 1) gap"));
  std::vector<double> want{0, 2, 4};
  for (int k = 6; k <= 30; k += 2) want.push_back(k);
  CHECK(steps_of("sq.h5") == want);
  const auto dt = test::read_doubles((scratch() / "sq.h5").string(), "/observables/dt/value");
  REQUIRE(dt.size() == want.size());
  CHECK(dt[2] == 0.1);   // frame of step 4, written before the failure
  CHECK(dt[3] == 0.02);  // after the resume
  // Settled at the Hertz equilibrium overlap (60/300)^(2/3) a.
  const auto gap = test::read_doubles((scratch() / "sq.h5").string(), "/observables/min_gap/value");
  CHECK(gap.back() == doctest::Approx(-std::pow(0.2, 2.0 / 3.0)).epsilon(1e-4));
}

TEST_CASE("CLI: spheres with neither pair forces nor lubrication are penetrable: overlaps are named, never a failure") {
  // Opposite forces drive two free-draining spheres through each other (no pair force).
  write_scene("through.toml", R"([particles]
positions = [[0, 0, 0], [3, 0, 0]]
[forces]
external_force = [[60, 0, 0], [-60, 0, 0]]
[hydrodynamics]
model = "free_draining"
[time]
dt = 0.1
steps = 6
)");
  const Result r = cli("run through.toml --out through.h5 --progress-interval 1000");
  CHECK(r.status == 0);
  // Gap 1 - 0.637 k a at step k: the pair overlaps from step 2 on and passes through by step 6.
  CHECK(contains(r.err, "step 2: 1 overlapping pair(s), deepest (0, 1) gap -0.273 a (overlap 0.273 of the smaller radius) "
                        "(continuing: without pair forces or lubrication the spheres are penetrable"));
}

TEST_CASE("CLI: a non-finite force stops the run with a checkpoint of the step before; a smaller dt continues") {
  // Morse with kappa = 1e4: at an overlap of 0.06 a, exp(2 kappa |h|) overflows. Forces of 50 kT/a
  // close the gap of 1 a by 0.265 a per step of 0.05: step 4 reaches h = -0.06.
  auto scene = [](double dt) {
    std::ostringstream o;
    o << "[particles]\npositions = [[0, 0, 0], [3, 0, 0], [0, 8, 0]]\n[forces]\nexternal_force = [[50, 0, 0], [-50, "
         "0, 0], [0, 0, 0]]\n[[forces.pair]]\nkind = \"morse\"\ndepth = 1.0\nkappa = 10000.0\n[hydrodynamics]\n"
         "model = \"free_draining\"\n[time]\nsteps = 20\ndt = "
      << dt << "\n[output]\nevery = 5\n";
    return o.str();
  };
  write_scene("nan.toml", scene(0.05));
  const Result r = cli("run nan.toml --out nan.h5 --quiet");
  MESSAGE(r.err);
  CHECK(r.status == 3);
  CHECK(contains(r.err, "the step from 3 to 4"));
  CHECK(contains(r.err, "step 4: particle 0 has a non-finite force"));
  CHECK(contains(r.err, "closest pairs: (0, 1) gap -0.06"));
  CHECK(io::read_checkpoint((scratch() / "nan.h5.ckpt").string()).state.step == 3);
  CHECK(steps_of("nan.h5") == std::vector<double>{0});

  write_scene("nan.toml", scene(0.001));
  const Result ok = cli("run nan.toml --out nan.h5 --resume --quiet");
  CHECK(ok.status == 0);
  CHECK(steps_of("nan.h5") == std::vector<double>{0, 5, 10, 15, 20});
}

TEST_CASE("CLI: a failure at the first evaluation removes every file the run created") {
  write_scene("first.toml", R"([particles]
positions = [[0, 0, 0], [1.8, 0, 0], [8, 0, 0]]
[[forces.pair]]
kind = "hertz"
[run]
max_overlap = 0.1
[time]
steps = 5
[output]
xyz = true
)");
  const Result r = cli("run first.toml --out first.h5 --quiet");
  MESSAGE(r.err);
  CHECK(r.status == 3);
  CHECK(contains(r.err, "step 0: 1 overlapping pair(s), the deepest beyond [run] max_overlap = 0.1"));
  CHECK(contains(r.err, "(0, 1) gap -0.2 a"));
  CHECK(contains(r.err, "no step was taken: removed first.h5"));
  for (const char* f : {"first.h5", "first.h5.shadow", "first.h5.ckpt", "first.h5.starting", "first.xyz"})
    CHECK_MESSAGE(!fs::exists(scratch() / f), f);
}

TEST_CASE("CLI: solve names the overlapping pairs and the pairs whose lubrication is regularised") {
  // Pair (0, 1) at symmetric gap 1e-8 (below the floor 1e-6), (2, 3) overlapping by 0.1 a,
  // (4, 5) at 1e-3 (not regularised).
  write_scene("close.toml", R"([particles]
positions = [[0, 0, 0], [2.00000001, 0, 0], [10, 0, 0], [11.9, 0, 0], [20, 0, 0], [22.001, 0, 0]]
[forces]
external_force = [0, 0, -1]
[hydrodynamics]
model = "stokesian"
)");
  const Result r = cli("solve close.toml --out close.h5 --quiet");
  MESSAGE(r.err);
  CHECK(r.status == 0);
  CHECK(contains(r.err, "1 overlapping pair(s): (2, 3) gap -0.1 a (overlap 0.1 of the smaller radius)"));
  CHECK(contains(r.err, "1 pair(s) closer than [hydrodynamics] lubrication_min_gap = 1e-06"));
  CHECK(contains(r.err, "(0, 1) gap 1e-08 a"));
  CHECK_FALSE(contains(r.err, "(4, 5)"));

  // Nothing close: nothing said.
  write_scene("apart.toml", "[particles]\npositions = [[0, 0, 0], [3, 0, 0]]\n[hydrodynamics]\nmodel = \"stokesian\"\n");
  const Result q = cli("solve apart.toml --out apart.h5 --quiet");
  CHECK(q.status == 0);
  CHECK(q.err.empty());
}
