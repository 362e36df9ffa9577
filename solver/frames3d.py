"""Frames of 3-D discrete elastic rods: parallel transport, reference and material frames.

Every edge j carries a reference frame (t_j, d_j, t_j x d_j) and a material frame rotated by
the edge's twist angle theta_j about t_j (Bergou et al. 2008, 2010; Jawed, Novelia &
O'Reilly 2018):

    m1 = cos(theta) d + sin(theta) (t x d),   m2 = -sin(theta) d + cos(theta) (t x d).

m1 is the strip's face normal (thickness direction), m2 = t x m1 its width direction.

Reference frames are carried between accepted states by time-parallel transport: between two
accepts, edge j's reference director is the exact function of its current tangent
``d_j(t) = P(t_hat_j -> t) d_hat_j`` of the tangent and director stored at the last accepted
state. ``material_frame_jet`` returns that frame and its first and second derivatives with
respect to the edge vector and the twist angle at *any* tangent (not only at the source), so
the energy between accepts is one smooth function of the state with exact derivatives.
The reference twist (the angle from the space-parallel transport of d_{i-1} to d_i about t_i)
is implicit in the twist kernel, which reads the twist straight off the two material frames.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def parallel_transport(v, a, b):
    """Transport the vector ``v`` by the rotation taking unit ``a`` to unit ``b`` about
    ``a x b`` (the minimal rotation). Returns a new (3,) array."""
    c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    wx = a[1] * b[2] - a[2] * b[1]
    wy = a[2] * b[0] - a[0] * b[2]
    wz = a[0] * b[1] - a[1] * b[0]
    s = wx * v[0] + wy * v[1] + wz * v[2]
    f = s / (1.0 + c)
    out = np.empty(3)
    out[0] = c * v[0] + (wy * v[2] - wz * v[1]) + f * wx
    out[1] = c * v[1] + (wz * v[0] - wx * v[2]) + f * wy
    out[2] = c * v[2] + (wx * v[1] - wy * v[0]) + f * wz
    return out


def unit_tangents(positions, edges):
    """(n_edges, 3) unit tangents of the edges ``edges`` (n_edges, 2) node indices."""
    e = positions[edges[:, 1]] - positions[edges[:, 0]]
    return e / np.linalg.norm(e, axis=1)[:, None]


def space_parallel_frames(tangents, normal):
    """Reference directors of a chain of edges: ``normal`` projected normal to the first
    tangent, then carried edge to edge by space-parallel transport (zero reference twist).

    ``normal`` may also be one vector per edge (n_edges, 3): each is projected normal to its
    own edge (a strip with a natural twist). Returns (n_edges, 3) unit directors."""
    n_edges = tangents.shape[0]
    normal = np.asarray(normal, dtype=float)
    d = np.empty((n_edges, 3))
    if normal.ndim == 1:
        v = normal - np.dot(normal, tangents[0]) * tangents[0]
        d[0] = v / np.linalg.norm(v)
        for j in range(1, n_edges):
            v = parallel_transport(d[j - 1], tangents[j - 1], tangents[j])
            v -= np.dot(v, tangents[j]) * tangents[j]
            d[j] = v / np.linalg.norm(v)
    else:
        v = normal - np.sum(normal * tangents, axis=1)[:, None] * tangents
        d[:] = v / np.linalg.norm(v, axis=1)[:, None]
    return d


@njit(cache=True)
def transport_frames(t_source, d_source, t_new):
    """Time-parallel transport of the reference directors ``d_source`` (n, 3) from the
    tangents ``t_source`` to ``t_new`` (re-orthonormalised against round-off)."""
    d = np.empty((d_source.shape[0], 3))
    for j in range(d_source.shape[0]):
        v = parallel_transport(d_source[j], t_source[j], t_new[j])
        c = v[0] * t_new[j, 0] + v[1] * t_new[j, 1] + v[2] * t_new[j, 2]
        for k in range(3):
            v[k] -= c * t_new[j, k]
        norm = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        for k in range(3):
            d[j, k] = v[k] / norm
    return d


def canonical_twist_offset(t0, d0, t, d_ref):
    """(n,) rad: the angle about ``t`` from the reference directors ``d_ref`` (n, 3) to the
    *canonical* ones, the stress-free directors ``d0`` carried from their tangents ``t0``
    straight to ``t`` by one parallel transport. A twist theta about d_ref is the twist
    theta - offset about the canonical directors: the same material frame, read in a
    convention that depends on the configuration only, not on the path that led to it
    (time-parallel frames pick up a holonomy along a path that turns in 3-D). Zero where an
    edge has turned back on its stress-free direction (no canonical frame there)."""
    c = np.einsum("ij,ij->i", t0, t)
    w = np.cross(t0, t)
    ok = 1.0 + c > 1e-8
    f = np.where(ok, np.einsum("ij,ij->i", w, d0) / np.where(ok, 1.0 + c, 1.0), 0.0)
    canon = c[:, None] * d0 + np.cross(w, d0) + f[:, None] * w
    canon -= np.einsum("ij,ij->i", canon, t)[:, None] * t
    canon /= np.linalg.norm(canon, axis=1)[:, None]
    off = np.arctan2(np.einsum("ij,ij->i", np.cross(d_ref, canon), t),
                     np.einsum("ij,ij->i", d_ref, canon))
    return np.where(ok, off, 0.0)


def reference_twist(tangents, directors, pairs):
    """Reference twist (rad) at each (edge_a, edge_b) pair: the signed angle about t_b from
    the space-parallel transport of d_a onto t_b to d_b."""
    out = np.empty(len(pairs))
    for k, (a, b) in enumerate(pairs):
        p = parallel_transport(directors[a], tangents[a], tangents[b])
        out[k] = np.arctan2(np.dot(np.cross(p, directors[b]), tangents[b]),
                            np.dot(p, directors[b]))
    return out


def material_directors(directors, tangents, theta):
    """(m1, m2), each (n, 3): the material frame of reference directors and twist angles."""
    b = np.cross(tangents, directors)
    c = np.cos(theta)[:, None]
    s = np.sin(theta)[:, None]
    return c * directors + s * b, -s * directors + c * b


@njit(cache=True)
def frame_jet_scratch():
    """Scratch arrays of `material_frame_jet_ws` (allocate once, reuse for every edge)."""
    return (np.empty(3), np.empty((3, 3)), np.empty((3, 3, 3)), np.empty(3), np.empty((3, 3)),
            np.empty(3), np.empty(3), np.empty((3, 3)), np.empty((3, 3, 3)), np.empty((3, 3)),
            np.empty((3, 3, 3)), np.empty((3, 3, 3)), np.empty(3), np.empty((3, 3)),
            np.empty((3, 3, 3)), np.empty((3, 3)), np.empty(3))


@njit(cache=True)
def material_frame_jet(e, theta, t_src, d_src, val, jac, hess):
    """Material frame of one edge and its derivatives w.r.t. p = (e_x, e_y, e_z, theta).

    ``e`` (3,) m: the edge vector; ``theta`` rad: its twist angle; ``t_src``, ``d_src``: unit
    tangent and reference director at the last accepted state. The reference director is
    d(t) = P(t_src -> t) d_src with t = e / |e|. Writes ``val`` (9,) = [t, m1, m2],
    ``jac`` (9, 4) = d val / dp (1/m for e, 1/rad for theta) and ``hess`` (9, 4, 4).
    """
    material_frame_jet_ws(e, theta, t_src, d_src, val, jac, hess, frame_jet_scratch())


@njit(cache=True)
def material_frame_jet_ws(e, theta, t_src, d_src, val, jac, hess, ws):
    """`material_frame_jet` writing its intermediates into ``ws`` (from
    `frame_jet_scratch`): no allocation, for the assembly loop."""
    t, T1, T2, w, W, u, d, D1, D2, dE, DT, dEE, b, bE, bEE, om, ga = ws
    ell = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    inv = 1.0 / ell
    for k in range(3):
        t[k] = e[k] * inv
    # dt/de and d2t/de2
    for k in range(3):
        for i in range(3):
            T1[k, i] = ((1.0 if k == i else 0.0) - t[k] * t[i]) * inv
    inv2 = inv * inv
    for k in range(3):
        for i in range(3):
            for j in range(i, 3):
                v = (3.0 * t[i] * t[j] * t[k]
                     - (t[i] if j == k else 0.0)
                     - (t[j] if i == k else 0.0)
                     - (t[k] if i == j else 0.0)) * inv2
                T2[k, i, j] = v
                T2[k, j, i] = v
    # d(t) = c d_src + w x d_src + w (w . d_src) / (1 + c), c = t_src . t, w = t_src x t;
    # c and w are linear in t, so all its derivatives w.r.t. the vector t are closed form.
    c = t_src[0] * t[0] + t_src[1] * t[1] + t_src[2] * t[2]
    w[0] = t_src[1] * t[2] - t_src[2] * t[1]
    w[1] = t_src[2] * t[0] - t_src[0] * t[2]
    w[2] = t_src[0] * t[1] - t_src[1] * t[0]
    s = w[0] * d_src[0] + w[1] * d_src[1] + w[2] * d_src[2]
    A = 1.0 / (1.0 + c)
    W[0, 0] = 0.0
    W[0, 1] = t_src[2]
    W[0, 2] = -t_src[1]
    W[1, 0] = -t_src[2]
    W[1, 1] = 0.0
    W[1, 2] = t_src[0]
    W[2, 0] = t_src[1]
    W[2, 1] = -t_src[0]
    W[2, 2] = 0.0
    for j in range(3):
        u[j] = W[j, 0] * d_src[0] + W[j, 1] * d_src[1] + W[j, 2] * d_src[2]
    d[0] = c * d_src[0] + (w[1] * d_src[2] - w[2] * d_src[1]) + w[0] * s * A
    d[1] = c * d_src[1] + (w[2] * d_src[0] - w[0] * d_src[2]) + w[1] * s * A
    d[2] = c * d_src[2] + (w[0] * d_src[1] - w[1] * d_src[0]) + w[2] * s * A
    for j in range(3):
        # W_j x d_src
        cx0 = W[j, 1] * d_src[2] - W[j, 2] * d_src[1]
        cx1 = W[j, 2] * d_src[0] - W[j, 0] * d_src[2]
        cx2 = W[j, 0] * d_src[1] - W[j, 1] * d_src[0]
        for k in range(3):
            cxk = cx0 if k == 0 else (cx1 if k == 1 else cx2)
            D1[k, j] = (t_src[j] * d_src[k] + cxk + W[j, k] * s * A + w[k] * u[j] * A
                        - w[k] * s * A * A * t_src[j])
    # D2[k, i, j] = A (W[j, k] (u[i] - A s t_src[i]) + W[i, k] (u[j] - A s t_src[j]))
    #   - A^2 w[k] (t_src[i] (u[j] - A s t_src[j]) + t_src[j] (u[i] - A s t_src[i]))
    #   = A (om[j, k] ga[i] + om[i, k] ga[j]), ga = u - A s t_src, om = W - A t_src w^T
    for i in range(3):
        ga[i] = u[i] - A * s * t_src[i]
        for k in range(3):
            om[i, k] = W[i, k] - A * t_src[i] * w[k]
    for k in range(3):
        for i in range(3):
            for j in range(i, 3):
                v = A * (om[j, k] * ga[i] + om[i, k] * ga[j])
                D2[k, i, j] = v
                D2[k, j, i] = v
    # chain to the edge vector: dd/de = D1 T1, d2d/de2 = D1 T2 + T1^T D2 T1
    for k in range(3):
        for i in range(3):
            acc = 0.0
            for m in range(3):
                acc += D1[k, m] * T1[m, i]
            dE[k, i] = acc
    for k in range(3):
        for m in range(3):
            for j in range(3):
                acc = 0.0
                for n in range(3):
                    acc += D2[k, m, n] * T1[n, j]
                DT[k, m, j] = acc
    for k in range(3):
        for i in range(3):
            for j in range(i, 3):
                acc = 0.0
                for m in range(3):
                    acc += D1[k, m] * T2[m, i, j] + T1[m, i] * DT[k, m, j]
                dEE[k, i, j] = acc
                dEE[k, j, i] = acc
    # b = t x d and its derivatives
    b[0] = t[1] * d[2] - t[2] * d[1]
    b[1] = t[2] * d[0] - t[0] * d[2]
    b[2] = t[0] * d[1] - t[1] * d[0]
    for i in range(3):
        # dt_i x d + t x dd_i
        bE[0, i] = (T1[1, i] * d[2] - T1[2, i] * d[1]) + (t[1] * dE[2, i] - t[2] * dE[1, i])
        bE[1, i] = (T1[2, i] * d[0] - T1[0, i] * d[2]) + (t[2] * dE[0, i] - t[0] * dE[2, i])
        bE[2, i] = (T1[0, i] * d[1] - T1[1, i] * d[0]) + (t[0] * dE[1, i] - t[1] * dE[0, i])
    for k in range(3):
        k1 = (k + 1) % 3
        k2 = (k + 2) % 3
        for i in range(3):
            for j in range(i, 3):
                v = (T2[k1, i, j] * d[k2] - T2[k2, i, j] * d[k1]
                     + T1[k1, i] * dE[k2, j] - T1[k2, i] * dE[k1, j]
                     + T1[k1, j] * dE[k2, i] - T1[k2, j] * dE[k1, i]
                     + t[k1] * dEE[k2, i, j] - t[k2] * dEE[k1, i, j])
                bEE[k, i, j] = v
                bEE[k, j, i] = v
    ct = np.cos(theta)
    st = np.sin(theta)
    for k in range(3):
        val[k] = t[k]
        val[3 + k] = ct * d[k] + st * b[k]
        val[6 + k] = -st * d[k] + ct * b[k]
        jac[k, 3] = 0.0  # the tangent does not depend on the twist angle
        for i in range(4):
            hess[k, i, 3] = 0.0
            hess[k, 3, i] = 0.0
        for i in range(3):
            jac[k, i] = T1[k, i]
            jac[3 + k, i] = ct * dE[k, i] + st * bE[k, i]
            jac[6 + k, i] = -st * dE[k, i] + ct * bE[k, i]
            for j in range(i, 3):
                h0 = T2[k, i, j]
                h1 = ct * dEE[k, i, j] + st * bEE[k, i, j]
                h2 = -st * dEE[k, i, j] + ct * bEE[k, i, j]
                hess[k, i, j] = h0
                hess[k, j, i] = h0
                hess[3 + k, i, j] = h1
                hess[3 + k, j, i] = h1
                hess[6 + k, i, j] = h2
                hess[6 + k, j, i] = h2
    for k in range(3):
        # d m1 / d theta = m2, d m2 / d theta = -m1
        jac[3 + k, 3] = val[6 + k]
        jac[6 + k, 3] = -val[3 + k]
        hess[3 + k, 3, 3] = -val[3 + k]
        hess[6 + k, 3, 3] = -val[6 + k]
        for i in range(3):
            hess[3 + k, i, 3] = jac[6 + k, i]
            hess[3 + k, 3, i] = jac[6 + k, i]
            hess[6 + k, i, 3] = -jac[3 + k, i]
            hess[6 + k, 3, i] = -jac[3 + k, i]
