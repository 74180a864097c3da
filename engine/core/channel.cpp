#include "engine/core/channel.hpp"

#include "engine/core/outline.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stokesian {

bool in_channel(const ChannelParams& c, const Domain& d, const Vec3& x) {
  const Vec3 r = x - channel_centre(d);
  switch (c.kind) {
    case ChannelParams::Kind::none: return true;
    case ChannelParams::Kind::plane: return r.y() > 0.0;
    case ChannelParams::Kind::slit: return std::abs(r.y()) < 0.5 * c.height;
    case ChannelParams::Kind::duct: return std::abs(r.y()) < 0.5 * c.height && std::abs(r.z()) < 0.5 * c.width;
    case ChannelParams::Kind::outline: return first_outside_channel(c, d, {x}) < 0;
  }
  return true;
}

long first_outside_channel(const ChannelParams& c, const Domain& d, const std::vector<Vec3>& x) {
  if (c.kind == ChannelParams::Kind::outline) {
    const Outline o = make_outline(c);
    for (std::size_t i = 0; i < x.size(); ++i)
      if (!(std::abs(x[i].z()) < 0.5 * c.depth && o.contains(Vec2(x[i].x(), x[i].y())))) return long(i);
    return -1;
  }
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!in_channel(c, d, x[i])) return long(i);
  return -1;
}

double cross_section_area(const ChannelParams& c, const Domain& d) {
  switch (c.kind) {
    case ChannelParams::Kind::slit: return c.height * (d.periodic() ? d.box.z() : c.depth);
    case ChannelParams::Kind::duct: return c.height * c.width;
    case ChannelParams::Kind::outline: {
      const Outline o = make_outline(c);
      return o.length(std::size_t(o.inlet)) * c.depth;
    }
    default: return 0.0;
  }
}

namespace {

// Duct: a = H/2, b = W/2. Sum over odd n of the correction series (header) and its derivatives,
// in units of 16 a^2 G / (mu pi^3).
struct DuctSeries {
  double u = 0, uy = 0, uz = 0;
};
DuctSeries duct_series(double a, double b, double eta, double zeta) {
  DuctSeries s;
  const double az = std::abs(zeta), sz = zeta < 0 ? -1.0 : 1.0;
  for (int k = 0; k < kDuctTerms; ++k) {
    const double n = 2.0 * k + 1.0, q = n * kPi / (2.0 * a);
    // cosh(q zeta)/cosh(q b) and sinh(q zeta)/cosh(q b) without overflow.
    const double e = std::exp(q * (az - b)), eb = std::exp(-2.0 * q * b), ez = std::exp(-2.0 * q * az);
    const double ch = e * (1.0 + ez) / (1.0 + eb), sh = sz * e * (1.0 - ez) / (1.0 + eb);
    const double sign = (k % 2 == 0) ? 1.0 : -1.0, n3 = n * n * n;
    const double c = std::cos(q * eta), si = std::sin(q * eta);
    s.u += sign / n3 * ch * c;
    s.uy += -sign / n3 * ch * q * si;
    s.uz += sign / n3 * sh * q * c;
    if (e < 1e-17 && k > 2) break;  // later terms are below 1e-17 of the first
  }
  return s;
}

}  // namespace

ChannelFlow::ChannelFlow(const ChannelParams& c, const Domain& d, double mean_velocity)
    : c_(c), d_(d), centre_(channel_centre(d)), mean_(mean_velocity) {
  if (c.kind == ChannelParams::Kind::slit) {
    // U = G H^2 / (12 mu)
    g_mu_ = 12.0 * mean_ / (c.height * c.height);
  } else if (c.kind == ChannelParams::Kind::duct) {
    const double a = 0.5 * c.height, b = 0.5 * c.width;
    double sum = 0.0;
    for (int k = 0; k < kDuctTerms; ++k) {
      const double n = 2.0 * k + 1.0, t = std::tanh(n * kPi * b / (2.0 * a)) / std::pow(n, 5);
      sum += t;
      if (t < 1e-18 * sum) break;
    }
    const double bracket = 1.0 - 192.0 * a / (std::pow(kPi, 5) * b) * sum;
    g_mu_ = 3.0 * mean_ / (a * a * bracket);
  } else {
    throw std::invalid_argument("ChannelFlow: a pressure-driven flow needs a slit or a duct");
  }
}

double ChannelFlow::velocity(const Vec3& x, double* du_dy, double* du_dz) const {
  if (du_dy) *du_dy = 0.0;
  if (du_dz) *du_dz = 0.0;
  if (!in_channel(c_, d_, x)) return 0.0;
  const Vec3 r = x - centre_;
  const double eta = r.y(), zeta = r.z();
  const double a = 0.5 * c_.height;
  double u = 0.5 * g_mu_ * (a * a - eta * eta), uy = -g_mu_ * eta, uz = 0.0;
  if (c_.kind == ChannelParams::Kind::duct) {
    const DuctSeries s = duct_series(a, 0.5 * c_.width, eta, zeta);
    const double k = 16.0 * a * a * g_mu_ / (kPi * kPi * kPi);
    u -= k * s.u;
    uy -= k * s.uy;
    uz -= k * s.uz;
  }
  if (du_dy) *du_dy = uy;
  if (du_dz) *du_dz = uz;
  return u;
}

void ChannelFlow::sample(const std::vector<Vec3>& x, FlowSample& out) const {
  const std::size_t n = x.size();
  out.u.assign(n, Vec3::Zero());
  out.omega.assign(n, Vec3::Zero());
  out.E.assign(n, Vec5::Zero());
  for (std::size_t i = 0; i < n; ++i) {
    double uy = 0, uz = 0;
    const double u = velocity(x[i], &uy, &uz);
    out.u[i] = Vec3(u, 0, 0);
    out.omega[i] = Vec3(0.0, 0.5 * uz, -0.5 * uy);
    Mat3 E = Mat3::Zero();
    E(0, 1) = E(1, 0) = 0.5 * uy;
    E(0, 2) = E(2, 0) = 0.5 * uz;
    out.E[i] = to_vec5(E);
  }
}

namespace {

// Cell of coordinate v on an increasing axis: index i with axis[i] <= v <= axis[i+1] and the weight
// t of axis[i+1]; false outside. A single-node axis is uniform: cell 0, weight 0.
bool locate(const std::vector<double>& ax, double v, std::size_t& i, double& t) {
  if (ax.size() == 1) {
    i = 0;
    t = 0.0;
    return true;
  }
  if (!(v >= ax.front() && v <= ax.back())) return false;
  i = std::size_t(std::upper_bound(ax.begin(), ax.end(), v) - ax.begin());
  i = std::min(std::max<std::size_t>(i, 1), ax.size() - 1) - 1;
  t = (v - ax[i]) / (ax[i + 1] - ax[i]);
  return true;
}

}  // namespace

TabulatedFlow::TabulatedFlow(std::shared_ptr<const FlowGrid> g) : g_(std::move(g)) {
  const FlowGrid& G = *g_;
  const std::size_t n[3] = {G.axis[0].size(), G.axis[1].size(), G.axis[2].size()};
  u_.resize(G.u.size());
  for (std::size_t k = 0; k < u_.size(); ++k) u_[k] = G.u[k].allFinite() ? G.u[k] : Vec3::Zero();
  du_.assign(u_.size(), Mat3::Zero());
  for (std::size_t k = 0; k < n[2]; ++k)
    for (std::size_t j = 0; j < n[1]; ++j)
      for (std::size_t i = 0; i < n[0]; ++i) {
        const std::size_t idx[3] = {i, j, k};
        Mat3& D = du_[G.index(i, j, k)];
        for (int c = 0; c < 3; ++c) {
          if (n[c] == 1) continue;
          std::size_t lo[3] = {i, j, k}, hi[3] = {i, j, k};
          if (idx[c] > 0) --lo[c];
          if (idx[c] + 1 < n[c]) ++hi[c];
          const double h = G.axis[std::size_t(c)][hi[c]] - G.axis[std::size_t(c)][lo[c]];
          D.col(c) = (u_[G.index(hi[0], hi[1], hi[2])] - u_[G.index(lo[0], lo[1], lo[2])]) / h;
        }
        moving_ = moving_ || u_[G.index(i, j, k)].norm() > 0;
        strain_ = strain_ || (D + D.transpose()).norm() > 0;
      }
}

Vec3 TabulatedFlow::velocity(const Vec3& x, Mat3* grad) const {
  const FlowGrid& G = *g_;
  if (grad) grad->setZero();
  std::size_t c[3];
  double t[3];
  for (int a = 0; a < 3; ++a)
    if (!locate(G.axis[std::size_t(a)], x[a], c[a], t[a])) return Vec3::Zero();
  Vec3 u = Vec3::Zero();
  for (int corner = 0; corner < 8; ++corner) {
    double w = 1.0;
    std::size_t id[3];
    for (int a = 0; a < 3; ++a) {
      const int up = (corner >> a) & 1;
      if (up && G.axis[std::size_t(a)].size() == 1) {
        w = 0.0;
        break;
      }
      id[a] = c[a] + std::size_t(up);
      w *= up ? t[a] : 1.0 - t[a];
    }
    if (w == 0.0) continue;
    const std::size_t k = G.index(id[0], id[1], id[2]);
    u += w * u_[k];
    if (grad) *grad += w * du_[k];
  }
  return u;
}

void TabulatedFlow::sample(const std::vector<Vec3>& x, FlowSample& out) const {
  const std::size_t n = x.size();
  out.u.resize(n);
  out.omega.resize(n);
  out.E.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Mat3 G;
    out.u[i] = velocity(x[i], &G);
    out.omega[i] = 0.5 * Vec3(G(2, 1) - G(1, 2), G(0, 2) - G(2, 0), G(1, 0) - G(0, 1));
    Mat3 E = 0.5 * (G + G.transpose());
    E -= (E.trace() / 3.0) * Mat3::Identity();
    out.E[i] = to_vec5(E);
  }
}

std::shared_ptr<const AmbientField> make_ambient_field(const FlowParams& f, const ChannelParams& c, const Domain& d) {
  if (f.kind == FlowParams::Kind::poiseuille && c.kind == ChannelParams::Kind::outline) {
    if (f.grid) return std::make_shared<TabulatedFlow>(f.grid);  // solved when the scene was read
    auto solved = std::make_shared<const OutlineFlow>(solve_outline_flow(make_outline(c), f.mean_velocity, f.grid_spacing));
    return std::make_shared<TabulatedFlow>(std::shared_ptr<const FlowGrid>(solved, &solved->grid));
  }
  if (f.kind == FlowParams::Kind::poiseuille) return std::make_shared<ChannelFlow>(c, d, f.mean_velocity);
  if (f.kind == FlowParams::Kind::tabulated) {
    if (!f.grid) throw std::invalid_argument("make_ambient_field: a tabulated flow without its grid");
    return std::make_shared<TabulatedFlow>(f.grid);
  }
  return std::make_shared<AmbientFlow>(ambient_flow(f));
}

}  // namespace stokesian
