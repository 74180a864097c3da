// Hydrodynamic solves: single-sphere analytic results, the CG-solved constrained mobility problem
// against a dense direct solve, and the Lanczos square root against the eigen-decomposition.
#include <doctest/doctest.h>

#include "engine/kernels/far_field.hpp"
#include "engine/hydrodynamics.hpp"
#include "engine/core/krylov.hpp"
#include "ewald/ewald_reference.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

using namespace stokesian;

namespace {
constexpr double pi = 3.14159265358979323846;

ResolvedModel model(HydroModel level, Moments m) {
  ResolvedModel r;
  r.level = level;
  r.moments = m;
  return r;
}

struct Config {
  std::vector<Vec3> x;
  std::vector<double> a;
};
Config random_config(int n, double L, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Config c;
  for (int i = 0; i < n; ++i) {
    c.x.emplace_back(L * u(rng), L * u(rng), L * u(rng));
    c.a.push_back(0.3 + 1.7 * u(rng));
  }
  return c;
}
}  // namespace

TEST_CASE("single rigid sphere in simple shear: stresslet -(20/3) pi mu a^3 E, co-rotation, advection") {
  // Analytic (Batchelor 1970): a torque-free force-free sphere translates with u_inf(x),
  // rotates with Omega_inf and exerts S = -(20/3) pi mu a^3 E_inf on the fluid.
  FlowParams fp;
  fp.kind = FlowParams::Kind::simple_shear;
  fp.rate = 0.7;
  const AmbientFlow flow = ambient_flow(fp);
  for (HydroModel level : {HydroModel::free_draining, HydroModel::far_field}) {
    Hydrodynamics h(model(level, Moments::FTS), 1.5, flow, 1e-12);
    const double a = 1.3;
    const std::vector<Vec3> x{Vec3(0.4, 2.0, -1.0)};
    const HydroResult r = h.solve(x, {a}, {}, {Vec3::Zero()}, {Vec3::Zero()});
    const Mat3 S = from_vec5(r.S[0]);
    const Mat3 expect = -(20.0 / 3.0) * pi * 1.5 * a * a * a * flow.E;
    CHECK((S - expect).norm() < 1e-10 * expect.norm());
    CHECK((r.U[0] - Vec3(0.7 * 2.0, 0, 0)).norm() < 1e-12);
    CHECK((r.Omega[0] - Vec3(0, 0, -0.35)).norm() < 1e-12);
  }
}

TEST_CASE("FTS mobility problem with fixed particles: CG agrees with a dense direct solve") {
  FlowParams fp;
  fp.kind = FlowParams::Kind::planar_extension;
  fp.rate = 0.3;
  const AmbientFlow flow = ambient_flow(fp);
  for (double tol : {1e-4, 1e-8, 1e-12}) {
    const Config c = random_config(15, 9.0, 11);
    std::vector<char> fixed(15, 0);
    fixed[2] = fixed[7] = 1;
    std::vector<Vec3> F(15), T(15);
    std::mt19937_64 rng(5);
    std::normal_distribution<double> g;
    for (int i = 0; i < 15; ++i) {
      F[std::size_t(i)] = Vec3(g(rng), g(rng), g(rng));
      T[std::size_t(i)] = Vec3(g(rng), g(rng), g(rng));
    }
    Hydrodynamics h(model(HydroModel::far_field, Moments::FTS), 1.0, flow, tol);
    const HydroResult r = h.solve(c.x, c.a, fixed, F, T);

    // Reference: dense M, unknowns by a direct LU solve of the principal sub-system.
    const MatX M = dense_mobility(c.x, c.a, 1.0, Moments::FTS);
    const int d = 11;
    std::vector<long> unk, kn;
    VecX xk = VecX::Zero(M.rows()), target = VecX::Zero(M.rows());
    const Vec5 E5 = to_vec5(flow.E);
    for (long i = 0; i < 15; ++i)
      for (int k = 0; k < d; ++k) {
        const long q = i * d + k;
        if (k >= 6) {
          unk.push_back(q);
          target[q] = -E5[k - 6];
        } else if (fixed[std::size_t(i)]) {
          unk.push_back(q);
          target[q] = k < 3 ? -flow.velocity(c.x[std::size_t(i)])[k] : -flow.Omega[k - 3];
        } else {
          kn.push_back(q);
          xk[q] = k < 3 ? F[std::size_t(i)][k] : T[std::size_t(i)][k - 3];
        }
      }
    MatX Mzz(unk.size(), unk.size());
    VecX b(unk.size());
    const VecX Mxk = M * xk;
    for (std::size_t p = 0; p < unk.size(); ++p) {
      b[long(p)] = target[unk[p]] - Mxk[unk[p]];
      for (std::size_t q = 0; q < unk.size(); ++q) Mzz(long(p), long(q)) = M(unk[p], unk[q]);
    }
    const VecX z = Mzz.lu().solve(b);
    VecX gen = xk;
    for (std::size_t p = 0; p < unk.size(); ++p) gen[unk[p]] = z[long(p)];
    const VecX vel = M * gen;
    double err = 0, scale = 0;
    for (long i = 0; i < 15; ++i) {
      const std::size_t s = std::size_t(i);
      const Vec3 Uref = fixed[s] ? Vec3::Zero() : Vec3(vel.segment<3>(i * d) + flow.velocity(c.x[s]));
      err = std::max(err, (r.U[s] - Uref).norm());
      scale = std::max(scale, Uref.norm());
      err = std::max(err, (r.S[s] - gen.segment<5>(i * d + 6)).norm() * 1e-2);
    }
    CAPTURE(tol);
    // CG stops at |r| <= tol |b|; M_zz has a condition number of order 10-100 here, so the
    // velocity error stays within 1e3 tol of the velocity scale.
    CHECK(err < 1e3 * tol * scale);
    for (int i : {2, 7}) CHECK(r.U[std::size_t(i)].norm() == 0.0);
  }
}

TEST_CASE("Lanczos square root of the far-field mobility agrees with the eigen-decomposition") {
  for (Moments m : {Moments::F, Moments::FT}) {
    for (double tol : {1e-3, 1e-6, 1e-10}) {
      const Config c = random_config(30, 8.0, 21);
      const MatX M = dense_mobility(c.x, c.a, 1.0, m);
      Eigen::SelfAdjointEigenSolver<MatX> eig(M);
      const MatX sq = eig.operatorSqrt();
      std::mt19937_64 rng(9);
      std::normal_distribution<double> g;
      VecX w(M.rows());
      for (auto& v : w) v = g(rng);
      VecX y;
      LinearOperator op = [&](const VecX& in, VecX& out) { out = M * in; };
      const KrylovResult kr = lanczos_sqrt(op, w, y, tol, 500);
      CAPTURE(tol);
      CHECK(kr.converged);
      // The stopping test measures the change between iterates; convergence is geometric, so the
      // true error is within a small factor of it: allow 10 tol.
      CHECK((y - sq * w).norm() <= 10 * tol * (sq * w).norm());
    }
  }
}

TEST_CASE("conjugate gradients meets the requested residual") {
  const Config c = random_config(20, 6.0, 2);
  const MatX M = dense_mobility(c.x, c.a, 1.0, Moments::FTS);
  VecX b = VecX::LinSpaced(M.rows(), -1.0, 1.0), x;
  LinearOperator op = [&](const VecX& in, VecX& out) { out = M * in; };
  for (double tol : {1e-2, 1e-6, 1e-10}) {
    x.setZero(b.size());
    const KrylovResult r = conjugate_gradient(op, b, x, tol, 1000);
    CHECK(r.converged);
    CHECK((b - M * x).norm() <= tol * b.norm() * (1 + 1e-6));
  }
}

TEST_CASE("GMRES meets the requested residual; its snapshot is the iterate of a run to the looser tolerance") {
  // A nonsymmetric operator: the FTS mobility plus a skew part. The snapshot (engine/core/krylov.hpp)
  // must be the iterate a separate run to its tolerance returns (within one cycle: the same
  // arithmetic), with its residual at or below that tolerance; across restarts too.
  const Config c = random_config(20, 6.0, 2);
  MatX A = dense_mobility(c.x, c.a, 1.0, Moments::FTS);
  const MatX K = MatX::Random(A.rows(), A.cols());
  A += 0.01 * (K - K.transpose());
  const VecX b = VecX::LinSpaced(A.rows(), -1.0, 1.0);
  LinearOperator op = [&](const VecX& in, VecX& out) { out = A * in; };
  for (int restart : {200, 7})
    for (double tol : {1e-3, 1e-6}) {
      CAPTURE(restart);
      CAPTURE(tol);
      VecX x = VecX::Zero(b.size()), y = VecX::Zero(b.size());
      GmresSnapshot snap;
      snap.tol = tol;
      const KrylovResult r = gmres(op, b, x, tol * 1e-3, 2000, restart, &snap);
      CHECK(r.converged);
      CHECK((b - A * x).norm() <= tol * 1e-3 * b.norm() * (1 + 1e-6));
      REQUIRE(snap.taken);
      CHECK((b - A * snap.x).norm() <= tol * b.norm() * (1 + 1e-6));
      CHECK(snap.iterations < r.iterations);
      const KrylovResult q = gmres(op, b, y, tol, 2000, restart);
      CHECK(q.iterations == snap.iterations);
      CHECK((y - snap.x).norm() <= 1e-12 * y.norm());
    }
}

TEST_CASE("free-draining Brownian displacements have variance 2 D dt (seeded, 5-sigma bound)") {
  // Sample variance of n = 3 * 20000 normal draws has relative standard error sqrt(2/n) ~ 0.0058;
  // 5 sigma = 0.029 makes a false failure essentially impossible for this fixed seed and any other.
  Hydrodynamics h(model(HydroModel::free_draining, Moments::F), 2.0, AmbientFlow{}, 1e-8);
  Rng rng(1234, 0);
  const double a = 0.5, kT = 1.7, dt = 0.01;
  double sum2 = 0;
  const int reps = 20000;
  for (int r = 0; r < reps; ++r) sum2 += h.brownian_displacement({Vec3::Zero()}, {a}, kT, dt, rng)[0].squaredNorm();
  const double D = kT / (6 * pi * 2.0 * a);
  CHECK(std::abs(sum2 / (3.0 * reps) / (2 * D * dt) - 1.0) < 5 * std::sqrt(2.0 / (3.0 * reps)));
}

TEST_CASE("fluctuation-dissipation: far-field Brownian displacements have covariance 2 kT dt M (open and periodic)") {
  // Sample covariance of n draws of the 9 translational components of 3 close spheres (FT
  // mobility, Lanczos square root). Each entry C_ij has standard error
  // sqrt((M_ii M_jj + M_ij^2) / n) (Wishart); every entry must lie within 5 of them (45 entries
  // at 5 sigma: a false failure has probability ~3e-5 for this seed and any other).
  const std::vector<Vec3> x{Vec3(1.0, 1.0, 1.0), Vec3(3.3, 1.2, 0.9), Vec3(2.0, 3.1, 1.5)};
  const std::vector<double> a{1.0, 0.8, 1.2};
  Domain box;
  box.kind = Domain::Kind::periodic;
  box.box = Vec3(9.0, 10.0, 11.0);
  box.shear_strain = 0.2;
  for (const bool periodic : {false, true}) {
    ResolvedModel m;
    m.level = HydroModel::far_field;
    m.moments = Moments::FT;
    // Periodic: the dense Ewald operator (PME agrees with it to the tolerance, test_ewald); a PME
    // product has a fixed grid cost that would make 20000 Lanczos draws slow.
    m.far_field = periodic ? "ewald" : "direct";
    const Domain dom = periodic ? box : Domain{};
    Hydrodynamics h(m, 1.0, AmbientFlow{}, 1e-8);
    const double kT = 1.0, dt = 0.5;
    const int n = 20000;
    Rng rng(77, 0);
    Eigen::Matrix<double, 9, 9> C = Eigen::Matrix<double, 9, 9>::Zero();
    for (int s = 0; s < n; ++s) {
      const auto d = h.brownian_displacement(x, a, kT, dt, rng, dom);
      Eigen::Matrix<double, 9, 1> v;
      for (int i = 0; i < 3; ++i) v.segment<3>(3 * i) = d[std::size_t(i)];
      C += v * v.transpose();
    }
    C /= double(n);
    // Reference: the dense mobility (direct or Ewald) restricted to the translational entries.
    const MatX Mfull = periodic ? MatX(ewald::ewald_mobility(x, a, 1.0, Moments::FT, dom)) : dense_mobility(x, a, 1.0, Moments::FT);
    int worst_i = 0, worst_j = 0;
    double worst = 0;
    for (int i = 0; i < 9; ++i)
      for (int j = 0; j < 9; ++j) {
        const int fi = 6 * (i / 3) + i % 3, fj = 6 * (j / 3) + j % 3;
        const double Mij = 2 * kT * dt * Mfull(fi, fj);
        const double Mii = 2 * kT * dt * Mfull(fi, fi), Mjj = 2 * kT * dt * Mfull(fj, fj);
        const double z = std::abs(C(i, j) - Mij) / std::sqrt((Mii * Mjj + Mij * Mij) / n);
        if (z > worst) {
          worst = z;
          worst_i = i;
          worst_j = j;
        }
      }
    CAPTURE(periodic);
    CAPTURE(worst_i);
    CAPTURE(worst_j);
    CHECK(worst < 5.0);
  }
}
