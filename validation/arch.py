"""The clamped cosine arch pushed at its midpoint: z = h/2 (1 - cos 2 pi x / l).

Reference: Qiu, Lang & Slocum (2004), J. MEMS 13(2): for the centrally clamped arch the
snap-through force is about 740 EI h / l^3 and the minimum about -370 EI h / l^3 (their
approximate closed-form values for large h/t).

- `clamped_arch`: the project's reference model (the benchmarks' and most tests'): clamps at
  the midpoints of the rods' end edges (DER reads a held edge's angle as the tangent at its
  midpoint), so the span between the clamps is exactly l; ``centre_clamped=False`` holds
  only the midpoint's x (its rotation free);
- `arch`: the arch as a user builds it, nodes from x = 0 to l, in the "fix" set-up (end
  edges held) or the "clamp" set-up (`Structure.clamp` at the end nodes and the midpoint).
"""

import numpy as np

from snapmorph.solver import Structure

T, L_SPAN, W, E = 0.5e-3, 0.1, 5e-3, 2.2e9


def clamped_arch(h, n_nodes=101, t=T, l=L_SPAN, w=W, E=E, centre_clamped=True):
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


def arch(h_over_t, n_nodes, setup, centre=True, E=E, t=T, l=L_SPAN, w=W):
    """The centre-clamped arch built as a user would (``centre=False``: only the midpoint's
    x held). Returns (structure, mid, h, EI)."""
    h = h_over_t * t
    x = np.linspace(0.0, l, n_nodes)
    z = 0.5 * h * (1 - np.cos(2 * np.pi * x / l))
    st = Structure()
    st.add_rod(np.stack([x, z], 1), width=w, thickness=t, E=E)
    mid = n_nodes // 2
    if setup == "fix":
        for k in (0, 1, n_nodes - 2, n_nodes - 1):
            st.fix(k, "xz")
        if centre:
            st.rigid([mid - 1, mid, mid + 1])
    else:
        st.clamp(0, toward=1)
        st.clamp(n_nodes - 1, toward=n_nodes - 2)
        if centre:
            st.clamp(mid, toward=mid + 1, hold_position=False)
    st.fix(mid, "x")
    return st, mid, h, E * w * t**3 / 12


def arch_path(h_over_t, method="mgdc", n_nodes=101):
    """The reference arch of rise h = h_over_t x t pushed to 2.2 h: (path, h, EI h / l^3)."""
    h = h_over_t * T
    st, mid, EI = clamped_arch(h, n_nodes=n_nodes)
    path = st.push(mid, (0.0, -1.0), 2.2 * h, method=method)
    return path, h, EI * h / L_SPAN**3


def first_peak_index(force):
    """Index of the first local maximum of a force history (the snap-through force)."""
    i = 1
    while i < len(force) - 1 and force[i + 1] >= force[i]:
        i += 1
    return i
