// Brownian Stokesian dynamics, fluctuation-dissipation (engine/brownian.hpp): the Brownian force xi
// of the accelerated solver has covariance (2 kT / dt) R_vv and the velocities it drives have
// covariance (2 kT / dt) R_vv^{-1}, R the dense SD reference resistance (engine/sd_dense.hpp: M_inf
// formed and inverted, direct or Ewald sum, plus the near field), v the entries whose force is
// given (mobile particles' F, T). Small polydisperse configurations with gaps 1e-3 ... 1e-1, open
// and sheared periodic boxes (dense Ewald far field; the PME product is tested against it in
// tests/test_ewald.cpp), with and without a fixed particle, FT and FTS.
//
// Statistics (seeded; fixed sample sizes): K independent draws give the sample covariance C. For
// Gaussian samples the standard error of C_ij is se_ij = sqrt((S_ii S_jj + S_ij^2) / K), S the true
// covariance. Every entry must satisfy |C_ij - S_ij| <= 4.5 se_ij: for the ~300-600 distinct
// entries tested per case, the chance that a correct sampler fails anywhere is below 600 * 6.8e-6
// = 0.4 % (Bonferroni). The test has power: the same draws are checked to FAIL against the
// covariance without the near field and without the far field (each part is needed).
#include <doctest/doctest.h>

#include <algorithm>

#include "engine/accuracy.hpp"
#include "engine/brownian.hpp"
#include "engine/methods.hpp"
#include "engine/sd_accelerated.hpp"
#include "engine/sd_dense.hpp"
#include "ewald/ewald_reference.hpp"
#include "support/sanitizer.hpp"
#include "support/threads.hpp"
#include "trees/placement.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <string>
#include <vector>

using namespace stokesian;

namespace {

struct Config {
  std::string name;
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain domain;
  std::vector<char> fixed;
};

// Four spheres of radii 1, 1.6, 0.7, 1.3: a chain with surface gaps 1e-3, 1e-2, 1e-1 (in units of
// the smaller radius of each pair), bent so that no three are collinear.
Config chain(bool periodic, bool with_fixed) {
  Config c;
  c.a = {1.0, 1.6, 0.7, 1.3};
  const double gaps[3] = {1e-3, 1e-2, 1e-1};
  const Vec3 dirs[3] = {Vec3(1, 0, 0), Vec3(0.6, 0.8, 0), Vec3(0.3, -0.2, 0.932737905)};
  c.x = {Vec3(0.4, -0.3, 0.2)};
  for (int k = 0; k < 3; ++k) {
    const double h = gaps[k] * std::min(c.a[std::size_t(k)], c.a[std::size_t(k + 1)]);
    c.x.push_back(c.x.back() + dirs[k].normalized() * (c.a[std::size_t(k)] + c.a[std::size_t(k + 1)] + h));
  }
  if (periodic) {
    c.domain.kind = Domain::Kind::periodic;
    c.domain.box = Vec3(14.0, 14.0, 14.0);
    c.domain.shear_strain = 0.3;
  }
  c.fixed.assign(4, 0);
  if (with_fixed) c.fixed[3] = 1;
  c.name = std::string(periodic ? "sheared periodic" : "open") + (with_fixed ? ", particle 3 fixed" : "");
  return c;
}

std::unique_ptr<AcceleratedStokesianDynamics> accelerated(const Config& c, Moments m, double tol) {
  const AccuracyKnobs k = derive_knobs(tol, HydroModel::stokesian, 1.6 / 0.7, any_fixed(c.fixed));
  auto op = far_field_methods().find(c.domain.periodic() ? "ewald" : "direct")->make(MobilitySpec{m, 1.0, k.far_field});
  return std::make_unique<AcceleratedStokesianDynamics>(std::move(op), 1.0, lubrication::NearFieldParams{}, k.krylov,
                                                        AcceleratedStokesianDynamics::kShift,
                                                        AcceleratedStokesianDynamics::Method::gmres,
                                                        AcceleratedStokesianDynamics::kFactorGap, k.brownian);
}

MatX restrict(const MatX& A, const std::vector<long>& v) {
  MatX B(long(v.size()), long(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i)
    for (std::size_t j = 0; j < v.size(); ++j) B(long(i), long(j)) = A(v[i], v[j]);
  return B;
}

// Largest |C_ij - S_ij| / se_ij over the entries.
double worst_z(const MatX& C, const MatX& S, long K) {
  double z = 0;
  for (long i = 0; i < S.rows(); ++i)
    for (long j = i; j < S.cols(); ++j) {
      const double se = std::sqrt((S(i, i) * S(j, j) + S(i, j) * S(i, j)) / double(K));
      z = std::max(z, std::abs(C(i, j) - S(i, j)) / se);
    }
  return z;
}

}  // namespace

TEST_CASE("fluctuation-dissipation: Brownian forces and velocities of accelerated SD against the dense reference") {
  const double kT = 1.0, dt = 0.5;  // xi scaled by sqrt(2 kT / dt) = 2
  const long K = 12000;
  for (Moments m : {Moments::FT, Moments::FTS})
    for (bool periodic : {false, true})
      for (bool with_fixed : {false, true}) {
        if (m == Moments::FTS && with_fixed && !periodic) continue;  // the six other cases cover it
        const Config c = chain(periodic, with_fixed);
        CAPTURE(c.name);
        const std::string level = to_string(m);
        CAPTURE(level);
        const int d = dof_per_particle(m);
        const long n = long(c.x.size());
        DenseStokesianDynamics ref(m, 1.0, AmbientFlow{}, lubrication::NearFieldParams{});
        const MatX R = ref.resistance(c.x, c.a, c.domain);
        const MatX Rnf = MatX(lubrication::NearField(m, 1.0).assemble(c.x, c.a, c.domain));
        const std::vector<char> given = force_given_flags(m, n, c.fixed);
        std::vector<long> v;
        for (long q = 0; q < n * d; ++q)
          if (given[std::size_t(q)]) v.push_back(q);
        const MatX Rvv = restrict(R, v), Rnf_vv = restrict(Rnf, v);
        const MatX Mvv = Rvv.llt().solve(MatX::Identity(Rvv.rows(), Rvv.cols()));

        auto solver = accelerated(c, m, 1e-6);
        solver->prepare({c.x, c.a, c.domain});
        const long nv = long(v.size());
        MatX Cxi = MatX::Zero(nv, nv), CU = MatX::Zero(nv, nv);
        const long KU = K / 4;  // velocities: a GMRES solve each
        FlowSample still;
        AmbientFlow{}.sample(c.x, still);
        const std::vector<Vec3> zero(std::size_t(n), Vec3::Zero());
        for (long k = 0; k < K; ++k) {
          Rng rng = RandomStream::for_purpose(7, Purpose::test, std::uint64_t(k));
          const VecX xi = solver->brownian_force(kT, dt, c.fixed, rng);
          VecX xv(nv);
          for (long i = 0; i < nv; ++i) xv[i] = xi[v[std::size_t(i)]] / 2.0;
          Cxi.noalias() += xv * xv.transpose();
          for (long q = 0; q < n * d; ++q)
            if (!given[std::size_t(q)]) REQUIRE(xi[q] == 0.0);
          if (k < KU) {
            const HydroResult r = solver->solve(HydroProblem{{c.x, c.a, c.domain}, c.fixed, still, zero, zero, &xi});
            VecX u(nv);
            for (long i = 0; i < nv; ++i) {
              const long q = v[std::size_t(i)], p = q / d, comp = q % d;
              u[i] = (comp < 3 ? r.U[std::size_t(p)][comp] : r.Omega[std::size_t(p)][comp - 3]) / 2.0;
            }
            CU.noalias() += u * u.transpose();
          }
        }
        Cxi /= double(K);
        CU /= double(KU);
        const double z_xi = worst_z(Cxi, Rvv, K), z_u = worst_z(CU, Mvv, KU);
        MESSAGE(c.name << " " << level << ": worst standardised deviation force " << z_xi << ", velocity " << z_u
                       << "; without near field " << worst_z(Cxi, Rvv - Rnf_vv, K));
        CHECK(z_xi < 4.5);
        CHECK(z_u < 4.5);
        // Power: without the near field, or with it alone, the same draws fail.
        CHECK(worst_z(Cxi, Rvv - Rnf_vv, K) > 10.0);
        CHECK(worst_z(Cxi, Rnf_vv + 1e-9 * MatX::Identity(nv, nv), K) > 10.0);
      }
}

TEST_CASE("Brownian force: the dense reference sampler has the same covariance; the same seed gives the same force") {
  const Config c = chain(true, true);
  const Moments m = Moments::FT;
  DenseStokesianDynamics dense(m, 1.0, AmbientFlow{}, lubrication::NearFieldParams{});
  const MatX R = dense.resistance(c.x, c.a, c.domain);
  const std::vector<char> given = force_given_flags(m, 4, c.fixed);
  std::vector<long> v;
  for (long q = 0; q < 24; ++q)
    if (given[std::size_t(q)]) v.push_back(q);
  const MatX Rvv = restrict(R, v);
  const long K = 12000;
  MatX C = MatX::Zero(long(v.size()), long(v.size()));
  for (long k = 0; k < K; ++k) {
    Rng rng = RandomStream::for_purpose(3, Purpose::test, std::uint64_t(k));
    const VecX xi = dense.brownian_force(0.5, 1.0, c.fixed, rng);  // sqrt(2 kT / dt) = 1
    VecX xv(long(v.size()));
    for (std::size_t i = 0; i < v.size(); ++i) xv[long(i)] = xi[v[i]];
    C.noalias() += xv * xv.transpose();
  }
  C /= double(K);
  CHECK(worst_z(C, Rvv, K) < 4.5);
  auto asd = accelerated(c, m, 1e-6);
  asd->prepare({c.x, c.a, c.domain});
  Rng r1 = RandomStream::for_purpose(11, Purpose::brownian, 5), r2 = RandomStream::for_purpose(11, Purpose::brownian, 5);
  const VecX a = asd->brownian_force(1.0, 0.1, c.fixed, r1), b = asd->brownian_force(1.0, 0.1, c.fixed, r2);
  CHECK((a - b).norm() == 0.0);
}

// Long-wave deflation (engine/brownian.hpp, LongWaveDeflation): in periodic boxes the far-field force
// is y = G (G M G)^{-1/2} psi. Reference: G formed column by column, (G M G)^{-1/2} by the dense
// eigendecomposition of the dense Ewald M (ewald/ewald_reference.hpp). Checked: G symmetric (1e-12),
// X X^T = M^{-1} for X = G (G M G)^{-1/2} (relative 1e-8: the covariance is M^{-1} exactly, whatever
// G), the Lanczos path equals X psi (relative 10 tol), and G does not depend on the thread count.
// 64 spheres at phi = 0.4 (3 wave vectors deflated) and 64 lognormal spheres at phi = 0.35 in a box
// at strain 0.3, F, FT, FTS.
TEST_CASE("long-wave deflation of the far-field sampler: covariance M^-1 exactly, symmetric, thread-independent") {
  struct Case {
    const char* name;
    PlacementParams::Sizes sizes;
    double phi, strain;
  };
  for (const Case& cs : {Case{"monodisperse phi 0.4", PlacementParams::Sizes::monodisperse, 0.4, 0.0},
                         Case{"lognormal phi 0.35, strain 0.3", PlacementParams::Sizes::lognormal, 0.35, 0.3}}) {
    PlacementParams pp;
    pp.count = 64;
    pp.sizes = cs.sizes;
    pp.equilibration_sweeps = 20;
    pp.seed = 5;
    const double L = std::cbrt(64.0 * 4.0 / 3.0 * kPi / cs.phi);
    const Placement pl = place_particles(pp, Vec3(L, L, L));
    const Domain dom = Domain::periodic_box(Vec3(L, L, L), cs.strain);
    const Configuration c{pl.position, pl.radius, dom};
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      if (test::kSanitized && m == Moments::FTS) continue;  // 704^2 eigendecomposition at -O0
      CAPTURE(cs.name);
      CAPTURE(to_string(m));
      const LongWaveDeflation G(c, m);
      REQUIRE(G.wave_vectors() > 0);
      ewald::EwaldFarField M(pl.position, pl.radius, 1.0, m, dom);
      const MatX& Md = *M.dense();
      const long n = Md.rows();
      MatX Gd(n, n);
      VecX e = VecX::Zero(n), col;
      for (long j = 0; j < n; ++j) {
        e[j] = 1.0;
        G.apply(e, col);
        Gd.col(j) = col;
        e[j] = 0.0;
      }
      CHECK((Gd - Gd.transpose()).norm() <= 1e-12 * Gd.norm());
      const MatX B = Gd * Md * Gd;
      Eigen::SelfAdjointEigenSolver<MatX> eig(0.5 * (B + B.transpose()));
      REQUIRE(eig.eigenvalues().minCoeff() > 0.0);
      const MatX X = Gd * eig.eigenvectors() * eig.eigenvalues().cwiseInverse().cwiseSqrt().asDiagonal() *
                     eig.eigenvectors().transpose();
      const MatX Minv = Md.llt().solve(MatX::Identity(n, n));
      CHECK((X * X.transpose() - Minv).norm() <= 1e-8 * Minv.norm());
      // The sampler is not the plain M^{-1/2}: G changes the square root, not the covariance.
      Eigen::SelfAdjointEigenSolver<MatX> em(Md);
      const MatX Mis = em.eigenvectors() * em.eigenvalues().cwiseInverse().cwiseSqrt().asDiagonal() *
                       em.eigenvectors().transpose();
      CHECK((X - Mis).norm() > 1e-3 * Mis.norm());
      const double tol = 1e-8;
      for (int r = 0; r < 3; ++r) {
        Rng rng = RandomStream::for_purpose(3, Purpose::test, std::uint64_t(r));
        VecX psi(n), y;
        for (auto& v : psi) v = rng.normal();
        LanczosReport rep;
        REQUIRE(far_field_inverse_sqrt(M, c, psi, y, tol, &rep).converged);
        CHECK(rep.wave_vectors == long(G.wave_vectors()));
        CHECK((y - X * psi).norm() <= 10 * tol * y.norm());
        // Same G on one thread and on every thread (fixed blocks, summed in order).
        VecX g1, g2;
        {
          const test::ThreadCount one(1);
          G.apply(psi, g1);
        }
        {
          const test::ThreadCount several(test::ThreadCount::kSeveral);
          G.apply(psi, g2);
        }
        CHECK((g1 - g2).norm() == 0.0);
      }
    }
  }
}

// Open domains are not deflated; a periodic box with few spheres per wave has nothing to deflate.
TEST_CASE("long-wave deflation: the identity in open domains and dilute boxes") {
  std::vector<Vec3> x{Vec3(0, 0, 0), Vec3(3, 0, 0)};
  std::vector<double> a{1.0, 1.0};
  const Domain open;
  CHECK(LongWaveDeflation({x, a, open}, Moments::FTS).empty());
  const Domain box = Domain::periodic_box(Vec3(10, 10, 10));
  CHECK(LongWaveDeflation({x, a, box}, Moments::FTS).empty());
}
