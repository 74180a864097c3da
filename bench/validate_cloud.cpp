// Validation (issue 18): the settling velocity of a spherical cloud of spheres against the thesis's
// formula (Buelow, thesis ch. 4, eq. 4.6 = 4.10; docs/clouds.md):
//   U_c = (6/5) sum_i N_i (a_i / a_c) U_St,i  =  (6/5) sum_k a_k^3 / a_c  U0   (lengths in L0 = 1 a),
// a_c = (sum_k a_k^3 / phi)^{1/3} the cloud radius, U_St,i = U0 a_i^2 the Stokes velocity of
// sphere i, U0 = g / (6 pi mu) that of radius 1 (each sphere's weight is g a_i^3). The thesis
// measures the mean velocity of all particles while the cloud is still spherical; here that is the
// initial configuration: spheres placed uniformly at random in the cloud sphere (random sequential
// addition, no overlaps), one far-field mobility product U = M F (force level, torque-free: the
// same velocities as the thesis's FT mobility problem, which has no lubrication), the mean of
// -U.e_z over all spheres. Also reported: Nitsche & Batchelor's monodisperse form (thesis eq. 4.5),
// which adds the single-sphere velocity: U_c + <U_St,k>; and both with a_c replaced by the radius of
// the sphere the centres fill, R_eff = sqrt(5/3 <|x - c|^2>) (the centres stay a_i inside the
// region, so R_eff ~ a_c - a: the cloud of point forces the formula describes is that smaller one).
// Families (kind): 0 monodisperse a = 1; 1 lognormal LN(-0.35, 0.04) (median e^{-0.35}, standard
// deviation of ln a 0.2: mean 0.72, as the thesis); 2 bidisperse, large radius 1, small lambda = 0.5,
// number fraction of small spheres nu = 0..0.95. Kinds 0 and 1: N = 1000, 2500, 5000 at the
// thesis's 12 volume fractions 0.01..0.2; kind 2: N = 1000, phi = 0.05 (thesis fig. 4.9); 4 seeds.
// Rows: kind, N, phi, nu, lambda, seed; values U_sim, U_formula, U_nb, U_formula_eff, U_nb_eff
// (units of U0), R (a_c), R_eff, seconds.
// Usage: validate_cloud [--quick] [--out DIR]; --quick: N = 1000, phi = 0.01, 0.1, one seed.
// Full: about 1 min on one core.
#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "trees/placement.hpp"

#include <cmath>
#include <cstdio>

using namespace stokesian;

namespace {

struct Result {
  double sim, formula, nb, R, R_eff, formula_eff, nb_eff;
};

Result settle(const PlacementParams& p) {
  const Placement pl = place_particles(p, Vec3::Zero());
  const std::size_t n = pl.position.size();
  VecX F(3 * long(n)), U;
  double sum_a3 = 0.0, sum_a2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = pl.radius[i];
    F.segment<3>(3 * long(i)) = Vec3(0, 0, -a * a * a);  // g = 1: weight a^3
    sum_a3 += a * a * a;
    sum_a2 += a * a;
  }
  mobility_product(pl.position, pl.radius, 1.0, Moments::F, F, U);
  const double U0 = 1.0 / (6.0 * kPi);
  double mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) mean -= U[3 * long(i) + 2];
  mean /= double(n) * U0;
  Result r;
  r.R = pl.sphere_radius;
  r.sim = mean;
  r.formula = 1.2 * sum_a3 / r.R;
  r.nb = r.formula + sum_a2 / double(n);
  // The sphere the centres fill: random placement keeps every sphere inside the region, so the
  // centres lie within R - a_i. Its radius is measured as sqrt(5/3 <|x - c|^2>) (the cloud_radius
  // observable; R for centres uniform in a sphere of radius R).
  Vec3 c = Vec3::Zero();
  for (const Vec3& x : pl.position) c += x;
  c /= double(n);
  double r2 = 0.0;
  for (const Vec3& x : pl.position) r2 += (x - c).squaredNorm();
  r.R_eff = std::sqrt(5.0 / 3.0 * r2 / double(n));
  r.formula_eff = 1.2 * sum_a3 / r.R_eff;
  r.nb_eff = r.formula_eff + sum_a2 / double(n);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "cloud_quick" : "cloud");
  const std::vector<double> phis = opt.quick ? std::vector<double>{0.01, 0.1}
                                             : std::vector<double>{0.01, 0.025, 0.03, 0.04, 0.05, 0.06,
                                                                   0.07, 0.08, 0.09, 0.1, 0.15, 0.2};
  const std::vector<long> Ns = opt.quick ? std::vector<long>{1000} : std::vector<long>{1000, 2500, 5000};
  const int seeds = opt.quick ? 1 : 4;
  auto base = [](long N, double phi, int seed) {
    PlacementParams p;
    p.pattern = PlacementParams::Pattern::random;
    p.region = PlacementParams::Region::sphere;
    p.count = N;
    p.volume_fraction = phi;
    p.equilibration_sweeps = 0;  // uniform random (RSA), as the thesis's Monte Carlo draw
    p.min_gap = 0.0;
    p.seed = std::uint64_t(1000 * seed + 7);
    return p;
  };
  std::printf("%4s %5s %6s %5s %6s %4s %9s %9s %9s %7s %9s\n", "kind", "N", "phi", "nu", "lambda", "seed", "U_sim",
              "U_(4.6)", "U_NB", "ratio", "/NB(Reff)");
  auto run = [&](int kind, const PlacementParams& p, double nu, double lambda, int seed) {
    Result r;
    const double t = bench::time_once([&] { r = settle(p); });
    std::printf("%4d %5ld %6.3f %5.2f %6.2f %4d %9.3f %9.3f %9.3f %7.4f %9.4f\n", kind, p.count, p.volume_fraction, nu,
                lambda, seed, r.sim, r.formula, r.nb, r.sim / r.formula, r.sim / r.nb_eff);
    std::fflush(stdout);
    res.add({{"kind", kind}, {"N", double(p.count)}, {"phi", p.volume_fraction}, {"nu", nu}, {"lambda", lambda},
             {"seed", seed}},
            {{"U_sim", r.sim}, {"U_formula", r.formula}, {"U_nb", r.nb}, {"R", r.R}, {"R_eff", r.R_eff},
             {"U_formula_eff", r.formula_eff}, {"U_nb_eff", r.nb_eff}, {"seconds", t}});
  };
  for (long N : Ns)
    for (double phi : phis)
      for (int seed = 1; seed <= seeds; ++seed) {
        PlacementParams p = base(N, phi, seed);
        run(0, p, 0.0, 1.0, seed);
        p.sizes = PlacementParams::Sizes::lognormal;
        p.radius = std::exp(-0.35);
        p.sigma = 0.2;
        run(1, p, 0.0, 1.0, seed);
      }
  const std::vector<double> nus = opt.quick ? std::vector<double>{0.5}
                                            : std::vector<double>{0.0,  0.05, 0.1,  0.15, 0.2,  0.25, 0.3,
                                                                  0.35, 0.4,  0.45, 0.5,  0.55, 0.6,  0.65,
                                                                  0.7,  0.75, 0.8,  0.85, 0.9,  0.95};
  for (double nu : nus)
    for (int seed = 1; seed <= seeds; ++seed) {
      PlacementParams p = base(1000, 0.05, seed);
      p.sizes = PlacementParams::Sizes::bidisperse;
      p.radius = 0.5;          // small
      p.radius_ratio = 2.0;    // large = 1
      p.large_fraction = 1.0 - nu;
      run(2, p, nu, 0.5, seed);
    }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
