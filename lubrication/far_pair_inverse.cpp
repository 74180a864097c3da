// R2B_inf as two-sphere scalars; mathematics in far_pair_inverse.hpp.
#include "lubrication/far_pair_inverse.hpp"

#include "engine/kernels/mobility_pair.hpp"

#include <array>
#include <cmath>
#include <stdexcept>

namespace stokesian::lubrication {

namespace {

using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 22, 22>;

// M2B_inf in the pair frame: sphere 1 at the origin, sphere 2 at r e_z; coordinates [sphere 1 | sphere 2].
Small pair_frame_mobility(double r, double a1, double a2, double mu, Moments m) {
  const int d = dof_per_particle(m);
  Small M = Small::Zero(2 * d, 2 * d);
  const Vec3 ez = Vec3::UnitZ();
  mobility::fill_pair_block(mobility::self_scalars(a1, mu), ez, m, M.data(), 2 * d);
  mobility::fill_pair_block(mobility::self_scalars(a2, mu), ez, m, M.data() + d * 2 * d + d, 2 * d);
  mobility::fill_pair_block(mobility::pair_scalars(a2, a1, r, mu, m), ez, m, M.data() + d, 2 * d);
  M.topRightCorner(d, d) = M.bottomLeftCorner(d, d).transpose();
  return M;
}

// R(g, g) = M(g, g)^{-1} for the coordinates g of one group (at most 22): Cholesky factor L, then
// L^{-1} by forward substitution and R = L^{-T} L^{-1}, in plain loops (Eigen's small fixed-size
// inverses went through its blocked triangular solves, a fifth of the pair block's time).
void invert_group(const Small& M, const std::vector<int>& g, Small& R) {
  const int k = int(g.size());
  double L[22][22], W[22][22];  // Cholesky factor (lower) and its inverse (lower)
  for (int i = 0; i < k; ++i)
    for (int j = 0; j <= i; ++j) {
      double v = M(g[std::size_t(i)], g[std::size_t(j)]);
      for (int q = 0; q < j; ++q) v -= L[i][q] * L[j][q];
      if (i == j) {
        if (!(v > 0.0)) throw std::runtime_error("FarPairInverse: two-body far-field mobility not positive definite");
        L[i][i] = std::sqrt(v);
      } else {
        L[i][j] = v / L[j][j];
      }
    }
  for (int j = 0; j < k; ++j) {
    W[j][j] = 1.0 / L[j][j];
    for (int i = j + 1; i < k; ++i) {
      double v = 0.0;
      for (int q = j; q < i; ++q) v -= L[i][q] * W[q][j];
      W[i][j] = v / L[i][i];
    }
  }
  for (int i = 0; i < k; ++i)
    for (int j = 0; j <= i; ++j) {
      double v = 0.0;
      for (int q = i; q < k; ++q) v += W[q][i] * W[q][j];
      R(g[std::size_t(i)], g[std::size_t(j)]) = R(g[std::size_t(j)], g[std::size_t(i)]) = v;
    }
}

// Member index in ResistanceScalars of scalar type t (0..10: XA YA YB XC YC XG YG YH XM YM ZM),
// self ("11"/"22") or cross ("12"/"21").
int member(int t, bool cross) { return 2 * t + (cross ? 1 : 0); }

}  // namespace

FarPairInverse::FarPairInverse(Moments m) : m_(m), d_(dof_per_particle(m)) {
  const int d = d_, n = 2 * d;
  // Groups: connected components of the pattern of M2B_inf at a generic pair.
  const Small M = pair_frame_mobility(3.3, 1.0, 1.7, 1.0, m);
  const double tiny = 1e-13 * M.cwiseAbs().maxCoeff();
  std::vector<int> group(std::size_t(n), -1);
  for (int s = 0; s < n; ++s) {
    if (group[std::size_t(s)] >= 0) continue;
    const int g = int(groups_.size());
    groups_.emplace_back();
    std::vector<int> stack{s};
    group[std::size_t(s)] = g;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      groups_[std::size_t(g)].push_back(i);
      for (int j = 0; j < n; ++j)
        if (group[std::size_t(j)] < 0 && std::abs(M(i, j)) > tiny) {
          group[std::size_t(j)] = g;
          stack.push_back(j);
        }
    }
  }
  // Owned entries of a block and their powers of L: A (F, U) 1, B (T, U) 2, C (T, Omega) 3,
  // G (S, U) 2, H (S, Omega) 3, M (S, e) 3.
  struct Region {
    int r0, c0, rows, cols, power;
  };
  std::vector<Region> regions{{0, 0, 3, 3, 1}};
  if (m != Moments::F) regions.insert(regions.end(), {{3, 0, 3, 3, 2}, {3, 3, 3, 3, 3}});
  if (m == Moments::FTS) regions.insert(regions.end(), {{6, 0, 5, 3, 2}, {6, 3, 5, 3, 3}, {6, 6, 5, 5, 3}});
  std::vector<std::array<int, 2>> entries;
  std::vector<int> power;
  for (const Region& g : regions)
    for (int i = 0; i < g.rows; ++i)
      for (int j = 0; j < g.cols; ++j) {
        entries.push_back({g.r0 + i, g.c0 + j});
        power.push_back(g.power);
      }
  const int ntypes = m == Moments::F ? 2 : m == Moments::FT ? 5 : 11;
  // Unit-scalar patterns of sphere 1's self block at L = 1 (a1 = a2 = 1/2, mu = 1), fitted by least
  // squares.
  MatX D(long(entries.size()), ntypes);
  for (int t = 0; t < ntypes; ++t) {
    ResistanceScalars s11{}, s22{};
    scalar_at(s11, member(t, false)) = 1.0;
    const PairMatrix R = two_sphere_resistance(Vec3(0.0, 0.0, 3.0), 0.5, 0.5, 1.0, s11, s22);
    for (std::size_t e = 0; e < entries.size(); ++e) D(long(e), t) = R(entries[e][0], entries[e][1]);
  }
  const MatX fit = D.completeOrthogonalDecomposition().pseudoInverse();
  for (int t = 0; t < ntypes; ++t)
    for (std::size_t e = 0; e < entries.size(); ++e)
      if (std::abs(fit(t, long(e))) > 1e-12) terms_.push_back({t, entries[e][0], entries[e][1], power[e], fit(t, long(e))});
  // The same patterns hold for the three other blocks (checked here, once).
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      for (int t = 0; t < ntypes; ++t) {
        ResistanceScalars s11{}, s22{};
        scalar_at(a == 0 ? s11 : s22, member(t, a != b)) = 1.0;
        const PairMatrix R = two_sphere_resistance(Vec3(0.0, 0.0, 3.0), 0.5, 0.5, 1.0, s11, s22);
        for (std::size_t e = 0; e < entries.size(); ++e)
          if (std::abs(R(11 * a + entries[e][0], 11 * b + entries[e][1]) - D(long(e), t)) > 1e-12)
            throw std::logic_error("FarPairInverse: the blocks' scalar patterns differ");
      }
    }
}

void FarPairInverse::scalars(double r, double a1, double a2, double mu, ResistanceScalars& s11_12,
                             ResistanceScalars& s22_21) const {
  const int d = d_;
  const Small M = pair_frame_mobility(r, a1, a2, mu, m_);
  Small R = Small::Zero(2 * d, 2 * d);
  for (const std::vector<int>& g : groups_) invert_group(M, g, R);
  s11_12 = ResistanceScalars{};
  s22_21 = ResistanceScalars{};
  const double rad[2] = {a1, a2};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      const double L = rad[a] + rad[b];
      const double scale[4] = {0.0, 1.0 / (mu * L), 1.0 / (mu * L * L), 1.0 / (mu * L * L * L)};
      ResistanceScalars& s = a == 0 ? s11_12 : s22_21;
      for (const Term& q : terms_)
        scalar_at(s, member(q.type, a != b)) += q.weight * scale[q.power] * R(d * a + q.row, d * b + q.col);
    }
}

}  // namespace stokesian::lubrication
