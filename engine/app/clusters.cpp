#include "engine/app/clusters.hpp"

#include "engine/core/errors.hpp"
#include "io/h5md.hpp"
#include "io/scene_toml.hpp"
#include "trees/clusters.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace stokesian::app {

int clusters(const std::string& trajectory, const ClusterOptions& opt, std::FILE* out) {
  if (!(opt.bond_gap >= 0.0) || !std::isfinite(opt.bond_gap))
    throw ConfigError("clusters: --gap " + std::to_string(opt.bond_gap) + " must be a finite gap >= 0 [a]");
  if (opt.min_size < 2) throw ConfigError("clusters: --min-size " + std::to_string(opt.min_size) + " must be >= 2");
  if (opt.every < 1) throw ConfigError("clusters: --every " + std::to_string(opt.every) + " must be >= 1");
  const io::TrajectoryInfo info = io::inspect_trajectory(trajectory);
  const Scene scene = io::parse_scene(info.scene_toml, trajectory + " (stored scene)");
  std::string path = opt.out;
  if (path.empty()) {
    path = trajectory;
    if (path.size() > 3 && path.compare(path.size() - 3, 3, ".h5") == 0) path.resize(path.size() - 3);
    path += ".clusters.h5";
  }

  struct Row {
    std::int64_t step;
    double time;
    long particles, clusters, largest;
    double mean_size, weight_mean_size, mean_radius;
    trees::FractalFit fractal;
    std::vector<long> histogram;
  };
  std::vector<Row> rows;
  auto column = [](const char* name) {
    io::TableColumn c;
    c.name = name;
    return c;
  };
  io::TableColumn c_frame = column("frame"), c_size = column("size"), c_mass = column("mass"), c_x = column("centre_x"),
                  c_y = column("centre_y"), c_z = column("centre_z"), c_rg = column("radius_of_gyration"),
                  c_feret = column("feret_diameter"), c_vx = column("velocity_x"), c_vy = column("velocity_y"),
                  c_vz = column("velocity_z"), c_span = column("spanning");
  const bool velocities = info.records("velocity");
  std::fprintf(out, "# %s: clusters by surface gap <= %g a (docs/clusters.md)\n", trajectory.c_str(), opt.bond_gap);
  std::fprintf(out, "# %10s %12s %9s %9s %9s %9s %9s %9s %9s %8s\n", "step", "time", "particles", "clusters",
               "singlets", "doublets", "triplets", "largest", "mean", "D_f");
  for (std::int64_t k = 0; k < info.frames; k += opt.every) {
    const io::Snapshot f = io::read_frame(trajectory, k, false);
    const std::size_t n = f.position.size();
    // Who takes part: not an empty slot, not a wall or fixed particle of the scene.
    std::vector<char> skip(n, 0);
    if (!f.id.empty())
      for (std::size_t i = 0; i < n; ++i) skip[i] = f.id[i] < 0;
    if (n == scene.positions.size() && !scene.fixed.empty()) {
      for (std::size_t i = 0; i < n; ++i) skip[i] = skip[i] || scene.fixed[i];
    } else {
      for (std::size_t i = n - std::min(n, scene.wall_count); i < n; ++i) skip[i] = 1;
    }
    const Domain d = f.periodic ? Domain::periodic_box(f.box, f.shear_strain) : Domain{};
    // NaN positions (empty slots) must not reach the cell list.
    std::vector<Vec3> x = f.position;
    for (std::size_t i = 0; i < n; ++i)
      if (skip[i]) x[i] = Vec3::Zero();
    const trees::Clusters c = trees::find_clusters(x, f.radius, d, opt.bond_gap, &skip);
    const auto shapes = trees::cluster_shapes(c, x, f.radius, d, velocities ? f.velocity : std::vector<Vec3>{});
    Row r;
    r.step = f.step;
    r.time = f.time;
    r.histogram = trees::size_histogram(c);
    r.clusters = long(c.members.size());
    r.particles = 0;
    double sum_a = 0.0, sum_n2 = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      if (!skip[i]) {
        ++r.particles;
        sum_a += f.radius[i];
      }
    for (const auto& m : c.members) sum_n2 += double(m.size()) * double(m.size());
    r.largest = c.members.empty() ? 0 : long(c.members[0].size());
    r.mean_size = r.clusters ? double(r.particles) / double(r.clusters) : NAN;
    r.weight_mean_size = r.particles ? sum_n2 / double(r.particles) : NAN;
    r.mean_radius = r.particles ? sum_a / double(r.particles) : NAN;
    r.fractal = trees::fractal_dimension(shapes, r.particles ? r.mean_radius : 1.0, opt.min_size);
    const double frame = double(rows.size());
    for (const auto& s : shapes) {
      c_frame.num.push_back(frame);
      c_size.num.push_back(double(s.size));
      c_mass.num.push_back(s.mass);
      c_x.num.push_back(s.centre.x());
      c_y.num.push_back(s.centre.y());
      c_z.num.push_back(s.centre.z());
      c_rg.num.push_back(s.radius_of_gyration);
      c_feret.num.push_back(s.feret);
      c_vx.num.push_back(velocities ? s.velocity.x() : NAN);
      c_vy.num.push_back(velocities ? s.velocity.y() : NAN);
      c_vz.num.push_back(velocities ? s.velocity.z() : NAN);
      c_span.num.push_back(s.spanning ? 1.0 : 0.0);
    }
    auto h = [&](std::size_t s) { return s < r.histogram.size() ? r.histogram[s] : 0L; };
    std::fprintf(out, "  %10lld %12.6g %9ld %9ld %9ld %9ld %9ld %9ld %9.4g %8.4g\n", static_cast<long long>(r.step),
                 r.time, r.particles, r.clusters, h(1), h(2), h(3), r.largest, r.mean_size, r.fractal.dimension);
    rows.push_back(std::move(r));
  }

  // Size histogram [frames][largest size over all frames] and its growth rate dN_s/dt: centred
  // differences between analysed frames, one-sided at the first and last (NaN with one frame).
  std::size_t width = 1;
  for (const Row& r : rows) width = std::max(width, r.histogram.size() - 1);
  const std::size_t nf = rows.size();
  io::Matrix2D hist{"size_histogram", nf, width, std::vector<double>(nf * width, 0.0)};
  io::Matrix2D rate{"growth_rate", nf, width, std::vector<double>(nf * width, NAN)};
  for (std::size_t k = 0; k < nf; ++k)
    for (std::size_t s = 1; s < rows[k].histogram.size(); ++s)
      hist.data[k * width + s - 1] = double(rows[k].histogram[s]);
  if (nf >= 2)
    for (std::size_t k = 0; k < nf; ++k) {
      const std::size_t lo = k == 0 ? 0 : k - 1, hi = k + 1 == nf ? k : k + 1;
      const double dt = rows[hi].time - rows[lo].time;
      for (std::size_t s = 0; s < width; ++s)
        rate.data[k * width + s] = dt > 0 ? (hist.data[hi * width + s] - hist.data[lo * width + s]) / dt : NAN;
    }
  io::TableColumn f_step = column("step"), f_time = column("time"), f_particles = column("particles"),
                  f_clusters = column("clusters"), f_largest = column("largest"), f_mean = column("mean_size"),
                  f_wmean = column("weight_mean_size"), f_df = column("fractal_dimension"),
                  f_kf = column("fractal_prefactor"), f_ma = column("mean_radius"), f_dfn = column("fractal_clusters");
  for (const Row& r : rows) {
    f_step.num.push_back(double(r.step));
    f_time.num.push_back(r.time);
    f_particles.num.push_back(double(r.particles));
    f_clusters.num.push_back(double(r.clusters));
    f_largest.num.push_back(double(r.largest));
    f_mean.num.push_back(r.mean_size);
    f_wmean.num.push_back(r.weight_mean_size);
    f_df.num.push_back(r.fractal.dimension);
    f_kf.num.push_back(r.fractal.prefactor);
    f_ma.num.push_back(r.mean_radius);
    f_dfn.num.push_back(double(r.fractal.clusters));
  }
  char gap[64], ms[32];
  std::snprintf(gap, sizeof gap, "%.10g", opt.bond_gap);
  std::snprintf(ms, sizeof ms, "%ld", opt.min_size);
  io::write_tables_h5(
      path,
      {{"frames", {f_step, f_time, f_particles, f_clusters, f_largest, f_mean, f_wmean, f_ma, f_df, f_kf, f_dfn}},
       {"clusters", {c_frame, c_size, c_mass, c_x, c_y, c_z, c_rg, c_feret, c_vx, c_vy, c_vz, c_span}}},
      {hist, rate},
      {{"trajectory", trajectory}, {"bond_gap", gap}, {"fractal_min_size", ms}, {"definitions", "docs/clusters.md"}});
  std::fprintf(out, "# wrote %s\n", path.c_str());
  return 0;
}

}  // namespace stokesian::app
