#pragma once
// Far-field grand mobility of a pair of spheres (any radii, any separation, overlapping included).
//
// Mathematics (full derivation: docs/mobility.md; symbolic check: tools/derive_mobility.py):
// the grand mobility relates [U - U_inf, Omega - Omega_inf, -E_inf] = M [F, T, S] with F, T, S the
// force, torque and stresslet each particle exerts on the fluid [Durlofsky, Brady & Bossis 1987,
// eq. 2.13]. Every pair block is a derivative of one radial function Psi with Fourier transform
//     Psi^(k) = -g_alpha(k a_alpha) g_beta(k a_beta) / (mu k^4),
// g(x) = sin x / x for force/velocity (surface average) and 3 (sin x - x cos x) / x^3 for
// torque/rotation and stresslet/strain (volume average) [Wajnryb, Mizerski, Zuk & Szymczak 2013;
// Zuk, Wajnryb, Mizerski & Szymczak 2014, eqs. 9-12]. Sources and responses:
//     F_j : u_i = (d_ij Lap - D_i D_j) Psi                   U = u
//     T_j : u_i = 1/2 eps_ilj D_l Lap Psi                    Omega = 1/2 curl u
//     S_jl: u_i = -(1/2 (d_ij D_l + d_il D_j) Lap - D_i D_j D_l) Psi     E = sym grad u
// The whole matrix is then a Gram matrix in k-space, hence symmetric positive definite for every
// configuration, and it reduces to the polydisperse RPY/Durlofsky form for r >= a_alpha + a_beta,
// where 8 pi mu Psi = r + c / r with c = 2 (w_alpha a_alpha^2 + w_beta a_beta^2),
// w = 1/6 for force and 1/10 for torque/stresslet. That is eqs. (3.30)-(3.40) of the thesis [T]
// (README.md) with two misprints corrected (docs/mobility.md: 1/8 Laplacian weight, + sign of z^m).
// For overlapping (|a-b| < r < a+b) and nested (r <= |a-b|) pairs 8 pi mu Psi r is a polynomial
// in r (tools/derive_scalars_table.py).
//
// Scalar functions (Kim & Karrila 1991 ch. 11 tensor forms, e = (x_alpha - x_beta) / r):
//   U  <- F : xa e e + ya (I - e e)             Omega <- F : yb  (F x e)
//   U  <- T : ybt (T x e)                       Omega <- T : xc e e + yc (I - e e)
//   E  <- F : xg (e e - I/3)(e.F) + yg (e F + F e - 2 e e (e.F))
//   U  <- S : xgt e (e.S.e) + ygt (2 S.e - 2 e (e.S.e))
//   E  <- T : yh (e (T x e) + (T x e) e)         Omega <- S : 2 yht e x (S.e)
//   E  <- S : xm d0 + ym d1 + zm d2 (projectors: mobility_pair.cpp)
// All scalars are dimensional (they include 1/(8 pi mu)).
#include "engine/core/sym_traceless.hpp"
#include "engine/core/types.hpp"

namespace stokesian::mobility {

struct PairScalars {
  double xa = 0, ya = 0;            // U <- F
  double yb = 0, ybt = 0;           // Omega <- F, U <- T
  double xc = 0, yc = 0;            // Omega <- T
  double xg = 0, yg = 0;            // E <- F
  double xgt = 0, ygt = 0;          // U <- S
  double yh = 0, yht = 0;           // E <- T, Omega <- S
  double xm = 0, ym = 0, zm = 0;    // E <- S
};

// Geometric regime of a pair.
enum class PairRegime { separate, overlapping, nested };
PairRegime pair_regime(double a_alpha, double a_beta, double r);

// Scalars of the block M^{alpha beta} (response at alpha of radius a_alpha, source at beta of
// radius a_beta) at centre distance r >= 0. Only the scalars needed for `m` are computed.
PairScalars pair_scalars(double a_alpha, double a_beta, double r, double mu, Moments m);

// Radial derivatives d1..d4 of 8 pi mu Psi(r) for one pair of kinds, at distance r > 0.
struct PsiDerivatives {
  double d1 = 0, d2 = 0, d3 = 0, d4 = 0;
};
// Scalars from the radial derivatives of any generating function Psi (e.g. the real-space part
// of an Ewald split), given for the kind pairs FF, TF (torque/stresslet kind at alpha), FT and TT.
// The formulas are those of tools/derive_scalars.py; the result includes 1/(8 pi mu).
PairScalars scalars_from_derivatives(const PsiDerivatives& ff, const PsiDerivatives& tf, const PsiDerivatives& ft,
                                     const PsiDerivatives& tt, double r, double mu, Moments m);

// Single-sphere (self) mobilities: 1/(6 pi mu a), 1/(8 pi mu a^3), 3/(20 pi mu a^3).
PairScalars self_scalars(double a, double mu);

// y_alpha += M^{alpha beta} x_beta. x and y point at one particle's d = dof_per_particle(m)
// entries in the layout [F(3) T(3) S(5)] / [U(3) Omega(3) E(5)]; e = (x_alpha - x_beta)/r.
void apply_pair(const PairScalars& s, const Vec3& e, Moments m, const double* x, double* y);

// y_alpha += M^{alpha alpha} x_alpha.
void apply_self(double a, double mu, Moments m, const double* x, double* y);

// The same d x d block written straight into column-major storage B (leading dimension ld), from
// closed forms of the contractions with the orthonormal basis P_p of engine/core/sym_traceless.hpp
// (P_p symmetric traceless, P_p : P_q = delta_pq), with Pe_p = P_p e and c_p = e . P_p e:
//   E_p <- F_k : xg c_p e_k + yg (2 (Pe_p)_k - 2 c_p e_k)        (U_k <- S_p: xgt, ygt alike)
//   E_p <- T_k : 2 yh (e x Pe_p)_k                              (Omega_k <- S_p: yht alike)
//   E_p <- S_q : 1.5 xm c_p c_q + ym (2 Pe_p.Pe_q - 2 c_p c_q) + zm (delta_pq - 2 Pe_p.Pe_q + c_p c_q / 2)
// and the F/T blocks as in apply_pair. The fast path of the dense assembly; tested against pair_block.
void fill_pair_block(const PairScalars& s, const Vec3& e, Moments m, double* B, long ld);

// Dense d x d block from the explicit Cartesian tensors a_ij, b_ij, c_ij, g_ijk, h_ijk, m_ijkl
// contracted with the symmetric-traceless basis. Reference path, independent of apply_pair.
MatX pair_block(const PairScalars& s, const Vec3& e, Moments m);

}  // namespace stokesian::mobility
