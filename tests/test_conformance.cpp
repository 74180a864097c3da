// Conformance: one test body that every registered far-field method (MobilityOperator) and every
// registered hydrodynamic solver (HydroSolver) passes against the dense references. A new method
// or solver is held to it by registering it (engine/methods.cpp); nothing here names one.
//
// Mobility operators, for F, FT, FTS, tolerances 1e-3, 1e-6, 1e-9 and open / periodic / sheared
// configurations with polydisperse, partly overlapping spheres:
//   accuracy     |M x - M_ref x| <= tol |M_ref x| (M_ref: dense_mobility from the explicit
//                tensors in open domains, the converged dense Ewald sum in periodic boxes);
//   symmetry     |x.M y - y.M x| <= 1e-10 |x| |y| |M| (tol |x| |y| |M| for a method whose products
//                are not exact adjoints, FarFieldMethodEntry::symmetric_to_roundoff);
//   SPD          M_ref is positive definite for every configuration (Zuk et al. 2014); the
//                operator is at the loosest tolerance whose error stays below the smallest
//                eigenvalue of M_ref;
//   life cycle   an operator moved to a configuration equals a fresh one there, and dense()
//                (when offered) equals the operator.
// Hydrodynamic solvers, with each far-field method of the domain, fixed particles, a linear
// ambient flow, a Brownian force f_B and a slip velocity u_s (engine/hydro_solver.hpp):
//   the solution equals that of R_ref V = f + f_B + M_ref^{-1} u_s solved densely with the
//   rigid-body constraints written out here, R_ref = M_ref^{-1} (+ R_nf from the O(N^2)
//   near-field twin at the Stokesian-dynamics level), to 1e3 tol (Krylov solves stop at a
//   relative residual tol; the constrained systems here have condition numbers below 1e2);
//   loads are reproduced and fixed particles do not move; solvers that sample Brownian motion
//   give displacements of covariance 2 kT dt M_tt (3000 draws, 12 %; resistance solvers through
//   their Brownian force, dt R^{-1} xi, M = R^{-1}); needs_drift is true
//   exactly when a near-field resistance enters.
#include <doctest/doctest.h>

#include "support/random.hpp"

#include "engine/core/sym_traceless.hpp"
#include "engine/hydro_solver.hpp"
#include "engine/kernels/far_field.hpp"
#include "engine/methods.hpp"
#include "ewald/ewald_reference.hpp"
#include "lubrication/near_field.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace stokesian;
using stokesian::test::random_vector;

namespace {

struct Config {
  std::string name;
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain domain;
};

Config random_config(const std::string& name, int n, const Vec3& L, double amin, double amax, std::uint64_t seed,
                     bool periodic, double strain = 0.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Config c;
  c.name = name;
  for (int i = 0; i < n; ++i) {
    c.x.emplace_back(L.x() * u(rng), L.y() * u(rng), L.z() * u(rng));
    c.a.push_back(amin + (amax - amin) * u(rng));
  }
  if (periodic) {
    c.domain.kind = Domain::Kind::periodic;
    c.domain.box = L;
    c.domain.shear_strain = strain;
  }
  return c;
}

std::vector<Config> operator_configs() {
  return {random_config("open", 12, Vec3(9, 9, 9), 0.5, 1.5, 3, false),
          random_config("periodic", 12, Vec3(12, 12, 12), 0.5, 1.2, 5, true),
          random_config("sheared", 10, Vec3(12, 10, 11), 0.4, 1.2, 7, true, 0.37)};
}


MatX reference_mobility(const Config& c, Moments m, double mu) {
  return c.domain.periodic() ? ewald::ewald_mobility(c.x, c.a, mu, m, c.domain) : dense_mobility(c.x, c.a, mu, m);
}

MatX operator_matrix(const MobilityOperator& op) {
  const Eigen::Index n = op.size();
  MatX M(n, n);
  VecX e = VecX::Zero(n), y;
  for (Eigen::Index j = 0; j < n; ++j) {
    e[j] = 1.0;
    op.apply(e, y);
    M.col(j) = y;
    e[j] = 0.0;
  }
  return M;
}

}  // namespace

TEST_CASE("every far-field method: accuracy, symmetry, positive definiteness and life cycle") {
  const double mu = 1.3;
  for (const FarFieldMethodEntry& method : far_field_methods().entries()) {
    for (const Config& c : operator_configs()) {
      if (c.domain.periodic() != method.periodic) continue;
      const Config other = random_config("other", int(c.x.size()), c.domain.periodic() ? c.domain.box : Vec3(9, 9, 9),
                                         0.5, 1.2, 99, c.domain.periodic(), c.domain.shear_strain);
      for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
        const MatX Mref = reference_mobility(c, m, mu);
        const double lambda_min = Eigen::SelfAdjointEigenSolver<MatX>(Mref).eigenvalues().minCoeff();
        CHECK(lambda_min > 0.0);  // the grand mobility is SPD for every configuration
        const VecX x = random_vector(Mref.rows(), 11), v = random_vector(Mref.rows(), 12);
        const VecX yref = Mref * x;
        bool pd_checked = false;
        for (double tol : {1e-3, 1e-6, 1e-9}) {
          CAPTURE(method.name);
          CAPTURE(c.name);
          CAPTURE(to_string(m));
          CAPTURE(tol);
          auto op = method.make(MobilitySpec{m, mu, tol});
          CHECK(std::string(op->name()) == method.name);
          CHECK(op->moments() == m);
          op->set_configuration({other.x, other.a, other.domain});  // first elsewhere, then here
          op->set_configuration({c.x, c.a, c.domain});
          REQUIRE(op->size() == Mref.rows());
          VecX y, w;
          op->apply(x, y);
          const double err = (y - yref).norm() / yref.norm();
          CHECK(err <= tol);
          // Symmetry.
          op->apply(v, w);
          const double asymmetry_bound = method.symmetric_to_roundoff ? 1e-10 : tol;
          CHECK(std::abs(x.dot(w) - v.dot(y)) <= asymmetry_bound * x.norm() * v.norm() * Mref.norm());
          // A fresh operator at this configuration gives the same product.
          auto fresh = method.make(MobilitySpec{m, mu, tol});
          fresh->set_configuration({c.x, c.a, c.domain});
          VecX yf;
          fresh->apply(x, yf);
          CHECK((yf - y).norm() <= 1e-14 * y.norm());
          // dense() when offered.
          if (const MatX* D = op->dense()) CHECK((*D * x - y).norm() <= 1e-12 * y.norm());
          CHECK(method.dense == (op->dense() != nullptr));
          // Positive definite where the error cannot reach the smallest eigenvalue: checked at the
          // loosest such tolerance (the operator's matrix costs one product per column).
          if (!pd_checked && tol * Mref.norm() < 0.5 * lambda_min) {
            pd_checked = true;
            const MatX M = operator_matrix(*op);
            const MatX S = 0.5 * (M + M.transpose());
            CHECK(Eigen::SelfAdjointEigenSolver<MatX>(S).eigenvalues().minCoeff() > 0.0);
          }
        }
        CHECK(pd_checked);
      }
    }
  }
}

namespace {

// The rigid-body problem solved densely, written out independently of engine/core/layout.hpp:
// R V = f + fB + Minv us for the unknown motion of mobile particles, V = [U - u, W - w, -E] with the
// motion of fixed particles and the strain rows given; moments = R V - Minv us.
struct Reference {
  std::vector<Vec3> U, Omega, F;
  std::vector<Vec5> S;
};

Reference solve_reference(const MatX& R, const MatX& Minv, Moments m, const Config& c, const std::vector<char>& fixed,
                          const std::vector<Vec3>& F, const std::vector<Vec3>& T, const AmbientFlow& flow,
                          const VecX& fB, const VecX& us) {
  const int d = dof_per_particle(m);
  const long n = long(c.x.size()), N = n * d;
  const Vec5 E5 = to_vec5(flow.E);
  VecX V = VecX::Zero(N), f = fB + Minv * us;
  std::vector<long> unknown;
  for (long i = 0; i < n; ++i) {
    const bool fx = fixed[std::size_t(i)] != 0;
    const Vec3 u = flow.velocity(c.x[std::size_t(i)]);
    for (int k = 0; k < d; ++k) {
      const long q = i * d + k;
      if (k >= 6) {
        V[q] = -E5[k - 6];
      } else if (fx) {
        V[q] = k < 3 ? -u[k] : -flow.Omega[k - 3];
      } else {
        unknown.push_back(q);
        f[q] += k < 3 ? F[std::size_t(i)][k] : T[std::size_t(i)][k - 3];
      }
    }
  }
  const VecX rest = f - R * V;
  MatX Ruu(unknown.size(), unknown.size());
  VecX b(unknown.size());
  for (std::size_t p = 0; p < unknown.size(); ++p) {
    b[long(p)] = rest[unknown[p]];
    for (std::size_t q = 0; q < unknown.size(); ++q) Ruu(long(p), long(q)) = R(unknown[p], unknown[q]);
  }
  const VecX Vu = Ruu.lu().solve(b);
  for (std::size_t p = 0; p < unknown.size(); ++p) V[unknown[p]] = Vu[long(p)];
  const VecX mom = R * V - Minv * us;
  Reference r;
  for (long i = 0; i < n; ++i) {
    const bool fx = fixed[std::size_t(i)] != 0;
    const Vec3 u = flow.velocity(c.x[std::size_t(i)]);
    r.U.push_back(fx ? Vec3::Zero() : Vec3(V.segment<3>(i * d) + u));
    r.F.push_back(mom.segment<3>(i * d));
    if (d > 3) r.Omega.push_back(fx ? Vec3::Zero() : Vec3(V.segment<3>(i * d + 3) + flow.Omega));
    if (d > 6) r.S.push_back(mom.segment<5>(i * d + 6));
  }
  return r;
}

// The reference mobility of a level: the analytic self blocks (free draining) or M_ref.
MatX level_mobility(HydroModel level, const Config& c, Moments m, double mu) {
  if (level != HydroModel::free_draining) return reference_mobility(c, m, mu);
  const int d = dof_per_particle(m);
  const long n = long(c.x.size());
  MatX M = MatX::Zero(n * d, n * d);
  for (long i = 0; i < n; ++i) {
    const double a = c.a[std::size_t(i)];
    for (int k = 0; k < d; ++k)
      M(i * d + k, i * d + k) = k < 3 ? 1.0 / (6 * kPi * mu * a) : k < 6 ? 1.0 / (8 * kPi * mu * a * a * a)
                                                                        : 3.0 / (20 * kPi * mu * a * a * a);
  }
  return M;
}

// The reference resistance of a level: M^{-1} (returned in Minv), plus the near field at the
// Stokesian-dynamics level.
MatX reference_resistance(HydroModel level, const Config& c, Moments m, double mu, MatX& Minv) {
  Minv = level_mobility(level, c, m, mu).inverse();
  MatX R = Minv;
  if (level == HydroModel::stokesian) {
    lubrication::NearField nf(m, mu);
    if (c.domain.periodic()) R += MatX(nf.assemble(c.x, c.a, c.domain));
    else R += nf.assemble_dense(c.x, c.a);
  }
  return R;
}

std::vector<Config> solver_configs() {
  Config close;
  close.name = "close pairs";
  close.x = {Vec3(0, 0, 0), Vec3(2.05, 0, 0), Vec3(0, 2.3, 0.4), Vec3(4.2, 1.0, -0.5), Vec3(2.0, 3.9, 1.0),
             Vec3(-2.2, -1.0, 1.5)};
  close.a = {1.0, 1.0, 0.9, 1.2, 0.8, 1.1};
  return {random_config("dilute", 8, Vec3(14, 14, 14), 0.5, 1.2, 21, false), close,
          random_config("periodic", 8, Vec3(12, 12, 12), 0.5, 1.0, 23, true),
          random_config("sheared", 8, Vec3(12, 11, 12), 0.5, 1.0, 25, true, 0.2)};
}

double max_diff(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double e = 0;
  for (std::size_t i = 0; i < a.size(); ++i) e = std::max(e, (a[i] - b[i]).norm());
  return e;
}
double max_norm(const std::vector<Vec3>& a) {
  double e = 0;
  for (const auto& v : a) e = std::max(e, v.norm());
  return e;
}

}  // namespace

TEST_CASE("every hydrodynamic solver: constrained solves with noise terms against the dense reference") {
  const double mu = 0.8;
  FlowParams fp;
  fp.kind = FlowParams::Kind::simple_shear;
  fp.rate = 0.4;
  const AmbientFlow flow = ambient_flow(fp);
  for (const SolverEntry& solver : hydro_solvers().entries()) {
    for (const Config& c : solver_configs()) {
      // Each far-field method of the domain the solver can use (free draining: none).
      std::vector<const FarFieldMethodEntry*> methods;
      for (const auto& e : far_field_methods().entries())
        if (e.periodic == c.domain.periodic() && (!solver.needs_dense || e.dense)) methods.push_back(&e);
      if (!solver.needs_far_field) methods = {nullptr};
      const long n = long(c.x.size());
      std::vector<char> fixed(std::size_t(n), 0);
      fixed[1] = 1;
      std::vector<Vec3> F, T;
      std::mt19937_64 rng(31);
      std::normal_distribution<double> g;
      for (long i = 0; i < n; ++i) {
        F.emplace_back(g(rng), g(rng), g(rng));
        T.emplace_back(g(rng), g(rng), g(rng));
      }
      for (const FarFieldMethodEntry* method : methods)
        for (Moments m : {Moments::FT, Moments::FTS})
          for (double tol : {1e-5, 1e-9}) {
            CAPTURE(solver.name);
            CAPTURE(method ? method->name : "none");
            CAPTURE(c.name);
            CAPTURE(to_string(m));
            CAPTURE(tol);
            SolverSetup setup;
            setup.knobs = derive_knobs(tol, solver.level, 1.0, true);  // particle 1 is fixed
            setup.spec = MobilitySpec{m, mu, setup.knobs.far_field};
            if (method) setup.far_field = method->make(setup.spec);
            auto s = solver.make(std::move(setup));
            CHECK(s->needs_drift() == (solver.level == HydroModel::stokesian));
            const Configuration conf{c.x, c.a, c.domain};
            s->prepare(conf);
            FlowSample sample;
            flow.sample(c.x, sample);
            const int d = dof_per_particle(m);
            const VecX fB = 0.3 * random_vector(n * d, 41), us = 0.2 * random_vector(n * d, 42);
            MatX Minv;
            const MatX R = reference_resistance(solver.level, c, m, mu, Minv);
            for (bool noise : {false, true}) {
              CAPTURE(noise);
              HydroProblem p{conf, fixed, sample, F, T};
              if (noise) {
                p.force_noise = &fB;
                p.slip = &us;
              }
              const HydroResult r = s->solve(p);
              const VecX zero = VecX::Zero(n * d);
              const Reference ref =
                  solve_reference(R, Minv, m, c, fixed, F, T, flow, noise ? fB : zero, noise ? us : zero);
              const double bound = 1e3 * tol;
              CHECK(max_diff(r.U, ref.U) <= bound * max_norm(ref.U));
              CHECK(max_diff(r.Omega, ref.Omega) <= bound * max_norm(ref.Omega));
              CHECK(max_diff(r.F, ref.F) <= bound * max_norm(ref.F));
              if (m == Moments::FTS) {
                double e = 0, scale = 0;
                for (long i = 0; i < n; ++i) {
                  e = std::max(e, (r.S[std::size_t(i)] - ref.S[std::size_t(i)]).norm());
                  scale = std::max(scale, ref.S[std::size_t(i)].norm());
                }
                CHECK(e <= bound * scale);
              }
              // Loads reproduced (with the noise force), fixed particles at rest.
              for (long i = 0; i < n; ++i) {
                const std::size_t k = std::size_t(i);
                if (fixed[k]) {
                  CHECK(r.U[k] == Vec3::Zero());
                  CHECK(r.Omega[k] == Vec3::Zero());
                } else {
                  const Vec3 given = F[k] + (noise ? Vec3(fB.segment<3>(i * d)) : Vec3::Zero());
                  CHECK((r.F[k] - given).norm() <= 1e3 * tol * given.norm());
                }
              }
            }
          }
    }
  }
}

TEST_CASE("every solver that samples Brownian motion: displacements of covariance 2 kT dt M_tt") {
  const double mu = 1.0, kT = 0.7, dt = 0.3;
  const Config c = random_config("three", 3, Vec3(5, 5, 5), 0.6, 1.3, 51, false);
  for (const SolverEntry& solver : hydro_solvers().entries()) {
    if (!solver.brownian) continue;
    for (Moments m : {Moments::F, Moments::FT}) {
      CAPTURE(solver.name);
      CAPTURE(to_string(m));
      SolverSetup setup;
      setup.knobs = derive_knobs(1e-10, solver.level, 1.0, false);
      setup.spec = MobilitySpec{m, mu, setup.knobs.far_field};
      if (solver.needs_far_field) setup.far_field = far_field_methods().find("direct")->make(setup.spec);
      auto s = solver.make(std::move(setup));
      s->prepare({c.x, c.a, c.domain});
      const MatX M = level_mobility(solver.level, c, m, mu);
      const int d = dof_per_particle(m);
      MatX Mtt(9, 9);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Mtt.block<3, 3>(3 * i, 3 * j) = M.block<3, 3>(d * i, d * j);
      Rng rng(61, 0);
      MatX C = MatX::Zero(9, 9);
      const int draws = 3000;
      FlowSample still;
      AmbientFlow{}.sample(c.x, still);
      const std::vector<Vec3> zero(3, Vec3::Zero());
      for (int k = 0; k < draws; ++k) {
        // Resistance solvers: displacement dt R^{-1} xi from the Brownian force (engine/brownian.hpp).
        std::vector<Vec3> dx;
        if (s->needs_drift()) {
          const VecX xi = s->brownian_force(kT, dt, {}, rng);
          dx = s->solve(HydroProblem{{c.x, c.a, c.domain}, {}, still, zero, zero, &xi}).U;
          for (auto& v : dx) v *= dt;
        } else {
          dx = s->brownian_displacement(kT, dt, rng);
        }
        Eigen::Matrix<double, 9, 1> v;
        for (int i = 0; i < 3; ++i) v.segment<3>(3 * i) = dx[std::size_t(i)];
        C += v * v.transpose();
      }
      C /= draws * 2.0 * kT * dt;
      CHECK((C - Mtt).norm() <= 0.12 * Mtt.norm());
    }
  }
}
