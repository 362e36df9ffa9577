"""Assembly of the 3-D rod energy, gradient and reduced banded tangent stiffness.

The state ``q`` is flat: ``3 n_nodes`` positions (x, y, z per node, m) then one twist angle
per edge (rad). Model arrays (built by `solver.structure3d.Structure3D`):

- ``edge_nodes`` (n_frames, 2) int: start and end node of each edge; rows past the rods'
  edges are fixed clamp frames (nodes -1);
- ``src_t``, ``src_d`` (n_frames, 3): the tangents and reference directors at the last
  accepted state (the source of time-parallel transport; a clamp frame's own frame);
- ``stretch_params`` (n_edges, 2): [EA (N), rest length (m)] of each rod edge;
- ``pair_edges`` (n_pairs, 2) int, ``pair_signs`` (n_pairs, 2): the two frames of each
  bending/twisting pair (interior node, rigid joint or clamp) and whether each enters along
  (+1) or against (-1) its edge direction; ``pair_params`` (n_pairs, 6):
  [k1, k2, kt (N m), kappa1_bar, kappa2_bar, psi_bar].

Constraints enter through ``dof_map`` as in the planar solver: full DOF -> reduced DOF or -1.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from snapmorph.solver.energies3d import pair_edge_scratch, pair_terms_edges, stretch_terms
from snapmorph.solver.frames3d import frame_jet_scratch, material_frame_jet_ws


def element_dofs3d(n_nodes, edge_nodes, n_edges, pair_edges, dof_map):
    """Full and reduced DOF indices of every element's local coordinates.

    Returns (stretch_full (n_edges, 6), stretch_red, pair_full (n_pairs, 14), pair_red);
    a pair's 14 local coordinates are, for each of its two frames, the start node's xyz,
    the end node's xyz and the edge's twist (all -1 for a clamp frame)."""
    node_dofs = (3 * edge_nodes[:n_edges, :, None] + np.arange(3)).reshape(n_edges, 6)
    stretch_full = np.ascontiguousarray(node_dofs, dtype=np.int64)
    frame_full = -np.ones((edge_nodes.shape[0], 7), dtype=np.int64)
    frame_full[:n_edges, :6] = node_dofs
    frame_full[:n_edges, 6] = 3 * n_nodes + np.arange(n_edges)
    pair_full = np.ascontiguousarray(frame_full[pair_edges].reshape(-1, 14), dtype=np.int64)

    def red(full):
        out = np.where(full >= 0, dof_map[np.maximum(full, 0)], -1)
        return np.ascontiguousarray(out, dtype=np.int64)

    return stretch_full, red(stretch_full), pair_full, red(pair_full)


@njit(cache=True)
def frame_jets(q, n_nodes, edge_nodes, src_t, src_d, vals, jacs, hesss):
    """Material frames [t, m1, m2] of every edge and clamp frame with their derivatives
    w.r.t. (edge vector, twist) (see `solver.frames3d.material_frame_jet`)."""
    e = np.empty(3)
    ws = frame_jet_scratch()
    for j in range(edge_nodes.shape[0]):
        a = edge_nodes[j, 0]
        b = edge_nodes[j, 1]
        if a < 0:
            t = src_t[j]
            d = src_d[j]
            for k in range(3):
                vals[j, k] = t[k]
                vals[j, 3 + k] = d[k]
            vals[j, 6] = t[1] * d[2] - t[2] * d[1]
            vals[j, 7] = t[2] * d[0] - t[0] * d[2]
            vals[j, 8] = t[0] * d[1] - t[1] * d[0]
            jacs[j, :, :] = 0.0
            hesss[j, :, :, :] = 0.0
            continue
        for k in range(3):
            e[k] = q[3 * b + k] - q[3 * a + k]
        material_frame_jet_ws(e, q[3 * n_nodes + j], src_t[j], src_d[j], vals[j], jacs[j],
                              hesss[j], ws)


@njit(cache=True)
def _scatter(full, red, n, g, h, dof_scale, band, grad_red, grad_full):
    for a in range(n):
        fa = full[a]
        if fa < 0:
            continue
        grad_full[fa] += g[a]
        ra = red[a]
        if ra < 0:
            continue
        ca = dof_scale[fa]
        grad_red[ra] += ca * g[a]
        for b in range(n):
            rb = red[b]
            if rb < 0 or rb > ra:
                continue
            band[ra - rb, rb] += ca * dof_scale[full[b]] * h[a, b]


# local coordinate of a pair -> (index into p = (e_a, theta_a, e_b, theta_b), sign)
_PAIR_P = np.array([0, 1, 2, 0, 1, 2, 3, 4, 5, 6, 4, 5, 6, 7], dtype=np.int64)
_PAIR_SIGN = np.array([-1.0, -1.0, -1.0, 1.0, 1.0, 1.0, 1.0,
                       -1.0, -1.0, -1.0, 1.0, 1.0, 1.0, 1.0])


@njit(cache=True)
def _scatter_pair(full, red, g8, h8, dof_scale, band, grad_red, grad_full):
    """Scatter a pair's gradient and Hessian in p = (e_a, theta_a, e_b, theta_b) straight
    into the full gradient, the reduced gradient and the band: local coordinate a of the 14
    (start xyz, end xyz, twist per frame) reads p[_PAIR_P[a]] with sign _PAIR_SIGN[a]."""
    for a in range(14):
        fa = full[a]
        if fa < 0:
            continue
        pa = _PAIR_P[a]
        ga = _PAIR_SIGN[a] * g8[pa]
        grad_full[fa] += ga
        ra = red[a]
        if ra < 0:
            continue
        ca = dof_scale[fa] * _PAIR_SIGN[a]
        grad_red[ra] += dof_scale[fa] * ga
        for b in range(14):
            rb = red[b]
            if rb < 0 or rb > ra:
                continue
            band[ra - rb, rb] += ca * dof_scale[full[b]] * _PAIR_SIGN[b] * h8[pa, _PAIR_P[b]]


@njit(cache=True)
def assemble_system3d(q, n_nodes, edge_nodes, src_t, src_d, stretch_params, pair_edges,
                      pair_signs, pair_params, stretch_full, stretch_red, pair_full, pair_red,
                      dof_scale, band, grad_red, grad_full):
    """Energy (J); writes the reduced band K, the reduced and the full gradient at ``q``.

    ``dof_scale`` (full,): dq_full = dof_scale * du_reduced (1 for positions, 1 / length for
    twists, so that reduced twist DOFs are lengths and the path followers' norms and
    tolerances weigh them like displacements)."""
    n_frames = edge_nodes.shape[0]
    return assemble_system3d_ws(q, n_nodes, edge_nodes, src_t, src_d, stretch_params,
                                pair_edges, pair_signs, pair_params, stretch_full, stretch_red,
                                pair_full, pair_red, dof_scale, band, grad_red, grad_full,
                                np.empty((n_frames, 9)), np.empty((n_frames, 9, 4)),
                                np.empty((n_frames, 9, 4, 4)), np.empty(0, dtype=np.int64))


@njit(cache=True)
def assemble_system3d_ws(q, n_nodes, edge_nodes, src_t, src_d, stretch_params, pair_edges,
                         pair_signs, pair_params, stretch_full, stretch_red, pair_full,
                         pair_red, dof_scale, band, grad_red, grad_full, vals, jacs, hesss,
                         heights):
    """`assemble_system3d` with the frames' jets written into the caller's ``vals``
    (n_frames, 9), ``jacs`` (n_frames, 9, 4), ``hesss`` (n_frames, 9, 4, 4): nothing is
    allocated per element, and nothing large per call. ``heights`` (n,): the band's
    envelope (`solver.banded.envelope_heights`; only it is cleared, the rest of the band
    must be zero), or empty (clear the whole band)."""
    if heights.shape[0] == band.shape[1]:
        for j in range(band.shape[1]):
            for k in range(heights[j] + 1):
                band[k, j] = 0.0
    else:
        band[:, :] = 0.0
    grad_red[:] = 0.0
    grad_full[:] = 0.0
    energy = 0.0
    frame_jets(q, n_nodes, edge_nodes, src_t, src_d, vals, jacs, hesss)
    x6 = np.empty(6)
    g6 = np.empty(6)
    h6 = np.empty((6, 6))
    for j in range(stretch_params.shape[0]):
        for k in range(6):
            x6[k] = q[stretch_full[j, k]]
        energy += stretch_terms(x6, stretch_params[j, 0], stretch_params[j, 1], g6, h6)
        _scatter(stretch_full[j], stretch_red[j], 6, g6, h6, dof_scale, band, grad_red, grad_full)
    g8 = np.empty(8)
    h8 = np.empty((8, 8))
    ws = pair_edge_scratch()
    for p in range(pair_edges.shape[0]):
        ea = pair_edges[p, 0]
        eb = pair_edges[p, 1]
        energy += pair_terms_edges(vals[ea], jacs[ea], hesss[ea], pair_signs[p, 0], vals[eb],
                                   jacs[eb], hesss[eb], pair_signs[p, 1], pair_params[p, 0],
                                   pair_params[p, 1], pair_params[p, 2], pair_params[p, 3],
                                   pair_params[p, 4], pair_params[p, 5], g8, h8, ws)
        _scatter_pair(pair_full[p], pair_red[p], g8, h8, dof_scale, band, grad_red, grad_full)
    return energy


@njit(cache=True)
def apply_scaled_increment(q, dof_map, dof_scale, du, scale):
    """q[j] += scale * dof_scale[j] * du[dof_map[j]] for every free full DOF."""
    for j in range(q.shape[0]):
        r = dof_map[j]
        if r >= 0:
            q[j] += scale * dof_scale[j] * du[r]
