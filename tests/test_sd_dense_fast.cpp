// The fast dense SD path (engine/sd_dense.cpp: LAPACK Cholesky of the reordered far field, only
// the force/torque block of M_inf^{-1} formed, R_vv factored per fixed set; the closed-form blocks
// of assemble_mobility) against plain references written here: the explicit-tensor far field
// (dense_mobility / the Ewald sum), its full inverse by Eigen, plus the dense near field, and the
// mobility problem solved directly on R_vv. Sweep: F, FT, FTS; open and periodic; with and
// without fixed particles; polydisperse radii with close pairs; N = 2 ... 100.
#include <doctest/doctest.h>

#include "engine/core/layout.hpp"
#include "engine/kernels/far_field.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "engine/sd_dense.hpp"
#include "ewald/ewald_reference.hpp"
#include "lubrication/near_field.hpp"
#include "support/sanitizer.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

using namespace stokesian;

namespace {

// n spheres, radii uniform in [0.6, 1.4], placed one by one at uniform random points of a cube of
// side L (periodic: minimum image) with surface gaps >= 0.02: dense enough that most spheres have
// a neighbour inside the lubrication cutoff.
struct Cloud {
  std::vector<Vec3> x;
  std::vector<double> a;
};
Cloud cloud(long n, double L, const Domain& dom, unsigned seed) {
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c;
  while (long(c.x.size()) < n) {
    const double ai = 0.6 + 0.8 * u(g);
    const Vec3 xi(L * u(g), L * u(g), L * u(g));
    bool ok = true;
    for (std::size_t j = 0; j < c.x.size() && ok; ++j)
      ok = dom.minimum_image(xi - c.x[j]).norm() >= ai + c.a[j] + 0.02;
    if (ok) {
      c.x.push_back(xi);
      c.a.push_back(ai);
    }
  }
  return c;
}

// Unit-variance random forces and torques on n particles, from generator g.
struct Loads {
  std::vector<Vec3> F, T;
};
Loads random_loads(long n, std::mt19937_64& g) {
  std::normal_distribution<double> nd;
  Loads l{std::vector<Vec3>(static_cast<std::size_t>(n)), std::vector<Vec3>(static_cast<std::size_t>(n))};
  for (std::size_t i = 0; i < l.F.size(); ++i) {
    l.F[i] = Vec3(nd(g), nd(g), nd(g));
    l.T[i] = Vec3(nd(g), nd(g), nd(g));
  }
  return l;
}

// Plain reference: R = M^{-1} + R_nf (M from the explicit tensors, inverted by Eigen's LLT),
// then R_vv V = f_v - R_vk V_k solved by Eigen's LLT and the moments R [V; V_k].
struct Reference {
  MatX R;
  HydroResult res;
};
Reference reference(const Cloud& c, const Domain& dom, Moments m, const AmbientFlow& flow, const std::vector<char>& fixed,
                    const std::vector<Vec3>& F, const std::vector<Vec3>& T) {
  const MatX M = dom.periodic() ? ewald::ewald_mobility(c.x, c.a, 1.0, m, dom) : dense_mobility(c.x, c.a, 1.0, m);
  Eigen::LLT<MatX> llt(M);
  REQUIRE(llt.info() == Eigen::Success);
  Reference ref;
  ref.R = llt.solve(MatX::Identity(M.rows(), M.cols()));
  ref.R += MatX(lubrication::NearField(m, 1.0).assemble(c.x, c.a, dom));
  ref.R = (0.5 * (ref.R + ref.R.transpose())).eval();
  FlowSample fs;
  flow.sample(c.x, fs);
  const RigidConstraints rc = RigidConstraints::of(m, fixed, F, T, fs);
  const auto& v = rc.force_given;
  const long nv = long(v.size());
  MatX Rvv(nv, nv);
  VecX rhs(nv);
  for (long i = 0; i < nv; ++i) {
    rhs[i] = rc.force[v[std::size_t(i)]] - ref.R.row(v[std::size_t(i)]).dot(rc.motion);
    for (long j = 0; j < nv; ++j) Rvv(i, j) = ref.R(v[std::size_t(i)], v[std::size_t(j)]);
  }
  const VecX V = Rvv.llt().solve(rhs);
  VecX gen = rc.motion;
  for (long i = 0; i < nv; ++i) gen[v[std::size_t(i)]] = V[i];
  ref.res = unpack_solution(m, fs, gen, ref.R * gen, fixed);
  return ref;
}

template <class V>
double rel(const std::vector<V>& a, const std::vector<V>& b) {
  REQUIRE(a.size() == b.size());
  double num = 0, den = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    num += (a[i] - b[i]).squaredNorm();
    den += b[i].squaredNorm();
  }
  return den > 0 ? std::sqrt(num / den) : std::sqrt(num);
}

}  // namespace

TEST_CASE("closed-form pair blocks equal the explicit tensor contraction (separate, overlapping, nested)") {
  std::mt19937_64 g(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int t = 0; t < 300; ++t) {
    Vec3 e(u(g), u(g), u(g));
    e.normalize();
    const double a = 1.0 + 0.9 * u(g), b = 1.0 + 0.9 * u(g);
    const double r = t % 3 == 0 ? (a + b) * (1.0 + 2.0 * std::abs(u(g)))          // separate
                     : t % 3 == 1 ? std::abs(a - b) + (a + b - std::abs(a - b)) * std::abs(u(g))  // overlapping
                                  : std::abs(a - b) * std::abs(u(g));                  // nested
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      const mobility::PairScalars s = mobility::pair_scalars(a, b, r, 1.3, m);
      const MatX ref = mobility::pair_block(s, e, m);
      const int d = dof_per_particle(m);
      MatX B = MatX::Constant(d + 2, d, 7.0);  // leading dimension d + 2: rows d, d+1 untouched
      mobility::fill_pair_block(s, e, m, B.data(), d + 2);
      CAPTURE(t);
      CHECK((B.topRows(d) - ref).norm() <= 1e-14 * ref.norm());
      CHECK((B.bottomRows(2).array() == 7.0).all());
    }
  }
}

TEST_CASE("assemble_mobility equals the explicit-tensor dense_mobility and is symmetric") {
  const Cloud c = cloud(40, 6.0, Domain{}, 3);
  std::vector<Vec3> x = c.x;
  x[1] = x[0] + Vec3(0.3, 0.1, 0.0);  // an overlapping pair
  x[2] = x[3];                        // coincident centres
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    const MatX ref = dense_mobility(x, c.a, 0.7, m);
    const MatX M = assemble_mobility(x, c.a, 0.7, m);
    CHECK((M - ref).norm() <= 1e-14 * ref.norm());
    CHECK((M - M.transpose()).norm() <= 1e-14 * M.norm());
  }
}

TEST_CASE("dense SD fast path equals the plain M^-1 + R_nf reference (F/FT/FTS, open/periodic, fixed, N 2-100)") {
  Domain box;
  box.kind = Domain::Kind::periodic;
  box.shear_strain = 0.1;
  AmbientFlow shear;  // simple shear plus a rotation: E_inf and Omega_inf both nonzero
  shear.E(0, 1) = shear.E(1, 0) = 0.35;
  shear.Omega = Vec3(0.1, 0.0, -0.35);
  int seed = 0;
  for (const bool periodic : {false, true}) {
    const std::vector<long> sizes = periodic ? std::vector<long>{2, 8, 30} : std::vector<long>{2, 5, 17, 45, 100};
    for (long n : sizes) {
      // Volume fraction about 0.15 (open) / 0.2 (periodic boxes: 0.07 at N = 30): many pairs inside the cutoff.
      // Periodic boxes at least 12.5 a: the near-field pair list needs the cutoff range below half an edge.
      const double L = std::max(periodic ? 12.5 : 0.0, std::cbrt(double(n) * 4.6 / (periodic ? 0.2 : 0.15)));
      box.box = Vec3(L, 1.1 * L, 0.95 * L);
      const Domain dom = periodic ? box : Domain{};
      const Cloud c = cloud(n, L, dom, unsigned(100 + seed++));
      std::mt19937_64 g{static_cast<unsigned>(seed)};
      const auto [F, T] = random_loads(n, g);
      for (const bool with_fixed : {false, true}) {
        std::vector<char> fixed;
        if (with_fixed) {
          fixed.assign(std::size_t(n), 0);
          for (long i = 0; i < n; i += 3) fixed[std::size_t(i)] = 1;
        }
        for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
          CAPTURE(periodic);
          CAPTURE(n);
          CAPTURE(with_fixed);
          CAPTURE(dof_per_particle(m));
          const Reference ref = reference(c, dom, m, shear, fixed, F, T);
          DenseStokesianDynamics sd(m, 1.0, shear);
          lubrication::NearFieldStats stats;
          const HydroResult r = sd.mobility_problem(c.x, c.a, fixed, F, T, dom, &stats);
          if (n >= 17) CHECK(stats.pairs > 0);
          CHECK(rel(r.U, ref.res.U) < 1e-10);
          CHECK(rel(r.F, ref.res.F) < 1e-10);
          if (m != Moments::F) {
            CHECK(rel(r.Omega, ref.res.Omega) < 1e-10);
            CHECK(rel(r.T, ref.res.T) < 1e-10);
          }
          if (m == Moments::FTS) CHECK(rel(r.S, ref.res.S) < 1e-10);
          // The lazily formed full R of the prepared configuration.
          CHECK((sd.resistance() - ref.R).norm() <= 1e-10 * ref.R.norm());
          // A second solve at the same configuration reuses the factor of R_vv; with the other
          // fixed set it must refactor.
          const HydroResult again = sd.mobility_problem(c.x, c.a, fixed, F, T, dom);
          CHECK(rel(again.U, r.U) == 0.0);
        }
      }
    }
  }
}

TEST_CASE("dense SD: a second solve with another fixed set refactors R_vv") {
  const Domain open;
  const Cloud c = cloud(20, 5.5, open, 9);
  std::vector<Vec3> F(20, Vec3(0, 0, -1)), T(20, Vec3::Zero());
  std::vector<char> none, some(20, 0);
  some[4] = some[11] = 1;
  for (Moments m : {Moments::FT, Moments::FTS}) {
    DenseStokesianDynamics sd(m, 1.0, AmbientFlow{});
    const Configuration cfg{c.x, c.a, open};
    sd.prepare(cfg);
    FlowSample fs;
    AmbientFlow{}.sample(c.x, fs);
    const HydroResult a = sd.solve(HydroProblem{cfg, none, fs, F, T});
    const HydroResult b = sd.solve(HydroProblem{cfg, some, fs, F, T});
    const HydroResult a2 = sd.solve(HydroProblem{cfg, none, fs, F, T});
    CHECK(rel(a.U, reference(c, open, m, AmbientFlow{}, none, F, T).res.U) < 1e-10);
    CHECK(rel(b.U, reference(c, open, m, AmbientFlow{}, some, F, T).res.U) < 1e-10);
    CHECK(b.U[4].norm() == 0.0);
    CHECK(rel(a2.U, a.U) == 0.0);
  }
}

// Held particles eliminated by the Schur complement (engine/sd_dense.hpp): the solve, with loads,
// an ambient flow, a force noise and a slip, equals the full factorisation (set_held_blocks(false),
// the reference twin) and the plain reference above, to 1e-10 relative; held fractions from a
// quarter to all of them; open, periodic and sheared periodic; F, FT, FTS. The held block's factor
// is kept while the held particles stay put (mobile ones moved: reused, same answers as a fresh
// solver) and refactored when one moves. Under AddressSanitizer (-O0) 16 spheres and two fractions.
TEST_CASE("dense SD: held particles by the Schur complement equal the full factorisation") {
  AmbientFlow shear;
  shear.E(0, 1) = shear.E(1, 0) = 0.35;
  shear.Omega = Vec3(0.0, 0.0, -0.35);
  int seed = 0;
  for (int geometry = 0; geometry < 3; ++geometry) {
    Domain dom;
    const long n = test::kSanitized ? 16 : geometry == 0 ? 60 : 40;
    const double L = geometry == 0 ? std::cbrt(double(n) * 4.6 / 0.15) : 12.5;
    if (geometry > 0) {
      dom.kind = Domain::Kind::periodic;
      dom.box = Vec3(L, 1.1 * L, 0.95 * L);
      dom.shear_strain = geometry == 2 ? 0.1 : 0.0;
    }
    const Cloud c = cloud(n, L, dom, unsigned(300 + seed++));
    std::mt19937_64 g{static_cast<unsigned>(seed)};
    std::normal_distribution<double> nd;  // noise and slip below
    const auto [F, T] = random_loads(n, g);
    for (const double fraction : test::kSanitized ? std::vector<double>{0.5, 1.0} : std::vector<double>{0.25, 0.5, 0.9, 1.0}) {
      std::vector<char> fixed(static_cast<std::size_t>(n), 0);
      for (long i = 0; i < n; ++i) fixed[std::size_t(i)] = (double(i) + 0.5) / double(n) < fraction ? 1 : 0;
      std::shuffle(fixed.begin(), fixed.end(), g);
      for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
        CAPTURE(geometry);
        CAPTURE(fraction);
        CAPTURE(dof_per_particle(m));
        const long dn = n * dof_per_particle(m);
        VecX noise(dn), slip(dn);
        for (long q = 0; q < dn; ++q) noise[q] = nd(g), slip[q] = 0.1 * nd(g);
        const Configuration cfg{c.x, c.a, dom};
        FlowSample fs;
        shear.sample(c.x, fs);
        DenseStokesianDynamics blocks(m, 1.0, shear), full(m, 1.0, shear);
        full.set_held_blocks(false);
        blocks.prepare(cfg);
        full.prepare(cfg);
        const HydroResult a = blocks.solve(HydroProblem{cfg, fixed, fs, F, T, &noise, &slip});
        const HydroResult b = full.solve(HydroProblem{cfg, fixed, fs, F, T, &noise, &slip});
        CHECK(!blocks.reused_held_factor());
        CHECK(rel(a.U, b.U) < 1e-10);
        CHECK(rel(a.F, b.F) < 1e-10);
        if (m != Moments::F) CHECK(rel(a.Omega, b.Omega) < 1e-10);
        if (m == Moments::FTS) CHECK(rel(a.S, b.S) < 1e-10);
        const Reference ref = reference(c, dom, m, shear, fixed, F, T);
        const HydroResult plain = blocks.solve(HydroProblem{cfg, fixed, fs, F, T});
        CHECK(rel(plain.U, ref.res.U) < 1e-10);
        CHECK(rel(plain.F, ref.res.F) < 1e-10);
        if (m == Moments::FTS) CHECK(rel(plain.S, ref.res.S) < 1e-10);
        for (long i = 0; i < n; ++i)
          if (fixed[std::size_t(i)]) CHECK(a.U[std::size_t(i)].norm() == 0.0);

        // Mobile particles moved (the held ones stay): the held factor is reused.
        Cloud moved = c;
        for (long i = 0; i < n; ++i)
          if (!fixed[std::size_t(i)]) moved.x[std::size_t(i)] += Vec3(0.004, -0.003, 0.002);
        const Configuration cfg2{moved.x, moved.a, dom};
        shear.sample(moved.x, fs);
        blocks.prepare(cfg2);
        const HydroResult r2 = blocks.solve(HydroProblem{cfg2, fixed, fs, F, T});
        CHECK(blocks.reused_held_factor());
        const Reference ref2 = reference(moved, dom, m, shear, fixed, F, T);
        CHECK(rel(r2.U, ref2.res.U) < 1e-10);
        CHECK(rel(r2.F, ref2.res.F) < 1e-10);
        // A held particle moved: refactored, and still right.
        const auto h = std::find(fixed.begin(), fixed.end(), char(1)) - fixed.begin();
        moved.x[std::size_t(h)] += Vec3(0.0, 0.0, 1e-3);
        const Configuration cfg3{moved.x, moved.a, dom};
        shear.sample(moved.x, fs);
        blocks.prepare(cfg3);
        const HydroResult r3 = blocks.solve(HydroProblem{cfg3, fixed, fs, F, T});
        CHECK(!blocks.reused_held_factor());
        const Reference ref3 = reference(moved, dom, m, shear, fixed, F, T);
        CHECK(rel(r3.F, ref3.res.F) < 1e-10);
      }
    }
  }
}

// MobilityOperator::dense_rows (the held path's mobile rows) against the rows of dense(): the
// direct sum and the Ewald sum (unsheared and at strain 0.2), F/FT/FTS, a few rows, all rows and
// none; within 1e-13 of the matrix's largest entry.
TEST_CASE("dense far fields: dense_rows equals those rows of dense()") {
  for (int geometry = 0; geometry < 3; ++geometry) {
    Domain dom;
    const long n = 24;
    const double L = 10.0;
    if (geometry > 0) {
      dom.kind = Domain::Kind::periodic;
      dom.box = Vec3(L, 1.2 * L, 0.9 * L);
      dom.shear_strain = geometry == 2 ? 0.2 : 0.0;
    }
    const Cloud c = cloud(n, L, dom, unsigned(77 + geometry));
    for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
      CAPTURE(geometry);
      CAPTURE(dof_per_particle(m));
      const MobilitySpec spec{m, 1.0, 1e-6};
      std::unique_ptr<MobilityOperator> op;
      if (geometry == 0) op = std::make_unique<DirectFarField>(spec);
      else op = std::make_unique<ewald::EwaldFarField>(spec);
      op->set_configuration({c.x, c.a, dom});
      const int d = dof_per_particle(m);
      for (const std::vector<long>& rows : {std::vector<long>{3}, std::vector<long>{0, 5, 6, 17, 23},
                                            std::vector<long>{}}) {
        MatX R;
        REQUIRE(op->dense_rows(rows, R));
        const MatX& M = *op->dense();
        REQUIRE(R.rows() == long(rows.size()) * d);
        REQUIRE(R.cols() == M.cols());
        for (std::size_t k = 0; k < rows.size(); ++k)
          CHECK((R.middleRows(long(k) * d, d) - M.middleRows(rows[k] * d, d)).cwiseAbs().maxCoeff() <=
                1e-13 * M.cwiseAbs().maxCoeff());
      }
      std::vector<long> all(static_cast<std::size_t>(n));
      for (long i = 0; i < n; ++i) all[std::size_t(i)] = i;
      MatX R;
      REQUIRE(op->dense_rows(all, R));
      CHECK((R - *op->dense()).cwiseAbs().maxCoeff() <= 1e-13 * op->dense()->cwiseAbs().maxCoeff());
    }
  }
}
