"""Clamped–clamped column under end shortening: the force plateau is Euler's 4 pi^2 EI / L^2.

A perfect column stays straight on the primary path; a small imperfection in the first
buckling mode (amplitude 3e-4 L) lets the path follower find the buckled branch.
The elastica of the clamped–clamped column (equivalent to a pinned column of half the
length) gives P / P_cr = (2 K(m) / pi)^2 and end shortening Delta / L = 2 (1 - E(m) / K(m)).
"""

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from snapmorph.solver import Structure

L, T, W, E = 0.1, 0.5e-3, 5e-3, 2.2e9
EI = E * W * T**3 / 12
P_CR = 4 * np.pi**2 * EI / L**2


def column(n_nodes=101, imperfection=3e-4):
    ds = L / (n_nodes - 2)  # clamps at the midpoints of the two end edges
    x = -0.5 * ds + ds * np.arange(n_nodes)
    z = imperfection * L * 0.5 * (1 - np.cos(2 * np.pi * np.clip(x, 0, L) / L))
    st = Structure()
    st.add_rod(np.stack([x, z], 1), width=W, thickness=T, E=E)
    st.fix(0, "xz")
    st.fix(1, "xz")
    st.rigid([n_nodes - 2, n_nodes - 1])
    st.fix(n_nodes - 1, "z")
    return st


def elastica_force(shortening):
    m = brentq(lambda m: 2 * (1 - ellipe(m) / ellipk(m)) - shortening / L, 1e-12, 0.99)
    return P_CR * (2 * ellipk(m) / np.pi) ** 2


def test_force_plateau_is_euler_load():
    path = column().push(100, direction=(-1.0, 0.0), distance=0.03 * L, method="mgdc")
    assert path.status == "ok"
    window = (path.displacement > 0.005 * L) & (path.displacement < 0.02 * L)
    plateau = path.force[window]
    assert abs(plateau.mean() / P_CR - 1) < 0.01
    assert np.ptp(plateau) / P_CR < 0.02  # flat: a plateau, not a ramp


def test_post_buckling_follows_the_elastica():
    path = column().push(100, direction=(-1.0, 0.0), distance=0.05 * L, method="mgdc")
    for d, F in zip(path.displacement, path.force):
        if 0.01 * L < d < 0.05 * L:
            assert abs(F / elastica_force(d) - 1) < 0.01
