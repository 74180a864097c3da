#pragma once
// PME parameters from one tolerance: the only place where accuracy is turned into numbers
// (docs/ewald.md s.4 derives each line; s.5 has the measured errors).
//
// Error model. For a random input x (unit variance per component) and particles at random
// positions of number density rho, the error of one output particle of y = M x has mean square
// e^2 = sum_j ||dM_ij||_F^2, where dM is what each approximation leaves out; it is compared with
// the mean square of (M x)_i itself, S^2 = S_self^2 + S_pair^2: S_self^2 = sum_c (self mobility of
// component c)^2 (the operator passes the mean over its particles; else that of radius a_max), and
// S_pair^2 = sum_{j != i} ||M_ij||_F^2 = (rho / V) sum_{k != 0} 2 alpha_full(k)^2 / k^4 (pme_pair_scale2:
// alpha below with the full Faxen functions j0(ka) and 3 j1(ka) / (ka); the lattice sum for the long
// waves, which make it grow with the box, the continuum beyond; radius a_max). With ||.||_F the
// Frobenius norm:
//   real space (pairs beyond the cutoff r_c = cutoff_gap + a_i + a_j; the largest of the radius
//   pairs (a_min, a_min), (a_min, a_max), (a_max, a_max)):
//     e_R^2 = rho int_{r_c}^inf 4 pi r^2 ||B_real(r)||_F^2 dr               (blocks of ewald_split.hpp)
//   wave truncation (modes outside the grid, |k| > k_in = min_d pi M_d / |a_d|):
//     e_K^2 = rho / (2 pi)^3 int_{|k|>k_in} 4 pi k^2 g(k)^2 2 alpha(k)^2 dk,   g = H(k) / (mu k^2)
//   aliasing and edges (spreading and interpolation): a particle at sub-grid offset tau_d spreads, per
//   axis and grid mode nu = k_d / K_d (K_d = 2 pi M_d / |a_d|), A_q(nu, tau) = sum_p phi^(q)(delta_p)
//   e^{-2 pi i nu delta_p} for its window derivatives q = 0..3 (the P sampled points), where the ideal is
//   I_q = (2 pi i nu)^q phihat(nu). The deviation D_q = A_q - I_q holds every alias along the axis and
//   the jumps of the truncated window and its derivatives at |delta| = P/2; its moments over the
//   offset, V_qq'(nu) = <conj(D_q) D_q'>_tau, follow by quadrature in tau. R(k) is a cubic polynomial
//   in k_d, R = sum_q k_d^q Rt_q, so one axis's deviation gives, per grid mode,
//     X_d(k) = alpha(k) sum_qq' Re[V_qq' i^q (-i)^q'] J_d^(q+q') tr(P_k Rt_q^+ Rt_q') / phihat(nu_d)^2,
//   J_d = M_d / |a_d|, and, first order in the deviations (one axis at a time),
//     e_A^2 = 2 [rho / (2 pi)^3 sum_d int g^2 X_d d^3k + (1 / (2 pi)^3)^2 sum_d (int g sqrt(X_d) d^3k)^2]
//   (pairs by Parseval over random positions; the particle's own deviation is coherent over k and
//   bounded by the second term; 2: spreading and interpolation), integrated over the cylinder
//   |k_d| <= K_d / 2, |k_perp| <= min K_perp / 2. The traces come in closed form from
//   R(k1)^+ R(k2) = P_F1 P_F2 I + P_T1 P_T2 [(k1.k2 I - k2 k1^T) / 4 (rotation rows)
//                   + (k1.k2 I + k2 k1^T) / 2 - k1 k2^T / 3 (strain rows)],
// and with k1 = k2 = k they give R(k)^+ R(k) = alpha(k) I + beta(k) k k^T (ewald_split.hpp's response operator)
// (Faxen factors P_F = 1 - a^2 k^2 / 6, P_T = 1 - a^2 k^2 / 10):
//     F: alpha = P_F^2, beta = 0;  FT: alpha = P_F^2 + k^2 P_T^2 / 4, beta = -P_T^2 / 4;
//     FTS: alpha = P_F^2 + 3 k^2 P_T^2 / 4, beta = -P_T^2 / 12.
// Wave truncation and aliasing are evaluated for the smallest and the largest radius and the worse
// kept (the largest sphere's Faxen factors vanish near k a = sqrt(6), the smallest sphere's do not).
// Each part gets a third of (kSafety tol)^2 S^2; kSafety (pme_parameters.cpp) is the one calibration
// constant, set from the measured errors so that the achieved error lies between tol / 10 and tol
// (docs/ewald.md s.5).
// Cost model. Among all (cutoff, grid upsampling sigma, support P, window shape) meeting the three
// bounds, the cheapest per product by
//     t = c_pair(m) pairs + 2 c_point(m) N P^3 + 6 c_fft G log2 G + c_grid G,   G = M0 M1 M2,
// plus, when the caller says how many products each configuration gets (products_per_update = n_p),
// the set-up of a new configuration shared among them:
//     t += [N (c_particle + c_window P) + c_entry(m) 2 pairs] / n_p
// (windows and slab order per particle; pair search, pair data and scalar cache per ordered pair),
// with the constants measured on the reference machine (bench_pme, bench_pme_setup, docs/ewald.md s.4).
// Lees-Edwards: the grid and all parameters are chosen for the longest reduced a_2 (|gamma'| = Lx / (2 Ly)),
// so they do not change with the strain (the FFT plans are kept while the box shears).
#include "ewald/lattice.hpp"
#include "ewald/real_space.hpp"
#include "ewald/window.hpp"

#include <array>
#include <optional>

namespace stokesian::ewald {

struct PmeParameters {
  double tolerance = 1e-6;      // requested relative error of M x
  double xi = 1.0;              // splitting parameter [1/a]
  double cutoff_gap = 1.0;      // real-space cutoff: pairs with |r| < cutoff_gap + a_i + a_j [a]
  std::array<int, 3> grid{};    // FFT grid M_d along the lattice directions
  int support = 4;              // window points per direction P
  WindowKind window = WindowKind::kaiser_bessel;
  double shape = 1.0;           // Kaiser-Bessel beta, or Gaussian standard deviation [grid spacings]
  double k_max = 1.0;           // radius of the sphere of wave vectors resolved by the grid [1/a]
  bool sheared = false;         // chosen for every strain (Lees-Edwards)
  // Model estimates (relative to S, the rms of (M x)_i, see above) and the modelled cost [s] per product.
  double est_real = 0, est_wave = 0, est_alias = 0, est_cost = 0;
  double est_setup = 0;  // modelled set-up of one configuration [s] (counted in est_cost / products_per_update)
  // Memory allowed for the real-space scalar cache [bytes] (real_space.hpp): the model prices the
  // pairs as cached when their scalars fit in it, and PmeFarField builds its real-space sum with it.
  double cache_bytes = double(RealSpaceSum::kDefaultCacheBytes);
};

struct PmeOptions {
  // Particles inside the real-space cutoff sphere; 0 = chosen by the cost model.
  double neighbours = 0.0;
  // Grid upsampling sigma (grid points / those needed to resolve k_in); 0 = chosen by the cost model.
  double sigma = 0.0;
  WindowKind window = WindowKind::kaiser_bessel;
  // Mean square self scale S^2 of the particles (see above); 0 = that of radius a_max.
  double self_scale2 = 0.0;
  // Products expected per configuration (between position updates): the cost model adds the set-up
  // divided by it. 0 = price the product alone (many products per configuration). Only the cost
  // changes with it, never the accuracy. The engine passes MobilitySpec::products_per_configuration.
  double products_per_update = 0.0;
  // Budget of the real-space scalar cache [bytes]; 0 = PmeParameters' default (256 MB).
  // bench/bench_pme_model.cpp studies what a budget growing with N would change.
  double cache_bytes = 0.0;
  // Use these parameters as they are (tests and benchmarks that probe the model's parts).
  std::optional<PmeParameters> fixed;
};

// Parameters for tolerance tol in [1e-14, 0.1] for n particles with radii in [a_min, a_max].
// A lattice with a non-zero strain gets strain-independent parameters (see above).
// Throws std::invalid_argument if the box is too small for the minimum-image real-space sum.
PmeParameters pme_parameters(double tol, const Lattice& lattice, int n, double a_min, double a_max, Moments m,
                             const PmeOptions& opt = {});

// Smallest integer >= n of the form 2^a 3^b 5^c with a >= 1 (even, FFT-friendly).
int fft_size(int n);

// The model's parts, exposed for tests and benchmarks: e_R^2, e_K^2, e_A^2 (not divided by S^2)
// for radius a, density rho and moments m; e_A^2 includes the window's edge jumps.
double pme_real_error2(double cutoff_gap, double xi, double a_i, double a_j, double rho, Moments m);
double pme_wave_error2(double k_in, double xi, double a, double rho, Moments m);
double pme_alias_error2(const std::array<int, 3>& M, const Vec3& lengths, const Window1D& w, double xi, double a,
                        double rho, Moments m);
double pme_self_scale2(double a, Moments m);
// S_pair^2 (above): mean square of the pairs' part of (M x)_i for unit-variance x and random positions
// in a box of these side lengths.
double pme_pair_scale2(const Vec3& box, double a, double rho, Moments m);

}  // namespace stokesian::ewald
