#!/usr/bin/python3
"""Write the pressure-driven flow through a rectangular duct as a fluid solver's grid export
(x, y, z, u, v, w per line), the input of [flow] kind = "tabulated" (docs/channels.md). It stands in
for a COMSOL/OpenFOAM/FEniCS export in configs/duct_tabulated.toml. Series: White, Viscous Fluid
Flow (3rd ed. 2006), the rectangular duct (the same closed form as engine/core/channel.hpp); duct
|y - cy| < H/2, |z - cz| < W/2, mean velocity U, nodes every h along y and z from wall to wall
(u = 0 on the walls) at x = 0 and Lx.

usage: write_duct_table.py OUT.csv H W U h Lx cy cz
"""
import sys

import numpy as np

out, H, W, U, h, Lx, cy, cz = sys.argv[1], *map(float, sys.argv[2:9])
a, b = H / 2, W / 2
n = np.arange(1, 4001, 2)
bracket = 1 - 192 * a / (np.pi**5 * b) * np.sum(np.tanh(n * np.pi * b / (2 * a)) / n**5)
G = 3 * U / (a * a * bracket)  # G / mu


def u(y, z):
    if abs(y) >= a or abs(z) >= b:
        return 0.0
    q = n * np.pi / (2 * a)
    ratio = np.exp(q * (abs(z) - b)) * (1 + np.exp(-2 * q * abs(z))) / (1 + np.exp(-2 * q * b))
    s = np.sum((-1.0) ** ((n - 1) // 2) / n**3 * ratio * np.cos(q * y))
    return 0.5 * G * (a * a - y * y) - 16 * a * a * G / np.pi**3 * s


ys = np.arange(-a, a + 1e-9, h)
zs = np.arange(-b, b + 1e-9, h)
with open(out, "w") as f:
    f.write(f"% rectangular duct H = {H} a, W = {W} a, mean velocity {U} a/time (tools/write_duct_table.py)\n")
    f.write("x,y,z,u,v,w\n")
    for x in (0.0, Lx):
        for y in ys:
            for z in zs:
                f.write(f"{x:.6g},{y + cy:.6g},{z + cz:.6g},{u(y, z):.9g},0,0\n")
print("wrote", out, len(ys) * len(zs) * 2, "nodes")
