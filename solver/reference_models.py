"""Reference structures with known answers, shared by the tests and the benchmarks.

- `clamped_arch`: the clamped–clamped cosine arch z = h/2 (1 - cos 2 pi x / l) pushed at its
  midpoint (Qiu, Lang & Slocum 2004: F_max about 740 EI h / l^3, F_min about -370);
  ``centre_clamped=False`` holds only the midpoint's x (its rotation free).
Clamps sit at the midpoints of the rods' end edges (DER reads a held edge's angle as the
tangent at its midpoint), so the span between the clamps is exactly l.
"""

from __future__ import annotations

import numpy as np

from snapmorph.solver.structure import Structure


def clamped_arch(h, n_nodes=101, t=0.5e-3, l=0.1, w=5e-3, E=2.2e9, centre_clamped=True):
    """Returns (structure, midpoint node, EI) for an arch of rise ``h`` (m) and span ``l``."""
    ds = l / (n_nodes - 2)
    x = -0.5 * ds + ds * np.arange(n_nodes)
    z = np.where((x > 0) & (x < l), 0.5 * h * (1 - np.cos(2 * np.pi * x / l)), 0.0)
    st = Structure()
    st.add_rod(np.stack([x, z], 1), width=w, thickness=t, E=E)
    for node in (0, 1, n_nodes - 2, n_nodes - 1):
        st.fix(node, "xz")
    mid = n_nodes // 2
    if centre_clamped:
        st.rigid([mid - 1, mid, mid + 1])
    st.fix(mid, "x")
    return st, mid, E * w * t**3 / 12
