#include "engine/sd_accelerated.hpp"

#include "engine/accuracy.hpp"
#include "engine/brownian.hpp"

#include "engine/core/errors.hpp"
#include "engine/core/parallel.hpp"
#include "engine/kernels/far_field.hpp"
#include "ewald/ewald_reference.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <cmath>
#include <limits>
#include <sstream>

namespace stokesian {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::vector<std::vector<std::size_t>> bisect_clusters(const std::vector<Vec3>& x, std::size_t cap) {
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<std::pair<std::size_t, std::size_t>> ranges;  // of `order`
  std::vector<std::pair<std::size_t, std::size_t>> todo{{0, order.size()}};
  while (!todo.empty()) {
    const auto [lo, hi] = todo.back();
    todo.pop_back();
    if (hi - lo <= cap) {
      ranges.emplace_back(lo, hi);
      continue;
    }
    Vec3 mn = x[order[lo]], mx = mn;
    for (std::size_t k = lo; k < hi; ++k) {
      mn = mn.cwiseMin(x[order[k]]);
      mx = mx.cwiseMax(x[order[k]]);
    }
    int axis;
    (mx - mn).maxCoeff(&axis);
    const std::size_t mid = lo + (hi - lo) / 2;
    std::nth_element(order.begin() + long(lo), order.begin() + long(mid), order.begin() + long(hi),
                     [&](std::size_t p, std::size_t q) { return x[p][axis] < x[q][axis]; });
    todo.emplace_back(lo, mid);
    todo.emplace_back(mid, hi);
  }
  std::sort(ranges.begin(), ranges.end());  // a fixed order, independent of the work list
  std::vector<std::vector<std::size_t>> clusters;
  for (const auto& [lo, hi] : ranges) clusters.emplace_back(order.begin() + long(lo), order.begin() + long(hi));
  return clusters;
}

AcceleratedStokesianDynamics::AcceleratedStokesianDynamics(std::unique_ptr<MobilityOperator> far_field, double mu,
                                                           lubrication::NearFieldParams p, double krylov_tolerance,
                                                           double shift, Method method, double factor_gap,
                                                           double brownian_tolerance)
    : m_(far_field->moments()), mu_(mu), op_(std::move(far_field)), near_(m_, mu, p), tol_(krylov_tolerance),
      shift_(shift), factor_gap_(factor_gap), brownian_tol_(brownian_tolerance), method_(method) {}

void AcceleratedStokesianDynamics::set_far_field(const Configuration& c) {
  const auto t0 = std::chrono::steady_clock::now();
  op_->set_configuration(c);
  stats_.seconds_far_field_setup = seconds_since(t0);
  stats_.totals.far_field_setup += stats_.seconds_far_field_setup;
}

void AcceleratedStokesianDynamics::assemble_near_field(const Configuration& c) {
  const auto t0 = std::chrono::steady_clock::now();
  config_.store(c);
  near_stats_ = {};
  near_.assemble(c.x, c.a, c.domain, Rnf_, &near_stats_);
  D_ = self_resistance(c.a, mu_, m_);
  stats_.seconds_near_field_assembly = seconds_since(t0);
  stats_.totals.near_field_assembly += stats_.seconds_near_field_assembly;
  if (!factored_) {  // first configuration: the entries of mobile particles' forces (no fixed particles)
    const int d = dof_per_particle(m_), dv = m_ == Moments::FTS ? 6 : d;
    factored_v_.clear();
    for (long i = 0; i < long(c.x.size()); ++i)
      for (int q = 0; q < dv; ++q) factored_v_.push_back(i * d + q);
  }
}

void AcceleratedStokesianDynamics::prepare(const Configuration& c) {
  set_far_field(c);
  assemble_near_field(c);
  factorise(factored_v_);
}

std::vector<PreparePhase> AcceleratedStokesianDynamics::prepare_phases(const Configuration& c) {
  const long n = long(c.x.size());
  return {{"far_field_setup", op_->set_configuration_uses_threads(n), [this, &c] { set_far_field(c); }, {}},
          {"near_field_assembly", true, [this, &c] { assemble_near_field(c); }, {}},  // parallel over pairs
          {"factorisation", false, [this] { factorise(factored_v_); }, {1}}};
}

// R~ = R_nf restricted to the entries v, plus the shift on its diagonal; factorised by CHOLMOD.
void AcceleratedStokesianDynamics::factorise(const std::vector<long>& v) {
  const auto t0 = std::chrono::steady_clock::now();
  const long n = Rnf_.rows();
  std::vector<int> pos(std::size_t(n), -1);
  for (std::size_t i = 0; i < v.size(); ++i) pos[std::size_t(v[i])] = int(i);
  std::vector<Eigen::Triplet<double, int>> t;
  const int d = dof_per_particle(m_);
  // Stored blocks (p, q), p <= q: a strong pair's entries (both at v) go to the upper triangle of R~.
  for (long p = 0; p < Rnf_.block_rows(); ++p)
    for (long b = Rnf_.row_begin(p); b < Rnf_.row_end(p); ++b) {
      const long q = Rnf_.col(b);
      if (p != q && factor_gap_ < 1e300) {
        const double r = config_.domain.minimum_image(config_.x[std::size_t(p)] - config_.x[std::size_t(q)]).norm();
        if (!(2.0 * r / (config_.a[std::size_t(p)] + config_.a[std::size_t(q)]) - 2.0 < factor_gap_)) continue;
      }
      const double* B = Rnf_.block(b);
      for (int w = 0; w < d; ++w) {
        const int cj = pos[std::size_t(q * d + w)];
        if (cj < 0) continue;
        for (int u = 0; u < (p == q ? w + 1 : d); ++u) {
          const int ri = pos[std::size_t(p * d + u)];
          if (ri >= 0) t.emplace_back(std::min(ri, cj), std::max(ri, cj), B[w * d + u]);
        }
      }
    }
  for (std::size_t i = 0; i < v.size(); ++i) t.emplace_back(int(i), int(i), shift_ * D_[v[i]]);
  Rt_.resize(long(v.size()), long(v.size()));
  Rt_.setFromTriplets(t.begin(), t.end());
  // R_nf is a sum of positive semi-definite pair blocks, so R~ fails only with a pair block that
  // is not: the error names the particle of the failing entry and its closest neighbour.
  near_.factorize(Rt_, factor_, config_.x, config_.a, config_.domain, &v);
  factored_v_ = v;
  factored_ = true;
  stats_.factor_nonzeros = factor_.factor_nonzeros();
  stats_.seconds_factorisation = seconds_since(t0);
  stats_.totals.factorisation += stats_.seconds_factorisation;
  factorise_held(v);
}

// Held particles: those whose force entry is not in v. Clusters by recursive bisection at the median
// along the longest extent of their centres.
void AcceleratedStokesianDynamics::factorise_held(const std::vector<long>& v) {
  const auto t0 = std::chrono::steady_clock::now();
  const int d = dof_per_particle(m_);
  const long n = long(config_.x.size());
  std::vector<char> mobile(std::size_t(n), 0);
  for (long e : v)
    if (e % d == 0) mobile[std::size_t(e / d)] = 1;
  std::vector<long> held;
  std::vector<Vec3> held_x;
  std::vector<double> held_a;
  for (long i = 0; i < n; ++i)
    if (!mobile[std::size_t(i)]) {
      held.push_back(i);
      held_x.push_back(config_.x[std::size_t(i)]);
      held_a.push_back(config_.a[std::size_t(i)]);
    }
  // Held particles do not move: the blocks of the last configuration are kept while the held
  // particles, their centres and radii are the same (bitwise).
  const double strain = config_.domain.reduced_strain();
  if (!held_lu_.empty() && held == held_ids_ && held_x == held_x_ && held_a == held_a_ && held_precondition_ &&
      config_.domain.kind == held_domain_.kind && config_.domain.box == held_domain_.box &&
      std::abs(strain - held_domain_.reduced_strain()) <= kHeldStrainReuse) {
    stats_.seconds_held_preconditioner = seconds_since(t0);
    return;
  }
  held_entries_.clear();
  held_lu_.clear();
  held_iterations_ = 0;
  coarse_members_.clear();
  coarse_offset_.clear();
  coarse_dims_.clear();
  coarse_size_ = 0;
  coarse_built_ = false;
  coarse_lu_ = {};
  held_ids_ = held;
  held_x_ = held_x;
  held_a_ = held_a;
  held_domain_ = config_.domain;
  if (held_precondition_ && !held.empty()) {
    // Centres of the held particles (an open domain: as they are).
    std::vector<Vec3> x(held.size());
    for (std::size_t k = 0; k < held.size(); ++k) x[k] = config_.x[std::size_t(held[k])];
    const auto clusters = bisect_clusters(x, std::size_t(kHeldCluster));
    ewald::EwaldReferenceOptions ewald_options;
    ewald_options.tail = kHeldEwaldTail;
    held_entries_.resize(clusters.size());
    held_lu_.resize(clusters.size());
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      std::vector<Vec3> xc;
      std::vector<double> ac;
      std::vector<long>& entries = held_entries_[c];
      for (std::size_t k : clusters[c]) {
        const long i = held[k];
        xc.push_back(x[k]);
        ac.push_back(config_.a[std::size_t(i)]);
        for (int q = 0; q < d; ++q) entries.push_back(i * d + q);
      }
      MatX P = config_.domain.periodic() ? ewald::ewald_mobility(xc, ac, mu_, m_, config_.domain, ewald_options)
                                         : assemble_mobility(xc, ac, mu_, m_);
      for (std::size_t r = 0; r < entries.size(); ++r) P.row(long(r)) *= D_[entries[r]];
      held_lu_[c].compute(P);
    }
    // Coarse clusters (more than one block): the same bisection with the cap doubled until the
    // columns (3 + 3 per direction of extent, at most 12 per cluster) fit kHeldCoarseColumns.
    if (held_coarse_ && clusters.size() > 1) {
      std::size_t cap = std::size_t(kHeldCluster);
      auto coarse = bisect_clusters(x, cap);
      while (12 * long(coarse.size()) > kHeldCoarseColumns) coarse = bisect_clusters(x, cap *= 2);
      for (const auto& cluster : coarse) {
        Vec3 centre = Vec3::Zero();
        for (std::size_t k : cluster) centre += x[k];
        centre /= double(cluster.size());
        Mat3 cov = Mat3::Zero();
        for (std::size_t k : cluster) cov += (x[k] - centre) * (x[k] - centre).transpose();
        cov /= double(cluster.size());
        // Linear directions: the principal axes with a spread (a sheet of wall particles has two),
        // scaled to unit variance; each member keeps its coordinates along them.
        Eigen::SelfAdjointEigenSolver<Mat3> es(cov);
        const double top = es.eigenvalues().maxCoeff();
        Mat3 dirs = Mat3::Zero();
        long m = 0;
        for (int q = 0; q < 3; ++q)
          if (top > 0.0 && es.eigenvalues()[q] > 1e-4 * top)
            dirs.col(m++) = es.eigenvectors().col(q) / std::sqrt(es.eigenvalues()[q]);
        std::vector<std::pair<long, Vec3>> members;
        for (std::size_t k : cluster) members.emplace_back(held[k], dirs.transpose() * (x[k] - centre));
        coarse_offset_.push_back(coarse_size_);
        coarse_dims_.push_back(m);
        coarse_size_ += 3 + 3 * m;
        coarse_members_.push_back(std::move(members));
      }
    }
  }
  held_wave_.reset();
  if (held_precondition_ && held_long_wave_ && !held.empty() && config_.domain.periodic()) {
    auto w = std::make_unique<LongWaveDeflation>(Configuration{held_x, held_a, config_.domain}, m_,
                                                 LongWaveDeflation::kMinRatio, kHeldWaveVectors);
    if (!w->empty()) held_wave_ = std::move(w);
  }
  stats_.held_clusters = int(held_lu_.size());
  stats_.held_wave_vectors = held_wave_ ? long(held_wave_->wave_vectors()) : 0;
  stats_.seconds_held_preconditioner = seconds_since(t0);
  stats_.totals.held_preconditioner += stats_.seconds_held_preconditioner;
}

// z <- P^-1 z: each cluster's entries solved with its block, the other entries unchanged.
void AcceleratedStokesianDynamics::apply_held_inverse(VecX& z) const {
  const int d = dof_per_particle(m_);
  auto wave = [&] {
    if (!held_wave_) return;
    VecX h(long(held_ids_.size()) * d), gh;
    for (std::size_t k = 0; k < held_ids_.size(); ++k)
      for (int q = 0; q < d; ++q) h[long(k) * d + q] = z[held_ids_[k] * d + q];
    held_wave_->apply(h, gh);
    for (std::size_t k = 0; k < held_ids_.size(); ++k)
      for (int q = 0; q < d; ++q) z[held_ids_[k] * d + q] = gh[long(k) * d + q];
  };
  wave();
  for (std::size_t c = 0; c < held_lu_.size(); ++c) {
    const std::vector<long>& e = held_entries_[c];
    VecX r(long(e.size()));
    for (std::size_t k = 0; k < e.size(); ++k) r[long(k)] = z[e[k]];
    r = held_lu_[c].solve(r);
    for (std::size_t k = 0; k < e.size(); ++k) z[e[k]] = r[long(k)];
  }
  wave();
}

// Z^T v and z += Z w: per coarse cluster, the sum of the translational entries of v (3) and their
// first moments along its scaled directions (3 per direction).
void AcceleratedStokesianDynamics::coarse_restrict(const VecX& v, VecX& out) const {
  const int d = dof_per_particle(m_);
  out.setZero(coarse_size_);
  for (std::size_t c = 0; c < coarse_members_.size(); ++c) {
    const long col = coarse_offset_[c], m = coarse_dims_[c];
    for (const auto& [i, r] : coarse_members_[c]) {
      const Vec3 f = v.segment<3>(i * d);
      out.segment<3>(col) += f;
      for (long p = 0; p < m; ++p) out.segment<3>(col + 3 + 3 * p) += r[p] * f;
    }
  }
}

void AcceleratedStokesianDynamics::coarse_extend(const VecX& w, VecX& z) const {
  const int d = dof_per_particle(m_);
  for (std::size_t c = 0; c < coarse_members_.size(); ++c) {
    const long col = coarse_offset_[c], m = coarse_dims_[c];
    for (const auto& [i, r] : coarse_members_[c]) {
      Vec3 f = w.segment<3>(col);
      for (long p = 0; p < m; ++p) f += r[p] * w.segment<3>(col + 3 + 3 * p);
      z.segment<3>(i * d) += f;
    }
  }
}

// Multiplicative (the held rows of A Z kept): c = E^-1 Z^T y, z = Z c + P_GBG (y - Pi_H A Z c),
// Pi_H the held entries (with all of A Z, I - P A = (I - P_GBG A)(I - Z E^-1 Z^T A); the held rows
// alone depend on the held particles only, so P does not depend on where the mobile ones were when
// it was built). Additive (A Z too large to keep): z = P_GBG y + Z E^-1 Z^T y.
void AcceleratedStokesianDynamics::apply_held_preconditioner(const VecX& y, VecX& z) const {
  if (!coarse_built_) {
    z = y;
    apply_held_inverse(z);
    return;
  }
  VecX zy;
  coarse_restrict(y, zy);
  const VecX c = coarse_lu_.solve(zy);
  z = y;
  if (AZ_.size()) {
    const int d = dof_per_particle(m_);
    const VecX azc = AZ_ * c;
    for (std::size_t k = 0; k < held_ids_.size(); ++k) z.segment(held_ids_[k] * d, d) -= azc.segment(long(k) * d, d);
  }
  apply_held_inverse(z);
  coarse_extend(c, z);
}

// E = Z^T A Z column by column: on a held-only vector A is D M (Q and C^ read the mobile entries
// only), so each column costs one far-field product, made by an operator set to the held particles
// alone when the solver has a factory (then E and the kept rows depend on them alone), else by A.
void AcceleratedStokesianDynamics::build_held_coarse(const LinearOperator& A, long n) {
  const auto t0 = std::chrono::steady_clock::now();
  MatX E(coarse_size_, coarse_size_);
  const int d = dof_per_particle(m_);
  const long nh = long(held_ids_.size()) * d;
  const bool keep = double(nh) * double(coarse_size_) <= kHeldCoarseKept;
  AZ_.resize(keep ? nh : 0, keep ? coarse_size_ : 0);
  // With a factory: D M on the held particles alone (their own operator), scattered back.
  std::unique_ptr<MobilityOperator> held_op;
  if (make_far_field_) {
    held_op = make_far_field_();
    held_op->set_configuration(Configuration{held_x_, held_a_, config_.domain});
  }
  VecX unit = VecX::Zero(coarse_size_), W(n), AW, col, Wh(nh), Mh;
  for (long j = 0; j < coarse_size_; ++j) {
    unit[j] = 1.0;
    W.setZero();
    coarse_extend(unit, W);
    unit[j] = 0.0;
    if (held_op) {
      for (std::size_t k = 0; k < held_ids_.size(); ++k) Wh.segment(long(k) * d, d) = W.segment(held_ids_[k] * d, d);
      held_op->apply(Wh, Mh);
      AW.setZero(n);
      for (std::size_t k = 0; k < held_ids_.size(); ++k)
        AW.segment(held_ids_[k] * d, d) = Mh.segment(long(k) * d, d).cwiseProduct(D_.segment(held_ids_[k] * d, d));
    } else {
      A(W, AW);
    }
    if (keep)
      for (std::size_t k = 0; k < held_ids_.size(); ++k) AZ_.col(j).segment(long(k) * d, d) = AW.segment(held_ids_[k] * d, d);
    coarse_restrict(AW, col);
    E.col(j) = col;
  }
  coarse_lu_.compute(E);
  coarse_built_ = true;
  stats_.held_coarse_columns = coarse_size_;
  stats_.seconds_held_coarse = seconds_since(t0);
  stats_.totals.held_coarse += stats_.seconds_held_coarse;
}

HydroResult AcceleratedStokesianDynamics::solve(const HydroProblem& p) {
  const RigidConstraints c = RigidConstraints::of(m_, p.fixed, p.force, p.torque, p.flow);
  const std::vector<long>& v = c.force_given;
  if (!factored_ || v != factored_v_) factorise(v);
  const long n = long(c.force.size()), nv = long(v.size());
  const auto t0 = std::chrono::steady_clock::now();

  // R_nf z from the symmetric blocks (lubrication/block_matrix.hpp): each stored block read once,
  // in parallel, the same bits for any thread count.
  auto near_product = [&](const VecX& z) -> VecX {
    VecX out;
    Rnf_.multiply(z, out);
    return out;
  };
  // g = f_v + f_B,v - R_vk V_k (c.motion vanishes at v).
  const VecX RVk = near_product(c.motion);
  VecX g(nv);
  for (long i = 0; i < nv; ++i) {
    const long e = v[std::size_t(i)];
    g[i] = c.force[e] - RVk[e] + (p.force_noise ? (*p.force_noise)[e] : 0.0);
  }
  // C z = R~ z - R_vv z for z on the v entries (zero elsewhere); the result on the v entries.
  VecX zv(nv), Cz;
  auto applyC = [&](const VecX& z, VecX& out) {
    for (long i = 0; i < nv; ++i) zv[i] = z[v[std::size_t(i)]];
    const VecX Rz = near_product(z);
    out = Rt_.selfadjointView<Eigen::Upper>() * zv;
    for (long i = 0; i < nv; ++i) out[i] -= Rz[v[std::size_t(i)]];
  };
  // Q z: R~^{-1} on the v entries, zero elsewhere.
  auto applyQ = [&](const VecX& z, VecX& out) {
    VecX zv(nv);
    for (long i = 0; i < nv; ++i) zv[i] = z[v[std::size_t(i)]];
    const VecX s = nv > 0 ? factor_.solve(zv) : VecX();
    out.setZero(n);
    for (long i = 0; i < nv; ++i) out[v[std::size_t(i)]] = s[i];
  };
  int products = 0;
  VecX Mz, y, t, q;
  // Right-hand side D [ (I - M C^) Q g~ + P_k V_k - u_s ].
  VecX gfull = VecX::Zero(n);
  for (long i = 0; i < nv; ++i) gfull[v[std::size_t(i)]] = g[i];
  applyQ(gfull, y);
  t = VecX::Zero(n);
  applyC(y, Cz);
  for (long i = 0; i < nv; ++i) t[v[std::size_t(i)]] = Cz[i];
  op_->apply(t, Mz);
  ++products;
  VecX b = y - Mz + c.motion;
  if (p.slip) b -= *p.slip;
  b = D_.cwiseProduct(b);
  // Operator W -> D [ M (W - C^ Q W) + Q W ].
  const LinearOperator A = [&](const VecX& W, VecX& out) {
    applyQ(W, q);
    applyC(q, Cz);
    t = W;
    for (long i = 0; i < nv; ++i) t[v[std::size_t(i)]] -= Cz[i];
    op_->apply(t, out);
    out += q;
    out.array() *= D_.array();
  };
  // Right preconditioning on the held rows: solve A P^-1 y = b, then W = P^-1 y.
  VecX Py;
  const LinearOperator AP = [&](const VecX& y, VecX& out) {
    apply_held_preconditioner(y, Py);
    A(Py, out);
  };
  const LinearOperator& Aused = held_lu_.empty() ? A : AP;
  // The coarse part costs one product per column. In a box at zero strain (open domains, still
  // periodic boxes: the blocks then last as long as the held particles) it is built at the first
  // solve with the blocks, so the run is the same whether or not it was resumed. In a sheared box the
  // blocks last a strain of kHeldStrainReuse; there it is built once the solves with these blocks
  // have spent kHeldCoarseSaving of their iterations (about what it saves) as many products as it
  // costs, so that whatever the blocks' lifetime it costs at most twice the better choice.
  if (held_coarse_ && !coarse_built_ && coarse_size_ > 0 && !held_lu_.empty() &&
      (coarse_at_once_ || held_domain_.shear_strain == 0.0 ||
       kHeldCoarseSaving * double(held_iterations_) >= double(coarse_size_)))
    build_held_coarse(A, n);
  // From the iterate y: V_v = R~^{-1}(g - W_v), X = W + C^ V, F = X + R_nf V.
  auto recover = [&](const VecX& iterate) {
    VecX W;
    apply_held_preconditioner(iterate, W);
    VecX rv(nv);
    for (long i = 0; i < nv; ++i) rv[i] = g[i] - W[v[std::size_t(i)]];
    const VecX Vv = nv > 0 ? factor_.solve(rv) : VecX();
    VecX V = c.motion, X = W;
    for (long i = 0; i < nv; ++i) V[v[std::size_t(i)]] = Vv[i];
    {
      VecX Vonly = VecX::Zero(n);
      for (long i = 0; i < nv; ++i) Vonly[v[std::size_t(i)]] = Vv[i];
      applyC(Vonly, Cz);
      for (long i = 0; i < nv; ++i) X[v[std::size_t(i)]] += Cz[i];
    }
    const VecX F = X + near_product(V);
    return unpack_solution(m_, p.flow, V, F, p.fixed);
  };
  auto fail = [&](const KrylovResult& kr, double asked) {
    std::ostringstream o;
    o << "accelerated SD: the Krylov solve " << describe(kr) << " after " << kr.iterations
      << " iterations (relative residual " << kr.relative_residual << ", asked " << asked << ") for "
      << config_.x.size() << " particles";
    if (near_stats_.worst_i >= 0)
      o << "; closest pair (" << near_stats_.worst_i << ", " << near_stats_.worst_j << ") at symmetric gap "
        << near_stats_.min_xi;
    throw PhysicsError(o.str());
  };
  // Warm start (engine/core/layout.hpp): the caller's iterate of a related solve. With held
  // particles it is the preconditioned iterate y (W = P^-1 y); their error-estimated passes compare
  // iterates of one run from wherever it started, and the error of each is set by its residual.
  const bool held = any_fixed(p.fixed);
  const bool warm = p.warm && method_ == Method::gmres && p.warm->iterate.size() == n;
  VecX Y = warm ? p.warm->iterate : VecX::Zero(n);
  KrylovResult kr;
  HydroResult res;
  int iterations = 0;
  auto run = [&](double tol, GmresSnapshot* snapshot = nullptr) {
    kr = method_ == Method::gmres ? gmres(Aused, b, Y, tol, kMaxIterations, kRestart, snapshot)
                                  : bicgstab(Aused, b, Y, tol, kMaxIterations);
    // A pass past the GMRES tolerance (held particles' error estimate) may stall at the round-off
    // floor of the problem (residuals near kMinResidual): its iterate already meets tol_, so it is kept.
    const bool floor = kr.status == KrylovStatus::stagnated && tol < tol_ && kr.relative_residual <= tol_;
    if (!kr.converged && !floor) fail(kr, tol);
    iterations += kr.iterations;
    products += kr.products;
  };
  // Held particles: the residual is relative to |b|, whose largest rows can be far larger than some
  // of the solved quantities (held particles in a flow: forces ~ 6 pi mu a |u_inf| against mobile
  // rotations ~ |grad u|; small holding forces on a wall), and the amplification from residual to
  // error depends on the held block (measured 0.1 ... 500). The solve therefore goes on past the
  // GMRES tolerance to a tenth of it, keeping the iterate where it passed the tolerance: the change
  // of every solved quantity between the two estimates the error, error(eps) ~ alpha eps. It then
  // continues to the residual that estimate asks for, until the estimated error is below
  // kHeldErrorTarget times the GMRES tolerance (at most kHeldPasses further passes).
  double estimate = 0.0;
  if (!held) {
    run(tol_);
    stats_.first_pass_iterations = iterations;
    res = recover(Y);
  } else {
    HydroResult prev;
    double eps0;
    if (method_ == Method::gmres) {
      GmresSnapshot snap;
      snap.tol = tol_;
      run(tol_ / 10.0, &snap);
      if (!snap.taken) {  // b = 0: converged at once, nothing to compare
        snap.x = Y;
        snap.relative_residual = kr.relative_residual;
        snap.iterations = kr.iterations;
      }
      prev = recover(snap.x);
      eps0 = snap.relative_residual;
      stats_.first_pass_iterations = snap.iterations;
    } else {
      run(tol_);
      stats_.first_pass_iterations = iterations;
      prev = recover(Y);
      eps0 = kr.relative_residual;
      run(tol_ / 10.0);
    }
    res = recover(Y);
    double eps1 = kr.relative_residual;
    // The estimate needs the residual to have fallen by at least half between the two iterates.
    auto estimate_error = [&] {
      return eps1 <= 0.5 * eps0 ? largest_relative_change(res, prev, p.fixed) * eps1 / (eps0 - eps1) : -1.0;
    };
    estimate = estimate_error();
    for (int pass = 0; pass < kHeldPasses && !(estimate >= 0.0 && estimate <= kHeldErrorTarget * tol_); ++pass) {
      const double next = std::max(estimate > 0.0 ? eps1 * kHeldErrorTarget * tol_ / estimate : eps1 / 10.0, kMinResidual);
      if (next >= eps1) break;
      prev = res;
      eps0 = eps1;
      run(next);
      res = recover(Y);
      eps1 = kr.relative_residual;
      estimate = estimate_error();
    }
    // The tolerance the knobs were derived from (engine/accuracy.hpp): beyond it the solve failed,
    // unless the residual reached the floor of double precision (then the change is round-off).
    if (estimate > tol_ / kKrylovFactor && eps1 > 10.0 * kMinResidual) {
      std::ostringstream o;
      o << "accelerated SD with held particles: the estimated relative error " << estimate
        << " is above the tolerance " << tol_ / kKrylovFactor << " after the refining passes (GMRES residual "
        << kr.relative_residual << ") for " << config_.x.size() << " particles";
      throw PhysicsError(o.str());
    }
  }
  stats_.held_error_estimate = estimate;
  if (!held_lu_.empty()) held_iterations_ += iterations;
  stats_.iterations = iterations;
  stats_.far_field_products = products;
  stats_.relative_residual = kr.relative_residual;
  stats_.seconds_krylov = seconds_since(t0);
  ++stats_.totals.solves;
  stats_.totals.iterations += iterations;
  stats_.totals.products += products;
  stats_.totals.krylov += stats_.seconds_krylov;
  res.iterations = iterations;
  res.regularised_pairs = near_stats_.regularised;
  if (p.warm) p.warm->iterate = Y;
  return res;
}

// Largest relative change (2-norms over particles) between two solutions of one problem: the
// mobile particles' U and Omega, the stresslets S and the held particles' forces F. Each block is
// measured in force units (U times 6 pi mu a, Omega times 8 pi mu a^3) against its own norm, but not
// below kNegligibleBlock of the largest block: a block that vanishes by symmetry (the rotation of a
// sphere pushed along a slit's midplane) holds only round-off, whose relative change means nothing.
double AcceleratedStokesianDynamics::largest_relative_change(const HydroResult& r, const HydroResult& q,
                                                             const std::vector<char>& fixed) const {
  double du = 0, u = 0, dw = 0, w = 0, ds = 0, s = 0, df = 0, f = 0;
  for (std::size_t i = 0; i < r.U.size(); ++i) {
    if (!fixed.empty() && fixed[i]) {
      df += (r.F[i] - q.F[i]).squaredNorm();
      f += r.F[i].squaredNorm();
      continue;
    }
    const double a = config_.a[i], cu = 6.0 * kPi * mu_ * a, cw = 8.0 * kPi * mu_ * a * a * a;
    du += cu * cu * (r.U[i] - q.U[i]).squaredNorm();
    u += cu * cu * r.U[i].squaredNorm();
    if (m_ != Moments::F) {
      dw += cw * cw * (r.Omega[i] - q.Omega[i]).squaredNorm();
      w += cw * cw * r.Omega[i].squaredNorm();
    }
  }
  if (m_ == Moments::FTS)
    for (std::size_t i = 0; i < r.S.size(); ++i) {
      ds += (r.S[i] - q.S[i]).squaredNorm();
      s += r.S[i].squaredNorm();
    }
  const double floor = kNegligibleBlock * std::sqrt(std::max({u, w, s, f}));
  double worst = 0.0;
  for (auto [d, v] : {std::pair{du, u}, {dw, w}, {ds, s}, {df, f}})
    if (d > 0.0) worst = std::max(worst, std::sqrt(d) / std::max(std::sqrt(v), floor));
  return worst;
}

std::vector<Vec3> AcceleratedStokesianDynamics::brownian_displacement(double, double, Rng&) {
  throw PhysicsError("accelerated Stokesian dynamics samples Brownian motion through brownian_force and a "
                     "drift-corrected integrator (fixman), not by displacements");
}

VecX AcceleratedStokesianDynamics::brownian_force(double kT, double dt, const std::vector<char>& fixed, Rng& rng) {
  const std::vector<char> given = force_given_flags(m_, long(config_.x.size()), fixed);
  const double pref = std::sqrt(2.0 * kT / dt);
  auto t0 = std::chrono::steady_clock::now();
  LanczosReport lr;
  VecX xi = far_field_brownian_force(*op_, {config_.x, config_.a, config_.domain}, given, pref, brownian_tol_, rng, &lr);
  stats_.lanczos_iterations = lr.iterations;
  stats_.deflated_wave_vectors = lr.wave_vectors;
  stats_.seconds_far_noise = seconds_since(t0);
  stats_.totals.lanczos_iterations += lr.iterations;
  stats_.totals.far_noise += stats_.seconds_far_noise;
  t0 = std::chrono::steady_clock::now();
  xi += pref * near_.brownian_force(config_.x, config_.a, config_.domain, given, rng.fork());
  stats_.seconds_near_noise = seconds_since(t0);
  stats_.totals.near_noise += stats_.seconds_near_noise;
  return xi;
}

}  // namespace stokesian
