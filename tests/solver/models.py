"""Model builders shared by the solver tests."""

import numpy as np

from solver import Structure


def clamped_rod_nodes(n_nodes, length):
    """Node abscissae of a rod whose clamp sits at the midpoint of its first edge.

    The clamped first edge straddles s = 0 (nodes at -ds/2 and +ds/2) and the last node is
    at s = length: the clamp then acts at s = 0 to second order in ds.
    """
    ds = length / (n_nodes - 1.5)
    return -0.5 * ds + ds * np.arange(n_nodes)


def clamped_arch(h, n_nodes=101, t=0.5e-3, l=0.1, w=5e-3, E=2.2e9):
    """Clamped–clamped cosine arch z = h/2 (1 - cos 2 pi x / l), both clamps at edge midpoints,
    midpoint held in rotation (three nodes rigid) and in x. Returns (structure, mid, EI)."""
    ds = l / (n_nodes - 2)
    x = -0.5 * ds + ds * np.arange(n_nodes)
    z = np.where((x > 0) & (x < l), 0.5 * h * (1 - np.cos(2 * np.pi * x / l)), 0.0)
    st = Structure()
    st.add_rod(np.stack([x, z], 1), width=w, thickness=t, E=E)
    for node in (0, 1, n_nodes - 2, n_nodes - 1):
        st.fix(node, "xz")
    mid = n_nodes // 2
    st.rigid([mid - 1, mid, mid + 1])
    st.fix(mid, "x")
    return st, mid, E * w * t**3 / 12
