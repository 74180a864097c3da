#pragma once
// A sphere beside walls of wall particles (issue 17), shared by the CI test (tests/test_channel.cpp)
// and the validation (bench/validate_slit.cpp): the flat-wall references and the constrained solve.
//   Faxen's parallel series      mu_par / mu_0  = 1 - 9/16 xi + 1/8 xi^3 - 45/256 xi^4 - 1/16 xi^5
//   Brenner's perpendicular one  mu_perp / mu_0 = 1 - 9/8 xi + 1/2 xi^3 (leading terms)
// xi = a / z, z the centre's distance from the wall's boundary plane (method note, validation 7).
//
// Two walls (a slit of height H): the point-force reflection of two no-slip planes [LM76], not the
// sum of the single walls' reflections. With in-plane Fourier transforms (wavenumber k) the
// disturbance of a Stokeslet at height s between planes z = 0 and z = H splits into the vertical
// velocity w, (D^2 - k^2)^2 w = source, and the vertical vorticity, (D^2 - k^2) zeta = source
// (D = d/dz), each the free-space solution plus a homogeneous one fixed by w = Dw = zeta = 0 on
// both planes. Free parts (unit force, mu = 1):
//   perpendicular force  w = (1 + k|z-s|) e^{-k|z-s|} / (4k)
//   parallel force (x)   w = i k_x W, W = -(z-s) e^{-k|z-s|} / (4k); zeta = -i k_y Z, Z = e^{-k|z-s|} / (2k).
// The regular (reflected) velocity at the source, averaged over the wave vector's direction:
//   u_perp = (1/2pi) int_0^inf k w_reg(s) dk,  u_par = (1/2pi) int_0^inf k (Z_reg(s) - DW_reg(s)) / 2 dk,
// and the sphere's mobility is 1 + 6 pi a u_reg + O(xi^3): the point-force term exactly, the
// finite-size terms (xi^3 and beyond) taken from each wall's series. For one plane (H -> inf) the
// reflection is -9/16 xi and -9/8 xi exactly; at the midplane it gives -1.0041 a/(H/2) parallel
// (Faxen's two-wall coefficient 1.004 [HB65]) and -1.4516 a/(H/2) perpendicular.
// [LM76] Liron & Mochon, J. Eng. Math. 10 (1976) 287; [HB65] Happel & Brenner (1965).
#include "engine/core/quadrature.hpp"
#include "engine/hydrodynamics.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <vector>

namespace stokesian::test_support {

inline double faxen_parallel(double xi) {
  return 1 - 9.0 / 16 * xi + std::pow(xi, 3) / 8 - 45.0 / 256 * std::pow(xi, 4) - std::pow(xi, 5) / 16;
}
inline double brenner_perpendicular(double xi) { return 1 - 9.0 / 8 * xi + 0.5 * std::pow(xi, 3); }

// The point-force reflection of two no-slip planes z = 0 and z = H at height s (0 < s < H), in units
// of 1/(6 pi mu a) for a sphere of radius a: parallel (d = 0) or perpendicular (d = 1) to the planes.
inline double two_plane_reflection(double s, double H, int d, double a = 1.0) {
  // Homogeneous solutions of (D^2 - k^2)^2 f = 0 decaying away from each plane, and derivatives.
  auto basis = [](double k, double H, double z, Eigen::Vector4d& f, Eigen::Vector4d& fp) {
    const double e0 = std::exp(-k * z), eH = std::exp(-k * (H - z));
    f = Eigen::Vector4d(e0, k * z * e0, eH, k * (H - z) * eH);
    fp = Eigen::Vector4d(-k * e0, k * e0 * (1 - k * z), k * eH, -k * eH * (1 - k * (H - z)));
  };
  // w_reg(s) (perpendicular) or DW_reg(s) (parallel) for the free part g, g' given at the planes.
  auto reflected = [&](double k, double g0, double gp0, double gH, double gpH, bool derivative) {
    Eigen::Matrix4d M;
    Eigen::Vector4d f, fp;
    basis(k, H, 0.0, f, fp);
    M.row(0) = f.transpose();
    M.row(1) = fp.transpose();
    basis(k, H, H, f, fp);
    M.row(2) = f.transpose();
    M.row(3) = fp.transpose();
    const Eigen::Vector4d c = M.partialPivLu().solve(-Eigen::Vector4d(g0, gp0, gH, gpH));
    basis(k, H, s, f, fp);
    return c.dot(derivative ? fp : f);
  };
  auto integrand = [&](double k) {
    const double e0 = std::exp(-k * s), eH = std::exp(-k * (H - s));
    if (d == 1) {
      const double g0 = (1 + k * s) * e0 / (4 * k), gH = (1 + k * (H - s)) * eH / (4 * k);
      const double gp0 = k * s * e0 / 4, gpH = -k * (H - s) * eH / 4;
      return k * reflected(k, g0, gp0, gH, gpH, false);
    }
    const double W0 = s * e0 / (4 * k), WH = -(H - s) * eH / (4 * k);
    const double Wp0 = -(1 - k * s) * e0 / (4 * k), WpH = -(1 - k * (H - s)) * eH / (4 * k);
    const double DW = reflected(k, W0, Wp0, WH, WpH, true);
    // Z_reg = alpha e^{-kz} + beta e^{-k(H-z)} with Z_reg = -e^{-k|z-s|}/(2k) on both planes.
    const double q = std::exp(-k * H), det = 1 - q * q;
    const double r0 = -e0 / (2 * k), rH = -eH / (2 * k);
    const double alpha = (r0 - q * rH) / det, beta = (rH - q * r0) / det;
    const double Z = alpha * e0 + beta * eH;
    return k * 0.5 * (Z - DW);
  };
  // Composite 8-point Gauss-Legendre over k in [0, 40 / min(s, H - s)] (the integrand decays as
  // e^{-2k min(s, H-s)}); 300 panels.
  const GaussLegendre q = gauss_legendre(8);
  const double kmax = 40.0 / std::min(s, H - s);
  const int panels = 300;
  const double hp = kmax / panels;
  double sum = 0;
  for (int p = 0; p < panels; ++p)
    for (std::size_t j = 0; j < q.x.size(); ++j) sum += q.w[j] * integrand((p + 0.5 + 0.5 * q.x[j]) * hp);
  return 6 * kPi * a * 0.5 * hp * sum / (2 * kPi);
}

// A sphere of radius 1 at distance z1 from one wall of a slit of height H: the flat-wall mobility,
// the two-plane point-force reflection plus each wall's finite-size series terms.
inline double slit_parallel(double z1, double H) {
  const double x1 = 1 / z1, x2 = 1 / (H - z1);
  return 1 + two_plane_reflection(z1, H, 0) + (faxen_parallel(x1) - 1 + 9.0 / 16 * x1) +
         (faxen_parallel(x2) - 1 + 9.0 / 16 * x2);
}
inline double slit_perpendicular(double z1, double H) {
  const double x1 = 1 / z1, x2 = 1 / (H - z1);
  return 1 + two_plane_reflection(z1, H, 1) + (brenner_perpendicular(x1) - 1 + 9.0 / 8 * x1) +
         (brenner_perpendicular(x2) - 1 + 9.0 / 8 * x2);
}

// One sphere (radius 1) at centre x among the held wall particles (radius 1), pushed along axis d
// by the force 6 pi mu a (mu = 1): the sphere's velocity component d is its mobility in units of
// 1/(6 pi mu a). The sphere is the last particle of the result.
inline HydroResult sphere_among_walls(Hydrodynamics& h, const std::vector<Vec3>& walls, const Vec3& x, int d) {
  std::vector<Vec3> pos = walls;
  pos.push_back(x);
  std::vector<double> a(pos.size(), 1.0);
  std::vector<char> fixed(pos.size(), 1);
  fixed.back() = 0;
  std::vector<Vec3> F(pos.size(), Vec3::Zero()), T(pos.size(), Vec3::Zero());
  F.back()[d] = 6 * kPi;
  return h.solve(pos, a, fixed, F, T);
}

}  // namespace stokesian::test_support
