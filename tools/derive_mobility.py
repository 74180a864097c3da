#!/usr/bin/env python3
"""Derive the radial generating functions of the far-field grand mobility.

Every block of the polydisperse RPY-type grand mobility (F, T, S) is a derivative of one radial
function Phi(r) with Fourier transform  Phi^(k) = g_alpha(k a) g_beta(k b) / (mu k^4),
where g = sin(x)/x for a force/velocity moment (surface average) and g = 3(sin x - x cos x)/x^3
for a torque/rotation or stresslet/strain moment (volume average). Then
    Phi(r) = 1/(2 pi^2 mu r) * FP int_0^inf sin(k r) g_alpha(k a) g_beta(k b) / k^3 dk .
Expanding the trigonometric products into sin/cos(c k)/k^n with c = +-r +-a +-b and using the
finite-part integrals
    int_0^inf cos(ck)/k^(2m)   dk = (-1)^m pi |c|^(2m-1) / (2 (2m-1)!)
    int_0^inf sin(ck)/k^(2m+1) dk = (-1)^m pi sgn(c) c^(2m) / (2 (2m)!)
gives Phi exactly, as a piecewise polynomial in r divided by r, in the three regimes
r >= a+b (separate), |a-b| <= r <= a+b (overlapping), r <= |a-b| (one sphere inside the other).
This script prints those forms; engine/kernels/mobility_pair.cpp implements them. Run: python3 tools/derive_mobility.py
"""
import sympy as sp

k, r, a, b, mu = sp.symbols('k r a b mu', positive=True)

# Elementary even factors as lists of (coef, trig, power, freq) meaning coef*trig(freq*k)/k^power.
def g_force(x):   # sin(kx)/(kx)
    return [(1/x, 'sin', 1, x)]
def g_torque(x):  # 3(sin kx - kx cos kx)/(kx)^3
    return [(3/x**3, 'sin', 3, x), (-3/x**2, 'cos', 2, x)]

def mul(A, B):
    out = []
    for (ca, ta, pa, fa) in A:
        for (cb, tb, pb, fb) in B:
            c = ca*cb; p = pa+pb
            if ta == 'sin' and tb == 'sin':
                out += [(c/2, 'cos', p, fa-fb), (-c/2, 'cos', p, fa+fb)]
            elif ta == 'cos' and tb == 'cos':
                out += [(c/2, 'cos', p, fa-fb), (c/2, 'cos', p, fa+fb)]
            elif ta == 'sin' and tb == 'cos':
                out += [(c/2, 'sin', p, fa+fb), (c/2, 'sin', p, fa-fb)]
            else:  # cos * sin
                out += [(c/2, 'sin', p, fa+fb), (-c/2, 'sin', p, fa-fb)]
    return out

def fp_integral(terms, signs):
    tot = 0
    for (c, t, p, f) in terms:
        s = signs(f)
        if t == 'cos':
            assert p % 2 == 0
            m = p//2
            tot += c*(-1)**m*sp.pi*(s*f)**(2*m-1)/(2*sp.factorial(2*m-1))
        else:
            assert p % 2 == 1
            m = (p-1)//2
            tot += c*(-1)**m*sp.pi*s*f**(2*m)/(2*sp.factorial(2*m))
    return tot

def phi(ga, gb, regime):
    terms = mul(mul([(1, 'sin', 3, r)], ga(a)), gb(b))
    sample = {'separate': {r: 10, a: 2, b: 1.5}, 'overlap': {r: 2, a: 1.5, b: 1.2},
              'inside': {r: sp.Rational(1, 10), a: 2, b: 1}}[regime]
    def signs(f):
        v = f.subs(sample)
        return 1 if v > 0 else (-1 if v < 0 else 0)
    return sp.simplify(fp_integral(terms, signs)/(2*sp.pi**2*mu*r))

if __name__ == '__main__':
    kinds = {'F': g_force, 'T': g_torque}
    for regime in ('separate', 'overlap', 'inside'):
        for ka, kb in (('F', 'F'), ('T', 'F'), ('F', 'T'), ('T', 'T')):
            P = phi(kinds[ka], kinds[kb], regime)
            print(f'{regime:8s} {ka}{kb}: 8*pi*mu*Phi*r =', sp.expand(sp.simplify(P*8*sp.pi*mu*r)))


def cxx_coefficients():
    """Print P(r) = 8 pi mu r Psi(r) (Psi = -Phi) as coefficient lists in powers of r, for C++."""
    kinds = {'F': g_force, 'T': g_torque}
    for regime in ('overlap', 'inside'):
        for ka, kb in (('F', 'F'), ('T', 'F'), ('F', 'T'), ('T', 'T')):
            P = sp.expand(-phi(kinds[ka], kinds[kb], regime)*8*sp.pi*mu*r)
            poly = sp.Poly(P, r)
            coeffs = [sp.simplify(poly.coeff_monomial(r**n)) for n in range(9)]
            body = ', '.join(sp.cxxcode(c) for c in coeffs)
            print(f'// {regime} {ka}{kb}\n{{{body}}},')
