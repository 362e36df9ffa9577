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
    """The column (clamps at the midpoints of the two end edges), its first mode seeded
    with ``imperfection`` x L; push node n_nodes - 1 along -x."""
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
    """The elastica's force (N) at an end shortening (m)."""
    m = brentq(lambda m: 2 * (1 - ellipe(m) / ellipk(m)) - shortening / L, 1e-12, 0.99)
    return P_CR * (2 * ellipk(m) / np.pi) ** 2
