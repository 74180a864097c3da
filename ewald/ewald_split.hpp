#pragma once
// Ewald splitting of the generating function Psi of the far-field grand mobility.
//
// Every pair block derives from one radial function with Fourier transform
//     Psi^(k) = -g_alpha(k a_alpha) g_beta(k a_beta) / (mu k^4)       (engine/kernels/mobility_pair.hpp).
// For separated spheres only the truncated Faxen factors matter: g -> P(k) = 1 - w a^2 k^2 with
// w = 1/6 (force kind) or 1/10 (torque/stresslet kind), so the pair polynomial is
//     P_alpha P_beta = 1 - c1 k^2 + c2 k^4,   c1 = w_a a_a^2 + w_b a_b^2,  c2 = w_a a_a^2 w_b a_b^2.
// The wave part multiplies it by Hasimoto's splitting function [Hasimoto 1959; docs/ewald.md (E3)]
//     H(k) = (1 + k^2 / (4 xi^2)) exp(-k^2 / (4 xi^2)),
// and the real part is the rest. In real space (8 pi mu times Psi, derived with sympy; the
// derivation is reproduced in docs/ewald.md s.2):
//     wave  W(r) = W0 + c1 W1 + c2 W2,
//        W0 = r erf(xi r) + exp(-xi^2 r^2) / (sqrt(pi) xi)
//        W1 = 2 erf(xi r) / r + 2 xi exp(-xi^2 r^2) / sqrt(pi)
//        W2 = -(xi^3 / sqrt(pi)) (20 - 8 xi^2 r^2) exp(-xi^2 r^2)
//     real  R(r) = (r + 2 c1 / r) - W(r)   (separated pairs; erfc forms, exponentially decaying)
// For overlapping or nested pairs the exact regularised kernel is kept: real = exact - W. The
// wave function W is smooth and even in r; near r = 0 its scalars come from its Taylor series
// (no cancellation), and at r = 0 they give the self wave term, which equals the k-integrals
//     UF: (1/(3 pi^2 mu)) int P_F^2 H dk,  OmegaT: (1/(12 pi^2 mu)) int k^2 P_T^2 H dk,
//     ES: (1/(10 pi^2 mu)) int k^2 P_T^2 H dk   (tested).
// Periodic grand mobility [docs/ewald.md (E6); the same construction as Beenakker 1986 (RPY) and
// Brady, Phillips, Lester & Bossis 1988 (FTS), whose splitting polynomial in H differs from ours,
// so their separate real, wave and self parts differ while the sums agree]:
//     M_ab = sum_images real(x_a - x_b + n) + (1/V) sum_{k != 0} R_a(k) G(k) R_b(k)^+ e^{ik.(x_a - x_b)}
//            + d_ab (M_self_free - wave(r = 0)),
// with G(k) = H(k) (I - kk/k^2) / (mu k^2) and R_a(k) the per-particle response operator
// (fourier_response below).
#include "engine/kernels/mobility_pair.hpp"
#include "engine/core/types.hpp"

#include <complex>

namespace stokesian::ewald {

using mobility::PairScalars;

// Scalars of the real-space part of the pair (alpha, beta) at distance r > 0 with splitting xi.
PairScalars real_scalars(double a_alpha, double a_beta, double r, double xi, double mu, Moments m);

// Scalars of the free-space inverse transform of the wave part at distance r >= 0.
PairScalars wave_scalars(double a_alpha, double a_beta, double r, double xi, double mu, Moments m);

// Self block of one particle that every Ewald sum adds: M_self_free - wave(r = 0). Isotropic:
// only xa = ya, xc = yc, xm = ym = zm are non-zero.
PairScalars self_correction(double a, double xi, double mu);

// Hasimoto splitting function H(k) for k^2 = k2.
double hasimoto(double k2, double xi);

// Per-particle response operator R(k) of radius a (d x 3, d = dof_per_particle(m)) such that the
// Fourier coefficient of the point-force density is f(k) = R(k)^+ x, and the response is R(k) u(k):
//   rows U: P_F(k) I;  rows Omega: P_T(k) (i/2) [k x];  rows E (5-basis m): P_T(k) i (B_m k)^T,
// with P_F = 1 - a^2 k^2 / 6, P_T = 1 - a^2 k^2 / 10 (truncated Faxen factors).
using MatXc = Eigen::Matrix<std::complex<double>, Eigen::Dynamic, Eigen::Dynamic>;
MatXc fourier_response(const Vec3& k, double a, Moments m);

}  // namespace stokesian::ewald
