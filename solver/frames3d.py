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


@njit(cache=True)
def canonical_twist_offset(t0, d0, t, d_ref):
    """(n,) rad: the angle about ``t`` from the reference directors ``d_ref`` (n, 3) to the
    *canonical* ones, the stress-free directors ``d0`` carried from their tangents ``t0``
    straight to ``t`` by one parallel transport. A twist theta about d_ref is the twist
    theta - offset about the canonical directors: the same material frame, read in a
    convention that depends on the configuration only, not on the path that led to it
    (time-parallel frames pick up a holonomy along a path that turns in 3-D). Zero where an
    edge has turned back on its stress-free direction (no canonical frame there)."""
    n = t.shape[0]
    out = np.zeros(n)
    canon = np.empty(3)
    for j in range(n):
        c = t0[j, 0] * t[j, 0] + t0[j, 1] * t[j, 1] + t0[j, 2] * t[j, 2]
        if not 1.0 + c > 1e-8:
            continue
        w0 = t0[j, 1] * t[j, 2] - t0[j, 2] * t[j, 1]
        w1 = t0[j, 2] * t[j, 0] - t0[j, 0] * t[j, 2]
        w2 = t0[j, 0] * t[j, 1] - t0[j, 1] * t[j, 0]
        f = (w0 * d0[j, 0] + w1 * d0[j, 1] + w2 * d0[j, 2]) / (1.0 + c)
        canon[0] = c * d0[j, 0] + (w1 * d0[j, 2] - w2 * d0[j, 1]) + f * w0
        canon[1] = c * d0[j, 1] + (w2 * d0[j, 0] - w0 * d0[j, 2]) + f * w1
        canon[2] = c * d0[j, 2] + (w0 * d0[j, 1] - w1 * d0[j, 0]) + f * w2
        ct = canon[0] * t[j, 0] + canon[1] * t[j, 1] + canon[2] * t[j, 2]
        for k in range(3):
            canon[k] -= ct * t[j, k]
        norm = np.sqrt(canon[0] * canon[0] + canon[1] * canon[1] + canon[2] * canon[2])
        for k in range(3):
            canon[k] /= norm
        # angle from d_ref to canon about t
        x0 = d_ref[j, 1] * canon[2] - d_ref[j, 2] * canon[1]
        x1 = d_ref[j, 2] * canon[0] - d_ref[j, 0] * canon[2]
        x2 = d_ref[j, 0] * canon[1] - d_ref[j, 1] * canon[0]
        sin_ = x0 * t[j, 0] + x1 * t[j, 1] + x2 * t[j, 2]
        cos_ = d_ref[j, 0] * canon[0] + d_ref[j, 1] * canon[1] + d_ref[j, 2] * canon[2]
        out[j] = np.arctan2(sin_, cos_)
    return out


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


# The jet kernel's scratch: one flat array addressed by constant offsets (no strides to
# multiply, no per-call allocation): r = t + t_src (3), T1 = dt/de (3 x 3), a = d phi/de
# (2 x 3: m1, m2), phi (2), S (2 x 3 x 3).
_JR, _JT1, _JA, _JPH, _JS = 0, 3, 12, 18, 20
_JET_SIZE = 38


@njit(cache=True)
def frame_jet_scratch():
    """Scratch of `material_frame_jet_ws` (allocate once, reuse for every edge)."""
    return np.empty(_JET_SIZE)


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
    `frame_jet_scratch`): no allocation, for the assembly loop.

    The transport of a vector v normal to t_src is P v = v - phi r, r = t + t_src,
    phi = (t . v) / (1 + t . t_src) = (e . v) / n with n = |e| + e . t_src; as dn/de = r,
    d phi/de = (v - phi r) / n = P v / n. P is a rotation (t_src to t), so each material
    director is m = P v of a fixed source vector (m1: v = cos(theta) d_src + sin(theta)
    t_src x d_src; m2: v = t_src x (m1's v)), and with a = m / n, T1 = dt/de =
    (I - t t^T) / |e| (1/m) and T2 = d2t/de2 (1/m^2):
        dm/de = -r a^T - phi T1,
        d2m_k/de_i de_j = r_k S_ij - a_i T1_kj - a_j T1_ki - phi T2_kij,
        S = (a r^T + r a^T + phi T1) / n;
    d/dtheta turns the frame about t (dm1 = m2, dm2 = -m1)."""
    ell = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    inv = 1.0 / ell
    inv2 = inv * inv
    for k in range(3):
        val[k] = e[k] * inv
    q = 1.0 / (1.0 + t_src[0] * val[0] + t_src[1] * val[1] + t_src[2] * val[2])
    n_inv = q * inv
    for k in range(3):
        ws[_JR + k] = val[k] + t_src[k]
    bs0 = t_src[1] * d_src[2] - t_src[2] * d_src[1]
    bs1 = t_src[2] * d_src[0] - t_src[0] * d_src[2]
    bs2 = t_src[0] * d_src[1] - t_src[1] * d_src[0]
    ct = np.cos(theta)
    st = np.sin(theta)
    for o in range(2):
        # source director of m1 (o = 0) and m2 (o = 1)
        ca = ct if o == 0 else -st
        cb = st if o == 0 else ct
        v0 = ca * d_src[0] + cb * bs0
        v1 = ca * d_src[1] + cb * bs1
        v2 = ca * d_src[2] + cb * bs2
        phi = (val[0] * v0 + val[1] * v1 + val[2] * v2) * q
        ws[_JPH + o] = phi
        val[3 + 3 * o] = v0 - phi * ws[_JR]
        val[4 + 3 * o] = v1 - phi * ws[_JR + 1]
        val[5 + 3 * o] = v2 - phi * ws[_JR + 2]
        for k in range(3):
            ws[_JA + 3 * o + k] = val[3 + 3 * o + k] * n_inv
    for k in range(3):
        for i in range(k, 3):
            v = ((1.0 if k == i else 0.0) - val[k] * val[i]) * inv
            ws[_JT1 + 3 * k + i] = v
            ws[_JT1 + 3 * i + k] = v
    for o in range(2):
        phi = ws[_JPH + o]
        for i in range(3):
            for j in range(i, 3):
                v = (ws[_JA + 3 * o + i] * ws[_JR + j] + ws[_JA + 3 * o + j] * ws[_JR + i]
                     + phi * ws[_JT1 + 3 * i + j]) * n_inv
                ws[_JS + 9 * o + 3 * i + j] = v
                ws[_JS + 9 * o + 3 * j + i] = v
    for k in range(3):
        jac[k, 3] = 0.0  # the tangent does not depend on the twist angle
        jac[3 + k, 3] = val[6 + k]
        jac[6 + k, 3] = -val[3 + k]
        for i in range(3):
            T1ki = ws[_JT1 + 3 * k + i]
            jac[k, i] = T1ki
            for o in range(2):
                jac[3 + 3 * o + k, i] = -ws[_JR + k] * ws[_JA + 3 * o + i] - ws[_JPH + o] * T1ki
    for k in range(3):
        tk = val[k]
        rk = ws[_JR + k]
        for i in range(3):
            ti = val[i]
            for j in range(i, 3):
                tj = val[j]
                T2 = (3.0 * ti * tj * tk - (ti if j == k else 0.0) - (tj if i == k else 0.0)
                      - (tk if i == j else 0.0)) * inv2
                hess[k, i, j] = T2
                hess[k, j, i] = T2
                for o in range(2):
                    h = (rk * ws[_JS + 9 * o + 3 * i + j]
                         - ws[_JA + 3 * o + i] * ws[_JT1 + 3 * k + j]
                         - ws[_JA + 3 * o + j] * ws[_JT1 + 3 * k + i] - ws[_JPH + o] * T2)
                    hess[3 + 3 * o + k, i, j] = h
                    hess[3 + 3 * o + k, j, i] = h
    for k in range(3):
        hess[k, 3, 3] = 0.0
        hess[3 + k, 3, 3] = -val[3 + k]
        hess[6 + k, 3, 3] = -val[6 + k]
        for i in range(3):
            hess[k, i, 3] = 0.0
            hess[k, 3, i] = 0.0
            v = jac[6 + k, i]
            hess[3 + k, i, 3] = v
            hess[3 + k, 3, i] = v
            v = -jac[3 + k, i]
            hess[6 + k, i, 3] = v
            hess[6 + k, 3, i] = v
