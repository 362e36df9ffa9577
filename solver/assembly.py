"""Assembly of the global energy, gradient and reduced banded tangent stiffness.

The element arrays travel together as one tuple ``elements``:

``(stretch_nodes (ne, 2) int, stretch_params (ne, 2) [EA, rest length],
   bend_nodes (nb, 3) int, bend_params (nb, 2) [EI / l_bar, kappa_bar],
   spring_nodes (ns, 2) int, spring_params (ns, 3) [k, rest offset x, rest offset z])``

Constraints enter through ``dof_map`` (the paper's constraint matrix W in index form): full
DOF ``j = 2 node + c`` (c = 0 for x, 1 for z) maps to reduced DOF ``dof_map[j] >= 0``, or
to ``-1`` when it is fixed or prescribed. Nodes that are tied or translate together share
reduced DOFs, so ``K_red = W^T K W`` is assembled by scattering straight into the band.

Dead loads (`assemble_dead_loads`, planar and 3-D alike) travel as one record ``loads`` =
``(full DOFs (m,) int, reduced DOFs (m,) int (-1 held), forces (m,) N, stress-free
coordinates (m,) m)``, one entry per loaded position coordinate: their potential
``-f (x - X)`` joins the energy and ``-f`` the gradients, through the same DOF map, so the
load on a tied or rigid-group node goes to its group's reduced DOF (``W^T f``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from snapmorph.solver.energies import (bending_gradient, bending_terms, dead_load_terms,
                                       spring_gradient, spring_terms, stretch_gradient,
                                       stretch_terms)


@njit(cache=True)
def _scatter(nodes, dofs, nloc, g, h, band, grad_red, grad_full):
    for a in range(nloc):
        grad_full[2 * nodes[a >> 1] + (a & 1)] += g[a]
        ra = dofs[a]
        if ra < 0:
            continue
        grad_red[ra] += g[a]
        for b in range(nloc):
            rb = dofs[b]
            if rb < 0 or rb > ra:
                continue
            band[ra - rb, rb] += h[a, b]


def element_dofs(elements, dof_map):
    """Reduced DOF of every local coordinate of every element: (stretch (ne, 4),
    bend (nb, 6), spring (ns, 4)) int arrays, -1 where fixed. Computed once per system."""
    out = []
    for conn in (elements[0], elements[2], elements[4]):
        full = (2 * conn[:, :, None] + np.arange(2)[None, None, :]).reshape(conn.shape[0], 2 * conn.shape[1])
        out.append(np.ascontiguousarray(dof_map[full], dtype=np.int64))
    return tuple(out)


@njit(cache=True, inline="always")
def _gather(q, nodes, k, x):
    """x = the positions (x, z per node) of an element's first ``k`` ``nodes`` in the flat
    ``q`` (k a constant at each call: the loop unrolls)."""
    for a in range(k):
        x[2 * a] = q[2 * nodes[a]]
        x[2 * a + 1] = q[2 * nodes[a] + 1]


@njit(cache=True)
def assemble_system(q, elements, dofs, band, grad_red, grad_full):
    """Energy (J); writes the reduced band K, reduced gradient and full gradient (N).

    ``q`` is the flat (2 n_nodes,) array of current positions in metres; ``dofs`` comes
    from `element_dofs` for the system's DOF map.
    """
    stretch_nodes, stretch_params, bend_nodes, bend_params, spring_nodes, spring_params = elements
    stretch_dofs, bend_dofs, spring_dofs = dofs
    band[:, :] = 0.0
    grad_red[:] = 0.0
    grad_full[:] = 0.0
    energy = 0.0
    x4, g4, h4 = np.empty(4), np.empty(4), np.empty((4, 4))
    x6, g6, h6 = np.empty(6), np.empty(6), np.empty((6, 6))
    for e in range(stretch_nodes.shape[0]):
        nodes = stretch_nodes[e]
        _gather(q, nodes, 2, x4)
        energy += stretch_terms(x4, stretch_params[e, 0], stretch_params[e, 1], g4, h4)
        _scatter(nodes, stretch_dofs[e], 4, g4, h4, band, grad_red, grad_full)
    for e in range(bend_nodes.shape[0]):
        nodes = bend_nodes[e]
        _gather(q, nodes, 3, x6)
        energy += bending_terms(x6, bend_params[e, 0], bend_params[e, 1], g6, h6)
        _scatter(nodes, bend_dofs[e], 6, g6, h6, band, grad_red, grad_full)
    for e in range(spring_nodes.shape[0]):
        nodes = spring_nodes[e]
        _gather(q, nodes, 2, x4)
        k, ox, oz = spring_params[e, 0], spring_params[e, 1], spring_params[e, 2]
        energy += spring_terms(x4, k, ox, oz, g4, h4)
        _scatter(nodes, spring_dofs[e], 4, g4, h4, band, grad_red, grad_full)
    return energy


@njit(cache=True)
def stiff_second_difference(q, q_plus, q_minus, elements, dofs, out):
    """The second difference g(q+) + g(q-) - 2 g(q) of the stiff terms' reduced gradient
    (N): stretching and bond springs, whose energies are quadratic in the edge lengths and
    so dominate the path's second-order term (`solver.mgdc`); bending, 10^4-10^6 times
    softer for a thin rod, is left out. Written into ``out`` (n,)."""
    stretch_nodes, stretch_params, _, _, spring_nodes, spring_params = elements
    stretch_dofs, _, spring_dofs = dofs
    out[:] = 0.0
    x, g, h = np.empty(4), np.empty(4), np.empty((4, 4))
    for e in range(stretch_nodes.shape[0]):
        nodes, rd = stretch_nodes[e], stretch_dofs[e]
        for state, weight in ((q_plus, 1.0), (q_minus, 1.0), (q, -2.0)):
            _gather(state, nodes, 2, x)
            stretch_terms(x, stretch_params[e, 0], stretch_params[e, 1], g, h)
            for a in range(4):
                if rd[a] >= 0:
                    out[rd[a]] += weight * g[a]
    for e in range(spring_nodes.shape[0]):
        nodes, rd = spring_nodes[e], spring_dofs[e]
        k, ox, oz = spring_params[e, 0], spring_params[e, 1], spring_params[e, 2]
        for state, weight in ((q_plus, 1.0), (q_minus, 1.0), (q, -2.0)):
            _gather(state, nodes, 2, x)
            spring_terms(x, k, ox, oz, g, h)
            for a in range(4):
                if rd[a] >= 0:
                    out[rd[a]] += weight * g[a]


@njit(cache=True)
def assemble_dead_loads(q, loads, grad_red, grad_full):
    """Energy (J) of the dead loads ``loads`` (the record of the module doc) at the full
    state ``q``; adds their gradient -f (N) into the reduced and the full gradient. No
    stiffness: K is the elastic one. Loaded coordinates are positions (3-D rods: reduced
    position DOFs are unscaled, ``dof_scale`` 1)."""
    full, red, force, ref = loads
    energy = 0.0
    for k in range(full.shape[0]):
        j = full[k]
        e, g = dead_load_terms(q[j], force[k], ref[k])
        energy += e
        grad_full[j] += g
        r = red[k]
        if r >= 0:
            grad_red[r] += g
    return energy


def no_loads():
    """The empty dead-load record (a structure without loads)."""
    none = np.zeros(0, dtype=np.int64)
    return none, none.copy(), np.zeros(0), np.zeros(0)


def load_record(full_dofs, forces, ref, dof_map):
    """The dead-load record of `assemble_dead_loads` for the full DOFs ``full_dofs`` with
    forces ``forces`` (N) and stress-free coordinates ``ref`` (m) under ``dof_map``."""
    full = np.ascontiguousarray(full_dofs, dtype=np.int64)
    red = np.ascontiguousarray(np.asarray(dof_map)[full], dtype=np.int64)
    return (full, red, np.ascontiguousarray(forces, dtype=float),
            np.ascontiguousarray(ref, dtype=float))


def total_energy(q, elements):
    """Total elastic energy (J) of the positions ``q``: the assembler run with every DOF
    marked fixed, so that nothing is scattered into a stiffness."""
    dofs = tuple(-np.ones((conn.shape[0], 2 * conn.shape[1]), dtype=np.int64)
                 for conn in (elements[0], elements[2], elements[4]))
    return assemble_system(np.ascontiguousarray(q, dtype=float), elements, dofs,
                           np.zeros((1, 1)), np.zeros(1), np.zeros(q.shape[0]))


@njit(cache=True)
def assemble_gradient(q, elements, dofs, grad_red, grad_full):
    """`assemble_system` without the stiffness: the energy (J), the reduced and the full
    gradient (N) at ``q``, the band untouched (a few microseconds against the full
    assembly's tens: what a state Newton has converged to needs, `solver.system.
    BandedSystem.settle`)."""
    stretch_nodes, stretch_params, bend_nodes, bend_params, spring_nodes, spring_params = elements
    stretch_dofs, bend_dofs, spring_dofs = dofs
    grad_red[:] = 0.0
    grad_full[:] = 0.0
    energy = 0.0
    x4, g4 = np.empty(4), np.empty(4)
    x6, g6 = np.empty(6), np.empty(6)
    for e in range(stretch_nodes.shape[0]):
        nodes = stretch_nodes[e]
        _gather(q, nodes, 2, x4)
        energy += stretch_gradient(x4, stretch_params[e, 0], stretch_params[e, 1], g4)
        _scatter_gradient(nodes, stretch_dofs[e], 4, g4, grad_red, grad_full)
    for e in range(bend_nodes.shape[0]):
        nodes = bend_nodes[e]
        _gather(q, nodes, 3, x6)
        energy += bending_gradient(x6, bend_params[e, 0], bend_params[e, 1], g6)
        _scatter_gradient(nodes, bend_dofs[e], 6, g6, grad_red, grad_full)
    for e in range(spring_nodes.shape[0]):
        nodes = spring_nodes[e]
        _gather(q, nodes, 2, x4)
        k, ox, oz = spring_params[e, 0], spring_params[e, 1], spring_params[e, 2]
        energy += spring_gradient(x4, k, ox, oz, g4)
        _scatter_gradient(nodes, spring_dofs[e], 4, g4, grad_red, grad_full)
    return energy


@njit(cache=True, inline="always")
def _scatter_gradient(nodes, dofs, nloc, g, grad_red, grad_full):
    for a in range(nloc):
        grad_full[2 * nodes[a >> 1] + (a & 1)] += g[a]
        if dofs[a] >= 0:
            grad_red[dofs[a]] += g[a]
