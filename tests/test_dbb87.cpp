// Validation against Durlofsky, Brady & Bossis (1987), J. Fluid Mech. 180, 21-49 ("DBB87"),
// the paper that introduced the construction of engine/sd_dense.hpp (R = M_inf^{-1} + R_nf).
// docs/validation_dbb87.md tabulates every number used here with its provenance.
//
// (1) DBB87 fig. 1: a straight chain of 15 equal spheres, centres 4a apart, settling broadside
//     (equal forces perpendicular to the chain): the drag coefficient of every sphere,
//     lambda_i = F / (6 pi mu a U_i).
// (2) DBB87 fig. 5: three equal spheres released on a horizontal line at x = -5, 0, 7 settle
//     under equal forces; their paths x(z) down to z = -784 a are compared with the published
//     figure (digitised), including its turning points and the final grouping.
//
// The paper's text and figures were not readable from here; the published values come from the
// digitisation by A. K. Townsend in his Python Stokesian-dynamics code (github.com/Pecnut/
// stokesian-dynamics; examples/example-a.py at commit 423012d7 for fig. 1 "extracted from the
// paper", examples/data/durlofsky_fig5_data.txt at commit f068b846 for fig. 5 "scraped from
// paper", set-ups in position_setups.py at commit 1033b801: chain centres 4a apart; fig. 5
// initial centres (-5,0,0), (0,0,0), (7,0,0) a).
#include <doctest/doctest.h>

#include "engine/sd_dense.hpp"
#include "engine/simulation.hpp"
#include "io/scene_toml.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

using namespace stokesian;

namespace {

// Drag coefficients lambda_i = F / (6 pi mu a U_i . f) of a straight chain of N unit spheres along
// x, centres `spacing` apart, each pushed with the unit force f (mu = 1, a = 1).
std::vector<double> chain_lambda(int N, double spacing, const Vec3& f, Moments m, double cutoff = 4.0) {
  std::vector<Vec3> x, F;
  for (int i = 0; i < N; ++i) {
    x.emplace_back(spacing * i, 0, 0);
    F.push_back(f);
  }
  lubrication::NearFieldParams p;
  p.cutoff = cutoff;
  DenseStokesianDynamics sd(m, 1.0, AmbientFlow{}, p);
  const HydroResult h = sd.mobility_problem(x, std::vector<double>(std::size_t(N), 1.0), {}, F, {});
  std::vector<double> lam;
  for (int i = 0; i < N; ++i) lam.push_back(1.0 / (6 * M_PI * h.U[std::size_t(i)].dot(f)));
  return lam;
}

}  // namespace

TEST_CASE("DBB87 fig. 1: drag of each sphere of a 15-sphere chain (spacing 4a) settling broadside") {
  // Centre sphere -> end sphere (the chain is mirror symmetric).
  // DBB87 fig. 1 (N = 15), digitised by Townsend (examples/example-a.py, "Extracted from the paper").
  const std::array<double, 8> dbb87{0.5018, 0.5029, 0.5054, 0.5102, 0.5183, 0.5321, 0.5559, 0.6170};
  // Independent near-exact solution: method of fundamental solutions ("fine" discretisation,
  // tol 1e-7), values hard-coded in a public research script that reproduces DBB87 fig. 1 (found
  // by code search; repository not identified, so this is corroboration, not a primary source).
  const std::array<double, 8> mfs{0.502587, 0.50343569, 0.50609488, 0.51095464,
                                  0.51888724, 0.53188422, 0.55555363, 0.61787316};
  // Townsend's own Python SD (FTS, same construction) in the same script ("townsend_data").
  const std::array<double, 8> townsend{0.50226895, 0.50311695, 0.50577411, 0.51063075,
                                       0.51856039, 0.53156096, 0.55527634, 0.61764888};

  // Default parameters: the near-field cutoff keeps pairs with s = 2r/(a_i+a_j) < 4, so
  // neighbours exactly 4a apart are coupled by the far field alone. With cutoff 4.5 they also get
  // the exact two-sphere correction.
  const std::vector<double> sd = chain_lambda(15, 4.0, Vec3(0, 0, 1), Moments::FTS);
  const std::vector<double> sd_nf = chain_lambda(15, 4.0, Vec3(0, 0, 1), Moments::FTS, 4.5);
  double worst_pub = 0, worst_mfs = 0, worst_mfs_nf = 0, worst_town = 0;
  for (int k = 0; k < 8; ++k) {
    const double ours = sd[std::size_t(7 + k)], ours_nf = sd_nf[std::size_t(7 + k)];
    CHECK(std::abs(ours / sd[std::size_t(7 - k)] - 1) < 1e-12);  // mirror symmetry
    MESSAGE("sphere " << k << " (0 = centre): DBB87 " << dbb87[std::size_t(k)] << "  MFS " << mfs[std::size_t(k)]
                      << "  ours " << ours << "  ours(cutoff 4.5) " << ours_nf);
    worst_pub = std::max(worst_pub, std::abs(ours / dbb87[std::size_t(k)] - 1));
    worst_town = std::max(worst_town, std::abs(ours / townsend[std::size_t(k)] - 1));
    worst_mfs = std::max(worst_mfs, std::abs(ours / mfs[std::size_t(k)] - 1));
    worst_mfs_nf = std::max(worst_mfs_nf, std::abs(ours_nf / mfs[std::size_t(k)] - 1));
  }
  MESSAGE("max rel. difference: vs DBB87 " << worst_pub << ", vs Townsend SD " << worst_town << ", vs MFS "
                                           << worst_mfs << " (cutoff 4.5: " << worst_mfs_nf << ")");
  // Digitised from a plotted curve: the reading error is about 1e-3 in lambda (0.2 %); measured
  // 0.112 %; allowed 0.3 %. The published points lie below the exact (MFS) ones by up to 0.16 %,
  // within that reading error, so the figure cannot tell the two variants below apart.
  CHECK(worst_pub < 3e-3);
  // Same construction, and at s = 4 his cutoff also leaves the pairs to the far field, so the
  // two codes solve the same linear system: measured 9e-9 (his 8-digit print-out); allowed 1e-6.
  CHECK(worst_town < 1e-6);
  // Against the exact solution: far-field coupling alone at s = 4 misses the two-sphere
  // correction (measured 6.3e-4, allowed 1.5e-3); with it the pairwise-additive SD agrees with
  // the MFS to 7.0e-5 (allowed 2e-4): at gaps of 2a the many-body part of the near field is
  // negligible.
  CHECK(worst_mfs < 1.5e-3);
  CHECK(worst_mfs_nf < 2e-4);
  // The end sphere feels the largest drag, the centre one the smallest (DBB87 fig. 1).
  CHECK(std::is_sorted(sd.begin() + 7, sd.end()));
}

namespace {

// Digitised paths of DBB87 fig. 5 (x, z in units of a; unlabelled points of all three paths).
// Source: Pecnut/stokesian-dynamics examples/data/durlofsky_fig5_data.txt (commit f068b846),
// rounded to 1e-4 in x and 1e-2 in z.
const std::vector<std::array<double, 2>> kFig5 = {
    {-4.9807, -3.23}, {-4.9513, -13.28}, {-4.8540, -22.05}, {-4.7466, -29.71}, {-4.5650, -37.22},
    {-4.3480, -43.58}, {-4.2696, -221.03}, {-4.2145, -235.41}, {-4.1628, -206.39}, {-4.1677, -51.18},
    {-4.0941, -245.17}, {-3.9792, -198.53}, {-3.9302, -58.40}, {-3.9384, -252.78}, {-3.7692, -190.28},
    {-3.7500, -258.52}, {-3.6927, -64.37}, {-3.5779, -264.81}, {-3.5312, -182.34}, {-3.5125, -70.41},
    {-3.3895, -271.59}, {-3.3689, -177.36}, {-3.2750, -76.94}, {-3.1503, -167.69}, {-3.1193, -277.97},
    {-3.0608, -84.92}, {-2.9782, -159.78}, {-2.8653, -93.70}, {-2.8454, -150.49}, {-2.8327, -284.42},
    {-2.7733, -141.88}, {-2.7561, -106.91}, {-2.7526, -114.99}, {-2.7300, -133.76}, {-2.7087, -121.72},
    {-2.7043, -129.63}, {-2.5626, -290.15}, {-2.2269, -296.11}, {-1.9077, -301.60}, {-1.6456, -309.94},
    {-1.3884, -317.01}, {-1.3170, -407.23}, {-1.2901, -398.34}, {-1.2333, -387.55}, {-1.1834, -325.46},
    {-1.1193, -374.81}, {-1.0929, -419.47}, {-1.0175, -333.16}, {-1.0053, -362.61}, {-0.9406, -346.26},
    {-0.9647, -356.14}, {-0.8390, -426.61}, {-0.4298, -433.31}, {-0.3414, -784.31}, {-0.2352, -780.54},
    {-0.0984, -770.72}, {0.0150, -764.38}, {0.0044, -5.17}, {-0.0031, -11.74}, {0.0029, -23.67}, {0.0032, -32.21},
    {-0.0099, -43.32}, {0.0345, -51.87}, {0.0532, -440.68}, {0.0594, -199.95}, {0.0863, -61.68}, {0.1324, -184.64},
    {0.1808, -753.53}, {0.1251, -207.16}, {0.1801, -69.83}, {0.2474, -217.91}, {0.3060, -172.81},
    {0.3616, -740.83}, {0.3242, -79.18}, {0.4533, -230.92}, {0.4473, -87.12}, {0.4343, -167.87}, {0.5543, -729.32},
    {0.5606, -447.24}, {0.6167, -96.06}, {0.6194, -159.61}, {0.6931, -244.26}, {0.6997, -720.05},
    {0.7947, -102.52}, {0.7609, -154.54}, {0.8497, -709.41}, {0.8702, -252.24}, {0.9826, -700.41},
    {0.9471, -108.16}, {0.9569, -147.22}, {1.0763, -262.86}, {1.1244, -693.04}, {1.0843, -452.66},
    {1.1355, -114.25}, {1.2504, -685.25}, {1.2021, -271.70}, {1.2102, -140.39}, {1.3471, -283.01},
    {1.4208, -674.27}, {1.3567, -121.77}, {1.4014, -290.75}, {1.4308, -133.39}, {1.5000, -301.35},
    {1.5270, -670.94}, {1.6000, -460.06}, {1.6260, -662.46}, {1.6042, -311.99}, {1.6542, -128.42},
    {1.6595, -320.01}, {1.7336, -331.46}, {1.7882, -407.06}, {1.8308, -653.57}, {1.8304, -132.18},
    {1.8671, -393.47}, {1.8731, -342.28}, {1.8515, -412.34}, {1.9839, -351.21}, {1.9651, -390.10},
    {2.0557, -642.64}, {2.0192, -119.98}, {2.0727, -419.25}, {2.1820, -359.93}, {2.1448, -382.53},
    {2.1483, -465.77}, {2.1428, -142.64}, {2.2494, -634.28}, {2.3786, -366.88}, {2.3379, -112.98},
    {2.4168, -628.19}, {2.4000, -373.80}, {2.4294, -148.28}, {2.4738, -426.15}, {2.5944, -620.48},
    {2.6431, -368.25}, {2.6321, -107.21}, {2.6435, -376.25}, {2.6556, -470.92}, {2.7435, -614.82},
    {2.7486, -153.75}, {2.9137, -382.84}, {2.9232, -609.64}, {2.9291, -361.11}, {2.9486, -434.76},
    {2.9672, -99.10}, {3.0977, -479.74}, {3.1170, -161.09}, {3.1437, -599.69}, {3.2412, -389.92},
    {3.2560, -354.86}, {3.2860, -93.88}, {3.3397, -594.25}, {3.4363, -167.67}, {3.5215, -442.36},
    {3.5277, -589.17}, {3.5748, -347.54}, {3.5560, -484.87}, {3.5850, -396.08}, {3.6620, -87.13},
    {3.7483, -582.96}, {3.8292, -173.17}, {3.8608, -342.28}, {3.9452, -403.57}, {3.9653, -491.45},
    {4.0135, -81.59}, {4.0343, -576.26}, {4.2170, -448.33}, {4.2221, -179.55}, {4.2449, -333.78},
    {4.2957, -568.11}, {4.3582, -499.24}, {4.3812, -73.09}, {4.4363, -409.99}, {4.5245, -562.08},
    {4.5882, -327.11}, {4.6069, -187.25}, {4.6366, -504.92}, {4.7163, -66.11}, {4.8105, -555.88},
    {4.8472, -455.93}, {4.8824, -321.25}, {4.9110, -416.91}, {4.9149, -510.66}, {4.9997, -192.77},
    {5.0637, -547.89}, {5.0990, -769.42}, {5.1087, -60.20}, {5.1279, -518.39}, {5.1704, -750.97},
    {5.1463, -759.87}, {5.2331, -741.09}, {5.2256, -313.09}, {5.2865, -730.97}, {5.3253, -719.57},
    {5.3339, -526.12}, {5.3498, -542.23}, {5.3354, -199.14}, {5.3568, -709.18}, {5.3955, -463.03},
    {5.4021, -423.33}, {5.4165, -700.65}, {5.4602, -54.62}, {5.4828, -690.68}, {5.5409, -534.91},
    {5.5193, -682.66}, {5.5281, -308.81}, {5.5844, -673.73}, {5.6493, -661.47}, {5.6879, -542.47},
    {5.6734, -651.41}, {5.6874, -205.54}, {5.7077, -641.30}, {5.7706, -550.71}, {5.7824, -630.72},
    {5.7707, -48.11}, {5.8236, -528.11}, {5.8294, -470.60}, {5.8376, -617.23}, {5.8495, -558.48},
    {5.8441, -626.22}, {5.8579, -564.14}, {5.8679, -607.12}, {5.8877, -301.63}, {5.8995, -581.64},
    {5.9000, -592.60}, {5.9073, -572.79}, {5.9085, -601.20}, {5.9667, -429.50}, {5.9984, -211.18},
    {6.0442, -520.23}, {6.0404, -42.22}, {6.2146, -294.96}, {6.2142, -478.11}, {6.2484, -512.94},
    {6.2605, -218.97}, {6.2692, -35.62}, {6.4525, -504.36}, {6.4516, -484.34}, {6.4988, -437.63},
    {6.5617, -494.03}, {6.5666, -28.17}, {6.5497, -288.20}, {6.5797, -223.56}, {6.7666, -20.30}, {6.8226, -229.49},
    {6.8031, -282.95}, {6.9633, -9.42}, {7.0320, -236.95}, {6.9876, -1.81}, {7.0359, -274.64}, {7.0552, -442.70},
    {7.1950, -265.75}, {7.2198, -250.31}, {7.2929, -258.93}, {7.5708, -449.25}, {7.7693, -638.54},
    {7.7879, -650.32}, {7.7907, -659.88}, {7.8156, -629.27}, {7.8243, -669.57}, {7.8573, -619.42},
    {7.8947, -682.06}, {7.9131, -612.61}, {8.0108, -603.09}, {7.9912, -692.65}, {8.0623, -702.91},
    {8.0864, -455.95}, {8.1086, -595.24}, {8.1490, -711.21}, {8.2372, -583.39}, {8.2693, -720.19},
    {8.3859, -573.87}, {8.4006, -729.89}, {8.5327, -563.43}, {8.5400, -738.69}, {8.5530, -464.16},
    {8.6877, -748.61}, {8.7122, -553.14}, {8.8680, -758.06}, {8.9063, -543.24}, {8.9704, -470.00},
    {9.0402, -767.14}, {9.0061, -540.40}, {9.1365, -528.88}, {9.1779, -776.82}, {9.2489, -477.79},
    {9.2346, -526.26}, {9.3463, -784.21}, {9.3568, -516.01}, {9.4454, -483.23}, {9.4758, -504.38},
    {9.5195, -494.77}
};

struct Path {
  std::vector<std::array<double, 3>> xz[3];  // per sphere: (t, x, z)
};

Path settle_three(const char* moments) {
  std::ostringstream toml;
  toml << "[particles]\npositions = [[-5, 0, 0], [0, 0, 0], [7, 0, 0]]\n"
       << "[forces]\nexternal_force = [0.0, 0.0, -1.0]\n"
       << "[hydrodynamics]\nmodel = \"stokesian\"\nmoments = \"" << moments << "\"\n"
       << "lubrication_cutoff = 4\nlubrication_taper = 0\n"  // published SD: hard step at s = 4
       << "[time]\ndt = 1.0\nsteps = 100000\nintegrator = \"rkf45\"\nrkf_tolerance = 1e-7\n";
  Simulation sim(io::parse_scene(toml.str(), "dbb87_fig5.toml"));
  State s = sim.initial_state();
  Path p;
  while (true) {
    double ztop = -INFINITY;
    for (int k = 0; k < 3; ++k) {
      const Vec3& x = s.position[std::size_t(k)];
      p.xz[k].push_back({s.time, x.x(), x.z()});
      ztop = std::max(ztop, x.z());
    }
    if (ztop < -795.0) break;
    REQUIRE(p.xz[0].size() < 100000);  // ~1200 steps expected
    sim.advance(s, sim.evaluate(s, s.position));
    s.dt = std::min(s.dt, 10.0);  // at most 0.6 a per step: the stored path is a fine polyline
  }
  return p;
}

// Horizontal distance from (x, z) to the nearest path at the same depth (every crossing of
// depth z by every sphere counts).
double horizontal_distance(const Path& p, double x, double z) {
  double best = INFINITY;
  for (const auto& path : p.xz)
    for (std::size_t i = 1; i < path.size(); ++i) {
      const auto &a = path[i - 1], &b = path[i];
      if ((a[2] - z) * (b[2] - z) > 0 || a[2] == b[2]) continue;
      const double w = (z - a[2]) / (b[2] - a[2]);
      best = std::min(best, std::abs(a[1] + w * (b[1] - a[1]) - x));
    }
  return best;
}

struct Agreement {
  double max_upper = 0, median_upper = 0, max_lower = 0, median_lower = 0;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

Agreement agreement(const Path& p) {
  std::vector<double> up, low;
  for (const auto& q : kFig5) (q[1] >= -600 ? up : low).push_back(horizontal_distance(p, q[0], q[1]));
  Agreement a;
  a.max_upper = *std::max_element(up.begin(), up.end());
  a.max_lower = *std::max_element(low.begin(), low.end());
  a.median_upper = median(up);
  a.median_lower = median(low);
  return a;
}

// Extreme x of sphere k over the depth window [zlo, zhi]: (x, z) at the extremum.
std::array<double, 2> extreme_x(const Path& p, int k, double zlo, double zhi, bool maximum) {
  std::array<double, 2> best{maximum ? -INFINITY : INFINITY, 0};
  for (const auto& q : p.xz[k])
    if (q[2] >= zlo && q[2] <= zhi && (maximum ? q[1] > best[0] : q[1] < best[0])) best = {q[1], q[2]};
  return best;
}

}  // namespace

TEST_CASE("DBB87 fig. 5: three spheres released on a horizontal line follow the published paths (FTS)") {
  // Three particles: OpenMP only adds overhead (on a loaded 2-core machine the FTS run took 94 s
  // with two threads, 2 s with one).
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Path fts = settle_three("FTS");
  const Path ft = settle_three("FT");
  omp_set_num_threads(threads);

  // Paths. Reading error of the digitised points: the figure spans about 19 a horizontally, so
  // ~0.5 % of the axis is ~0.1 a. Measured (FTS) down to z = -600 a: max 0.16 a, median 0.04 a;
  // allowed 0.25 a and 0.08 a. Below -600 a the measured deviation grows to max 0.49 a (median
  // 0.08 a): the three-sphere problem amplifies small differences (chaotic scattering, Janosi et
  // al. 1997, Phys. Rev. E 56, 2858) and Townsend reports the same drift at the bottom of the
  // figure with his SD; allowed 0.75 a and 0.15 a. The integration error is far below this
  // (rkf_tolerance 1e-6, 1e-8 and 1e-10 give the same figures to 1e-3 a; the 1e-8 and 1e-10
  // paths differ by at most 2.5e-3 a).
  const Agreement a = agreement(fts);
  MESSAGE("FTS vs DBB87 fig. 5, horizontal distance (a): z >= -600: max " << a.max_upper << " median "
                                                                          << a.median_upper << "; z < -600: max "
                                                                          << a.max_lower << " median "
                                                                          << a.median_lower);
  CHECK(a.max_upper < 0.25);
  CHECK(a.median_upper < 0.08);
  CHECK(a.max_lower < 0.75);
  CHECK(a.median_lower < 0.15);
  // The comparison discriminates: without stresslets (FT) the paths leave the published ones
  // (measured medians 0.28 a above -600 a, 0.79 a below; max 2.7 a and 6.0 a).
  const Agreement b = agreement(ft);
  MESSAGE("FT vs DBB87 fig. 5: z >= -600: max " << b.max_upper << " median " << b.median_upper << "; z < -600: max "
                                                << b.max_lower << " median " << b.median_lower);
  CHECK(b.max_upper > 1.0);
  CHECK(b.median_lower > 0.4);

  // Turning points of the paths, compared with the most extreme digitised point of that path in
  // the same window (points are ~8-15 a apart in depth, so the depth of a flat extremum is known
  // to ~15 a; x within 0.15 a, the reading error plus the sampling of the curve).
  struct Turn {
    const char* what;
    int sphere;
    double zlo, zhi;
    bool maximum;
    double x_pub, z_pub;  // digitised (DBB87 fig. 5)
  };
  for (const Turn& t : {Turn{"left sphere, leftmost excursion", 0, -300, -150, false, -4.2696, -221.03},
                        Turn{"middle sphere, rightmost excursion", 1, -350, -150, true, 7.2929, -258.93},
                        Turn{"right sphere, leftmost excursion", 2, -300, -100, false, 0.0594, -199.95},
                        Turn{"right sphere, later rightmost excursion", 2, -600, -400, true, 9.5195, -494.77},
                        Turn{"left sphere, rightmost excursion", 0, -700, -500, true, 5.9085, -601.20}}) {
    const auto e = extreme_x(fts, t.sphere, t.zlo, t.zhi, t.maximum);
    MESSAGE(std::string(t.what) << ": published x " << t.x_pub << " at z " << t.z_pub << "; ours x " << e[0] << " at z " << e[1]);
    CHECK(std::abs(e[0] - t.x_pub) < 0.15);
    CHECK(std::abs(e[1] - t.z_pub) < 20.0);
  }

  // Final grouping (fig. 5, bottom): the two spheres released at x = 0 and 7 end side by side at
  // the same depth (paths end at -784.3 and -784.2 a in the figure) while the sphere released at
  // x = -5 trails (its path ends at -769.4 a, ~15 a higher, if the three paths end at one time).
  // Ours when the pair is at z = -784.2: trailing sphere at about -772 a (12 a higher).
  const auto& A = fts.xz[0];
  const auto& B = fts.xz[1];
  const auto& C = fts.xz[2];
  std::size_t i = 0;
  while (0.5 * (B[i][2] + C[i][2]) > -784.2) ++i;
  MESSAGE("when the pair reaches z = -784.2: z_B " << B[i][2] << ", z_C " << C[i][2] << ", trailing z_A " << A[i][2]
                                                   << " (x: " << A[i][1] << ", " << B[i][1] << ", " << C[i][1] << ")");
  CHECK(std::abs(B[i][2] - C[i][2]) < 1.0);
  CHECK(A[i][2] - B[i][2] > 8.0);
  CHECK(A[i][2] - B[i][2] < 20.0);
  CHECK(B[i][1] < A[i][1]);  // order across: released at 0, then -5, then 7
  CHECK(A[i][1] < C[i][1]);
}
