// Fast real-space Ewald sum (ewald/real_space.hpp) against a plain reference written here: pairs from
// trees::neighbor_pairs, exact ewald::real_scalars per pair, mobility::apply_pair, plus
// ewald::self_correction (what PmeFarField::apply_real computes). xi and cutoff_gap come from
// ewald::pme_parameters for each tolerance.
//
// Error metric: rel_error(y, y_ref) = ||y - y_ref|| / ||y_ref|| for y = M x on a random Gaussian x.
// Required: rel_error <= 1e-3 tol (the tables are built to 1e-4 tol per scalar, real_space.hpp).
#include <doctest/doctest.h>

#include "support/random.hpp"

#include "engine/kernels/mobility_pair.hpp"
#include "ewald/ewald_split.hpp"
#include "ewald/lattice.hpp"
#include "ewald/pme_parameters.hpp"
#include "ewald/real_space.hpp"
#include "trees/neighbor_list.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <random>
#include <string>

using namespace stokesian;
using stokesian::test::random_vector;

namespace {

Domain box(const Vec3& L, double strain) {
  Domain d;
  d.kind = Domain::Kind::periodic;
  d.box = L;
  d.shear_strain = strain;
  return d;
}

struct Case {
  std::string name;
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain domain;
};

// Uniform random centres (overlaps allowed, so overlapping and nested pairs occur) and radii
// uniform in [amin, amax]; the box edge ratio `shape` and volume fraction phi set L.
Case make_case(const std::string& name, int n, double phi, double amin, double amax, const Vec3& shape,
               double strain, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Case c;
  c.name = name;
  double vol = 0.0;
  for (int i = 0; i < n; ++i) {
    c.a.push_back(amin + (amax - amin) * u(rng));
    vol += 4.0 / 3.0 * kPi * std::pow(c.a.back(), 3);
  }
  const double s = std::cbrt(vol / phi / (shape.x() * shape.y() * shape.z()));
  const Vec3 L = s * shape;
  for (int i = 0; i < n; ++i) c.x.emplace_back(L.x() * u(rng), L.y() * u(rng), L.z() * u(rng));
  c.domain = box(L, strain);
  return c;
}

// The plain reference: y = sum over neighbor_pairs of real_scalars blocks + self_correction.
VecX reference(const Case& c, double gap, double xi, double mu, Moments m, const VecX& in) {
  const int d = dof_per_particle(m);
  const long n = long(c.x.size());
  VecX out = VecX::Zero(n * d);
  for (long i = 0; i < n; ++i) {
    const mobility::PairScalars s = ewald::self_correction(c.a[i], xi, mu);
    for (int k = 0; k < 3; ++k) out[i * d + k] += s.xa * in[i * d + k];
    for (int k = 3; k < std::min(d, 6); ++k) out[i * d + k] += s.xc * in[i * d + k];
    for (int k = 6; k < d; ++k) out[i * d + k] += s.xm * in[i * d + k];
  }
  for (const trees::NeighborPair& p : trees::neighbor_pairs(c.x, c.a, c.domain, gap)) {
    const Vec3 e = p.dist > 0.0 ? Vec3(p.r / p.dist) : Vec3::UnitZ();
    mobility::apply_pair(ewald::real_scalars(c.a[p.i], c.a[p.j], p.dist, xi, mu, m), e, m, in.data() + p.j * d,
                         out.data() + p.i * d);
    mobility::apply_pair(ewald::real_scalars(c.a[p.j], c.a[p.i], p.dist, xi, mu, m), Vec3(-e), m,
                         in.data() + p.i * d, out.data() + p.j * d);
  }
  return out;
}

// About 60 particles inside the cutoff sphere: a typical PME balance, and a cutoff well inside half
// the box for these sizes (the automatic choice may sit at the cap 0.5 L - 2 a_max, where
// cutoff_gap + 2 a_max can exceed L / 2 by one rounding and the minimum-image check rejects it).
ewald::PmeOptions options() {
  ewald::PmeOptions o;
  o.neighbours = 60.0;
  return o;
}

std::vector<Case> cases() {
  return {make_case("mono phi 0.1", 600, 0.1, 1.0, 1.0, Vec3(1, 1, 1), 0.0, 1),
          make_case("mono phi 0.45", 500, 0.45, 1.0, 1.0, Vec3(1, 1, 1), 0.0, 2),
          make_case("poly ratio 10", 500, 0.15, 0.2, 2.0, Vec3(1, 1, 1), 0.0, 3),
          make_case("mono LE 0.3", 500, 0.2, 1.0, 1.0, Vec3(1.2, 1.0, 0.9), 0.3, 4),
          make_case("poly ratio 4 LE 0.5", 500, 0.3, 0.5, 2.0, Vec3(1.0, 1.1, 1.0), 0.5, 5)};
}

}  // namespace

TEST_CASE("real space: fast sum equals the plain reference (tol 1e-3, 1e-6, 1e-10; F, FT, FTS)") {
  const double mu = 0.7;
  for (const Case& c : cases()) {
    const ewald::Lattice lat = ewald::Lattice::from_domain(c.domain);
    const auto [amin, amax] = std::minmax_element(c.a.begin(), c.a.end());
    for (double tol : {1e-3, 1e-6, 1e-10})
      for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
        const ewald::PmeParameters p = ewald::pme_parameters(tol, lat, int(c.x.size()), *amin, *amax, m, options());
        const ewald::RealSpaceSum fast(c.x, c.a, c.domain, p.cutoff_gap, p.xi, mu, m, tol);
        const VecX in = random_vector(fast.size(), 11);
        VecX y;
        fast.apply(in, y);
        const VecX ref = reference(c, p.cutoff_gap, p.xi, mu, m, in);
        const double err = (y - ref).norm() / ref.norm();
        const std::size_t npairs = trees::neighbor_pairs(c.x, c.a, c.domain, p.cutoff_gap).size();
        std::printf("%-20s tol %.0e %-3s pairs %7zu (overlap %5zu) intervals %4d table %.1e rel.err %.2e\n",
                    c.name.c_str(), tol, to_string(m), fast.pairs(), fast.overlapping_pairs(), fast.table_intervals(),
                    fast.table_error(), err);
        CAPTURE(c.name);
        CAPTURE(tol);
        CAPTURE(to_string(m));
        CHECK(fast.pairs() == npairs);
        CHECK(fast.direct_tables() == (*amin == *amax));  // the poly cases have 500 distinct radii
        CHECK(fast.table_error() <= fast.table_target());
        CHECK(err <= 1e-3 * tol);
      }
  }
}

// Radii drawn from `values` (each sphere uniformly), other fields as make_case.
Case with_radii(Case c, const std::vector<double>& values, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
  for (double& a : c.a) a = values[pick(rng)];
  return c;
}

// A few distinct radii (at most 4) read the pair scalars from tables per pair of radii
// (real_space.hpp). Two references: the general tables (their twin, built to the same per-scalar
// bound: products agree to 1e-3 tol from tol 1e-2 to 1e-12; below 1e-11 the tables stop at their
// floor of 2e-14 per scalar, so the bound is then 1e-14) and the plain pair sum of this file with
// the exact real_scalars (1e-3 tol, down to 1e-10, as the first test). Open cube and sheared box,
// cached and uncached.
TEST_CASE("real space: the per-radius-class tables agree with the general ones (tol 1e-2 ... 1e-12; F, FT, FTS)") {
  const double mu = 1.3;
  for (const Case& c : {make_case("mono phi 0.3", 400, 0.3, 1.0, 1.0, Vec3(1, 1, 1), 0.0, 21),
                        make_case("mono a 0.5 LE 0.4", 400, 0.15, 0.5, 0.5, Vec3(1.1, 1.0, 0.9), 0.4, 22),
                        with_radii(make_case("bi 1 : 2.5", 400, 0.08, 1.0, 1.0, Vec3(1, 1, 1), 0.0, 23), {1.0, 2.5}, 24),
                        with_radii(make_case("four radii LE 0.3", 400, 0.06, 1.0, 1.0, Vec3(1, 1.2, 1), 0.3, 25),
                                   {0.4, 1.0, 1.7, 3.0}, 26)}) {
    const ewald::Lattice lat = ewald::Lattice::from_domain(c.domain);
    const auto [amin, amax] = std::minmax_element(c.a.begin(), c.a.end());
    for (double tol : {1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12})
      for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
        // 60 neighbours force xi near 1 / a: at 1e-12 with radii 1 and 2.5 (FT) no window of at most 32
        // points meets the aliasing-and-edge model there; the free search's parameters are used instead.
        ewald::PmeParameters p;
        try {
          p = ewald::pme_parameters(tol, lat, int(c.x.size()), *amin, *amax, m, options());
        } catch (const std::invalid_argument&) {
          p = ewald::pme_parameters(tol, lat, int(c.x.size()), *amin, *amax, m);
        }
        const VecX in = random_vector(long(c.x.size()) * dof_per_particle(m), 17);
        ewald::RealSpaceSum::force_general_tables(true);
        const ewald::RealSpaceSum general(c.x, c.a, c.domain, p.cutoff_gap, p.xi, mu, m, tol, 0);
        ewald::RealSpaceSum::force_general_tables(false);
        const ewald::RealSpaceSum direct(c.x, c.a, c.domain, p.cutoff_gap, p.xi, mu, m, tol, 0);
        const ewald::RealSpaceSum direct_cached(c.x, c.a, c.domain, p.cutoff_gap, p.xi, mu, m, tol);
        VecX yg, yd, yc;
        general.apply(in, yg);
        direct.apply(in, yd);
        direct_cached.apply(in, yc);
        const double diff = (yd - yg).norm() / yg.norm();
        std::printf("%-18s tol %.0e %-3s intervals %5d / %5d (per class / general), table %.1e / %.1e, |diff| %.1e\n",
                    c.name.c_str(), tol, to_string(m), direct.table_intervals(), general.table_intervals(),
                    direct.table_error(), general.table_error(), diff);
        CAPTURE(c.name);
        CAPTURE(tol);
        CAPTURE(to_string(m));
        CHECK(direct.direct_tables());
        CHECK(!general.direct_tables());
        CHECK(direct_cached.cached());
        CHECK(direct.table_error() <= direct.table_target());
        CHECK(diff <= std::max(1e-3 * tol, 1e-14));
        CHECK((yc - yd).norm() <= 1e-14 * yd.norm());
        // And against the plain reference (exact real_scalars per pair), the contract of the first
        // test, down to 1e-10.
        if (tol >= 1e-10) {
          const VecX ref = reference(c, p.cutoff_gap, p.xi, mu, m, in);
          CHECK((yd - ref).norm() / ref.norm() <= 1e-3 * tol);
        }
      }
  }
}

TEST_CASE("real space: bitwise independent of the thread count and of the scalar cache; update_positions equals a new build") {
  for (const Case& c : {make_case("poly LE", 800, 0.3, 0.3, 1.5, Vec3(1.0, 1.0, 1.2), 0.37, 9),
                        make_case("mono LE", 800, 0.3, 1.0, 1.0, Vec3(1.0, 1.0, 1.2), 0.37, 10),
                        with_radii(make_case("bi LE", 800, 0.3, 1.0, 1.0, Vec3(1.0, 1.0, 1.2), 0.37, 11), {0.6, 1.4}, 12)}) {
  CAPTURE(c.name);
  const ewald::Lattice lat = ewald::Lattice::from_domain(c.domain);
  const double tol = 1e-6;
  const auto [amin, amax] = std::minmax_element(c.a.begin(), c.a.end());
  for (Moments m : {Moments::F, Moments::FTS}) {
    const ewald::PmeParameters p = ewald::pme_parameters(tol, lat, int(c.x.size()), *amin, *amax, m, options());
    const VecX in = random_vector(long(c.x.size()) * dof_per_particle(m), 5);
    const int saved = omp_get_max_threads();
    omp_set_num_threads(1);
    const ewald::RealSpaceSum one(c.x, c.a, c.domain, p.cutoff_gap, p.xi, 1.0, m, tol);
    VecX y1;
    one.apply(in, y1);
    omp_set_num_threads(2);
    const ewald::RealSpaceSum two(c.x, c.a, c.domain, p.cutoff_gap, p.xi, 1.0, m, tol);
    VecX y2;
    two.apply(in, y2);
    VecX y21;
    one.apply(in, y21);  // object built on 1 thread, applied on 2
    // Without the per-entry scalar cache (tables evaluated in the product): equal to rounding
    // (fused multiply-adds may differ), and bitwise independent of the thread count as well.
    const ewald::RealSpaceSum uncached(c.x, c.a, c.domain, p.cutoff_gap, p.xi, 1.0, m, tol, 0);
    VecX y3, y31;
    uncached.apply(in, y3);
    omp_set_num_threads(1);
    uncached.apply(in, y31);
    CHECK(one.cached());
    CHECK(!uncached.cached());
    CHECK((y3 - y1).norm() <= 1e-14 * y1.norm());
    CHECK((y3.array() == y31.array()).all());
    // The baseline (non-AVX2) kernels give the same product to rounding, cached or not.
    ewald::RealSpaceSum::force_baseline_kernels(true);
    const ewald::RealSpaceSum base(c.x, c.a, c.domain, p.cutoff_gap, p.xi, 1.0, m, tol);
    VecX y4, y5;
    base.apply(in, y4);
    uncached.apply(in, y5);
    ewald::RealSpaceSum::force_baseline_kernels(false);
    CHECK((y4 - y1).norm() <= 1e-14 * y1.norm());
    CHECK((y5 - y1).norm() <= 1e-14 * y1.norm());
    omp_set_num_threads(saved);
    CHECK(y1.size() == y2.size());
    CHECK((y1.array() == y2.array()).all());
    CHECK((y1.array() == y21.array()).all());

    // Moved positions, some outside the primary box: update equals a fresh build, bitwise.
    std::mt19937_64 rng(3);
    std::normal_distribution<double> g(0.0, 0.8);
    std::vector<Vec3> x2 = c.x;
    for (Vec3& v : x2) v += Vec3(g(rng), g(rng), g(rng));
    ewald::RealSpaceSum moved(c.x, c.a, c.domain, p.cutoff_gap, p.xi, 1.0, m, tol);
    moved.update_positions(x2);
    const ewald::RealSpaceSum fresh(x2, c.a, c.domain, p.cutoff_gap, p.xi, 1.0, m, tol);
    VecX ya, yb;
    moved.apply(in, ya);
    fresh.apply(in, yb);
    CHECK(moved.pairs() == fresh.pairs());
    CHECK((ya.array() == yb.array()).all());
    // And both equal the reference at the new positions.
    Case c2 = c;
    c2.x = x2;
    const VecX ref = reference(c2, p.cutoff_gap, p.xi, 1.0, m, in);
    CHECK((ya - ref).norm() / ref.norm() <= 1e-3 * tol);

    // A new strain (Lees-Edwards step), same box: update equals a fresh build, bitwise.
    c2.domain = c.domain.strained_by(0.21);
    moved.update_positions(x2, c2.domain);
    const ewald::RealSpaceSum sheared(x2, c.a, c2.domain, p.cutoff_gap, p.xi, 1.0, m, tol);
    VecX yc, yd;
    moved.apply(in, yc);
    sheared.apply(in, yd);
    CHECK((yc.array() == yd.array()).all());
    const VecX ref2 = reference(c2, p.cutoff_gap, p.xi, 1.0, m, in);
    CHECK((yc - ref2).norm() / ref2.norm() <= 1e-3 * tol);
    Domain other = c.domain;
    other.box.x() *= 1.01;
    CHECK_THROWS_AS(moved.update_positions(x2, other), std::invalid_argument);
  }
  }
}

TEST_CASE("real space: bad input is rejected") {
  const Case c = make_case("small", 50, 0.1, 1.0, 1.0, Vec3(1, 1, 1), 0.0, 7);
  const double L = c.domain.box.x();
  // Interaction range above half the box: the minimum-image pair list cannot represent it.
  CHECK_THROWS_AS(ewald::RealSpaceSum(c.x, c.a, c.domain, 0.5 * L, 1.0, 1.0, Moments::F, 1e-6), std::invalid_argument);
  CHECK_THROWS_AS(ewald::RealSpaceSum(c.x, c.a, Domain{}, 1.0, 1.0, 1.0, Moments::F, 1e-6), std::invalid_argument);
  CHECK_THROWS_AS(ewald::RealSpaceSum(c.x, c.a, c.domain, 1.0, 1.0, 1.0, Moments::F, 0.5), std::invalid_argument);
  CHECK_THROWS_AS(ewald::RealSpaceSum(c.x, c.a, c.domain, -1.0, 1.0, 1.0, Moments::F, 1e-6), std::invalid_argument);
  ewald::RealSpaceSum ok(c.x, c.a, c.domain, 1.0, 1.0, 1.0, Moments::F, 1e-6);
  CHECK_THROWS_AS(ok.update_positions(std::vector<Vec3>(3)), std::invalid_argument);
  VecX y;
  CHECK_THROWS_AS(ok.apply(VecX::Zero(7), y), std::invalid_argument);
  const ewald::RealSpaceSum empty;
  empty.apply(VecX(), y);
  CHECK(y.size() == 0);
}
