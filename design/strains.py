"""Surface strain of the planar rods of an array or a unit, from node positions (issue 23).

The largest strain in a rod's cross-section at node i is the axial strain plus the bending
strain of its outer fibre, ``|eps_i| + |kappa_i - kappa_bar_i| t_i / 2`` (dimensionless):
``eps_i`` the mean stretch ``|e| / |e_bar| - 1`` of the node's two edges, ``kappa_i`` the
curvature the solver's bending energy uses, the integrated curvature ``2 tan(phi_i / 2)``
(phi the turning angle between the two edges, paper App. A) over the Voronoi length
``(|e_bar_{i-1}| + |e_bar_i|) / 2``, ``kappa_bar_i`` the same of the stress-free shape (the
arch is formed stress free), ``t_i`` the thickness of the two edge halves at the node. The
end nodes carry their edge's axial strain only. Signs are dropped: a sheet yields in tension
or compression alike at the datasheet's elastic limit (`solver.materials`).
"""

from __future__ import annotations

import numpy as np

from snapmorph.units.metrics import surface_strain

__all__ = ["rod_surface_strain", "unit_strains", "largest_strain", "path_strain"]


def rod_surface_strain(x, X, thickness) -> np.ndarray:
    """(N,) surface strain of one rod at its N nodes: positions ``x`` (N, 2) m, stress-free
    positions ``X`` (N, 2) m, ``thickness`` (N-1, 2) m of each edge's two halves (or a
    scalar). Module doc for the formula; the units' own (`units.metrics.surface_strain`)."""
    return surface_strain(np.asarray(x, float), np.asarray(X, float), thickness)


def _node_strains(model, P, rods=None):
    """(n_nodes,) surface strain at every node of ``rods`` (indices into model.rods; default
    all); a node shared by two rods keeps the larger."""
    out = np.zeros(model.n_nodes)
    for r in range(len(model.rods)) if rods is None else rods:
        idx, _, thickness = model.rods[r]
        s = rod_surface_strain(P[idx], model.reference[idx], thickness)
        out[idx] = np.maximum(out[idx], s)
    return out


def _largest(model, node_strain, i) -> tuple:
    """(strain, where) of unit i's base and arch nodes."""
    u, m = model.units[i], model.meshes[i]
    best, where = -1.0, ""
    for name, nodes in (("base", m.base), ("arch", m.arch)):
        if len(nodes) == 0:
            continue
        k = int(np.argmax(node_strain[nodes]))
        if node_strain[nodes[k]] > best:
            best = float(node_strain[nodes[k]])
            third = (model.reference[nodes[k], 0] - m.offset) / u.L
            part = "start" if third < 1 / 3 else ("end" if third > 2 / 3 else "middle")
            where = f"{name}, {part}"
    return best, where


def _unit_rods(model, i) -> list:
    """Indices of the rods unit i has nodes on."""
    m = model.meshes[i]
    mine = np.concatenate([m.base, m.arch])
    return [r for r, (idx, _, _) in enumerate(model.rods) if np.isin(mine, idx).any()]


def unit_strains(model, positions) -> list:
    """[(strain, where)] for every unit of an `design.arrays.ArrayModel` at ``positions``
    (n_nodes, 2) m: the largest surface strain over the unit's base and arch nodes, and where
    it sits ("arch" or "base", "start" / "middle" / "end" third of the unit)."""
    node_strain = _node_strains(model, np.asarray(positions, float))
    return [_largest(model, node_strain, i) for i in range(len(model.units))]


def largest_strain(model, positions) -> tuple:
    """(strain, unit index, where) of the largest surface strain of the array at
    ``positions`` (`unit_strains`)."""
    per_unit = unit_strains(model, positions)
    i = int(np.argmax([s for s, _ in per_unit]))
    return per_unit[i][0], i, per_unit[i][1]


def path_strain(model, states, unit: int) -> tuple:
    """(largest surface strain, where) of unit ``unit`` over ``states`` (K, n_nodes, 2) m,
    e.g. the samples of its snap (`unit_strains`)."""
    best = (0.0, "base, start")
    rods = _unit_rods(model, unit)
    for P in states:
        s = _largest(model, _node_strains(model, np.asarray(P, float), rods), unit)
        if s[0] > best[0]:
            best = s
    return best
