// The lubrication cutoff as an accuracy knob (lubrication/cutoff.hpp, docs/lubrication.md section 7):
// the switched near-field correction is continuous across the band, two spheres inside the band
// are the exact two-sphere solution, and with the automatic band the two-sphere SD mobility is
// within the tolerance of the exact one at every separation (or within the documented floor when
// the cap binds). Exact reference: two_sphere_resistance() from the series (not the tables the
// near field uses).
#include <doctest/doctest.h>

#include "engine/core/errors.hpp"
#include "engine/kernels/far_field.hpp"
#include "io/scene_toml.hpp"
#include "lubrication/cutoff.hpp"
#include "lubrication/near_field.hpp"
#include "lubrication/resistance_functions.hpp"
#include "support/cli.hpp"

#include <Eigen/Eigenvalues>
#include <omp.h>

#include <cmath>
#include <fstream>
#include <map>
#include <utility>
#include <memory>
#include <string>
#include <vector>

using namespace stokesian;
using namespace stokesian::lubrication;

namespace {

const Moments kLevels[] = {Moments::F, Moments::FT, Moments::FTS};
const double kRatios[] = {1.0, 2.0, 10.0, 0.5, 0.1};
const Vec3 kDir = Vec3(0.3, -0.5, 0.8).normalized();

// Exact two-sphere resistance at level m from the series, sphere 1 (radius 1) at 0, sphere 2 at r_vec.
MatX exact_resistance(const Vec3& r_vec, double a2, Moments m) {
  static std::map<double, std::unique_ptr<ResistanceSeries>> series;  // per lambda, built once
  auto get = [&](double lam) -> const ResistanceSeries& {
    auto& s = series[lam];
    if (!s) s = std::make_unique<ResistanceSeries>(lam);
    return *s;
  };
  const double xi = r_vec.norm() / (0.5 * (1.0 + a2)) - 2.0;
  const PairMatrix R = two_sphere_resistance(r_vec, 1.0, a2, 1.0, get(a2).at_gap(xi),
                                             relabel_spheres(get(1.0 / a2).at_gap(xi)));
  const int d = dof_per_particle(m);
  MatX out(2 * d, 2 * d);
  for (int p = 0; p < 2; ++p)
    for (int q = 0; q < 2; ++q) out.block(p * d, q * d, d, d) = R.block(11 * p, 11 * q, d, d);
  return out;
}

// Two-sphere SD resistance: the inverse two-body far-field mobility plus the assembled near field.
MatX sd_resistance(const NearField& nf, const Vec3& r_vec, double a2) {
  const MatX M2 = dense_mobility({Vec3::Zero(), r_vec}, {1.0, a2}, 1.0, nf.moments());
  return M2.llt().solve(MatX::Identity(M2.rows(), M2.cols())) + nf.assemble_dense({Vec3::Zero(), r_vec}, {1.0, a2});
}

MatX inverse(const MatX& R) { return R.llt().solve(MatX::Identity(R.rows(), R.cols())); }

// The error norm of cutoff.hpp: || D^1/2 (M_a - M_b) D^1/2 ||_2, D the isolated-sphere resistances.
double pair_error(const MatX& Ra, const MatX& Rb, double a2, Moments m) {
  const int d = dof_per_particle(m);
  VecX Dh(2 * d);
  for (int p = 0; p < 2; ++p) {
    const double a = p == 0 ? 1.0 : a2;
    for (int k = 0; k < d; ++k)
      Dh(p * d + k) = std::sqrt(k < 3 ? 6 * kPi * a : (k < 6 ? 8 * kPi * a * a * a : 20.0 / 3.0 * kPi * a * a * a));
  }
  const MatX E = Dh.asDiagonal() * (inverse(Ra) - inverse(Rb)) * Dh.asDiagonal();
  Eigen::SelfAdjointEigenSolver<MatX> es(0.5 * (E + E.transpose()), Eigen::EigenvaluesOnly);
  return es.eigenvalues().cwiseAbs().maxCoeff();
}

// Approach mobility of equal spheres along their line of centres: relative velocity per unit
// equal and opposite force, from the level-m mobility M = R^{-1}.
double approach_mobility(const MatX& R, Moments m) {
  const int d = dof_per_particle(m);
  VecX f = VecX::Zero(2 * d);
  f.segment<3>(0) = -kDir;
  f.segment<3>(d) = kDir;
  const VecX u = inverse(R) * f;
  return kDir.dot(u.segment<3>(d) - u.segment<3>(0));
}

NearFieldParams band_params(double s_in, double s_cut) {
  NearFieldParams p;
  p.cutoff = s_cut;
  p.taper = s_cut - s_in;
  return p;
}

std::string parse_error(const std::string& hydro) {
  try {
    io::parse_scene("[particles]\npositions = [[0, 0, 0], [3, 0, 0]]\n[hydrodynamics]\n" + hydro, "s.toml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("cutoff_for_tolerance: the measured fit, never below 4, capped, monotone") {
  for (Moments m : kLevels) {
    INFO(std::string(to_string(m)));
    double prev = 0.0;
    for (double tol : {1e-1, 1e-2, 3e-3, 1e-3, 1e-4, 1e-6, 1e-10}) {
      const CutoffBand b = cutoff_for_tolerance(tol, m);
      CHECK(b.s_in >= kStandardCutoff);
      CHECK(b.s_cut == doctest::Approx(b.s_in + kAutoTaper));
      CHECK(b.s_cut <= kDefaultMaxAutoCutoff);
      CHECK(b.s_in >= prev);
      prev = b.s_in;
      if (b.s_cut < kDefaultMaxAutoCutoff)
        CHECK(far_field_pair_error(b.s_in, m) <= tol * (1 + 1e-12));
      else
        CHECK(tol <= tolerance_floor(m) * (1 + 1e-12));
    }
    CHECK(cutoff_for_tolerance(1.0, m).s_in == kStandardCutoff);
    // a wider cap reaches tighter tolerances
    const CutoffBand wide = cutoff_for_tolerance(1e-4, m, 30.0);
    CHECK(far_field_pair_error(wide.s_in, m) == doctest::Approx(1e-4));
  }
  CHECK(tolerance_floor(Moments::F) == doctest::Approx(6.8 / std::pow(5.5, 4)));
  CHECK(tolerance_floor(Moments::FTS) == doctest::Approx(32.0 / std::pow(5.5, 6)));
  CHECK_THROWS_AS(cutoff_for_tolerance(0.0, Moments::F), std::invalid_argument);
  CHECK_THROWS_AS(cutoff_for_tolerance(1e-3, Moments::F, 4.2), std::invalid_argument);
}

TEST_CASE("the switch: 1 inside, 0 outside, C2 across both ends of the band") {
  const CutoffBand b{4.0, 4.5};
  CHECK(cutoff_weight(3.0, b) == 1.0);
  CHECK(cutoff_weight(4.0, b) == 1.0);
  CHECK(cutoff_weight(4.5, b) == 0.0);
  CHECK(cutoff_weight(9.0, b) == 0.0);
  CHECK(cutoff_weight(4.25, b) == doctest::Approx(0.5));
  for (double e : {4.0, 4.5}) {
    for (double h : {1e-2, 1e-3}) {
      // value, slope and curvature from either side agree to O(h)
      const double w0 = cutoff_weight(e, b), wl = cutoff_weight(e - h, b), wr = cutoff_weight(e + h, b);
      CHECK(std::abs(wr - wl) <= 3 * h * h);               // w' = 0 at the ends: jump of w is O(h^3)
      CHECK(std::abs(wr - 2 * w0 + wl) / (h * h) <= 200 * h);  // w'' = 0 at the ends
    }
  }
  // hard step
  const CutoffBand hard{4.0, 4.0};
  CHECK(cutoff_weight(3.999999, hard) == 1.0);
  CHECK(cutoff_weight(4.0, hard) == 0.0);
}

TEST_CASE("two spheres inside the band are the exact two-sphere solution (F, FT, FTS; ratios 1, 2, 10 and inverses)") {
  for (Moments m : kLevels)
    for (double lam : kRatios) {
      INFO(std::string(to_string(m)));
      CAPTURE(lam);
      const NearField nf(m, 1.0, band_params(5.0, 5.5));
      double worst = 0.0;
      for (double s : {2.001, 2.01, 2.1, 2.5, 3.0, 4.0, 4.9, 5.0}) {
        const Vec3 r = kDir * (0.5 * s * (1.0 + lam));
        const MatX Rex = exact_resistance(r, lam, m), Rsd = sd_resistance(nf, r, lam);
        worst = std::max(worst, (Rsd - Rex).norm() / Rex.norm());
      }
      CHECK(worst < 1e-6);  // the table's interpolation error (docs/lubrication.md 2.5)
    }
}

TEST_CASE("R_nf and the two-sphere SD mobility are continuous across s_in and s_cut; the hard step is not") {
  const double lam = 1.0;
  for (Moments m : kLevels) {
    INFO(std::string(to_string(m)));
    HydroParams h;  // lubrication_cutoff = "auto" at the default tolerance 1e-6
    h.lubrication_cutoff_auto = true;
    const NearFieldParams smooth = near_field_params(h, m);
    CHECK(smooth.taper == doctest::Approx(kAutoTaper));
    const NearField nf(m, 1.0, smooth);
    for (double edge : {smooth.cutoff - smooth.taper, smooth.cutoff}) {
      CAPTURE(edge);
      double prev_jump = 0.0;
      for (double h : {1e-2, 1e-3, 1e-4}) {
        auto at = [&](double s) { return kDir * (0.5 * s * (1.0 + lam)); };
        const MatX Rl = nf.assemble_dense({Vec3::Zero(), at(edge - h)}, {1.0, lam});
        const MatX Rr = nf.assemble_dense({Vec3::Zero(), at(edge + h)}, {1.0, lam});
        const double jump = (Rr - Rl).norm() / (6 * kPi);
        const double mob = std::abs(approach_mobility(sd_resistance(nf, at(edge + h), lam), m) -
                                    approach_mobility(sd_resistance(nf, at(edge - h), lam), m)) *
                           (6 * kPi);
        CHECK(jump < h);  // Lipschitz in s (a hard step stays ~1e-2 whatever h)
        CHECK(mob < h);
        if (prev_jump > 0) CHECK(jump < 0.2 * prev_jump);  // -> 0 with the step
        prev_jump = jump;
      }
    }
    // Published SD (explicit cutoff 4, no taper) jumps at 4 by a step that does not shrink.
    NearFieldParams hard;
    hard.cutoff = 4.0;
    const NearField nh(m, 1.0, hard);
    for (double h : {1e-3, 1e-5}) {
      const double dm = std::abs(approach_mobility(sd_resistance(nh, kDir * (4.0 + h), 1.0), m) -
                                 approach_mobility(sd_resistance(nh, kDir * (4.0 - h), 1.0), m)) /
                        approach_mobility(sd_resistance(nh, kDir * 4.0, 1.0), m);
      CHECK(dm > 1e-4);
      MESSAGE(std::string(to_string(m)) << ": hard step at s = 4, relative jump of the approach mobility " << dm);
    }
  }
}

TEST_CASE("auto cutoff: two-sphere SD mobility within the tolerance (or the cap's floor) at every separation") {
  // Fine grid from near contact to s = 20 (step 0.04: 12 points in each band of width 0.5). The
  // pair matrices are tiny: one thread (the OpenMP regions of the far-field kernel only cost here).
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  std::vector<double> grid;
  for (double s = 2.005; s <= 20.0; s += 0.04) grid.push_back(s);
  const double tols[] = {1e-2, 3e-3, 1e-3, 1e-6};
  for (Moments m : kLevels)
    for (double lam : {1.0, 2.0, 10.0, 0.1}) {
      INFO(std::string(to_string(m)));
      CAPTURE(lam);
      std::vector<std::unique_ptr<NearField>> fields;
      for (double tol : tols) {
        HydroParams h;
        h.lubrication_cutoff_auto = true;
        h.tolerance = tol;
        fields.push_back(std::make_unique<NearField>(m, 1.0, near_field_params(h, m)));
      }
      std::vector<double> worst(std::size(tols), 0.0);
      for (double s : grid) {
        const Vec3 r = kDir * (0.5 * s * (1.0 + lam));
        const MatX Rex = exact_resistance(r, lam, m);
        for (std::size_t k = 0; k < fields.size(); ++k)
          worst[k] = std::max(worst[k], pair_error(sd_resistance(*fields[k], r, lam), Rex, lam, m));
      }
      for (std::size_t k = 0; k < fields.size(); ++k) {
        const double bound = std::max(tols[k], tolerance_floor(m));
        CAPTURE(tols[k]);
        CHECK(worst[k] <= bound);
        MESSAGE(std::string(to_string(m)) << " lambda " << lam << " tol " << tols[k] << " band [" << fields[k]->params().cutoff -
                                  fields[k]->params().taper << ", " << fields[k]->params().cutoff << "]: worst error "
                                  << worst[k] << " (bound " << bound << ")");
      }
    }
  omp_set_num_threads(threads);
}

TEST_CASE("a wider cap meets tolerances to 1e-6 (FTS) and 1e-4 (F) at every separation") {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  std::vector<double> grid;
  for (double s = 2.005; s <= 25.0; s += 0.05) grid.push_back(s);
  for (auto [m, tol] : {std::pair{Moments::F, 1e-4}, std::pair{Moments::FTS, 1e-5}, std::pair{Moments::FTS, 1e-6}}) {
    for (double lam : {1.0, 2.0, 10.0}) {
      INFO(std::string(to_string(m)));
      CAPTURE(lam);
      HydroParams h;
      h.lubrication_cutoff_auto = true;
      h.tolerance = tol;
      const NearField nf(m, 1.0, near_field_params(h, m, 30.0));
      double worst = 0.0;
      for (double s : grid) {
        const Vec3 r = kDir * (0.5 * s * (1.0 + lam));
        worst = std::max(worst, pair_error(sd_resistance(nf, r, lam), exact_resistance(r, lam, m), lam, m));
      }
      CHECK(worst <= tol);
      MESSAGE(std::string(to_string(m)) << " lambda " << lam << " tol " << tol << ", cap 30: worst error " << worst);
    }
  }
  omp_set_num_threads(threads);
}

TEST_CASE("near_field_params: explicit cutoff and taper, the published hard step, the pair search follows s_cut") {
  HydroParams h;  // the default: published SD
  CHECK(!h.lubrication_cutoff_auto);
  CHECK(h.lubrication_cutoff == 4.0);
  NearFieldParams p = near_field_params(h, Moments::FTS);
  CHECK(p.cutoff == 4.0);
  CHECK(p.taper == 0.0);  // explicit cutoff, "auto" taper: published SD
  h.lubrication_taper_auto = false;
  h.lubrication_taper = 1.0;
  p = near_field_params(h, Moments::FTS);
  CHECK(p.cutoff == 4.0);
  CHECK(p.taper == 1.0);
  HydroParams a;
  a.lubrication_cutoff_auto = true;
  a.tolerance = 1e-3;
  a.lubrication_taper_auto = false;
  a.lubrication_taper = 1.5;
  p = near_field_params(a, Moments::FTS);
  CHECK(p.cutoff - p.taper == doctest::Approx(cutoff_for_tolerance(1e-3, Moments::FTS).s_in));
  CHECK(p.taper == 1.5);

  // The sparse assembly finds the pairs of the band (not only those within 4): a chain of spheres
  // at s = 4.2 gets its tapered pairs, and equals the dense reference.
  NearFieldParams band = band_params(4.0, 5.0);
  const NearField nf(Moments::FT, 1.0, band);
  std::vector<Vec3> x;
  for (int i = 0; i < 4; ++i) x.push_back(Vec3(4.2 * i, 0.1 * i, 0));
  const std::vector<double> a1(4, 1.0);  // neighbours at s = 4.2 (in the band), the others at s >= 8.4
  NearFieldStats st;
  const SparseMatrix R = nf.assemble(x, a1, Domain{}, &st);
  CHECK(st.pairs == 3);
  CHECK(st.tapered == 3);
  CHECK((MatX(R) - nf.assemble_dense(x, a1)).norm() <= 1e-14 * nf.assemble_dense(x, a1).norm());
  NearFieldParams old;  // published SD: nothing beyond s = 4
  CHECK(NearField(Moments::FT, 1.0, old).assemble(x, a1, Domain{}).nonZeros() == 0);
  CHECK_THROWS_AS(NearField(Moments::FT, 1.0, band_params(1.5, 4.0)), std::invalid_argument);
}

TEST_CASE("scene keys: lubrication_cutoff and lubrication_taper accept \"auto\" or a number, errors name the key") {
  using stokesian::test::contains;
  // no keys: published SD (s_cut = 4, hard step), as in earlier versions
  const Scene d = io::parse_scene("[particles]\npositions = [[0, 0, 0], [3, 0, 0]]\n", "s.toml");
  CHECK(!d.hydro.lubrication_cutoff_auto);
  CHECK(d.hydro.lubrication_cutoff == 4.0);
  CHECK(d.hydro.lubrication_taper_auto);
  CHECK(near_field_params(d.hydro, Moments::FT).cutoff == 4.0);
  CHECK(near_field_params(d.hydro, Moments::FT).taper == 0.0);
  const Scene e = io::parse_scene(
      "[particles]\npositions = [[0, 0, 0], [3, 0, 0]]\n[hydrodynamics]\nlubrication_cutoff = 4\nlubrication_taper = 0.5\n",
      "s.toml");
  CHECK(!e.hydro.lubrication_cutoff_auto);
  CHECK(e.hydro.lubrication_cutoff == 4.0);
  CHECK(!e.hydro.lubrication_taper_auto);
  CHECK(e.hydro.lubrication_taper == 0.5);
  const Scene f = io::parse_scene(
      "[particles]\npositions = [[0, 0, 0], [3, 0, 0]]\n[hydrodynamics]\nlubrication_cutoff = \"auto\"\ntolerance = 1e-2\n",
      "s.toml");
  CHECK(f.hydro.lubrication_cutoff_auto);
  CHECK(near_field_params(f.hydro, Moments::FTS).cutoff == doctest::Approx(4.5));
  CHECK(near_field_params(f.hydro, Moments::FTS).taper == doctest::Approx(0.5));
  // round trip through the resolved scene
  for (const Scene* s : {&d, &e, &f}) {
    const Scene back = io::parse_scene(io::resolved_toml(*s), "resolved");
    CHECK(back.hydro.lubrication_cutoff_auto == s->hydro.lubrication_cutoff_auto);
    CHECK(back.hydro.lubrication_taper_auto == s->hydro.lubrication_taper_auto);
    CHECK(back.hydro.lubrication_cutoff == s->hydro.lubrication_cutoff);
    CHECK(back.hydro.lubrication_taper == s->hydro.lubrication_taper);
  }
  CHECK(io::scene_differences(io::resolved_toml(d), io::resolved_toml(e)).size() == 1);  // the taper
  CHECK(io::scene_differences(io::resolved_toml(d), io::resolved_toml(f)).size() == 2);  // cutoff, tolerance

  std::string m = parse_error("lubrication_cutoff = \"wide\"\n");
  CHECK(contains(m, "s.toml:4: [hydrodynamics] lubrication_cutoff: \"wide\" is not \"auto\" or a number"));
  CHECK(contains(m, "(2, 100]"));
  m = parse_error("lubrication_cutoff = 2\n");
  CHECK(contains(m, "s.toml:4: [hydrodynamics] lubrication_cutoff: value 2 out of range (allowed (2, 100])"));
  m = parse_error("lubrication_cutoff = true\n");
  CHECK(contains(m, "s.toml:4: [hydrodynamics] lubrication_cutoff: expected a number"));
  m = parse_error("lubrication_taper = -1\n");
  CHECK(contains(m, "s.toml:4: [hydrodynamics] lubrication_taper: value -1 out of range (allowed [0, 98])"));
  m = parse_error("lubrication_cutoff = 3\nlubrication_taper = 1.5\n");
  CHECK(contains(m, "s.toml:5: [hydrodynamics] lubrication_taper: value 1.5 out of range (allowed [0, 1]"));
  m = parse_error("lubrication_taper = \"smooth\"\n");
  CHECK(contains(m, "s.toml:4: [hydrodynamics] lubrication_taper: \"smooth\" is not \"auto\" or a number"));

  // the CLI: exit 2, the message on stderr, nothing written
  stokesian::test::ScratchDir dir("stokesian_lub_cutoff_");
  {
    std::ofstream f(dir.path / "bad.toml");
    f << "[particles]\npositions = [[0, 0, 0], [3, 0, 0]]\n[hydrodynamics]\nlubrication_cutoff = 1.5\n";
  }
  const auto r = stokesian::test::run_stokesian("check " + (dir.path / "bad.toml").string(), dir.path);
  CHECK(r.status == 2);
  CHECK(contains(r.err, "bad.toml:4: [hydrodynamics] lubrication_cutoff: value 1.5 out of range (allowed (2, 100])"));
}

// The measurement behind the fit of lubrication/cutoff.hpp (docs/lubrication.md section 7): the
// two-sphere error of the far field alone, worst over 49 size ratios in [1, 16] (geometric) and
// 20, 50, 100 (lambda and 1/lambda give the same error), printed per s; checks the fit bounds it.
// Skipped by default (~15 s): ./tests/test_lubrication_cutoff --no-skip -tc="*far-field error scan*"
TEST_CASE("far-field error scan: the fit e(s) <= A s^-p holds for s in [4, 60]" * doctest::skip()) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  std::vector<double> lams;
  for (int k = 0; k <= 48; ++k) lams.push_back(std::pow(16.0, k / 48.0));
  for (double l : {20.0, 50.0, 100.0}) lams.push_back(l);
  const double ss[] = {4.0, 4.25, 4.5, 5.0, 5.5, 6.0, 7.0, 8.0, 10.0, 14.0, 20.0, 30.0, 60.0};
  for (Moments m : kLevels) {
    for (double s : ss) {
      double worst = 0.0, at = 0.0;
      for (double lam : lams) {
        const Vec3 r = kDir * (0.5 * s * (1.0 + lam));
        const MatX M2 = dense_mobility({Vec3::Zero(), r}, {1.0, lam}, 1.0, m);
        const double e = pair_error(inverse(M2), exact_resistance(r, lam, m), lam, m);
        if (e > worst) worst = e, at = lam;
      }
      MESSAGE(std::string(to_string(m)) << " s " << s << ": worst e " << worst << " at lambda " << at << ", e s^p "
                                        << worst * std::pow(s, m == Moments::FTS ? 6 : 4));
      CHECK(worst <= far_field_pair_error(s, m));
    }
  }
  omp_set_num_threads(threads);
}
