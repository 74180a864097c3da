// Validation (issue 17): a sphere beside walls of wall particles, and the short-time
// self-diffusivity across a slit (Lee et al. 2024 [L24] figs. 4a and 5; docs/channels.md).
//
// Part "mobility" (kind 0). One sphere of radius 1 beside square patches of wall particles (radius 1,
// one layer, gap 0.05, open domain): one plane wall (patch side 80 a) and a slit of height 32 a
// (patches 64 a). Constrained Stokesian dynamics as [L24] fig. 4a (accelerated SD, FT, octree far
// field, tolerance 1e-4, lubrication below the published cutoff 2r/(a_i+a_j) = 4, i.e. gaps < 2 a);
// the mobility along x (parallel) and y (perpendicular) in units of 1/(6 pi mu a) against the gap h
// between the sphere's surface and the walls' boundary plane. References (xi = a/z, z = 1 + h):
// Faxen's parallel series 1 - 9/16 xi + 1/8 xi^3 - 45/256 xi^4 - 1/16 xi^5 and the leading terms
// of Brenner's perpendicular series 1 - 9/8 xi + 1/2 xi^3; for the slit, two flat planes: their
// point-force reflection (Liron & Mochon 1976) plus each wall's finite-size terms
// (tests/support/wall_mobility.hpp), and, for comparison, the two walls' series superposed.
//
// Part "diffusion" (kind 1). Slit of height H = 6 a between one-layer walls in a periodic box
// 16.4 x 10.05 x 16.4 a (8 x 8 wall sites of spacing 2.05 per wall), interior spheres of radius 1 in
// equilibrium hard-sphere configurations (random placement with Monte Carlo in the fluid region) at
// phi = 0.1, 0.25, 0.4 of the fluid volume. Accelerated SD (PME, lubrication), FTS (rigid spheres:
// the stresslets are solved for, as for the bulk D_s0 of validate_diffusion), tolerance 1e-4.
// For every interior particle i and direction d the solve with the unit force e_d on i (all other
// interior particles force- and torque-free, walls held) gives M_ii,dd; the short-time
// self-diffusivity is kT M_ii,dd ([L24] eq. 3.2), reported as D/D0 = 6 pi mu a M_ii,dd with
// D_par = (D_xx + D_zz)/2 and D_perp = D_yy against the centre height y - c_y. [L24] compares with
// Swan & Brady (2011); we have no table of those values, so the check is the trend [L24] reports:
// D_perp < D_par throughout at phi >= 0.25, comparable at the centre at phi = 0.1.
// Rows: kind 0: geometry (0 plane, 1 slit), h, par, perp, par_ref, perp_ref (flat walls), par_sup,
//               perp_sup (the single walls superposed; equal to the references for the plane);
//       kind 1: phi, seed, eta (centre height y - c_y), Dpar, Dperp, N (interior);
//       kind 2: phi, seed, N, seconds;  kind 3: the slit's references on a fine grid of h.
// Usage: [BENCH_SLIT_SEEDS=K] [BENCH_SLIT_PHI=phi] [BENCH_SLIT_SWEEPS=n] validate_slit [--quick]
// [--out DIR]; --quick: the slit at h = 3 and 15, and phi = 0.1 with one configuration (a smoke
// run). Full: K = 3 configurations per phi (seeds 1..K), about 10 min on 2 cores; K = 12 about
// 45 min. BENCH_SLIT_PHI: that volume fraction's diffusivities only (no mobility part);
// BENCH_SLIT_SWEEPS: the placement's Monte Carlo sweeps (0: random sequential addition alone);
// BENCH_SLIT_MIN_GAP: its hard-core margin [a] (defaults: those of [particles]; the scene parser
// checks the combination, naming the key); BENCH_SLIT_WALL_RADIUS, BENCH_SLIT_LAYERS: the walls'
// particle radius [a] and layers (defaults 1, 1; the box edge across the walls follows);
// BENCH_SLIT_TOLERANCE: the diffusion solves' [hydrodynamics] tolerance (default 1e-4, 1e-10..1e-2).
// Each knob is checked when read (bench::env_number: a malformed or out-of-range value stops the driver,
// naming it). The far field's own tolerance scales with (a_min/a_max)^3
// (engine/accuracy.cpp), so smaller wall particles make each solve dearer at the same tolerance.
#include "bench/harness.hpp"
#include "engine/core/channel.hpp"
#include "engine/hydrodynamics.hpp"
#include "engine/model.hpp"
#include "io/scene_toml.hpp"
#include "lubrication/near_field.hpp"
#include "tests/support/wall_mobility.hpp"
#include "trees/placement.hpp"
#include "trees/walls.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <sstream>

using namespace stokesian;

using test_support::brenner_perpendicular;
using test_support::faxen_parallel;

namespace {

double mobility(Hydrodynamics& h, const std::vector<Vec3>& walls, const Vec3& x, int d) {
  return test_support::sphere_among_walls(h, walls, x, d).U.back()[d];
}

}  // namespace

int main(int argc, char** argv) {
  const bench::Options opt = bench::parse_options(argc, argv);
  bench::Results res(opt.quick ? "slit_quick" : "slit");

  // Mobility beside walls (left out when BENCH_SLIT_PHI asks for one volume fraction's diffusivities).
  if (!std::getenv("BENCH_SLIT_PHI")) {
    ResolvedModel m;
    m.level = HydroModel::stokesian;
    m.solver = "accelerated_sd";
    m.moments = Moments::FT;
    m.far_field = "tree";
    Hydrodynamics h(m, 1.0, AmbientFlow{}, 1e-4, lubrication::near_field_params(HydroParams{}, Moments::FT), 1.0);
    for (int geo = opt.quick ? 1 : 0; geo < 2; ++geo) {
      ChannelParams c;
      c.kind = geo == 0 ? ChannelParams::Kind::plane : ChannelParams::Kind::slit;
      c.height = 32.0;
      c.length = c.depth = geo == 0 ? 80.0 : 64.0;
      const std::vector<Vec3> w = wall_particles(c, Domain{});
      const std::vector<double> gaps = opt.quick ? std::vector<double>{3.0, 15.0}
                                                 : std::vector<double>{0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0,
                                                                       6.0, 8.0, 10.0, 12.5, 15.0};
      for (double gap : gaps) {
        const double z1 = 1.0 + gap, z2 = geo == 0 ? 1e300 : 32.0 - z1;
        const Vec3 x(0.0, (geo == 0 ? 0.0 : -16.0) + z1, 0.0);
        const double par = mobility(h, w, x, 0), perp = mobility(h, w, x, 1);
        const double par_sup = faxen_parallel(1 / z1) + faxen_parallel(1 / z2) - 1;
        const double perp_sup = brenner_perpendicular(1 / z1) + brenner_perpendicular(1 / z2) - 1;
        const double par_ref = geo == 0 ? par_sup : test_support::slit_parallel(z1, 32.0);
        const double perp_ref = geo == 0 ? perp_sup : test_support::slit_perpendicular(z1, 32.0);
        std::printf("%s h %5.2f: parallel %.4f (flat %.4f, %+.1f %%), perpendicular %.4f (flat %.4f, %+.1f %%)\n",
                    geo == 0 ? "plane" : "slit ", gap, par, par_ref, 100 * (par / par_ref - 1), perp, perp_ref,
                    100 * (perp / perp_ref - 1));
        res.add({{"kind", 0}, {"geometry", geo}, {"h", gap}, {"walls", double(w.size())}},
                {{"par", par},
                 {"perp", perp},
                 {"par_ref", par_ref},
                 {"perp_ref", perp_ref},
                 {"par_sup", par_sup},
                 {"perp_sup", perp_sup}});
      }
    }
  }

  // The slit's flat-wall references on a fine grid, for the chart.
  for (int i = 0; i <= 60; ++i) {
    const double gap = 0.05 * std::pow(15.0 / 0.05, i / 60.0), z1 = 1.0 + gap;
    res.add({{"kind", 3}, {"h", gap}},
            {{"par_ref", test_support::slit_parallel(z1, 32.0)}, {"perp_ref", test_support::slit_perpendicular(z1, 32.0)}});
  }

  // Self-diffusivity across a 6 a slit.
  std::vector<double> phis = opt.quick ? std::vector<double>{0.1} : std::vector<double>{0.1, 0.25, 0.4};
  if (std::getenv("BENCH_SLIT_PHI")) phis = {bench::env_number("BENCH_SLIT_PHI", 0, 1e-3, 0.6)};
  // Configurations per phi: 3, or BENCH_SLIT_SEEDS (1-100).
  const int seeds = opt.quick ? 1 : int(bench::env_number("BENCH_SLIT_SEEDS", 3, 1, 100, true));
  // Monte Carlo sweeps of the placement ([particles] equilibration_sweeps; default 100 there).
  const long sweeps = long(bench::env_number("BENCH_SLIT_SWEEPS", -1, 0, 1e6, true));  // -1: the default
  // The placement's hard-core margin ([particles] min_gap [a], default there 1e-3).
  const char* gap_env = std::getenv("BENCH_SLIT_MIN_GAP");
  const double min_gap = bench::env_number("BENCH_SLIT_MIN_GAP", PlacementParams{}.min_gap, 0, 1);
  // The wall layout ([walls] radius [a] and layers; the [walls] defaults otherwise): the box edge
  // across the walls holds H + 2 x thickness + gap (trees/walls.hpp).
  const char* rw_env = std::getenv("BENCH_SLIT_WALL_RADIUS");
  const char* layers_env = std::getenv("BENCH_SLIT_LAYERS");
  ChannelParams layout;
  layout.kind = ChannelParams::Kind::slit;
  layout.height = 6.0;
  layout.radius = bench::env_number("BENCH_SLIT_WALL_RADIUS", layout.radius, 0.1, 2);
  layout.layers = long(bench::env_number("BENCH_SLIT_LAYERS", double(layout.layers), 1, 4, true));
  const double r_w = layout.radius;
  const long layers = layout.layers;
  const double box_y = layout.height + 2 * wall_thickness(layout) + layout.gap;
  const double tolerance = bench::env_number("BENCH_SLIT_TOLERANCE", 1e-4, 1e-10, 1e-2);
  for (double phi : phis)
    for (int seed = 1; seed <= seeds; ++seed) {
      std::ostringstream scene;
      scene.precision(17);
      scene << "[domain]\nkind = \"periodic\"\nbox = [16.4, " << box_y << ", 16.4]\n[walls]\nkind = \"slit\"\nheight = 6.0\n";
      if (rw_env || layers_env) scene << "radius = " << r_w << "\nlayers = " << layers << "\n";
      scene << "[particles]\ngenerate = \"random\"\nvolume_fraction = " << phi << "\nseed = " << seed;
      if (sweeps >= 0) scene << "\nequilibration_sweeps = " << sweeps;
      if (gap_env) scene << "\nmin_gap = " << min_gap;
      scene << "\n[hydrodynamics]\nmodel = \"stokesian\"\nsolver = \"accelerated\"\nmoments = \"FTS\"\ntolerance = " << tolerance << "\n";
      const Scene s = io::parse_scene(scene.str(), "slit_diffusion.toml");
      const ResolvedModel m = resolve_model(s);
      Hydrodynamics h(m, 1.0, AmbientFlow{}, s.hydro.tolerance, lubrication::near_field_params(s.hydro, m.moments), 1.0);
      const Configuration conf{s.positions, s.radii, s.domain};
      const std::size_t n = s.positions.size(), ni = s.interior_count();
      const auto t0 = std::chrono::steady_clock::now();
      h.prepare(conf);
      const std::vector<Vec3> zero(n, Vec3::Zero());
      for (std::size_t i = 0; i < ni; ++i) {
        double D[3];
        for (int d = 0; d < 3; ++d) {
          std::vector<Vec3> F = zero;
          F[i][d] = 6 * kPi;
          D[d] = h.solve(conf, s.fixed, F, zero).U[i][d];
        }
        res.add({{"kind", 1}, {"phi", phi}, {"seed", double(seed)}, {"eta", s.positions[i].y() - 0.5 * box_y},
                 {"N", double(ni)}},
                {{"Dpar", 0.5 * (D[0] + D[2])}, {"Dperp", D[1]}});
      }
      const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("diffusion phi %.2f seed %d: %zu interior spheres, %zu wall particles, %.1f s\n", phi, seed, ni,
                  s.wall_count, sec);
      res.add({{"kind", 2}, {"phi", phi}, {"seed", double(seed)}, {"N", double(ni)},
               {"sweeps", double(sweeps >= 0 ? sweeps : PlacementParams{}.equilibration_sweeps)}, {"min_gap", min_gap},
               {"wall_radius", r_w}, {"layers", double(layers)}, {"walls", double(s.wall_count)},
               {"tolerance", tolerance}},
              {{"seconds", sec}});
    }
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
