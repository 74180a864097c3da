#!/usr/bin/env python3
"""Express the 15 pair-mobility scalars through radial derivatives of Psi (= -Phi of derive_mobility.py).

Sources (field at x from a unit moment at the origin, Psi of the pair's kinds):
  F_j : u_i = (d_ij Lap - D_i D_j) Psi
  T_j : u_i = 1/2 eps_ilj D_l Lap Psi
  S_jl: u_i = -(1/2 (d_ij D_l + d_il D_j) Lap Psi - D_i D_j D_l Psi)
Responses at x: U = u, Omega = 1/2 curl u, E = sym grad u.
The scalars are read off at e = z. Run: python3 tools/derive_scalars.py
"""
import sympy as sp
x, y, z = sp.symbols('x y z', real=True)
R = sp.symbols('R', positive=True)
f = sp.Function('f')
X = [x, y, z]
rr = sp.sqrt(x**2 + y**2 + z**2)
Psi = f(rr)
D = lambda e, i: sp.diff(e, X[i])
lap = lambda e: sum(sp.diff(e, X[i], 2) for i in range(3))
eps = sp.LeviCivita
d = lambda i, j: 1 if i == j else 0

def u_F(j):  return [d(i, j)*lap(Psi) - D(D(Psi, i), j) for i in range(3)]
def u_T(j):  return [sp.Rational(1, 2)*sum(eps(i, l, j)*D(lap(Psi), l) for l in range(3)) for i in range(3)]
def u_S(j, l):
    LP = lap(Psi)
    return [-(sp.Rational(1, 2)*(d(i, j)*D(LP, l) + d(i, l)*D(LP, j)) - D(D(D(Psi, i), j), l)) for i in range(3)]
def U(u, i): return u[i]
def Om(u, i): return sp.Rational(1, 2)*sum(eps(i, m, n)*D(u[n], m) for m in range(3) for n in range(3))
def E(u, i, k): return sp.Rational(1, 2)*(D(u[i], k) + D(u[k], i))

dd = sp.symbols('d1 d2 d3 d4')
def at_axis(e):
    e = e.subs({x: 0, y: 0}).subs(z, R).doit()
    for n in range(4, 0, -1):
        e = e.subs(sp.Derivative(f(R), (R, n)), dd[n-1])
    return sp.simplify(e)

xa, yz = 0, 0
res = {
 'xa (U<-F, ee)': U(u_F(2), 2), 'ya (U<-F, perp)': U(u_F(0), 0),
 'yb (Om<-F: Om = yb F x e)': Om(u_F(1), 0),
 'ybt (U<-T: U = ybt T x e)': U(u_T(1), 0),
 'xc (Om<-T, ee)': Om(u_T(2), 2), 'yc (Om<-T, perp)': Om(u_T(0), 0),
 'xg (E<-F: 3/2 E_zz<-F_z)': sp.Rational(3, 2)*E(u_F(2), 2, 2), 'yg (E_xz<-F_x)': E(u_F(0), 0, 2),
 'xgt (U_z<-S_zz, 3/2)': sp.Rational(3, 2)*U(u_S(2, 2), 2), 'ygt (U_x<-S_xz)': U(u_S(0, 2), 0),
 'yh (E_xz<-T_y)': E(u_T(1), 0, 2), 'yht (Om_y<-S_xz)': Om(u_S(0, 2), 1),
 'xm (3/2 E_zz<-S_zz)': sp.Rational(3, 2)*E(u_S(2, 2), 2, 2), 'ym (2 E_xz<-S_xz)': 2*E(u_S(0, 2), 0, 2),
 'zm (2 E_xy<-S_xy)': 2*E(u_S(0, 1), 0, 1),
}
for name, e in res.items():
    print(f'{name:28s} =', at_axis(e))
