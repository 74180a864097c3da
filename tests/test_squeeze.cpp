// The thesis's squeeze lubrication (lubrication/squeeze.hpp, docs/lubrication.md section 8).
// References: the exact two-sphere resistance of Jeffrey & Onishi (lubrication/resistance_functions,
// from the series), whose squeeze singularity the no-slip form reproduces without the thesis's k1;
// the asymptotes of the slip form (Hocking's limit for h >> d and the logarithm for h << d), derived
// by hand; the k1, k2 fits as printed in the thesis (eqs. 5.5, 5.7).
#include <doctest/doctest.h>

#include "engine/core/errors.hpp"
#include "engine/core/sym_traceless.hpp"
#include "io/scene_toml.hpp"
#include "lubrication/near_field.hpp"
#include "lubrication/resistance_functions.hpp"
#include "lubrication/squeeze.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <cmath>
#include <string>

using namespace stokesian;
using namespace stokesian::lubrication;

namespace {
// The thesis's fits with natural logarithms.
double k1(double h, double ar) {
  const double L = std::log(h / (2 * ar));
  return 1.041 - 0.281 * L - 0.0351 * L * L;
}
double k2(double h, double ar) {
  const double L = std::log(h / (2 * ar));
  return 1.309 - 0.082 * L - 0.009 * L * L;
}
}  // namespace

TEST_CASE("squeeze: the no-slip form without k1 is the squeeze singularity of the exact two-sphere resistance") {
  // -n.R_ij.n of the exact pair (force on i from the motion of j along n) ~ 6 pi mu a_r^2 / h as h -> 0.
  for (double lambda : {1.0, 0.5, 0.1, 2.0}) {
    const double ai = 1.0, aj = lambda, ar = ai * aj / (ai + aj);
    double last = 1e300;
    for (double h : {1e-2, 1e-3, 1e-4}) {  // k1 (ln) > 0 here; it turns negative below h/(2 a_r) ~ 2e-5
      const PairMatrix R = two_sphere_resistance(Vec3(ai + aj + h, 0, 0), ai, aj, 1.0);
      const double exact = -R(0, 11);
      const double model = squeeze_no_slip(h, ar, 1.0) / k1(h, ar);
      const double err = std::abs(model / exact - 1.0);
      CAPTURE(lambda);
      CAPTURE(h);
      CAPTURE(exact);
      CAPTURE(model);
      CHECK(err < last);  // converges as the gap closes
      if (h <= 1e-4) CHECK(err < 5e-3);
      last = err;
    }
  }
}

TEST_CASE("squeeze: the slip form tends to the no-slip form for h >> d and to its logarithm for h << d") {
  const double ar = 0.5, mu = 1.0;
  // Hocking: c_sl/k2 = c_ns/k1 (1 + O(d/h)).
  for (double h : {1e-2, 0.1, 1.0}) {
    const double d = 1e-6;
    CHECK(squeeze_slip(h, ar, mu, d) / k2(h, ar) == doctest::Approx(squeeze_no_slip(h, ar, mu) / k1(h, ar)).epsilon(1e-3));
  }
  // h << d: (h + 6d) ln((h + 6d)/h) - (2a_r + 6d) ln(1 + 6d/2a_r) -> 6d (ln(6d/h) - 1) + O(d^2/a_r),
  // so c_sl/k2 -> (2 pi mu a_r^2 / d)(ln(6d/h) - 1). (k2 > 0 needs h/(2 a_r) > 2.7e-8.)
  for (double h : {1e-7, 3e-7}) {
    const double d = 1e-4;
    const double asym = 2 * kPi * mu * ar * ar / d * (std::log(6 * d / h) - 1.0);
    CHECK(squeeze_slip(h, ar, mu, d) / k2(h, ar) == doctest::Approx(asym).epsilon(1e-3));
  }
}

TEST_CASE("squeeze: the blended coefficient is continuous, the forms hold in their regimes, gaps floor at contact") {
  const SqueezeParams p;  // 1e-6, 1e-3, 0.25
  const double ai = 1.0, aj = 0.5, ar = ai * aj / (ai + aj), mu = 2.0;
  for (double g : {p.slip_gap, p.transition_gap}) {
    const double below = squeeze_coefficient(g * (1 - 1e-9), ai, aj, mu, p);
    const double above = squeeze_coefficient(g * (1 + 1e-9), ai, aj, mu, p);
    CHECK(std::abs(above - below) < 1e-6 * above);
  }
  CHECK(squeeze_coefficient(1e-4, ai, aj, mu, p) == doctest::Approx(squeeze_slip(1e-4, ar, mu, p.slip_gap)));
  CHECK(squeeze_coefficient(0.5, ai, aj, mu, p) == doctest::Approx(squeeze_no_slip(0.5, ar, mu)));
  CHECK(squeeze_coefficient(1e-9, ai, aj, mu, p) == squeeze_coefficient(p.contact_gap, ai, aj, mu, p));
  CHECK(squeeze_coefficient(-0.01, ai, aj, mu, p) == squeeze_coefficient(p.contact_gap, ai, aj, mu, p));
  // In the band the coefficient lies between the two forms; it decreases with the gap from 1e-5 on.
  // (Below, the k2 fit falls faster than the slip logarithm grows: for these radii c peaks at
  // h ~ 3e-6 and is 3 % lower at the contact gap 1e-6; docs/lubrication.md section 8.)
  CHECK(squeeze_coefficient(p.contact_gap, ai, aj, mu, p) < squeeze_coefficient(3e-6, ai, aj, mu, p));
  double prev = 1e300;
  for (double h = 1e-5; h < 3.0; h *= 1.2) {
    const double c = squeeze_coefficient(h, ai, aj, mu, p);
    CAPTURE(h);
    CHECK(c > 0.0);
    CHECK(c < prev);
    prev = c;
    if (h > p.slip_gap && h < p.transition_gap) {
      const double ns = squeeze_no_slip(h, ar, mu), sl = squeeze_slip(h, ar, mu, p.slip_gap);
      CHECK(c >= std::min(ns, sl) * (1 - 1e-12));
      CHECK(c <= std::max(ns, sl) * (1 + 1e-12));
    }
  }
  // Printed values (method notes, thesis 2.3): equal spheres a = 1, v = 1, per 6 pi mu: 326 with no
  // slip and 152.7 with slip (prefactor 1/d^2) at h = 1e-3.
  CHECK(squeeze_no_slip(1e-3, 0.5, 1.0) / (6 * kPi) == doctest::Approx(326.2).epsilon(2e-3));
  CHECK(squeeze_slip(1e-3, 0.5, 1.0, 1e-3) / (6 * kPi) == doctest::Approx(152.7).epsilon(2e-3));
}

TEST_CASE("squeeze: the pair block is a normal force on the force rows, symmetric, momentum-conserving, PSD") {
  NearFieldParams np;
  np.model = Lubrication::squeeze;
  for (Moments m : {Moments::F, Moments::FT, Moments::FTS}) {
    const NearField nf(m, 1.3, np);
    const int d = dof_per_particle(m);
    const Vec3 r(0.7, -1.1, 1.0);
    const Vec3 rv = r.normalized() * (1.0 + 0.4 + 0.02);
    const MatX B = nf.pair_block(rv, 1.0, 0.4);
    const double c = squeeze_coefficient(0.02, 1.0, 0.4, 1.3, np.squeeze);
    const Vec3 n = rv.normalized();
    CHECK((B - B.transpose()).norm() < 1e-12 * B.norm());
    CHECK(n.dot(B.block<3, 3>(0, d) * n) == doctest::Approx(-c));
    CHECK((B.block<3, 3>(0, 0) - c * n * n.transpose()).norm() < 1e-12 * c);
    for (int k = 0; k < 2 * d; ++k)
      if (k % d >= 3 && k % d < 6) CHECK(B.row(k).norm() == 0.0);  // no torque coupling
    CHECK((B.block(0, 0, 3, 2 * d) + B.block(d, 0, 3, 2 * d)).norm() < 1e-12 * c);  // F_i = -F_j
    // Rank one: the dissipation c w^2 of the normal relative velocity w alone.
    CHECK(Eigen::FullPivLU<MatX>(B).setThreshold(1e-10).rank() == 1);
    const Eigen::SelfAdjointEigenSolver<MatX> es(B);
    CHECK(es.eigenvalues().minCoeff() > -1e-12 * c);
  }
  // A pair beyond the cutoff has no near field; the dense reference twin agrees with the sparse one.
  const NearField nf(Moments::FT, 1.0, np);
  const std::vector<Vec3> x{{0, 0, 0}, {2.05, 0, 0}, {0, 2.3, 0.1}, {9, 0, 0}};
  const std::vector<double> a{1.0, 1.0, 1.2, 1.0};
  const MatX dense = nf.assemble_dense(x, a);
  const MatX sparse = MatX(nf.assemble(x, a, Domain{}));
  CHECK((dense - sparse).norm() < 1e-12 * dense.norm());
  CHECK(dense.block(18, 0, 6, 24).norm() == 0.0);
}

TEST_CASE("squeeze: the force follows the particles' own relative velocity, also in an ambient strain") {
  // The squeeze force of the thesis acts on n.(U_j - U_i) in absolute velocities. The FTS block
  // therefore couples the force rows to the strain columns: for particles moving with a pure strain
  // flow E (v_U = 0, e = -E coordinates in both e columns) the force vanishes only if c is applied
  // to n.(U_j - U_i) = r n.E.n. Reference for the sign and size: the exact two-sphere resistance,
  // whose singular part has the same structure, -n.R_FiE / (-n.R_FiUj.n) -> r q as h -> 0 (q the
  // coordinates of n n; the two e columns summed, since they always carry the same strain).
  NearFieldParams np;
  np.model = Lubrication::squeeze;
  const NearField nf(Moments::FTS, 1.0, np);
  for (double lambda : {1.0, 0.5, 0.2}) {
    const Vec3 n = Vec3(0.3, 0.8, -0.52).normalized();
    const double h = 1e-4, r = 1.0 + lambda + h;
    const Vec5 q = to_vec5(n * n.transpose());
    const MatX B = nf.pair_block(r * n, 1.0, lambda);
    const PairMatrix R = two_sphere_resistance(r * n, 1.0, lambda, 1.0);
    Vec5 sq, ex;
    for (int k = 0; k < 5; ++k) {
      sq[k] = n.dot(B.block<3, 1>(0, 6 + k) + B.block<3, 1>(0, 17 + k));
      ex[k] = n.dot(R.block<3, 1>(0, 6 + k) + R.block<3, 1>(0, 17 + k));
    }
    const double csq = -n.dot(B.block<3, 3>(0, 11) * n), cex = -n.dot(R.block<3, 3>(0, 11) * n);
    CAPTURE(lambda);
    CHECK((sq / csq - r * q).norm() < 1e-12 * r);
    CHECK((ex / cex - r * q).norm() < 2e-3 * r);  // the exact pair, O(h ln h) from its leading term
  }
  // Two spheres carried by a planar extension with no force: w = 0 in absolute velocities means
  // the squeeze force is zero; the strain columns then cancel the ambient relative velocity.
  const Vec3 rv(2.05, 0.0, 0.0);
  const MatX B = nf.pair_block(rv, 1.0, 1.0);
  VecX v = VecX::Zero(22);
  Mat3 E = Mat3::Zero();
  E(0, 0) = 0.5;
  E(1, 1) = -0.5;
  v.segment<5>(6) = -to_vec5(E);
  v.segment<5>(17) = -to_vec5(E);
  // Particles moving with the flow: U - U_inf = 0; the pair is pulled apart at r n.E.n = 1.025.
  const VecX F = B * v;  // force on the fluid: -c w n on particle 0 with w = 1.025
  const double c = squeeze_coefficient(0.05, 1.0, 1.0, 1.0, np.squeeze);
  CHECK(F[0] == doctest::Approx(-c * 1.025));
  CHECK(F[11] == doctest::Approx(c * 1.025));
}

TEST_CASE("squeeze: scene keys, the recorded choice and bad input") {
  const std::string base =
      "[particles]\npositions = [[0, 0, 0], [2.1, 0, 0]]\n[forces]\ngravity = [0, 0, -1]\n"
      "[hydrodynamics]\nmodel = \"stokesian\"\n";
  const Scene s = io::parse_scene(base + "lubrication = \"squeeze\"\nsqueeze_slip_gap = 2e-3\n", "sq.toml");
  CHECK(s.hydro.lubrication == Lubrication::squeeze);
  CHECK(s.hydro.squeeze.slip_gap == 2e-3);
  CHECK(s.hydro.squeeze.transition_gap == 0.25);
  CHECK(near_field_params(s.hydro, Moments::FT).model == Lubrication::squeeze);
  CHECK(io::parse_scene(base, "sq.toml").hydro.lubrication == Lubrication::exact);
  auto error_of = [&](const std::string& extra) {
    try {
      io::parse_scene(base + extra, "sq.toml");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string e = error_of("lubrication = \"thin\"\n");
  CHECK(e.find("lubrication") != std::string::npos);
  CHECK(e.find("squeeze") != std::string::npos);
  e = error_of("lubrication = \"squeeze\"\nsqueeze_contact_gap = 0.01\n");
  CHECK(e.find("sq.toml") != std::string::npos);
  CHECK(e.find("squeeze_contact_gap") != std::string::npos);
  CHECK(e.find("contact < slip < transition") != std::string::npos);
  e = error_of("lubrication = 1\n");  // a wrong type names the allowed values too
  CHECK(e.find("\"exact\", \"squeeze\"") != std::string::npos);
  e = error_of("squeeze_transition_gap = -1\n");
  CHECK(e.find("squeeze_transition_gap") != std::string::npos);
}
