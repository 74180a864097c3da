#!/usr/bin/env python3
"""Tables for engine/kernels/mobility_pair.cpp.

(1) C[s][m]: the pair-mobility scalar s (formulas of tools/derive_scalars.py) for Psi = r^m equals
    C[s][m] * r^(m - k_s) (k_s = 2 for a, 3 for b and g, 4 for c, h and m), m = -1..7; summing monomials avoids cancellation between derivatives.
(2) The coefficients q_m of 8 pi mu Psi(r) = sum_m q_m r^m in the overlapping and nested regimes,
    factored so that near-cancelling sums (e.g. (a-b)^4) are evaluated accurately.
Run: python3 tools/derive_scalars_table.py
"""
import sympy as sp
exec(open(__file__.replace('derive_scalars_table.py', 'derive_mobility.py')).read().split("if __name__")[0])
R = sp.symbols('R', positive=True)
d1, d2, d3, d4 = sp.symbols('d1 d2 d3 d4')
S = {'xa': (2*d1/R, 2), 'ya': (d2 + d1/R, 2), 'yb': (-d3/2 - d2/R + d1/R**2, 3),
     'xc': ((-R**2*d3/2 - R*d2 + d1)/R**3, 4), 'yc': (-d4/4 - 3*d3/(4*R) + d2/(2*R**2) - d1/(2*R**3), 4),
     'xg': (3*(R*d2 - d1)/R**2, 3), 'yg': (d3/2, 3), 'yh': ((-R**3*d4 - R**2*d3 + 6*R*d2 - 6*d1)/(4*R**3), 4),
     'xm': (3*(-R**2*d3 + 2*R*d2 - 2*d1)/R**3, 4), 'ym': (-d4/2 + d3/(2*R) - 3*d2/R**2 + 3*d1/R**3, 4),
     'zm': (-d3/R, 4)}
print('// C[s][m+1], m = -1..7, scalars in the order', list(S))
for name, (expr, k) in S.items():
    row = []
    for m in range(-1, 8):
        p = R**m
        v = expr.subs({d1: sp.diff(p, R), d2: sp.diff(p, R, 2), d3: sp.diff(p, R, 3), d4: sp.diff(p, R, 4)})
        row.append(sp.simplify(v / R**(m - k)))
    print('{' + ', '.join(f'{sp.Rational(c).p}.0/{sp.Rational(c).q}.0' if c != 0 else '0' for c in row) + '},  //', name)
kinds = {'F': g_force, 'T': g_torque}
for regime in ('overlap', 'inside'):
    for ka, kb in (('F', 'F'), ('T', 'F'), ('F', 'T'), ('T', 'T')):
        P = sp.expand(-phi(kinds[ka], kinds[kb], regime)*8*sp.pi*mu*r)
        poly = sp.Poly(P, r)
        coeffs = [sp.factor(poly.coeff_monomial(r**n)) for n in range(9)]
        print(f'// {regime} {ka}{kb}: q_m for m = -1..7')
        for n, c in enumerate(coeffs):
            if c != 0:
                print(f'q[{n}] = {sp.cxxcode(c)};')
