// Resource estimates; the formulas are stated in resources.hpp.
#include "engine/resources.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/types.hpp"
#include "engine/methods.hpp"
#include "engine/pair_forces.hpp"
#include "engine/sd_accelerated.hpp"
#include "lubrication/near_field.hpp"
#include "ewald/lattice.hpp"
#include "ewald/pme_parameters.hpp"
#include "trees/tree_mobility.hpp"
#include "ewald/real_space.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace stokesian {

namespace {

using Keys = std::vector<std::pair<std::string, std::string>>;

std::string num(double x) {
  char b[48];
  std::snprintf(b, sizeof b, "%.4g", x);
  return b;
}

// The particle keys the scene uses (count, volume_fraction, positions or file).
Keys particle_keys(const Scene& s) {
  Keys k;
  for (const char* key : {"count", "volume_fraction", "positions", "file"})
    if (s.lines.count(std::string("particles.") + key)) k.push_back({"particles", key});
  if (k.empty()) k.push_back({"particles", "positions/file/count"});
  return k;
}

void add_key(Keys& k, const Scene& s, const char* table, const char* key, bool always = false) {
  if (always || s.lines.count(std::string(table) + "." + key)) k.push_back({table, key});
}

// Number density [1/a^3] (resources.hpp).
double density(const Scene& s, double a_max) {
  const double n = double(s.positions.size());
  if (s.domain.periodic()) return n / s.domain.box.prod();
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& x : s.positions) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const Vec3 extent = (hi - lo).array() + 2.0 * a_max;
  return n / extent.prod();
}

double neighbours(double n, double rho, double r) { return std::min(n - 1.0, rho * 4.0 / 3.0 * kPi * r * r * r); }

// Far-field product cost per pair [s] for the direct sum at d entries per particle.
double direct_pair_seconds(int d) { return d == 3 ? 11e-9 : d == 6 ? 18e-9 : 50e-9; }

}  // namespace

const ResourceComponent& ResourceEstimate::largest() const {
  return *std::max_element(components.begin(), components.end(),
                           [](const ResourceComponent& a, const ResourceComponent& b) { return a.bytes < b.bytes; });
}

const ResourceComponent* ResourceEstimate::find(const std::string& prefix) const {
  for (const auto& c : components)
    if (c.name.compare(0, prefix.size(), prefix) == 0) return &c;
  return nullptr;
}

std::string ResourceEstimate::describe(const std::string& indent) const {
  std::ostringstream o;
  for (const auto& c : components) o << indent << c.name << ": " << format_bytes(c.bytes) << " (" << c.formula << ")\n";
  o << indent << "peak memory: about " << format_bytes(peak_bytes) << "\n";
  o << indent << "time per step: about " << num(seconds_per_step)
    << " s on one thread (rough, from operation counts; docs/reliability.md)";
  return o.str();
}

std::string scene_keys(const Scene& s, const Keys& keys) {
  std::string out;
  for (const auto& [table, key] : keys) {
    if (!out.empty()) out += ", ";
    out += "[" + table + "] " + key;
    const auto it = s.lines.find(table + "." + key);
    if (it != s.lines.end() && it->second > 0) out += " (line " + std::to_string(it->second) + ")";
  }
  return out;
}

ResourceEstimate estimate_resources(const Scene& s, const ResolvedModel& model) {
  ResourceEstimate e;
  const double N = double(s.positions.size());
  const int d = dof_per_particle(model.moments);
  const double n = d * N;
  double a_min = 1.0, a_max = 1.0;
  if (!s.radii.empty()) {
    const auto [lo, hi] = std::minmax_element(s.radii.begin(), s.radii.end());
    a_min = *lo;
    a_max = *hi;
  }
  const double rho = N > 0 ? density(s, a_max) : 0.0;
  const std::string dN = "d = " + std::to_string(d) + ", N = " + num(N);
  const Keys pk = particle_keys(s);
  Keys model_keys = pk;
  add_key(model_keys, s, "hydrodynamics", "model");
  add_key(model_keys, s, "hydrodynamics", "moments");
  add_key(model_keys, s, "hydrodynamics", "far_field");

  const double evaluations = model.integrator == "midpoint" ? 2
                             : model.integrator == "fixman" ? 3
                             : model.integrator == "rkf45"  ? 6
                                                            : 1;
  double eval_seconds = 0.1e-6 * N;

  e.components.push_back({"scene and particle arrays", kBytesPerParticle * N,
                          num(kBytesPerParticle) + " bytes per particle, N = " + num(N), pk});

  if (!s.forces.pair.empty() && N > 1) {
    double hc = 0.0;
    for (const auto& p : s.forces.pair) hc = std::max(hc, forces::resolved_cutoff(p, a_max));
    const double nb = neighbours(N, rho, hc + 2 * a_max);
    Keys k = pk;
    k.push_back({"forces.pair", "cutoff"});
    e.components.push_back({"pair-force neighbour list", 48.0 * N * nb,
                            "48 bytes x N x " + num(nb) + " neighbours within the cut-off", k});
    eval_seconds += 0.05e-6 * N * nb / 2;
  }

  if (model.level != HydroModel::free_draining) {
    const std::string solver = solver_of(model);
    const SolverEntry* se = hydro_solvers().find(solver);
    const bool dense_far = model.far_field == "ewald" || (se && se->needs_dense);
    double product = 0.0;  // seconds per far-field product
    if (dense_far) {
      e.components.push_back({"far-field matrix (" + model.far_field + ", dense)", 8.0 * n * n,
                              "(d N)^2 doubles, " + dN, model_keys});
      if (model.far_field == "ewald") {
        product = 1e-9 * n * n;
        eval_seconds += 40e-6 * N * N / 2 * (d * d / 9.0);  // matrix rebuilt for each configuration
      } else {
        product = direct_pair_seconds(d) * N * N;
      }
    } else if (model.far_field == "pme") {
      try {
        const ewald::Lattice lattice = ewald::Lattice::from_domain(s.domain);
        const double ff_tol = derive_knobs(s.hydro.tolerance, model.level, a_max / a_min, model.fixed_particles).far_field;  // as the run asks
        ewald::PmeOptions po;  // as the run's operator chooses them (engine/hydrodynamics.cpp)
        po.products_per_update = far_field_products_per_configuration(model);
        const ewald::PmeParameters p =
            ewald::pme_parameters(ff_tol, lattice, int(std::min(N, 2e9)), a_min, a_max, model.moments, po);
        const double G = double(p.grid[0]) * p.grid[1] * ((p.grid[2] + p.support + 3) / 4 * 4);  // padded rows
        const double spectral = double(p.grid[0]) * p.grid[1] * (p.grid[2] / 2 + 1);
        Keys gk = model_keys;
        add_key(gk, s, "domain", "box", true);
        add_key(gk, s, "hydrodynamics", "tolerance");
        // ewald/pme.hpp: 3 force-density fields (padded rows) and their spectra, and the Fourier
        // kernel's two factors per spectral point.
        e.components.push_back({"PME grid", 8.0 * 3 * G + 16.0 * 3 * spectral + 16.0 * spectral,
                                "grid " + std::to_string(p.grid[0]) + " x " + std::to_string(p.grid[1]) + " x " +
                                    std::to_string(p.grid[2]) +
                                    " x 3 doubles, its spectrum and kernel, from far-field tolerance " + num(ff_tol),
                                gk});
        const double P = p.support;
        const double pairs = N * neighbours(N, rho, p.cutoff_gap + 2 * a_max) / 2;
        // Pair data and scalar cache of the real-space sum (ewald/real_space.hpp), within the
        // budget the parameters carry.
        double cache = ewald::RealSpaceSum::cache_bytes_for(2 * pairs, model.moments);
        if (cache > p.cache_bytes) cache = 0.0;
        e.components.push_back({"PME windows and pairs", 8.0 * (12 * P + 2) * N + 12.0 * N +
                                                              ewald::RealSpaceSum::pair_bytes_for(2 * pairs) + cache,
                                "support P = " + num(P) + ", " + num(pairs) + " real-space pairs within cut-off gap " +
                                    num(p.cutoff_gap) + " a",
                                gk});
        product = p.est_cost;  // the PME cost model (ewald/pme_parameters.hpp), one thread, set-up shared
      } catch (const std::invalid_argument&) {
        // The box is too small for the minimum-image real-space sum: the operator reports it.
      }
    } else if (model.far_field == "tree") {
      const double ff_tol = derive_knobs(s.hydro.tolerance, model.level, a_max / a_min, model.fixed_particles).far_field;
      const trees::TreeParameters p = trees::tree_parameters(std::max(ff_tol, 1e-14), model.moments);
      Keys tk = model_keys;
      add_key(tk, s, "hydrodynamics", "tolerance");
      e.components.push_back({"octree expansions and lists", trees::tree_memory_bytes(p, model.moments, N),
                              "theta " + num(p.theta) + ", order " + std::to_string(p.order) +
                                  " from far-field tolerance " + num(ff_tol) + " (trees/tree_mobility.hpp)",
                              tk});
      product = trees::tree_product_seconds(p, model.moments, N);
    } else {
      product = direct_pair_seconds(d) * N * N;
    }
    if (solver == "mobility_cg") {
      const double vectors = 8 + (model.brownian ? 202 : 0);
      e.components.push_back({"Krylov vectors", 8.0 * n * vectors,
                              num(vectors) + " vectors of d N doubles (CG" +
                                  std::string(model.brownian ? ", Lanczos basis" : "") + "), " + dN,
                              model_keys});
      // one product, or ~20 CG iterations when velocities are given (fixed particles, FTS strain)
      eval_seconds += far_field_products_per_solve(model) * product;
    } else if (solver == "dense_sd") {
      e.components.push_back({"SD resistance and factors", 3 * 8.0 * n * n,
                              "3 (d N)^2 doubles: far-field factor (or the held block's, kept, and the mobile "
                              "Schur complement's), resistance block, its Cholesky factor; " + dN,
                              model_keys});
      // Flops of the factorisations (engine/sd_dense.hpp): n^3 (5/3) without held particles; with
      // n_H entries held, n_H^2 n_I + n_I^2 n_H + (5/3) n_I^3, plus n_H^3 / 3 per configuration in a
      // sheared box (the held block changes with the strain; elsewhere it is factored once).
      double held = 0.0;
      for (char f : s.fixed) held += f ? d : 0.0;
      const double ni = n - held;
      const bool sheared = s.flow.kind == FlowParams::Kind::simple_shear && s.domain.periodic();
      const double flops = held > 0 ? held * held * ni + ni * ni * held + 5.0 / 3.0 * ni * ni * ni +
                                          (sheared ? held * held * held / 3.0 : 0.0)
                                    : 5.0 / 3.0 * n * n * n;
      eval_seconds += flops / 5e9 + 7e-6 * N * N / 2 * (d * d / 121.0);
    } else {
      eval_seconds += far_field_products_per_solve(model) * product;
    }
    if (model.brownian) eval_seconds += 30 * product / evaluations;  // one square root per step
    if (model.level == HydroModel::stokesian) {
      const double cut = lubrication::near_field_params(s.hydro, model.moments).cutoff;
      const double r_nf = cut * a_max;
      const double p_nf = N * neighbours(N, rho, r_nf) / 2;
      Keys k = model_keys;
      add_key(k, s, "hydrodynamics", "lubrication_cutoff");
      // Symmetric d x d blocks (lubrication/block_matrix.hpp), one per particle and pair; dense SD
      // also keeps both triangles in compressed columns (12 bytes per entry) and their triplets (16).
      const bool dense = model.solver == "dense_sd";
      e.components.push_back({"near-field sparse matrix",
                              (N + p_nf) * d * d * 8.0 + (dense ? (N + 2 * p_nf) * d * d * 28.0 : 0.0),
                              num(p_nf) + " pairs with 2r/(a_i+a_j) < " + num(cut) + ", " + dN,
                              k});
      if (model.brownian) {
        // Lanczos basis of the far-field Brownian force M^{-1/2} psi (engine/brownian.hpp): one
        // vector of d N doubles per iteration, ~100 at most in bench_brownian.
        e.components.push_back({"Brownian force (Lanczos basis)", 100 * 8.0 * n,
                                "about 100 vectors of d N doubles, " + dN, model_keys});
      }
      if (model.solver == "accelerated_sd") {
        // GMRES basis (restart + 1 vectors), the pair blocks' diagonal parts of one chunk of 16384
        // pairs during assembly (2 d^2 doubles per pair), the product's slice buffers (at most
        // kChunks d N doubles), the factorised velocity block (~a third of R_nf's entries).
        const double gmres = (AcceleratedStokesianDynamics::kRestart + 1) * N * d * 8.0;
        const double buffer = std::min(p_nf, 16384.0) * 2.0 * d * d * 8.0 +
                              lubrication::SymmetricBlockMatrix::kChunks * n * 8.0;  // slices' product buffers
        const double factored = (N + 2 * p_nf) * d * d * 12.0 / 3.0;
        // Held particles: the held-row preconditioner's coarse part, E (at most kHeldCoarseColumns
        // squared) and A Z when kept (at most kHeldCoarseKept entries; engine/sd_accelerated.hpp).
        double held = 0.0;
        for (char f : s.fixed) held += f ? 1.0 : 0.0;
        const double columns = std::min(double(AcceleratedStokesianDynamics::kHeldCoarseColumns), 12.0 * held / 16.0);
        const double coarse = held > 0 ? columns * columns * 8.0 * 2.0 +
                                             (n * columns <= AcceleratedStokesianDynamics::kHeldCoarseKept ? n * columns * 8.0 : 0.0)
                                       : 0.0;
        e.components.push_back({"accelerated SD solve", gmres + buffer + factored + coarse,
                                "GMRES(" + std::to_string(AcceleratedStokesianDynamics::kRestart) +
                                    ") basis, near-field assembly buffer, factorised velocity block" +
                                    (held > 0 ? ", held preconditioner's coarse part" : ""),
                                model_keys});
      }
    }
  }
  for (const auto& c : e.components) e.peak_bytes += c.bytes;
  e.seconds_per_step = evaluations * eval_seconds;
  return e;
}

void require_resources(const Scene& s, const ResourceEstimate& est, const MemoryBudget& budget, std::FILE* warn) {
  if (!budget.known()) {
    if (warn)
      std::fprintf(warn,
                   "stokesian: warning: %s: available memory unknown (no /proc/meminfo, no STOKESIAN_MEMORY_LIMIT); "
                   "the estimated peak of %s is not checked\n",
                   s.source.c_str(), format_bytes(est.peak_bytes).c_str());
    return;
  }
  if (est.components.empty()) return;
  const ResourceComponent& big = est.largest();
  if (est.peak_bytes > budget.bytes) {
    throw ConfigError(s.source + ": this scene needs about " + format_bytes(est.peak_bytes) +
                      " of memory (largest part: " + big.name + ", " + format_bytes(big.bytes) + ": " + big.formula +
                      "), but only " + format_bytes(budget.bytes) + " is available (" + budget.source +
                      "); driven by " + scene_keys(s, big.keys) +
                      " (allowed: an estimated peak within the available memory; docs/reliability.md)");
  }
  if (warn && est.peak_bytes > kMemoryWarnFraction * budget.bytes)
    std::fprintf(warn,
                 "stokesian: warning: %s: the run will need about %s of the %s available (%s); largest part: %s, %s, "
                 "driven by %s\n",
                 s.source.c_str(), format_bytes(est.peak_bytes).c_str(), format_bytes(budget.bytes).c_str(),
                 budget.source.c_str(), big.name.c_str(), format_bytes(big.bytes).c_str(),
                 scene_keys(s, big.keys).c_str());
}

}  // namespace stokesian
