#include "lubrication/near_field.hpp"

#include "engine/core/parallel.hpp"
#include "engine/core/sym_traceless.hpp"

#include "engine/kernels/far_field.hpp"
#include "engine/kernels/mobility_pair.hpp"
#include "trees/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "engine/core/errors.hpp"

namespace stokesian::lubrication {

namespace {
// The level-m rows and columns of a pair matrix in the 22-entry FTS layout [F1 T1 S1 F2 T2 S2].
MatX level_block(const PairMatrix& R, Moments m) {
  const int d = dof_per_particle(m);
  MatX out(2 * d, 2 * d);
  for (int q = 0; q < 2 * d; ++q)
    for (int p = 0; p < 2 * d; ++p) out(p, q) = R(p < d ? p : p - d + 11, q < d ? q : q - d + 11);
  return out;
}
}  // namespace

NearField::NearField(Moments m, double mu, NearFieldParams p) : m_(m), mu_(mu), p_(p), far_inverse_(m) {
  if (!(p.cutoff > 2.0) || !(p.taper >= 0.0) || !(p.cutoff - p.taper >= 2.0) || !(p.min_gap > 0.0))
    throw std::invalid_argument("NearField: need cutoff > 2, 0 <= taper <= cutoff - 2, min_gap > 0");
  const SqueezeParams& q = p.squeeze;
  if (p.model == Lubrication::squeeze && !(q.contact_gap > 0.0 && q.contact_gap < q.slip_gap && q.slip_gap < q.transition_gap))
    throw std::invalid_argument("NearField: squeeze gaps need 0 < contact_gap < slip_gap < transition_gap");
}

NearFieldParams near_field_params(const HydroParams& h, Moments moments, double max_cutoff) {
  NearFieldParams p;
  p.min_gap = h.lubrication_min_gap;
  p.model = h.lubrication;
  p.squeeze = h.squeeze;
  if (h.lubrication_cutoff_auto) {
    const CutoffBand b = cutoff_for_tolerance(h.tolerance, moments, max_cutoff);
    p.cutoff = b.s_cut;
    p.taper = b.s_cut - b.s_in;
    if (!h.lubrication_taper_auto) {  // the tolerance fixes s_in; the taper only widens the band
      p.taper = h.lubrication_taper;
      p.cutoff = b.s_in + h.lubrication_taper;
    }
  } else {
    p.cutoff = h.lubrication_cutoff;
    p.taper = h.lubrication_taper_auto ? 0.0 : h.lubrication_taper;
  }
  return p;
}

MatX NearField::exact_pair(const Vec3& r_vec, double ai, double aj) const {
  ResistanceScalars s12, s21;
  tables_.pair_scalars(r_vec.norm(), ai, aj, s12, s21);
  return level_block(two_sphere_resistance(r_vec, ai, aj, mu_, s12, s21), m_);
}

MatX NearField::pair_block(const Vec3& r_vec_in, double ai, double aj) const {
  if (p_.model == Lubrication::squeeze) return pair_block_reference(r_vec_in, ai, aj);
  // Regularised gap: evaluate at xi >= min_gap along the line of centres.
  const double r = r_vec_in.norm(), half = 0.5 * (ai + aj);
  const double xi = r / half - 2.0;
  const Vec3 dir = r > 0 ? Vec3(r_vec_in / r) : Vec3::UnitZ();
  const Vec3 r_vec = xi < p_.min_gap ? Vec3(dir * half * (2.0 + p_.min_gap)) : r_vec_in;
  const double rn = r_vec.norm();
  ResistanceScalars s12, s21, f12, f21;
  tables_.pair_scalars(rn, ai, aj, s12, s21);
  far_inverse_.scalars(rn, ai, aj, mu_, f12, f21);
  for (int k = 0; k < kNumScalars; ++k) {
    scalar_at(s12, k) -= scalar_at(f12, k);
    scalar_at(s21, k) -= scalar_at(f21, k);
  }
  return level_block(two_sphere_resistance(r_vec, ai, aj, mu_, s12, s21), m_);
}

MatX NearField::pair_block_reference(const Vec3& r_vec_in, double ai, double aj) const {
  const int d = dof_per_particle(m_);
  if (p_.model == Lubrication::squeeze) {
    // c g g^T with w = g.v the normal velocity of j relative to i (squeeze.hpp): in the generalised
    // velocities v = [U_i - U_inf(x_i), Omega_i, e_i, U_j - U_inf(x_j), Omega_j, e_j] (e = -E_inf
    // coordinates, the same in both e columns) w = n.(U_j - U_i) = n.(v_Uj - v_Ui) + r n.E_inf.n, and
    // r n.E_inf.n = -(r/2) q.(e_i + e_j) with q the coordinates of n n (engine/core/sym_traceless.hpp).
    // F and FT have no e columns: there the ambient strain does not enter (as for exact lubrication).
    const double r = r_vec_in.norm();
    const Vec3 n = r > 0 ? Vec3(r_vec_in / r) : Vec3::UnitZ();
    VecX g = VecX::Zero(2 * d);
    g.segment<3>(0) = -n;
    g.segment<3>(d) = n;
    if (m_ == Moments::FTS) {
      const Vec5 q = to_vec5(n * n.transpose());
      g.segment<5>(6) = -0.5 * r * q;
      g.segment<5>(d + 6) = -0.5 * r * q;
    }
    return squeeze_coefficient(r - ai - aj, ai, aj, mu_, p_.squeeze) * g * g.transpose();
  }
  // Regularised gap: evaluate at xi >= min_gap along the line of centres.
  const double r = r_vec_in.norm(), half = 0.5 * (ai + aj);
  const double xi = r / half - 2.0;
  const Vec3 dir = r > 0 ? Vec3(r_vec_in / r) : Vec3::UnitZ();
  const Vec3 r_vec = xi < p_.min_gap ? Vec3(dir * half * (2.0 + p_.min_gap)) : r_vec_in;
  const MatX Rex = exact_pair(r_vec, ai, aj);
  // Two-body far-field mobility of the same pair (sphere i at 0, j at r_vec), inverted.
  // Blocks from the closed forms (mobility::fill_pair_block, as the dense assembly uses; the
  // explicit-tensor dense_mobility is the reference it is tested against); (0,1) = (1,0)^T.
  MatX M2(2 * d, 2 * d);
  mobility::fill_pair_block(mobility::self_scalars(ai, mu_), Vec3::UnitZ(), m_, M2.data(), 2 * d);
  mobility::fill_pair_block(mobility::self_scalars(aj, mu_), Vec3::UnitZ(), m_, M2.data() + d * 2 * d + d, 2 * d);
  const double rn = r_vec.norm();
  mobility::fill_pair_block(mobility::pair_scalars(aj, ai, rn, mu_, m_), Vec3(r_vec / rn), m_, M2.data() + d, 2 * d);
  M2.topRightCorner(d, d) = M2.bottomLeftCorner(d, d).transpose();
  const MatX Rinf = M2.llt().solve(MatX::Identity(M2.rows(), M2.cols()));
  return Rex - Rinf;
}

NearField::WeightedPairs NearField::weighted_pairs(const std::vector<Vec3>& x, const std::vector<double>& a,
                                                  const Domain& domain) const {
  WeightedPairs wp;
  const double amax = *std::max_element(a.begin(), a.end());
  // exact tables for few distinct size ratios, interpolated in ln(lambda) otherwise
  if (p_.model == Lubrication::exact) tables_.prepare_radii(a);
  wp.pairs = trees::neighbor_pairs(x, a, domain, (p_.cutoff - 2.0) * amax);
  for (std::size_t k = 0; k < wp.pairs.size(); ++k) {
    const auto& p = wp.pairs[k];
    const double w = weight(2.0 * p.dist / (a[std::size_t(p.i)] + a[std::size_t(p.j)]));
    if (w > 0.0) {
      wp.in.push_back(k);
      wp.w.push_back(w);
    }
  }
  return wp;
}

SparseMatrix NearField::assemble(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                                 NearFieldStats* stats) const {
  SymmetricBlockMatrix R;
  assemble(x, a, domain, R, stats);
  return R.to_sparse();
}

void NearField::assemble(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                         SymmetricBlockMatrix& R, NearFieldStats* stats) const {
  const int d = dof_per_particle(m_);
  const long dd = long(d) * d;
  const WeightedPairs wp = weighted_pairs(x, a, domain);
  const auto& pairs = wp.pairs;
  const auto& in = wp.in;
  const auto& wt = wp.w;
  // The block pattern first (block_matrix.hpp: diagonal, then the upper partners ascending), then
  // the pair blocks in parallel, a chunk of pairs at a time: the off-diagonal block straight into its
  // place, the two diagonal parts into a chunk buffer whose parts each particle then adds in pair
  // order (the same sums for any thread count). The peak memory is the matrix plus 2 d^2 doubles per
  // pair of one chunk.
  const long n = long(x.size());
  std::vector<std::vector<int>> upper(static_cast<std::size_t>(n));
  std::vector<char> has_pair(static_cast<std::size_t>(n), 0);
  for (std::size_t k : in) {
    const int i = pairs[k].i, j = pairs[k].j;
    upper[std::size_t(std::min(i, j))].push_back(std::max(i, j));
    has_pair[std::size_t(i)] = has_pair[std::size_t(j)] = 1;
  }
  for (auto& u : upper) std::sort(u.begin(), u.end());
  R.reset(n, d, has_pair, upper);
  // Every off-diagonal block is written whole by its pair below;
  // only the diagonal blocks, which sum their pairs' parts, start from zero.
  for (long q = 0; q < n; ++q)
    if (has_pair[std::size_t(q)]) std::fill_n(R.block(R.row_begin(q)), dd, 0.0);
  NearFieldStats st;
  for (std::size_t m = 0; m < in.size(); ++m) {
    const auto& p = pairs[in[m]];
    const double xi = 2.0 * p.dist / (a[std::size_t(p.i)] + a[std::size_t(p.j)]) - 2.0;
    ++st.pairs;
    st.tapered += wt[m] < 1.0;
    st.regularised += p_.model == Lubrication::exact ? xi < p_.min_gap
                                                      : p.dist - a[std::size_t(p.i)] - a[std::size_t(p.j)] < p_.squeeze.contact_gap;
    st.overlaps += xi < 0;
    if (xi < st.min_xi) {
      st.min_xi = xi;
      st.worst_i = p.i;
      st.worst_j = p.j;
    }
  }
  // Incidences (pair m, side) per particle, m ascending: each particle's diagonal block adds its
  // pairs' parts in this order.
  std::vector<long> first(std::size_t(n) + 1, 0);
  for (std::size_t m = 0; m < in.size(); ++m) {
    ++first[std::size_t(pairs[in[m]].i) + 1];
    ++first[std::size_t(pairs[in[m]].j) + 1];
  }
  for (long q = 0; q < n; ++q) first[std::size_t(q) + 1] += first[std::size_t(q)];
  std::vector<long> incidence(static_cast<std::size_t>(first.back()));
  std::vector<long> cursor(first.begin(), first.end() - 1);
  for (std::size_t m = 0; m < in.size(); ++m) {
    incidence[std::size_t(cursor[std::size_t(pairs[in[m]].i)]++)] = 2 * long(m);
    incidence[std::size_t(cursor[std::size_t(pairs[in[m]].j)]++)] = 2 * long(m) + 1;
  }
  std::copy(first.begin(), first.end() - 1, cursor.begin());  // per particle: next incidence to add
  const long chunk = 16384;
  const bool parallel = long(in.size()) >= parallel::kNearFieldPairs;
  std::vector<double> diag(std::size_t(std::min<long>(chunk, long(in.size()))) * std::size_t(2 * dd));
  for (long m0 = 0; m0 < long(in.size()); m0 += chunk) {
    const long m1 = std::min<long>(m0 + chunk, long(in.size()));
#pragma omp parallel for schedule(dynamic, 8) if (parallel)
    for (long m = m0; m < m1; ++m) {
      const auto& p = pairs[in[std::size_t(m)]];
      const double ai = a[std::size_t(p.i)], aj = a[std::size_t(p.j)];
      MatX B = pair_block(-p.r, ai, aj);  // r_vec = x_j - x_i
      if (wt[std::size_t(m)] < 1.0) B *= wt[std::size_t(m)];
      // The stored block (min, max): A_ij = B(0:d, d:2d) when i < j, else A_ji = B(d:2d, 0:d).
      const bool ij = p.i < p.j;
      double* off = R.block(R.find(std::min(p.i, p.j), std::max(p.i, p.j)));
      double* dg = diag.data() + std::size_t(m - m0) * std::size_t(2 * dd);
      for (int v = 0; v < d; ++v)
        for (int u = 0; u < d; ++u) {
          off[v * d + u] = ij ? B(u, d + v) : B(d + u, v);
          dg[v * d + u] = B(u, v);
          dg[dd + v * d + u] = B(d + u, d + v);
        }
    }
#pragma omp parallel for schedule(dynamic, 64) if (parallel)
    for (long q = 0; q < n; ++q) {
      long& t = cursor[std::size_t(q)];
      if (t == first[std::size_t(q) + 1] || incidence[std::size_t(t)] / 2 >= m1) continue;
      double* qq = R.block(R.row_begin(q));
      for (; t < first[std::size_t(q) + 1] && incidence[std::size_t(t)] / 2 < m1; ++t) {
        const long m = incidence[std::size_t(t)] / 2, side = incidence[std::size_t(t)] % 2;
        const double* dg = diag.data() + std::size_t(m - m0) * std::size_t(2 * dd) + std::size_t(side * dd);
        for (long e = 0; e < dd; ++e) qq[e] += dg[e];
      }
    }
  }
  if (stats) *stats = st;
}

void NearField::factorize(const SparseMatrix& R, CholmodFactor& factor, const std::vector<Vec3>& x,
                          const std::vector<double>& a, const Domain& domain, const std::vector<long>* entries) const {
  try {
    factor.factorize(R);
  } catch (const NotPositiveDefinite& e) {
    const long d = dof_per_particle(m_);
    const long p = (entries && e.column >= 0 && e.column < long(entries->size()) ? (*entries)[std::size_t(e.column)]
                                                                                 : e.column) / d;
    long q = -1;
    double best = 1e300, gap = 0.0;
    for (long j = 0; j < long(x.size()); ++j) {
      if (j == p) continue;
      const double r = domain.minimum_image(x[std::size_t(p)] - x[std::size_t(j)]).norm();
      const double xi = 2.0 * r / (a[std::size_t(p)] + a[std::size_t(j)]) - 2.0;
      if (xi < best) {
        best = xi;
        gap = r - a[std::size_t(p)] - a[std::size_t(j)];
        q = j;
      }
    }
    std::ostringstream o;
    o << "near-field resistance: " << e.what() << " (particle " << p;
    if (q >= 0) o << "; closest pair (" << p << ", " << q << ") at surface gap " << gap << " a, symmetric gap " << best;
    o << ")";
    throw PhysicsError(o.str());
  }
}

VecX NearField::brownian_force(const std::vector<Vec3>& x, const std::vector<double>& a, const Domain& domain,
                               const std::vector<char>& given, const RandomStream& rng) const {
  const int d = dof_per_particle(m_);
  const long n = long(x.size());
  if (long(given.size()) != n * d) throw std::invalid_argument("NearField::brownian_force: `given` needs d N flags");
  VecX f = VecX::Zero(n * d);
  if (n < 2) return f;
  // The same pairs, weights and order as assemble().
  const WeightedPairs wp = weighted_pairs(x, a, domain);
  const auto& pairs = wp.pairs;
  const auto& in = wp.in;
  const auto& wt = wp.w;
  const std::size_t stride = std::size_t(2 * d);
  std::vector<double> out(in.size() * stride, 0.0);  // each pair's force on its 2 d entries
  std::vector<double> worst_pivot(in.size(), 0.0);    // most negative relative pivot per pair
#pragma omp parallel for schedule(dynamic, 8) if (long(in.size()) >= parallel::kNearFieldPairs)
  for (long m = 0; m < long(in.size()); ++m) {
    const auto& p = pairs[in[std::size_t(m)]];
    int idx[22], k = 0;  // given entries of the pair, in pair layout [i entries, j entries]
    for (int u = 0; u < 2 * d; ++u)
      if (given[std::size_t((u < d ? p.i : p.j) * d + u % d)]) idx[k++] = u;
    if (k == 0) continue;
    const MatX B = pair_block(-p.r, a[std::size_t(p.i)], a[std::size_t(p.j)]);
    MatX Bg(k, k);
    for (int r = 0; r < k; ++r)
      for (int c = 0; c < k; ++c) Bg(r, c) = wt[std::size_t(m)] * B(idx[r], idx[c]);
    const Eigen::LDLT<MatX> ldlt(Bg);
    VecX D = ldlt.vectorD();
    const double dmax = D.cwiseAbs().maxCoeff();
    worst_pivot[std::size_t(m)] = dmax > 0 ? D.minCoeff() / dmax : 0.0;
    D = D.cwiseMax(0.0).cwiseSqrt();
    RandomStream r = rng;
    r.seek_normal(std::uint64_t(m) * stride);
    VecX w(k);
    for (int q = 0; q < 2 * d; ++q) {  // 2 d draws per pair whatever k is (fixed slice)
      const double z = r.normal();
      if (q < k) w[q] = z;
    }
    VecX t = ldlt.matrixL() * D.cwiseProduct(w).eval();
    t = ldlt.transpositionsP().transpose() * t;
    double* o = out.data() + std::size_t(m) * stride;
    for (int q = 0; q < k; ++q) o[idx[q]] = t[q];
  }
  for (std::size_t m = 0; m < in.size(); ++m) {
    const auto& p = pairs[in[m]];
    if (worst_pivot[m] < -1e-10) {
      std::ostringstream o;
      o << "near-field Brownian force: the lubrication block of pair (" << p.i << ", " << p.j
        << ") is not positive semi-definite (relative pivot " << worst_pivot[m] << ") at symmetric gap "
        << 2.0 * p.dist / (a[std::size_t(p.i)] + a[std::size_t(p.j)]) - 2.0;
      throw PhysicsError(o.str());
    }
    const double* o = out.data() + m * stride;
    for (int u = 0; u < d; ++u) {
      f[long(p.i) * d + u] += o[u];
      f[long(p.j) * d + u] += o[d + u];
    }
  }
  return f;
}

MatX NearField::assemble_dense(const std::vector<Vec3>& x, const std::vector<double>& a) const {
  const int d = dof_per_particle(m_);
  const long n = long(x.size());
  if (p_.model == Lubrication::exact) tables_.prepare_radii(a);
  MatX R = MatX::Zero(n * d, n * d);
  for (long i = 0; i < n; ++i)
    for (long j = i + 1; j < n; ++j) {
      const Vec3 rv = x[std::size_t(j)] - x[std::size_t(i)];
      const double ai = a[std::size_t(i)], aj = a[std::size_t(j)];
      const double w = weight(2.0 * rv.norm() / (ai + aj));
      if (!(w > 0.0)) continue;
      const MatX B = w * pair_block(rv, ai, aj);
      R.block(i * d, i * d, d, d) += B.topLeftCorner(d, d);
      R.block(i * d, j * d, d, d) += B.topRightCorner(d, d);
      R.block(j * d, i * d, d, d) += B.bottomLeftCorner(d, d);
      R.block(j * d, j * d, d, d) += B.bottomRightCorner(d, d);
    }
  return R;
}

}  // namespace stokesian::lubrication
