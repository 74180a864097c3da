#include "trees/tree_mobility.hpp"

#include "engine/core/sym_traceless.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "trees/near_pairs.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

namespace stokesian::trees {

namespace {

int derivative_order(Moments m) { return m == Moments::FTS ? 3 : 2; }

constexpr double kPi = 3.14159265358979323846;

// Potentials per expansion (phi_x, phi_y, phi_z, psi), stored interleaved: E[index * kPot + pot].
constexpr int kPot = 4;

// Positions in a multi-index set of order >= 3 of the first, second and third unit derivatives.
struct DerivativeIndex {
  int i1[3], i2[3][3], i3[3][3][3];
  explicit DerivativeIndex(const MultiIndexSet& set) {
    for (int a = 0; a < 3; ++a) {
      int e[3] = {0, 0, 0};
      e[a] = 1;
      i1[a] = set.index(e[0], e[1], e[2]);
      for (int b = 0; b < 3; ++b) {
        int f[3] = {e[0], e[1], e[2]};
        ++f[b];
        i2[a][b] = set.index(f[0], f[1], f[2]);
        for (int c = 0; c < 3; ++c) {
          int g[3] = {f[0], f[1], f[2]};
          ++g[c];
          i3[a][b][c] = set.index(g[0], g[1], g[2]);
        }
      }
    }
  }
};

// y (times 8 pi mu) += the responses [U, Omega, E] of a sphere of radius ai at offset R from the
// potentials' origin, from the derivatives P[pot * nb + beta] (pot: phi_x, phi_y, phi_z, psi) of
// the four potentials (the formulas of the header).
void add_responses(const double* P, int nb, const DerivativeIndex& ix, const Vec3& R, double ai, Moments m,
                   double* y) {
  auto phi = [&](int j, int b) { return P[j * nb + b]; };
  auto psi = [&](int b) { return P[3 * nb + b]; };
  for (int a = 0; a < 3; ++a) {
    double u = phi(a, 0) + psi(ix.i1[a]);
    double divgrad = 0;
    for (int j = 0; j < 3; ++j) {
      u -= R[j] * phi(j, ix.i1[a]);
      divgrad += phi(j, ix.i2[a][j]);
    }
    y[a] += u - (ai * ai / 3.0) * divgrad;
  }
  if (!has_torque(m)) return;
  Mat3 G;  // G(k, a) = d_k u_a
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) {
      double g = phi(a, ix.i1[k]) - phi(k, ix.i1[a]) + psi(ix.i2[a][k]);
      for (int j = 0; j < 3; ++j) g -= R[j] * phi(j, ix.i2[a][k]);
      G(k, a) = g;
    }
  y[3] += 0.5 * (G(1, 2) - G(2, 1));
  y[4] += 0.5 * (G(2, 0) - G(0, 2));
  y[5] += 0.5 * (G(0, 1) - G(1, 0));
  if (!has_stresslet(m)) return;
  Mat3 E = 0.5 * (G + G.transpose());
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      double t = 0;
      for (int j = 0; j < 3; ++j) t += phi(j, ix.i3[a][b][j]);
      E(a, b) -= (ai * ai / 5.0) * t;
    }
  const Vec5 e5 = to_vec5(E);
  for (int r = 0; r < 5; ++r) y[6 + r] += e5[r];
}

// y_i += exact pair blocks of the sources j in [begin, end) of `order` (j != i).
void add_pairs(const std::vector<int>& order, int begin, int end, int i, const std::vector<Vec3>& x,
               const std::vector<double>& a, double mu, Moments m, const VecX& in, double* yi, long& count) {
  const int d = dof_per_particle(m);
  for (int q = begin; q < end; ++q) {
    const int j = order[std::size_t(q)];
    if (j == i) continue;
    const Vec3 rij = x[std::size_t(i)] - x[std::size_t(j)];
    const double r = rij.norm();
    const Vec3 e = r > 0 ? Vec3(rij / r) : Vec3::UnitZ();
    mobility::apply_pair(mobility::pair_scalars(a[std::size_t(i)], a[std::size_t(j)], r, mu, m), e, m,
                         in.data() + long(j) * d, yi);
    ++count;
  }
}

// L_beta += sum_gamma M_gamma D_(beta + gamma) for the four potentials, the terms of beta being
// terms[begin[beta] .. begin[beta + 1]) = (gamma, beta + gamma); then psi about the target's centre:
// + (c_S - c_T)_j phi_j = - R_j phi_j. Compiled for AVX2/FMA too (chosen at run time).
STOKESIAN_TREE_CLONES
void convert(const double* M, const double* D, const Vec3& R, const std::array<int, 2>* terms, const int* begin, int nl,
             double* L) {
  // the four potentials of an index as one 4-wide vector (GCC/Clang vector extension)
  typedef double Pot4 __attribute__((vector_size(32)));
  const double r0 = R[0], r1 = R[1], r2 = R[2];
  for (int b = 0; b < nl; ++b) {
    const int k0 = begin[b], k1 = begin[b + 1];
    if (k0 == k1) continue;
    Pot4 acc = {0, 0, 0, 0}, acc2 = {0, 0, 0, 0};  // two chains hide the add latency
    int k = k0;
    for (; k + 1 < k1; k += 2) {
      Pot4 m, m2;
      std::memcpy(&m, M + kPot * terms[k][0], sizeof m);
      std::memcpy(&m2, M + kPot * terms[k + 1][0], sizeof m2);
      acc += m * D[terms[k][1]];
      acc2 += m2 * D[terms[k + 1][1]];
    }
    if (k < k1) {
      Pot4 m;
      std::memcpy(&m, M + kPot * terms[k][0], sizeof m);
      acc += m * D[terms[k][1]];
    }
    acc += acc2;
    double* l = L + kPot * b;
    l[0] += acc[0];
    l[1] += acc[1];
    l[2] += acc[2];
    l[3] += acc[3] - (r0 * acc[0] + r1 * acc[1] + r2 * acc[2]);
  }
}

// out = sum over terms[k0 .. k1) of L_(term[2]) w_(term[1]), four potentials at once (the shift of
// a local expansion to a child's centre or a target: L'_beta = sum_delta L_(beta + delta) w_delta).
STOKESIAN_TREE_CLONES
void shift_sum(const double* L, const double* w, const std::array<int, 3>* terms, int k0, int k1, double* out) {
  typedef double Pot4 __attribute__((vector_size(32)));
  Pot4 acc = {0, 0, 0, 0}, acc2 = {0, 0, 0, 0};
  int k = k0;
  for (; k + 1 < k1; k += 2) {
    Pot4 l, l2;
    std::memcpy(&l, L + kPot * terms[k][2], sizeof l);
    std::memcpy(&l2, L + kPot * terms[k + 1][2], sizeof l2);
    acc += l * w[terms[k][1]];
    acc2 += l2 * w[terms[k + 1][1]];
  }
  if (k < k1) {
    Pot4 l;
    std::memcpy(&l, L + kPot * terms[k][2], sizeof l);
    acc += l * w[terms[k][1]];
  }
  acc += acc2;
  std::memcpy(out, &acc, sizeof acc);
}

// Four conversions into one target at once, one source per vector lane (the fast path of
// downward(); convert() above is its plain twin and takes the remainder of a list): the
// derivatives of 1/r at the four R = c_T - c_S by the recurrence of inverse_distance_derivatives,
// the kept moments (gamma_z <= 1) gathered lane-wise, then per beta
//     A_pot = sum_gamma M_(gamma, pot) D_(beta + gamma)   (lanes: sources),
// psi corrected lane-wise (- R_j phi_j) and the lanes summed into L. terms4 index the kept moments.
STOKESIAN_TREE_CLONES
void convert4(const double* const* M, const double* rx, const double* ry, const double* rz, const MultiIndexSet& deriv,
              const int* keep, int nkeep, const std::array<int, 2>* terms4, const int* begin, int nl, double* work,
              double* L) {
  typedef double V4 __attribute__((vector_size(32)));
  V4 x, y, z;
  std::memcpy(&x, rx, sizeof x);
  std::memcpy(&y, ry, sizeof y);
  std::memcpy(&z, rz, sizeof z);
  V4* D = reinterpret_cast<V4*>(work);           // nl derivatives
  V4* MV = D + nl;                                // nkeep x 4 potentials
  const V4 inv_r2 = 1.0 / (x * x + y * y + z * z);
  for (int l = 0; l < 4; ++l) D[0][l] = std::sqrt(inv_r2[l]);
  for (int k = 1; k < deriv.size(); ++k) {
    const MultiIndexSet::Recurrence& rc = deriv.recurrence(k);
    const V4 acc = rc.first_weight[0] * x * D[rc.first[0]] + rc.first_weight[1] * y * D[rc.first[1]] +
                   rc.first_weight[2] * z * D[rc.first[2]] + rc.second_weight[0] * D[rc.second[0]] +
                   rc.second_weight[1] * D[rc.second[1]] + rc.second_weight[2] * D[rc.second[2]];
    D[k] = -acc * inv_r2;
  }
  for (int c = 0; c < nkeep; ++c) {
    const int g = kPot * keep[c];
    for (int pot = 0; pot < kPot; ++pot) MV[kPot * c + pot] = V4{M[0][g + pot], M[1][g + pot], M[2][g + pot], M[3][g + pot]};
  }
  for (int b = 0; b < nl; ++b) {
    const int k0 = begin[b], k1 = begin[b + 1];
    if (k0 == k1) continue;
    V4 a0 = {0, 0, 0, 0}, a1 = a0, a2 = a0, a3 = a0, c0 = a0, c1 = a0, c2 = a0, c3 = a0;  // two chains
    int k = k0;
    for (; k + 1 < k1; k += 2) {
      const V4* m = MV + kPot * terms4[k][0];
      const V4 d = D[terms4[k][1]];
      const V4* m2 = MV + kPot * terms4[k + 1][0];
      const V4 d2 = D[terms4[k + 1][1]];
      a0 += m[0] * d;
      a1 += m[1] * d;
      a2 += m[2] * d;
      a3 += m[3] * d;
      c0 += m2[0] * d2;
      c1 += m2[1] * d2;
      c2 += m2[2] * d2;
      c3 += m2[3] * d2;
    }
    if (k < k1) {
      const V4* m = MV + kPot * terms4[k][0];
      const V4 d = D[terms4[k][1]];
      a0 += m[0] * d;
      a1 += m[1] * d;
      a2 += m[2] * d;
      a3 += m[3] * d;
    }
    a0 += c0;
    a1 += c1;
    a2 += c2;
    a3 += c3 - (x * a0 + y * a1 + z * a2);
    double* l = L + kPot * b;
    l[0] += (a0[0] + a0[1]) + (a0[2] + a0[3]);
    l[1] += (a1[0] + a1[1]) + (a1[2] + a1[3]);
    l[2] += (a2[0] + a2[1]) + (a2[2] + a2[3]);
    l[3] += (a3[0] + a3[1]) + (a3[2] + a3[3]);
  }
}

}  // namespace

namespace {

// Terms of one conversion after the harmonic reduction: gamma with gamma_z <= 1 and |gamma| <= p
// (2m + 1 of order m), beta with beta_z <= 1 and |beta + gamma| <= p + k.
double conversion_terms(int p, int k) {
  double t = 0;
  for (int m = 0; m <= p; ++m) t += (2.0 * m + 1) * (p + k - m + 1) * (p + k - m + 1);
  return t;
}

// Unit costs on one thread (fitted to the times of one product at N = 3e4, uniform cube, phi = 0.1,
// leaf 64, theta 0.35-0.6, p 3-11, 2026-11-25, within 2.5 %; docs/tree.md): a near pair (the
// vectorised closed forms of F, FT, FTS), one conversion (0.05 us + 0.40 ns per term) and, per
// particle, the moments and the evaluation of its local expansion (22/25/29 ns per multi-index of
// order p + k).
double pair_seconds(Moments m) { return m == Moments::F ? 3.1e-9 : (m == Moments::FT ? 5.1e-9 : 11.3e-9); }
double particle_seconds(int p, Moments m) {
  const double per_index = m == Moments::F ? 22e-9 : (m == Moments::FT ? 25e-9 : 29e-9);
  return per_index * multi_index_count(p + derivative_order(m));
}
double conversion_seconds(int p, Moments m) { return 0.05e-6 + 0.40e-9 * conversion_terms(p, derivative_order(m)); }

}  // namespace

double tree_error_model(const TreeParameters& p, Moments m) {
  const double geometric = std::pow(p.theta, p.order + 1);
  if (m == Moments::FTS) return 0.05 * (p.order + 1) * geometric;
  const double c = std::max(0.2 / (p.order + 1), 0.025);
  return (m == Moments::FT ? 4.0 * c : c) * geometric;  // FT: tree_mobility.hpp
}

namespace {

// Modelled seconds per particle of one product (fmm), one thread.
double cost_per_particle(const TreeParameters& p, Moments m) {
  const double x = p.theta / 0.5;
  return 1770 * std::pow(x, -2.5) * pair_seconds(m) + 10.8 * std::pow(x, -2.05) * conversion_seconds(p.order, m) +
         particle_seconds(p.order, m);
}

}  // namespace

long tree_auto_from(double tolerance, Moments m) {
  if (!(tolerance > 0)) return 0;
  // Rows: product tolerance >= 5e-5 (measured at 1e-3 and 1e-4), >= 5e-7 (1e-6), below (1e-8).
  const int row = tolerance >= 5e-5 ? 0 : tolerance >= 5e-7 ? 1 : 2;
  static constexpr long kFrom[3][3] = {{8000, 20000, 30000},    // F
                                       {5000, 15000, 20000},    // FT
                                       {7000, 12000, 23000}};   // FTS
  return kFrom[m == Moments::F ? 0 : m == Moments::FT ? 1 : 2][row];
}

double tree_product_seconds(const TreeParameters& p, Moments m, double n) { return n * cost_per_particle(p, m); }

double tree_memory_bytes(const TreeParameters& p, Moments m, double n) {
  const double nodes = std::max(1.0, n / 4);
  const double expansion = 4.0 * (multi_index_count(p.order) + multi_index_count(p.order + derivative_order(m)));
  const double lists = 10.8 * std::pow(p.theta / 0.5, -2.05) * n + 2 * nodes;  // conversion and pair lists
  return nodes * (8.0 * expansion + sizeof(OctreeNode) + 16.0) + 4.0 * lists + (4.0 + 32.0) * n;
}

TreeParameters tree_parameters(double tolerance, Moments m) {
  if (!(tolerance >= 1e-14 && tolerance <= 0.5))
    throw std::invalid_argument("tree far field: tolerance " + std::to_string(tolerance) + " outside [1e-14, 0.5]");
  TreeParameters best;
  double best_cost = -1;
  for (int step = 0; step <= 9; ++step) {
    TreeParameters p;
    p.theta = 0.15 + 0.05 * step;
    p.leaf_size = 0;  // tuned per configuration
    p.evaluation = TreeEvaluation::fmm;
    for (p.order = 0; p.order <= 20 && tree_error_model(p, m) > tolerance; ++p.order) {
    }
    if (p.order > 20) continue;
    const double cost = cost_per_particle(p, m);
    if (best_cost < 0 || cost < best_cost) {
      best = p;
      best_cost = cost;
    }
  }
  return best;
}

TreeFarField::TreeFarField(const MobilitySpec& spec) : TreeFarField(spec, tree_parameters(spec.tolerance, spec.moments)) {}

TreeFarField::TreeFarField(const MobilitySpec& spec, const TreeParameters& parameters)
    : m_(spec.moments),
      mu_(spec.viscosity),
      p_(parameters),
      moment_set_(parameters.order),
      deriv_set_(parameters.order + derivative_order(spec.moments)),
      beta_set_(derivative_order(spec.moments)) {
  if (!(p_.theta > 0 && p_.theta < 1))
    throw std::invalid_argument("tree far field: theta " + std::to_string(p_.theta) + " outside (0, 1)");
  if (p_.order < 0 || p_.order > 30)
    throw std::invalid_argument("tree far field: order " + std::to_string(p_.order) + " outside [0, 30]");
  if (p_.leaf_size < 0) throw std::invalid_argument("tree far field: leaf size < 0");
  const int ng = moment_set_.size(), nb = beta_set_.size();
  sum_index_.resize(std::size_t(ng * nb));
  for (int g = 0; g < ng; ++g)
    for (int b = 0; b < nb; ++b) {
      const auto& al = moment_set_[g];
      const auto& be = beta_set_[b];
      sum_index_[std::size_t(g * nb + b)] = deriv_set_.index(al[0] + be[0], al[1] + be[1], al[2] + be[2]);
    }
  // Local expansions have order q = p + k (k the highest target derivative), so that every
  // response is accurate to the order of the moments.
  const int nl = deriv_set_.size();
  for (int b = 0; b < nl; ++b) {
    shift_begin_.push_back(int(shift_terms_.size()));
  // Moment shift to a parent's centre (upward pass): M'_gamma = sum_(delta <= gamma) M_(gamma - delta)
  // w_delta, grouped by gamma, as (gamma, delta, gamma - delta).
  for (int g = 0; g < ng; ++g) {
    m2m_begin_.push_back(int(m2m_terms_.size()));
    const auto& ga = moment_set_[g];
    for (int dl = 0; dl < ng; ++dl) {
      const auto& de = moment_set_[dl];
      if (de[0] <= ga[0] && de[1] <= ga[1] && de[2] <= ga[2])
        m2m_terms_.push_back({g, dl, moment_set_.index(ga[0] - de[0], ga[1] - de[1], ga[2] - de[2])});
    }
  }
  m2m_begin_.push_back(int(m2m_terms_.size()));
    const auto& be = deriv_set_[b];
    for (int g = 0; g < nl; ++g) {
      const auto& al = deriv_set_[g];
      const int sum = deriv_set_.index(al[0] + be[0], al[1] + be[1], al[2] + be[2]);
      if (sum >= 0) shift_terms_.push_back({b, g, sum});
    }
  }
  shift_begin_.push_back(int(shift_terms_.size()));
  // Harmonic reduction of the conversion (every D_alpha is harmonic in alpha: D_(alpha + 2e_z) =
  // -D_(alpha + 2e_x) - D_(alpha + 2e_y)). Moments with gamma_z >= 2 are folded onto gamma - 2e_z +
  // 2e_x and gamma - 2e_z + 2e_y (same order, highest gamma_z first); only locals with beta_z <= 1
  // are converted, the others rebuilt by the same identity (lowest beta_z first). Both are exact
  // for the truncated sums (the folded indices have the same order), and cut the terms of one
  // conversion from ~p^6/36 to ~p^4/3 (conversion_terms).
  for (int g = ng - 1; g >= 0; --g) {
    const auto& al = moment_set_[g];
    if (al[2] >= 2)
      moment_fold_.push_back({g, moment_set_.index(al[0] + 2, al[1], al[2] - 2), moment_set_.index(al[0], al[1] + 2, al[2] - 2)});
  }
  std::stable_sort(moment_fold_.begin(), moment_fold_.end(), [&](const auto& u, const auto& v) {
    return moment_set_[u[0]][2] > moment_set_[v[0]][2];
  });
  for (int b = 0; b < nl; ++b) {
    const auto& be = deriv_set_[b];
    if (be[2] >= 2)
      local_rebuild_.push_back({b, deriv_set_.index(be[0] + 2, be[1], be[2] - 2), deriv_set_.index(be[0], be[1] + 2, be[2] - 2)});
  }
  std::stable_sort(local_rebuild_.begin(), local_rebuild_.end(), [&](const auto& u, const auto& v) {
    return deriv_set_[u[0]][2] < deriv_set_[v[0]][2];
  });
  m2l_term_begin_.push_back(0);
  for (int b = 0; b < nl; ++b) {
    const auto& be = deriv_set_[b];
    if (be[2] <= 1)
      for (int g = 0; g < ng; ++g) {
        const auto& al = moment_set_[g];
        const int sum = deriv_set_.index(al[0] + be[0], al[1] + be[1], al[2] + be[2]);
        if (al[2] <= 1 && sum >= 0) m2l_terms_.push_back({g, sum});
      }
    m2l_term_begin_.push_back(int(m2l_terms_.size()));
  }
  // the same terms on the kept moments (gamma_z <= 1), for convert4
  std::vector<int> compact(static_cast<std::size_t>(ng), -1);
  for (int g = 0; g < ng; ++g)
    if (moment_set_[g][2] <= 1) {
      compact[std::size_t(g)] = int(moment_keep_.size());
      moment_keep_.push_back(g);
    }
  for (const auto& term : m2l_terms_) m2l_terms4_.push_back({compact[std::size_t(term[0])], term[1]});
}

void TreeFarField::set_configuration(const Configuration& c) {
  if (c.domain.periodic()) throw std::invalid_argument("tree far field: the domain is periodic (use ewald or pme)");
  x_ = c.x;
  a_ = c.a;
  // Leaf size: given, or tuned (fmm): the candidates' trees and lists are built and the one of least
  // modelled cost (pairs x pair_seconds + conversions x conversion_seconds) is kept; re-tuned when N
  // changes and every kRetune configurations. Deterministic (counts, not timings).
  constexpr long kRetune = 32;
  if (p_.leaf_size > 0 || p_.evaluation != TreeEvaluation::fmm) {
    leaf_size_ = p_.leaf_size > 0 ? p_.leaf_size : 32;
  } else if (x_.size() != tuned_n_ || ++since_tuned_ >= kRetune) {
    double best = -1;
    for (int leaf : {32, 64, 128}) {
      tree_ = build_octree(x_, a_, leaf);
      build_interaction_lists();
      double pairs = 0;
      for (std::size_t t = 0; t + 1 < p2p_begin_.size(); ++t)
        for (int k = p2p_begin_[t]; k < p2p_begin_[t + 1]; ++k)
          pairs += double(tree_.nodes[t].size()) * tree_.nodes[std::size_t(p2p_source_[std::size_t(k)])].size();
      const double cost = pairs * pair_seconds(m_) + double(m2l_source_.size()) * conversion_seconds(p_.order, m_);
      if (best < 0 || cost < best) {
        best = cost;
        leaf_size_ = leaf;
      }
    }
    tuned_n_ = x_.size();
    since_tuned_ = 0;
  }
  tree_ = build_octree(x_, a_, leaf_size_);
  const std::size_t n = x_.size();
  sorted_.x.resize(n);
  sorted_.y.resize(n);
  sorted_.z.resize(n);
  sorted_.a.resize(n);
  for (std::size_t q = 0; q < n; ++q) {
    const std::size_t i = std::size_t(tree_.order[q]);
    sorted_.x[q] = x_[i].x();
    sorted_.y[q] = x_[i].y();
    sorted_.z[q] = x_[i].z();
    sorted_.a[q] = a_[i];
  }
  moments_.assign(tree_.nodes.size() * kPot * std::size_t(moment_set_.size()), 0.0);
  if (p_.evaluation == TreeEvaluation::fmm) {
    locals_.assign(tree_.nodes.size() * kPot * std::size_t(deriv_set_.size()), 0.0);
    build_interaction_lists();
  }
}

// Dual-tree traversal from (root, root): a well-separated pair is converted, two leaves are summed
// pair by pair, otherwise the node with the larger radius (a non-leaf) is split. Lists are built
// serially, in a fixed order, per target node.
void TreeFarField::build_interaction_lists() {
  const int nn = int(tree_.nodes.size());
  parent_.assign(std::size_t(nn), -1);
  for (int k = 0; k < nn; ++k)
    for (int c = 0; c < tree_.nodes[std::size_t(k)].child_count; ++c)
      parent_[std::size_t(tree_.nodes[std::size_t(k)].first_child + c)] = k;
  std::vector<std::vector<int>> m2l(static_cast<std::size_t>(nn)), p2p(static_cast<std::size_t>(nn));
  if (nn > 0) {
    std::vector<std::pair<int, int>> stack{{0, 0}};
    while (!stack.empty()) {
      const auto [t, s] = stack.back();
      stack.pop_back();
      const OctreeNode& T = tree_.nodes[std::size_t(t)];
      const OctreeNode& S = tree_.nodes[std::size_t(s)];
      const double dist = (T.centre - S.centre).norm();
      const double rr = T.radius + S.radius;
      if (t != s && rr < p_.theta * dist && dist - rr > T.a_max + S.a_max) {
        m2l[std::size_t(t)].push_back(s);
        continue;
      }
      if (T.leaf() && S.leaf()) {
        p2p[std::size_t(t)].push_back(s);
        continue;
      }
      const bool split_target = S.leaf() || (!T.leaf() && T.radius >= S.radius);
      // pushed in reverse so that children are visited in their stored order
      if (split_target) {
        for (int c = T.child_count - 1; c >= 0; --c) stack.push_back({T.first_child + c, s});
      } else {
        for (int c = S.child_count - 1; c >= 0; --c) stack.push_back({t, S.first_child + c});
      }
    }
  }
  auto flatten = [&](const std::vector<std::vector<int>>& lists, std::vector<int>& begin, std::vector<int>& flat) {
    begin.assign(1, 0);
    flat.clear();
    for (const auto& l : lists) {
      flat.insert(flat.end(), l.begin(), l.end());
      begin.push_back(int(flat.size()));
    }
  };
  flatten(m2l, m2l_begin_, m2l_source_);
  flatten(p2p, p2p_begin_, p2p_source_);
}

// Moments of the four potentials of every node, summed from its particles (the source terms of
// the header). M[pot][g] multiplies d^g G(x - c).
// Moments of every node, deepest level first: a leaf's from its particles (P2M), an inner node's by
// shifting its children's (M2M, exact for the truncated moments): with Delta = c_child - c_node,
//   M_gamma += sum_(delta <= gamma) M^child_(gamma - delta) (-Delta)^delta / delta!
// for each potential, then psi += Delta_j phi_j (psi's charges and dipoles carry s = x - c).
void TreeFarField::compute_moments(const VecX& in) const {
  const int d = dof_per_particle(m_);
  const int ng = moment_set_.size();
  const long nodes = long(tree_.nodes.size());
  const bool torque = has_torque(m_), stresslet = has_stresslet(m_);
  std::vector<std::vector<int>> levels(static_cast<std::size_t>(tree_.depth) + 1);
  for (long k = 0; k < nodes; ++k) levels[std::size_t(tree_.nodes[std::size_t(k)].level)].push_back(int(k));
#pragma omp parallel
  {
    std::vector<double> w(static_cast<std::size_t>(ng));
    for (int level = tree_.depth; level >= 0; --level) {
      const std::vector<int>& at = levels[std::size_t(level)];
#pragma omp for schedule(dynamic, 4)
    for (std::size_t n = 0; n < at.size(); ++n) {
      const int k = at[n];
      const OctreeNode& node = tree_.nodes[std::size_t(k)];
      double* M = moments_.data() + std::size_t(k) * kPot * std::size_t(ng);
      std::fill(M, M + kPot * ng, 0.0);
      if (!node.leaf()) {
        for (int c = node.first_child; c < node.first_child + node.child_count; ++c) {
          const double* MC = moments_.data() + std::size_t(c) * kPot * std::size_t(ng);
          const Vec3 delta = tree_.nodes[std::size_t(c)].centre - node.centre;
          scaled_powers(delta, moment_set_, w.data());
          for (int g = 0; g < ng; ++g) {
            double l[kPot];
            shift_sum(MC, w.data(), m2m_terms_.data(), m2m_begin_[std::size_t(g)], m2m_begin_[std::size_t(g) + 1], l);
            double* mg = M + kPot * g;
            mg[0] += l[0];
            mg[1] += l[1];
            mg[2] += l[2];
            mg[3] += l[3] + delta[0] * l[0] + delta[1] * l[1] + delta[2] * l[2];
          }
        }
        continue;
      }
      for (int q = node.begin; q < node.end; ++q) {
        const std::size_t i = std::size_t(tree_.order[std::size_t(q)]);
        const double* src = in.data() + long(i) * d;
        const Vec3 s = x_[i] - node.centre;
        const Vec3 F(src[0], src[1], src[2]);
        Mat3 D = Mat3::Zero();
        Mat3 S = Mat3::Zero();
        if (torque) {
          const Vec3 T(src[3], src[4], src[5]);
          // D_jl = -1/2 eps_jlm T_m
          D(0, 1) = -0.5 * T.z();
          D(1, 0) = 0.5 * T.z();
          D(0, 2) = 0.5 * T.y();
          D(2, 0) = -0.5 * T.y();
          D(1, 2) = -0.5 * T.x();
          D(2, 1) = 0.5 * T.x();
        }
        if (stresslet) {
          Vec5 s5;
          for (int r = 0; r < 5; ++r) s5[r] = src[6 + r];
          S = from_vec5(s5);
          D += S;
        }
        const double a2 = a_[i] * a_[i];
        const Vec3 psi_dipole = D.transpose() * s + (a2 / 3.0) * F;  // (s_j D_jl + a^2/3 F_l)
        const double psi_charge = s.dot(F);
        const Mat3 Q = (a2 / 5.0) * S;
        scaled_powers(s, moment_set_, w.data());
        for (int g = 0; g < ng; ++g) {
          const double wg = w[std::size_t(g)];
          for (int j = 0; j < 3; ++j) M[g * kPot + j] += F[j] * wg;
          M[g * kPot + 3] += psi_charge * wg;
          // dipoles: coefficient -moment_l w_g at g + e_l
          for (int l = 0; l < 3; ++l) {
            const int gl = moment_set_.plus(g, l);
            if (gl < 0) continue;
            for (int j = 0; j < 3; ++j) M[gl * kPot + j] -= D(j, l) * wg;
            M[gl * kPot + 3] -= psi_dipole[l] * wg;
            if (stresslet)
              for (int jj = 0; jj < 3; ++jj) {
                const int gjl = moment_set_.plus(gl, jj);
                if (gjl >= 0) M[gjl * kPot + 3] += Q(jj, l) * wg;
              }
          }
        }
      }
    }
    }
  }
}

void TreeFarField::apply(const VecX& in, VecX& out) const {
  const int d = dof_per_particle(m_);
  const long n = long(x_.size());
  if (in.size() != n * d)
    throw std::invalid_argument("tree far field: input of size " + std::to_string(in.size()) + ", expected " +
                                std::to_string(n * d));
  out.setZero(n * d);
  if (n == 0) return;
  const double t0 = omp_get_wtime();
  compute_moments(in);
  const double t1 = omp_get_wtime();
  if (p_.evaluation == TreeEvaluation::fmm)
    apply_fmm(in, out);
  else
    apply_barnes_hut(in, out);
  stats_.upward_seconds = t1 - t0;
  stats_.downward_seconds = omp_get_wtime() - t1;
}

void TreeFarField::apply_fmm(const VecX& in, VecX& out) const {
  stats_ = TreeProductStats{};
  {
    const std::size_t ng = std::size_t(moment_set_.size()), nodes = tree_.nodes.size();
    for (std::size_t k = 0; k < nodes; ++k) {
      double* M = moments_.data() + k * kPot * ng;
      for (const auto& f : moment_fold_)
        for (int pot = 0; pot < kPot; ++pot) {
          M[kPot * f[1] + pot] -= M[kPot * f[0] + pot];
          M[kPot * f[2] + pot] -= M[kPot * f[0] + pot];
          M[kPot * f[0] + pot] = 0;
        }
    }
  }
  {
    const int d = dof_per_particle(m_);
    const std::size_t n = x_.size();
    for (int c = 0; c < d; ++c) sorted_.in[c].resize(n);
    for (std::size_t q = 0; q < n; ++q)
      for (int c = 0; c < d; ++c) sorted_.in[c][q] = in[long(tree_.order[q]) * d + c];
  }
  pair_count_ = 0;
  long m2l_count = 0;
  for (std::size_t k = 0; k + 1 < m2l_begin_.size(); ++k) m2l_count += m2l_begin_[k + 1] - m2l_begin_[k];
#pragma omp parallel
#pragma omp single
  downward(0, in, out);
  stats_.m2l = m2l_count;
  stats_.pair_interactions = pair_count_;
}

// Local expansion of node t: shifted from its parent's, plus the conversions of its list; a leaf
// then evaluates its targets (expansion + exact pairs); children are tasks.
void TreeFarField::downward(int t, const VecX& in, VecX& out) const {
  const int ng = moment_set_.size(), nl = deriv_set_.size();
  const OctreeNode& T = tree_.nodes[std::size_t(t)];
  double* L = locals_.data() + std::size_t(t) * kPot * std::size_t(nl);
  std::fill(L, L + kPot * nl, 0.0);
  std::vector<double> tmp(static_cast<std::size_t>(nl));
  // conversions of the list (locals with beta_z <= 1), psi about the target's centre:
  // + (c_S - c_T)_j phi_j
  std::vector<double> D(static_cast<std::size_t>(nl));
  const int q_end = m2l_begin_[std::size_t(t) + 1];
  int q_first = m2l_begin_[std::size_t(t)];
  if (q_end - q_first >= 4) {
    const int nkeep = int(moment_keep_.size());
    std::vector<double> work(static_cast<std::size_t>(4 * (nl + kPot * nkeep)) + 4);
    // 32-byte alignment for the 4-wide vectors
    double* w = work.data();
    while (reinterpret_cast<std::uintptr_t>(w) % 32 != 0) ++w;
    for (; q_first + 4 <= q_end; q_first += 4) {
      const double* Ms[4];
      double rx[4], ry[4], rz[4];
      for (int l = 0; l < 4; ++l) {
        const int s = m2l_source_[std::size_t(q_first + l)];
        const OctreeNode& S = tree_.nodes[std::size_t(s)];
        Ms[l] = moments_.data() + std::size_t(s) * kPot * std::size_t(ng);
        rx[l] = T.centre[0] - S.centre[0];
        ry[l] = T.centre[1] - S.centre[1];
        rz[l] = T.centre[2] - S.centre[2];
      }
      convert4(Ms, rx, ry, rz, deriv_set_, moment_keep_.data(), nkeep, m2l_terms4_.data(), m2l_term_begin_.data(), nl,
               w, L);
    }
  }
  for (int q = q_first; q < q_end; ++q) {
    const int s = m2l_source_[std::size_t(q)];
    const OctreeNode& S = tree_.nodes[std::size_t(s)];
    const double* M = moments_.data() + std::size_t(s) * kPot * std::size_t(ng);
    const Vec3 R = T.centre - S.centre;
    inverse_distance_derivatives(R, deriv_set_, D.data());
    convert(M, D.data(), R, m2l_terms_.data(), m2l_term_begin_.data(), nl, L);
  }
  if (m2l_begin_[std::size_t(t)] < m2l_begin_[std::size_t(t) + 1])
    for (const auto& r : local_rebuild_)
      for (int pot = 0; pot < kPot; ++pot) L[kPot * r[0] + pot] = -L[kPot * r[1] + pot] - L[kPot * r[2] + pot];
  if (parent_[std::size_t(t)] >= 0) {
    const int par = parent_[std::size_t(t)];
    const double* LP = locals_.data() + std::size_t(par) * kPot * std::size_t(nl);
    const Vec3 shift = T.centre - tree_.nodes[std::size_t(par)].centre;
    // L_beta += sum_delta LP_(beta + delta) shift^delta / delta!  (scaled_powers takes -shift),
    // then psi about the child's centre: + (c_parent - c_child)_j phi_j
    scaled_powers(-shift, deriv_set_, tmp.data());
    for (int b = 0; b < nl; ++b) {
      double l[kPot];
      shift_sum(LP, tmp.data(), shift_terms_.data(), shift_begin_[std::size_t(b)], shift_begin_[std::size_t(b) + 1], l);
      L[kPot * b] += l[0];
      L[kPot * b + 1] += l[1];
      L[kPot * b + 2] += l[2];
      L[kPot * b + 3] += l[3] - (shift[0] * l[0] + shift[1] * l[1] + shift[2] * l[2]);
    }
  }
  if (!T.leaf()) {
    for (int c = 0; c < T.child_count; ++c) {
      const int child = T.first_child + c;
#pragma omp task default(shared) firstprivate(child) if (tree_.nodes[std::size_t(child)].size() > 24)
      downward(child, in, out);
    }
#pragma omp taskwait
    return;
  }
  // targets of the leaf
  const int d = dof_per_particle(m_);
  const int nb = beta_set_.size();
  const DerivativeIndex ix(beta_set_);
  std::vector<double> P(static_cast<std::size_t>(4 * nb));
  const double scale = 1.0 / (8.0 * kPi * mu_);
  long pairs = 0;
  for (int q = T.begin; q < T.end; ++q) {
    const int i = tree_.order[std::size_t(q)];
    const double ai = a_[std::size_t(i)];
    double* yi = out.data() + long(i) * d;
    mobility::apply_self(ai, mu_, m_, in.data() + long(i) * d, yi);
    const Vec3 R = x_[std::size_t(i)] - T.centre;
    scaled_powers(-R, deriv_set_, tmp.data());  // R^delta / delta!
    std::fill(P.begin(), P.end(), 0.0);
    for (int b = 0; b < nb; ++b) {
      const auto& be = beta_set_[b];
      const int bb = deriv_set_.index(be[0], be[1], be[2]);
      double l[kPot];
      shift_sum(L, tmp.data(), shift_terms_.data(), shift_begin_[std::size_t(bb)], shift_begin_[std::size_t(bb) + 1], l);
      for (int pot = 0; pot < kPot; ++pot) P[std::size_t(pot * nb + b)] = l[pot];
    }
    double y[11] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    add_responses(P.data(), nb, ix, R, ai, m_, y);
    for (int r = 0; r < d; ++r) yi[r] += scale * y[r];
    for (int k = p2p_begin_[std::size_t(t)]; k < p2p_begin_[std::size_t(t) + 1]; ++k) {
      const OctreeNode& S = tree_.nodes[std::size_t(p2p_source_[std::size_t(k)])];
      add_pairs_sorted(sorted_, S.begin, S.end, q, ai, mu_, m_, yi, pairs);
    }
  }
#pragma omp atomic
  pair_count_ += pairs;
}

void TreeFarField::apply_barnes_hut(const VecX& in, VecX& out) const {
  const int d = dof_per_particle(m_);
  const long n = long(x_.size());
  const int ng = moment_set_.size(), nb = beta_set_.size(), nd = deriv_set_.size();
  const double scale = 1.0 / (8.0 * kPi * mu_);
  const double theta2 = p_.theta * p_.theta;
  const DerivativeIndex ix(beta_set_);
  long node_count = 0, pair_count = 0;
#pragma omp parallel reduction(+ : node_count, pair_count)
  {
    std::vector<double> D(static_cast<std::size_t>(nd));
    std::vector<double> P(static_cast<std::size_t>(4 * nb));  // d^beta of the 4 potentials
    std::vector<int> stack;
    stack.reserve(256);
#pragma omp for schedule(dynamic, 32)
    for (long q = 0; q < n; ++q) {
      const int i = tree_.order[std::size_t(q)];
      const Vec3 xi = x_[std::size_t(i)];
      const double ai = a_[std::size_t(i)];
      double* yi = out.data() + long(i) * d;
      mobility::apply_self(ai, mu_, m_, in.data() + long(i) * d, yi);
      double y[11] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
      stack.clear();
      stack.push_back(0);
      while (!stack.empty()) {
        const int k = stack.back();
        stack.pop_back();
        const OctreeNode& node = tree_.nodes[std::size_t(k)];
        const Vec3 R = xi - node.centre;
        const double R2 = R.squaredNorm();
        const bool far = node.radius * node.radius < theta2 * R2 && std::sqrt(R2) - node.radius > ai + node.a_max;
        if (!far) {
          if (node.leaf())
            add_pairs(tree_.order, node.begin, node.end, i, x_, a_, mu_, m_, in, yi, pair_count);
          else
            for (int c = 0; c < node.child_count; ++c) stack.push_back(node.first_child + c);
          continue;
        }
        ++node_count;
        inverse_distance_derivatives(R, deriv_set_, D.data());
        const double* M = moments_.data() + std::size_t(k) * kPot * std::size_t(ng);
        std::fill(P.begin(), P.end(), 0.0);
        for (int g = 0; g < ng; ++g) {
          const double m0 = M[kPot * g], m1 = M[kPot * g + 1], m2 = M[kPot * g + 2], m3 = M[kPot * g + 3];
          const int* si = sum_index_.data() + std::size_t(g * nb);
          for (int b = 0; b < nb; ++b) {
            const double dv = D[std::size_t(si[b])];
            P[std::size_t(b)] += m0 * dv;
            P[std::size_t(nb + b)] += m1 * dv;
            P[std::size_t(2 * nb + b)] += m2 * dv;
            P[std::size_t(3 * nb + b)] += m3 * dv;
          }
        }
        add_responses(P.data(), nb, ix, R, ai, m_, y);
      }
      for (int r = 0; r < d; ++r) yi[r] += scale * y[r];
    }
  }
  stats_ = TreeProductStats{};
  stats_.node_interactions = node_count;
  stats_.pair_interactions = pair_count;
}

}  // namespace stokesian::trees
