// Benchmark of the fast PME far field (issue 12, ewald/pme.hpp): time per product against N, moments,
// volume fraction and tolerance, its phases, 1 and 2 threads, the achieved error, memory, the
// speed-accuracy trade with the direct O(N^2) sum as the scale, Lees-Edwards shear, and the new
// product on the configurations of the previous implementation's benchmark (bench_ewald,
// bench_pme_large) for a like-for-like comparison. Charted by bench/plot_pme.py.
//
// Configurations (kinds 0-2): n spheres of radius a = 1, centres uniform in the cubic periodic box
// [0, L)^3, L = (n 4 pi / 3 / phi)^(1/3), drawn from std::mt19937_64(seed = n); overlaps allowed
// (the real-space pair count depends on the density only). Input x uniform in [-1, 1]^(dof N).
// Achieved error = ||M_pme x - M_ref x|| / ||M_ref x||, M_ref x the PME product of the same
// configuration at tolerance 1e-12 (1e-10 for N >= --ref10-from, default 3 10^5, where the 1e-12
// object is too large; none where even that exceeds --mem-gb; 1e-11 where the 1e-12 object cannot be built; ref_tol says which). tests/test_ewald.cpp checks the PME against the dense
// Ewald sum over the tolerance sweep, so the reference is good to about its own tolerance.
//
// Rows (params are numbers; "kind" tells them apart):
//   kind 0, PME: N, phi, dof, tol, threads, grid (M0), support P, shape, xi, cutoff_gap,
//     pairs_per_particle, est_real/est_wave/est_alias/est_cost (model), error, ref_tol, load1 (one-minute
//     load average after the row: with other runnable work, 2-thread times are not valid), rss_mb
//     (peak RSS of the process during this row, MB: /proc/self/clear_refs reset, VmHWM);
//     phases setup (constructor), wave (apply_wave), real (apply_real), product (apply).
//   kind 1, direct open-domain mobility_product (engine/kernels/far_field.hpp) on the phi = 0.1
//     configuration: N, dof, threads; phase product.
//   kind 2, Lees-Edwards (FTS, phi 0.1): N, dof, tol, threads, strain, grid0..2, support, error
//     (against the reference of the same strain), kept (1: the strain-0.31 object is the strain-0.3
//     one after set_configuration with the new strain and kept grid and plans), fresh_diff (relative
//     difference from a new object at that strain); phases setup (constructor, or set_configuration
//     for the strain change), product.
//   kind 3, new PME on the previous benchmark's configurations (bench::random_cloud, radii 0.5-1.5,
//     phi 0.1, seed N, L = (N 4.19 1.25 / 0.1)^(1/3)): N, dof, tol, threads, error; phases setup,
//     product. Previous numbers: bench/results/ewald_pme.json and pme_large.json (commit 07f964e).
//   kind 4, the reference products (2 threads): N, phi, dof, ref_tol, strain, grid, support,
//     pairs_per_particle, rss_mb; phases setup, product.
//   bench_pme [--quick] [--out DIR] [--max-n N] [--ref10-from N] [--only N] [--mem-gb G]
//             [--name NAME] [--moments F|FTS|F,FTS] [--tols a,b,..] [--no-reference] [--unguarded]
// (--name: results file NAME.json; --moments, --tols: restrict the sweep; --no-reference: no error;
// --unguarded: rows at N > 10^5 without a smaller-N row to scale from are run, e.g. with --only)
// (--only: that N alone, e.g. 300000; --mem-gb, default 14: skip rows whose peak RSS scaled from the
// previous N would exceed it, printed). N > 10^5 runs last, on 2 threads with one timed repeat;
// error -1 where the reference was skipped.
// --quick (~10 s on two free cores, ~40 s on a loaded machine): N = 1000 and 2000, tolerances 1e-3, 1e-4, 1e-6 (and 1e-2, 1e-8,
// 1e-10 at N = 1000, phi = 0.1), Lees-Edwards, direct and the previous configuration at N = 1000.
// Two-thread times need two free cores: with other runnable processes every OpenMP region of a product
// can wait a scheduler time slice (measured: ~0.1 s per product whatever N, against ms on one thread).
// The full run: N = 10^3 ... 10^6 (with 3 10^k), --max-n caps it.
#include "bench/harness.hpp"
#include "engine/kernels/far_field.hpp"
#include "ewald/pme.hpp"

#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

using namespace stokesian;

namespace {

constexpr double kPi = 3.14159265358979323846;

double rel_error(const VecX& y, const VecX& ref) { return (y - ref).norm() / ref.norm(); }

struct Config {
  std::vector<Vec3> x;
  std::vector<double> a;
  Domain dom;
};

// Monodisperse a = 1, centres uniform in the cube (overlaps allowed), volume fraction phi.
Config spheres(long n, double phi, unsigned long seed) {
  const double L = std::cbrt(double(n) * 4.0 * kPi / 3.0 / phi);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Config c;
  c.x.reserve(n);
  for (long i = 0; i < n; ++i) {
    const double x = L * u(rng), y = L * u(rng), z = L * u(rng);
    c.x.emplace_back(x, y, z);
  }
  c.a.assign(n, 1.0);
  c.dom.kind = Domain::Kind::periodic;
  c.dom.box = Vec3(L, L, L);
  return c;
}

VecX random_input(long len, unsigned long seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  VecX v(len);
  for (long i = 0; i < len; ++i) v[i] = u(rng);
  return v;
}

// Peak resident set: reset the high-water mark (Linux clear_refs "5"), read VmHWM later.
bool reset_peak_rss() {
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  return bool(f);
}
double peak_rss_mb() {
  std::ifstream f("/proc/self/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;  // kB
  rusage r{};
  getrusage(RUSAGE_SELF, &r);
  return double(r.ru_maxrss) / 1024.0;
}

// One-minute load average (other work on the machine: 2-thread times are only valid near load 2).
double load1() {
  std::ifstream f("/proc/loadavg");
  double l = -1.0;
  f >> l;
  return l;
}

template <class F>
double median_of(F&& f, int reps) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) t.push_back(bench::time_once(f));
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

int reps_for(long n, bool quick) { return quick ? 3 : n <= 10000 ? 5 : n <= 100000 ? 3 : 1; }

}  // namespace

int main(int argc, char** argv) {
  // Own options first, the harness's (--quick, --out) after.
  long max_n = 1000000, ref10_from = 300000, only = 0;
  double mem_gb = 14.0;
  std::string name = "pme", moments = "F,FTS";
  bool no_reference = false, unguarded = false;
  std::vector<double> only_tols;
  std::vector<char*> rest{argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--max-n") && i + 1 < argc) max_n = std::atol(argv[++i]);
    else if (!std::strcmp(argv[i], "--ref10-from") && i + 1 < argc) ref10_from = std::atol(argv[++i]);
    else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) only = std::atol(argv[++i]);
    else if (!std::strcmp(argv[i], "--mem-gb") && i + 1 < argc) mem_gb = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--name") && i + 1 < argc) name = argv[++i];
    else if (!std::strcmp(argv[i], "--moments") && i + 1 < argc) moments = argv[++i];
    else if (!std::strcmp(argv[i], "--tols") && i + 1 < argc) {
      for (char* t = std::strtok(argv[++i], ","); t; t = std::strtok(nullptr, ",")) only_tols.push_back(std::atof(t));
    } else if (!std::strcmp(argv[i], "--no-reference")) no_reference = true;
    else if (!std::strcmp(argv[i], "--unguarded")) unguarded = true;
    else rest.push_back(argv[i]);
  }
  const bench::Options opt = bench::parse_options(int(rest.size()), rest.data());
  const bool quick = opt.quick;
  bench::Results res(quick ? "pme_quick" : name);
  const int max_threads = std::min(2, omp_get_max_threads());
  const bool rss_reset = reset_peak_rss();
  if (!rss_reset) std::printf("note: /proc/self/clear_refs not writable: rss_mb is the process peak so far\n");

  std::vector<long> sizes = quick ? std::vector<long>{1000, 2000}
                                  : std::vector<long>{1000, 3000, 10000, 30000, 100000, 1000000};
  auto skip = [&](long n) { return n > max_n || (only > 0 && n != only); };
  if (only > 0 && std::find(sizes.begin(), sizes.end(), only) == sizes.end()) sizes.push_back(only);
  sizes.erase(std::remove_if(sizes.begin(), sizes.end(), skip), sizes.end());
  const std::vector<double> base_tols{1e-3, 1e-4, 1e-6};
  const std::vector<double> extra_tols{1e-2, 1e-8, 1e-10};  // speed-accuracy and error sweep
  const long accuracy_n1 = quick ? 1000 : 10000, accuracy_n2 = quick ? 0 : 100000;

  // Memory guard: a row (or reference) is skipped when its peak RSS, scaled by N from the same row at
  // the largest smaller N, would exceed --mem-gb (the machine is shared; an out-of-memory kill must not
  // happen). Printed; the JSON holds only measured rows.
  std::map<std::string, std::pair<long, double>> last_rss;
  auto key = [](const char* what, Moments m, double phi, double tol, int threads) {
    char b[96];
    std::snprintf(b, sizeof b, "%s %s %.2f %.0e %d", what, to_string(m), phi, tol, threads);
    return std::string(b);
  };
  auto fits = [&](const std::string& k, long n) {
    const auto it = last_rss.find(k);
    if (it == last_rss.end()) {  // nothing to scale from: small N only
      if (n <= 100000 || unguarded) return true;
      std::printf("skipped %s N=%ld: no smaller-N row to estimate its memory from\n", k.c_str(), n);
      return false;
    }
    const double est = it->second.second * double(n) / double(it->second.first) / 1024.0;
    if (est <= mem_gb) return true;
    std::printf("skipped %s N=%ld: estimated peak RSS %.1f GB above --mem-gb %.1f\n", k.c_str(), n, est, mem_gb);
    std::fflush(stdout);
    return false;
  };

  // Returns the reference tolerance, or 0 if the reference is skipped (errors then recorded as -1).
  auto reference = [&](const Config& c, Moments m, const VecX& v, long n, double phi, VecX& yref) {
    double ref_tol = n >= ref10_from ? 1e-10 : 1e-12;
    const std::string k = key("reference", m, phi, 1e-12, max_threads);
    if (!fits(k, n)) return 0.0;
    omp_set_num_threads(max_threads);
    reset_peak_rss();
    std::unique_ptr<ewald::PmeFarField> pme;
    double setup = 0.0;
    for (;;) {  // a reference the PME cannot build at 1e-12 is taken at 1e-11 (recorded in ref_tol, printed)
      try {
        setup = bench::time_once([&] { pme = std::make_unique<ewald::PmeFarField>(c.x, c.a, 1.0, m, c.dom, ref_tol); });
        break;
      } catch (const std::exception& e) {
        if (ref_tol >= 1e-11) throw;
        std::printf("%-3s N=%7ld phi=%.1f reference at tol %.0e failed (%s); using 1e-11\n", to_string(m), n, phi,
                    ref_tol, e.what());
        ref_tol = 1e-11;
      }
    }
    const double product = bench::time_once([&] { pme->apply(v, yref); });
    const auto& p = pme->parameters();
    const double rss = peak_rss_mb();
    last_rss[k] = {n, rss};
    res.add({{"kind", 4}, {"N", double(n)}, {"phi", phi}, {"dof", double(dof_per_particle(m))}, {"ref_tol", ref_tol},
             {"strain", c.dom.shear_strain},
             {"grid", double(p.grid[0])}, {"support", double(p.support)},
             {"pairs_per_particle", double(pme->real_pairs()) / double(n)}, {"rss_mb", rss}},
            {{"setup", setup}, {"product", product}});
    std::printf("%-3s N=%7ld phi=%.1f reference tol %.0e: setup %.2f product %.2f s, grid %d P %d, %.0f MB\n",
                to_string(m), n, phi, ref_tol, setup, product, p.grid[0], p.support, rss);
    std::fflush(stdout);
    return ref_tol;
  };

  // --- kinds 0 and 4: the sweep (N > 10^5: 2 threads, one timed repeat, after the other kinds) ----
  auto sweep = [&](long n) {
    const bool large = n > 100000;
    for (double phi : {0.1, 0.4}) {
      const Config c = spheres(n, phi, std::uint64_t(n));
      for (Moments m : {Moments::F, Moments::FTS}) {
        if ((m == Moments::F && moments.find('F') == std::string::npos) ||
            (m == Moments::FTS && moments.find("FTS") == std::string::npos) || (m == Moments::F && moments == "FTS"))
          continue;
        const int dof = dof_per_particle(m);
        const VecX v = random_input(n * dof, std::uint64_t(n) + 17);
        VecX yref, y, tmp;
        const double ref_tol = no_reference ? 0.0 : reference(c, m, v, n, phi, yref);
        std::vector<double> tols = only_tols.empty() ? base_tols : only_tols;
        const bool accuracy = (n == accuracy_n1 && (!quick || phi == 0.1)) || (n == accuracy_n2 && phi == 0.1);
        if (accuracy) tols.insert(tols.end(), extra_tols.begin(), extra_tols.end());
        for (double tol : tols) {
          const bool extra = std::find(extra_tols.begin(), extra_tols.end(), tol) != extra_tols.end();
          for (int threads = max_threads; threads >= 1; --threads) {
            if ((extra || large) && threads != max_threads) continue;  // extra tolerances, large N: 2 threads
            const std::string k = key("pme", m, phi, tol, threads);
            if (!fits(k, n)) continue;
            omp_set_num_threads(threads);
            reset_peak_rss();
            std::map<std::string, double> ph;
            std::unique_ptr<ewald::PmeFarField> pme;
            ph["setup"] = bench::time_once([&] { pme = std::make_unique<ewald::PmeFarField>(c.x, c.a, 1.0, m, c.dom, tol); });
            pme->apply(v, y);  // warm-up; the result for the error
            const double err = ref_tol > 0 ? rel_error(y, yref) : -1.0;
            const int reps = reps_for(n, quick);
            ph["wave"] = median_of([&] { pme->apply_wave(v, tmp); }, reps);
            ph["real"] = median_of([&] { pme->apply_real(v, tmp); }, reps);
            ph["product"] = median_of([&] { pme->apply(v, tmp); }, reps);
            const double rss = peak_rss_mb();
            last_rss[k] = {n, rss};
            const auto& p = pme->parameters();
            const double ppp = double(pme->real_pairs()) / double(n);
            res.add({{"kind", 0}, {"N", double(n)}, {"phi", phi}, {"dof", double(dof)}, {"tol", tol},
                     {"threads", double(threads)}, {"grid", double(p.grid[0])}, {"support", double(p.support)},
                     {"shape", p.shape}, {"xi", p.xi}, {"cutoff_gap", p.cutoff_gap}, {"pairs_per_particle", ppp},
                     {"est_real", p.est_real}, {"est_wave", p.est_wave}, {"est_alias", p.est_alias},
                     {"est_cost", p.est_cost}, {"error", err}, {"ref_tol", ref_tol}, {"rss_mb", rss}, {"load1", load1()}},
                    ph);
            std::printf("%-3s N=%7ld phi=%.1f tol=%.0e thr=%d setup %.4f wave %.4f real %.4f product %.4f s"
                        " (model %.4f) M=%d P=%d pairs/N=%.1f err=%.2e (x%.2f) %.0f MB\n",
                        to_string(m), n, phi, tol, threads, ph["setup"], ph["wave"], ph["real"], ph["product"],
                        p.est_cost, p.grid[0], p.support, ppp, err, err / tol, rss);
            std::fflush(stdout);
          }
        }
        if (!quick) res.write(opt.out);  // partial results survive an interrupted run
      }
    }
  };
  for (long n : sizes)
    if (n <= 100000) sweep(n);

  // --- kind 1: direct O(N^2) product (open domain), the time scale ------------------------------------
  for (long n : quick ? std::vector<long>{1000} : std::vector<long>{1000, 3000, 10000}) {
    if (skip(n)) continue;
    const Config c = spheres(n, 0.1, std::uint64_t(n));
    for (Moments m : {Moments::F, Moments::FTS}) {
      const int dof = dof_per_particle(m);
      const VecX v = random_input(n * dof, std::uint64_t(n) + 17);
      VecX y;
      omp_set_num_threads(max_threads);
      const double t = median_of([&] { mobility_product(c.x, c.a, 1.0, m, v, y); }, n <= 3000 ? 3 : 1);
      res.add({{"kind", 1}, {"N", double(n)}, {"dof", double(dof)}, {"threads", double(max_threads)}}, {{"product", t}});
      std::printf("%-3s N=%7ld direct (open, %d threads) %.3f s\n", to_string(m), n, max_threads, t);
      std::fflush(stdout);
    }
  }

  // --- kind 2: Lees-Edwards -------------------------------------------------------------------------
  for (long n : quick ? std::vector<long>{1000} : std::vector<long>{10000, 100000}) {
    if (skip(n)) continue;
    const Moments m = Moments::FTS;
    const int dof = dof_per_particle(m);
    const double tol = 1e-4;
    Config c = spheres(n, 0.1, std::uint64_t(n));
    const VecX v = random_input(n * dof, std::uint64_t(n) + 17);
    const int reps = reps_for(n, quick);
    const std::vector<double> strains{0.0, 0.3, 0.31};
    std::vector<VecX> refs(strains.size());
    for (std::size_t s = 0; s < strains.size(); ++s) {  // the reference at each strain
      c.dom.shear_strain = strains[s];
      reference(c, m, v, n, 0.1, refs[s]);
    }
    for (int threads = max_threads; threads >= 1; --threads) {
      std::unique_ptr<ewald::PmeFarField> sheared;
      for (std::size_t s = 0; s < strains.size(); ++s) {
        const double strain = strains[s];
        c.dom.shear_strain = strain;
        const VecX& yref = refs[s];
        VecX y, tmp;
        omp_set_num_threads(threads);
        reset_peak_rss();
        std::map<std::string, double> ph;
        std::unique_ptr<ewald::PmeFarField> fresh;
        double kept = 0.0, fresh_diff = 0.0;
        ewald::PmeFarField* pme = nullptr;
        if (strain == 0.31) {
          const auto grid_before = sheared->parameters().grid;
          ph["setup"] = bench::time_once([&] { sheared->set_configuration(Configuration{c.x, c.a, c.dom}); });
          kept = sheared->parameters().grid == grid_before ? 1.0 : 0.0;
          pme = sheared.get();
        } else {
          std::unique_ptr<ewald::PmeFarField>& slot = strain == 0.0 ? fresh : sheared;
          ph["setup"] = bench::time_once([&] { slot = std::make_unique<ewald::PmeFarField>(c.x, c.a, 1.0, m, c.dom, tol); });
          pme = slot.get();
        }
        pme->apply(v, y);
        const double err = rel_error(y, yref);
        if (strain == 0.31) {  // against a new object at this strain
          ewald::PmeFarField other(c.x, c.a, 1.0, m, c.dom, tol);
          other.apply(v, tmp);
          fresh_diff = rel_error(y, tmp);
        }
        ph["product"] = median_of([&] { pme->apply(v, tmp); }, reps);
        const auto& p = pme->parameters();
        res.add({{"kind", 2}, {"N", double(n)}, {"dof", double(dof)}, {"tol", tol}, {"threads", double(threads)},
                 {"strain", strain}, {"grid0", double(p.grid[0])}, {"grid1", double(p.grid[1])},
                 {"grid2", double(p.grid[2])}, {"support", double(p.support)},
                 {"pairs_per_particle", double(pme->real_pairs()) / double(n)}, {"error", err}, {"kept", kept},
                 {"fresh_diff", fresh_diff}, {"rss_mb", peak_rss_mb()}, {"load1", load1()}},
                ph);
        std::printf("FTS N=%7ld LE strain %.2f thr=%d %s %.4f product %.4f s grid %dx%dx%d P %d err %.2e%s\n", n,
                    strain, threads, strain == 0.31 ? "set_configuration" : "setup", ph["setup"], ph["product"],
                    p.grid[0], p.grid[1], p.grid[2], p.support, err,
                    strain == 0.31 ? (kept ? " (grid kept)" : " (grid CHANGED)") : "");
        if (strain == 0.31) std::printf("    vs a new object at strain 0.31: relative difference %.2e\n", fresh_diff);
        std::fflush(stdout);
      }
    }
  }

  // --- kind 3: the previous benchmark's configurations -----------------------------------------------
  struct Old {
    long n;
    std::vector<Moments> ms;
    std::vector<double> tols;
  };
  const std::vector<Old> olds =
      quick ? std::vector<Old>{{1000, {Moments::F, Moments::FTS}, {1e-4}}}
            : std::vector<Old>{{1000, {Moments::F, Moments::FTS}, {1e-3, 1e-4, 1e-6}},
                               {2000, {Moments::F, Moments::FTS}, {1e-3, 1e-4, 1e-6}},
                               {4000, {Moments::F, Moments::FTS}, {1e-3, 1e-4, 1e-6}},
                               {8000, {Moments::F, Moments::FTS}, {1e-3, 1e-4, 1e-6}},
                               {16000, {Moments::F}, {1e-3, 1e-4}},
                               {32000, {Moments::F}, {1e-3, 1e-4}},
                               {64000, {Moments::F}, {1e-3, 1e-4}},
                               {100000, {Moments::F}, {1e-3, 1e-4}}};
  for (const Old& o : olds) {
    if (skip(o.n)) continue;
    const long n = o.n;
    const double L = std::cbrt(double(n) * 4.19 * 1.25 / 0.1);
    const bench::Cloud cloud = bench::random_cloud(n, L, std::uint64_t(n));
    Domain dom;
    dom.kind = Domain::Kind::periodic;
    dom.box = Vec3(L, L, L);
    for (Moments m : o.ms) {
      const int dof = dof_per_particle(m);
      const VecX v = random_input(n * dof, std::uint64_t(n) + 17);
      VecX yref, y, tmp;
      omp_set_num_threads(max_threads);
      ewald::PmeFarField(cloud.x, cloud.a, 1.0, m, dom, 1e-12).apply(v, yref);
      for (double tol : o.tols) {
        for (int threads = max_threads; threads >= 1; --threads) {
          omp_set_num_threads(threads);
          std::map<std::string, double> ph;
          std::unique_ptr<ewald::PmeFarField> pme;
          ph["setup"] = bench::time_once(
              [&] { pme = std::make_unique<ewald::PmeFarField>(cloud.x, cloud.a, 1.0, m, dom, tol); });
          pme->apply(v, y);
          const double err = rel_error(y, yref);
          ph["product"] = median_of([&] { pme->apply(v, tmp); }, reps_for(n, quick));
          res.add({{"kind", 3}, {"N", double(n)}, {"dof", double(dof)}, {"tol", tol}, {"threads", double(threads)},
                   {"error", err}},
                  ph);
          std::printf("%-3s N=%7ld previous config tol=%.0e thr=%d setup %.4f product %.4f s err %.2e\n",
                      to_string(m), n, tol, threads, ph["setup"], ph["product"], err);
          std::fflush(stdout);
        }
      }
    }
  }

  if (!quick) res.write(opt.out);
  for (long n : sizes)
    if (n > 100000) sweep(n);
  std::printf("wrote %s\n", res.write(opt.out).c_str());
  return 0;
}
