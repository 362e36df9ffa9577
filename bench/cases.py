"""Benchmark cases, importable by the benchmark driver and by tests."""

import numpy as np

from solver import Structure


def clamped_arch(n_nodes=101, h_over_t=10, t=0.5e-3, l=0.1, w=5e-3, E=2.2e9):
    """The clamped–clamped cosine arch with its centre clamped (issue 2's benchmark)."""
    h = h_over_t * t
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
    return st, mid, h


def clamped_arch_push():
    st, mid, h = clamped_arch()
    return st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")


def specimen_unit(**kw):
    from solver.unit import UnitGeometry, simulate_unit

    return simulate_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), **kw)
