"""Energy kernels of 3-D discrete elastic rods (Bergou et al. 2008, 2010; Jawed, Novelia &
O'Reilly 2018), each returning its value and writing its exact gradient and Hessian.

- stretching, per edge: ``E_s = 1/2 (EA / |e_bar|) (|e| - |e_bar|)^2``; local coordinates
  ``[xa, ya, za, xb, yb, zb]`` (m).
- bending, per pair of edges meeting at a node (or at a rigid joint or a clamp):
  ``E_b = 1/2 k1 (kappa1 - kappa1_bar)^2 + 1/2 k2 (kappa2 - kappa2_bar)^2`` with the
  curvature binormal ``kb = 2 t_a x t_b / (1 + t_a . t_b)`` and the material curvatures
  ``kappa1 = 1/2 (m2_a + m2_b) . kb`` (bending through the thickness, k1 = EI1 / l_bar) and
  ``kappa2 = -1/2 (m1_a + m1_b) . kb`` (bending in the strip's plane, k2 = EI2 / l_bar);
  kappa are integrated (dimensionless), l_bar the Voronoi length.
- twisting, per pair of edges: ``E_t = 1/2 kt (psi - psi_bar)^2``, kt = GJ / l_bar, where psi
  is the twist angle from frame a to frame b: with Q = sum_k b_k a_k^T the rotation between
  the frames (t, m1, m2), ``tan(psi / 2) = ((sum_k a_k x b_k) . t_a) / (1 + tr Q)``. This is
  theta_b - theta_a + the reference twist, read off the material frames directly.

Reference kernels: bending and twisting take the 18 frame components
``z = [t_a, m1_a, m2_a, t_b, m1_b, m2_b]`` as independent variables (gradient (18,), Hessian
(18, 18)); `chain_pair` carries them to the edges' vectors and twist angles through
`solver.frames3d.material_frame_jet`. The assembly uses `pair_terms_edges`, the same energy
formed straight in the edge coordinates (no 18 x 18 matrix, no allocation; tested equal to
the reference kernels to round-off and against finite differences).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def stretch_terms(x, EA, rest_length, grad, hess):
    """Stretching energy (J) of one edge; ``x`` = [xa, ya, za, xb, yb, zb] (m), EA (N),
    rest length (m). Writes dE/dx into ``grad`` (6,) and d2E/dx2 into ``hess`` (6, 6)."""
    e = np.empty(3)
    for k in range(3):
        e[k] = x[3 + k] - x[k]
    length = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
    k_axial = EA / rest_length
    stretch = length - rest_length
    c = k_axial * stretch / length
    for i in range(3):
        ti = e[i] / length
        grad[i] = -k_axial * stretch * ti
        grad[3 + i] = k_axial * stretch * ti
        for j in range(3):
            tj = e[j] / length
            # d2E/de2 = k t t^T + (k stretch / |e|) (I - t t^T)
            h = k_axial * ti * tj + c * ((1.0 if i == j else 0.0) - ti * tj)
            hess[i, j] = h
            hess[3 + i, 3 + j] = h
            hess[i, 3 + j] = -h
            hess[3 + i, j] = -h
    return 0.5 * k_axial * stretch * stretch


@njit(cache=True, inline="always")
def _eps(i, j, k):
    """Levi-Civita symbol for indices in 0..2."""
    return 0.5 * (i - j) * (j - k) * (k - i)


# the six non-zero Levi-Civita entries (i, j, k, sign)
_PERMS = np.array([[0, 1, 2, 1], [1, 2, 0, 1], [2, 0, 1, 1],
                   [0, 2, 1, -1], [2, 1, 0, -1], [1, 0, 2, -1]], dtype=np.int64)


@njit(cache=True)
def _triple(z, p, q, r, coef, grad, hess):
    """Add coef * p . (q x r) (p, q, r: offsets of 3-vectors in z) to grad and hess; returns
    its value."""
    val = 0.0
    for n in range(6):
        i = p + _PERMS[n, 0]
        j = q + _PERMS[n, 1]
        k = r + _PERMS[n, 2]
        e = float(_PERMS[n, 3])
        ce = coef * e
        val += e * z[i] * z[j] * z[k]
        grad[i] += ce * z[j] * z[k]
        grad[j] += ce * z[i] * z[k]
        grad[k] += ce * z[i] * z[j]
        hess[i, j] += ce * z[k]
        hess[j, i] += ce * z[k]
        hess[i, k] += ce * z[j]
        hess[k, i] += ce * z[j]
        hess[j, k] += ce * z[i]
        hess[k, j] += ce * z[i]
    return coef * val


@njit(cache=True)
def _dot(z, p, q, grad, hess):
    """Add z[p:p+3] . z[q:q+3] to grad and hess (p != q); returns its value."""
    val = 0.0
    for i in range(3):
        val += z[p + i] * z[q + i]
        grad[p + i] += z[q + i]
        grad[q + i] += z[p + i]
        hess[p + i, q + i] += 1.0
        hess[q + i, p + i] += 1.0
    return val


@njit(cache=True)
def _quotient(num, gn, hn, den, gd, hd, grad, hess):
    """grad, hess of num / den from those of num and den; returns the value."""
    inv = 1.0 / den
    f = num * inv
    n = grad.shape[0]
    for i in range(n):
        grad[i] = (gn[i] - f * gd[i]) * inv
    for i in range(n):
        for j in range(n):
            hess[i, j] = (hn[i, j] - f * hd[i, j]
                          - (gn[i] * gd[j] + gd[i] * gn[j]) * inv
                          + 2.0 * f * gd[i] * gd[j] * inv) * inv
    return f


# z offsets of t_a, t_b and the two directors summed into u, per curvature (kappa1: m2,
# kappa2: m1 with a minus sign)
_CURV_U = np.array([[6, 15], [3, 12]], dtype=np.int64)
# z offset of each 3-block a curvature reads (t_a, t_b, the two directors summed into u) and
# its y offset, per curvature
_CURV_OZ = np.array([[0, 9, 6, 15], [0, 9, 3, 12]], dtype=np.int64)
_CURV_OY = np.array([0, 3, 6, 6], dtype=np.int64)


@njit(cache=True)
def pair_scratch():
    """Scratch arrays of the allocation-free pair kernels (`pair_terms`, `chain_pair_ws`):
    allocate once, reuse for every pair."""
    return (np.empty(9), np.empty(9), np.empty((9, 9)), np.empty(9), np.empty((9, 9)),
            np.empty(9), np.empty((9, 9)), np.empty(18), np.empty((18, 18)), np.empty(18),
            np.empty((18, 18)), np.empty(18), np.empty((18, 8)), np.empty((18, 8)))


@njit(cache=True)
def _curvature9_ws(y, g9, h9, gn, hn, gd, hd):
    """f = u . (t_a x t_b) / (1 + t_a . t_b) of y = [t_a, t_b, u] (9,); writes its
    gradient (9,) and Hessian (9, 9); gn, hn, gd, hd: (9,), (9, 9) scratch."""
    gn[:] = 0.0
    hn[:, :] = 0.0
    gd[:] = 0.0
    hd[:, :] = 0.0
    num = _triple(y, 6, 0, 3, 1.0, gn, hn)
    den = 1.0 + _dot(y, 0, 3, gd, hd)
    return _quotient(num, gn, hn, den, gd, hd, g9, h9)


@njit(cache=True)
def _curvature9(y, g9, h9):
    """`_curvature9_ws` with its own scratch."""
    return _curvature9_ws(y, g9, h9, np.empty(9), np.empty((9, 9)), np.empty(9),
                          np.empty((9, 9)))


@njit(cache=True)
def material_curvature(z, which, grad, hess):
    """kappa1 (``which`` = 1) or kappa2 (2) of the frame pair ``z`` (18,); writes its gradient
    (18,) and Hessian (18, 18) w.r.t. z."""
    y = np.empty(9)
    g9 = np.empty(9)
    h9 = np.empty((9, 9))
    zi = np.empty(9, dtype=np.int64)  # z index of each y component (u: the first director)
    ua = _CURV_U[which - 1, 0]
    ub = _CURV_U[which - 1, 1]
    sgn = 1.0 if which == 1 else -1.0
    for k in range(3):
        y[k] = z[k]
        y[3 + k] = z[9 + k]
        y[6 + k] = sgn * (z[ua + k] + z[ub + k])
    kappa = _curvature9(y, g9, h9)
    grad[:] = 0.0
    hess[:, :] = 0.0
    # z index and sign of each y component; u appears twice (both directors)
    for k in range(3):
        zi[k] = k
        zi[3 + k] = 9 + k
    for a in range(6):
        grad[zi[a]] = g9[a]
        for b in range(6):
            hess[zi[a], zi[b]] = h9[a, b]
    for k in range(3):
        for base in (ua, ub):
            grad[base + k] = sgn * g9[6 + k]
            for b in range(6):
                hess[base + k, zi[b]] = sgn * h9[6 + k, b]
                hess[zi[b], base + k] = sgn * h9[b, 6 + k]
            for m in range(3):
                for base2 in (ua, ub):
                    hess[base + k, base2 + m] = h9[6 + k, 6 + m]
    return kappa


@njit(cache=True)
def bending_add(z, k1, k2, kappa1_bar, kappa2_bar, grad, hess, ws):
    """Add the bending energy's gradient and Hessian of `bending_terms` to ``grad`` (18,),
    ``hess`` (18, 18); returns the energy (J). ``ws``: `pair_scratch` (no allocation)."""
    y, g9, h9, gn, hn, gd, hd = ws[0], ws[1], ws[2], ws[3], ws[4], ws[5], ws[6]
    energy = 0.0
    for which in range(1, 3):
        ua = _CURV_U[which - 1, 0]
        ub = _CURV_U[which - 1, 1]
        sgn = 1.0 if which == 1 else -1.0
        for k in range(3):
            y[k] = z[k]
            y[3 + k] = z[9 + k]
            y[6 + k] = sgn * (z[ua + k] + z[ub + k])
        kappa = _curvature9_ws(y, g9, h9, gn, hn, gd, hd)
        kk = k1 if which == 1 else k2
        dk = kappa - (kappa1_bar if which == 1 else kappa2_bar)
        energy += 0.5 * kk * dk * dk
        for A in range(4):
            za = _CURV_OZ[which - 1, A]
            ya = _CURV_OY[A]
            sa = 1.0 if A < 2 else sgn
            for i in range(3):
                grad[za + i] += kk * dk * sa * g9[ya + i]
            for B in range(4):
                zb = _CURV_OZ[which - 1, B]
                yb = _CURV_OY[B]
                s_ab = kk * sa * (1.0 if B < 2 else sgn)
                for i in range(3):
                    gi = g9[ya + i]
                    for j in range(3):
                        hess[za + i, zb + j] += s_ab * (gi * g9[yb + j] + dk * h9[ya + i, yb + j])
    return energy


@njit(cache=True)
def bending_terms(z, k1, k2, kappa1_bar, kappa2_bar, grad, hess):
    """Bending energy (J) of a frame pair ``z`` (18,) with stiffnesses k1, k2 = EI / l_bar
    (N m) and natural integrated curvatures; writes grad (18,) and hess (18, 18).

    Each curvature depends on 9 numbers (t_a, t_b and the sum of two directors): its
    derivatives are taken in those and scattered to the four 3-blocks of z it reads."""
    grad[:] = 0.0
    hess[:, :] = 0.0
    return bending_add(z, k1, k2, kappa1_bar, kappa2_bar, grad, hess, pair_scratch())


@njit(cache=True)
def _twist_parts(z, gx, hx, gy, hy):
    """X = 1 + tr Q and Y = (sum_k a_k x b_k) . t_a of ``z`` with their gradients and
    Hessians (written into the scratch gx, hx, gy, hy); returns (X, Y)."""
    gx[:] = 0.0
    hx[:, :] = 0.0
    gy[:] = 0.0
    hy[:, :] = 0.0
    X = 1.0 + _dot(z, 0, 9, gx, hx) + _dot(z, 3, 12, gx, hx) + _dot(z, 6, 15, gx, hx)
    Y = _triple(z, 0, 3, 12, 1.0, gy, hy) + _triple(z, 0, 6, 15, 1.0, gy, hy)
    return X, Y


@njit(cache=True)
def twist_angle(z, grad, hess):
    """Twist psi (rad) from frame a to frame b of ``z`` (18,); writes grad and hess."""
    gx = np.empty(18)
    hx = np.empty((18, 18))
    gy = np.empty(18)
    hy = np.empty((18, 18))
    X, Y = _twist_parts(z, gx, hx, gy, hy)
    r2 = X * X + Y * Y
    psi = 2.0 * np.arctan2(Y, X)
    N = np.empty(18)
    for i in range(18):
        N[i] = X * gy[i] - Y * gx[i]
        grad[i] = 2.0 * N[i] / r2
    for i in range(18):
        for j in range(18):
            hess[i, j] = (2.0 * (X * hy[i, j] - Y * hx[i, j] + gx[j] * gy[i] - gy[j] * gx[i]) / r2
                          - 4.0 * N[i] * (X * gx[j] + Y * gy[j]) / (r2 * r2))
    return psi


@njit(cache=True)
def twist_add(z, kt, psi_bar, grad, hess, ws):
    """Add the twisting energy's gradient and Hessian of `twist_terms` to ``grad`` (18,),
    ``hess`` (18, 18); returns the energy (J). ``ws``: `pair_scratch` (no allocation).
    The Hessian of psi is formed entry by entry inside kt (g g^T + (psi - psi_bar) H)."""
    gx, hx, gy, hy, g = ws[7], ws[8], ws[9], ws[10], ws[11]
    X, Y = _twist_parts(z, gx, hx, gy, hy)
    r2 = X * X + Y * Y
    inv_r2 = 1.0 / r2
    psi = 2.0 * np.arctan2(Y, X)
    d = psi - psi_bar
    kd = kt * d
    for i in range(18):
        g[i] = 2.0 * (X * gy[i] - Y * gx[i]) * inv_r2
        grad[i] += kd * g[i]
    for i in range(18):
        # 4 N_i / r2^2 = 2 g_i / r2
        c_i = 2.0 * g[i] * inv_r2
        for j in range(18):
            h = (2.0 * (X * hy[i, j] - Y * hx[i, j] + gx[j] * gy[i] - gy[j] * gx[i]) * inv_r2
                 - c_i * (X * gx[j] + Y * gy[j]))
            hess[i, j] += kt * (g[i] * g[j] + d * h)
    return 0.5 * kt * d * d


@njit(cache=True)
def twist_terms(z, kt, psi_bar, grad, hess):
    """Twisting energy (J) of a frame pair ``z`` with stiffness kt = GJ / l_bar (N m) and
    natural twist psi_bar (rad); writes grad (18,) and hess (18, 18)."""
    grad[:] = 0.0
    hess[:, :] = 0.0
    return twist_add(z, kt, psi_bar, grad, hess, pair_scratch())


@njit(cache=True)
def pair_frames(val_a, sign_a, val_b, sign_b, z):
    """z (18,) from the two edges' frames [t, m1, m2]; an edge used against its direction
    (sign -1) enters as the proper frame (-t, m1, -m2)."""
    for k in range(3):
        z[k] = sign_a * val_a[k]
        z[3 + k] = val_a[3 + k]
        z[6 + k] = sign_a * val_a[6 + k]
        z[9 + k] = sign_b * val_b[k]
        z[12 + k] = val_b[3 + k]
        z[15 + k] = sign_b * val_b[6 + k]


@njit(cache=True)
def chain_pair(gz, hz, jac_a, hess_a, sign_a, jac_b, hess_b, sign_b, g8, h8):
    """Carry a gradient (18,) and Hessian (18, 18) w.r.t. z to p = (e_a, theta_a, e_b,
    theta_b) (8,) through the frames' derivatives (`material_frame_jet`):
    g8 = J^T gz, h8 = J^T hz J + sum_c gz_c d2 z_c / dp2 (J block diagonal, 9 x 4 blocks)."""
    ws = pair_scratch()
    chain_pair_ws(gz, hz, jac_a, hess_a, sign_a, jac_b, hess_b, sign_b, g8, h8, ws)


@njit(cache=True)
def chain_pair_ws(gz, hz, jac_a, hess_a, sign_a, jac_b, hess_b, sign_b, g8, h8, ws):
    """`chain_pair` with the scratch ``ws`` of `pair_scratch` (no allocation). Only J's two
    diagonal 9 x 4 blocks are written and read."""
    J, HJ = ws[12], ws[13]
    for c in range(9):
        f = sign_a if (c < 3 or c >= 6) else 1.0
        fb = sign_b if (c < 3 or c >= 6) else 1.0
        for r in range(4):
            J[c, r] = f * jac_a[c, r]
            J[9 + c, 4 + r] = fb * jac_b[c, r]
    for i in range(18):
        for r in range(8):
            blk = 0 if r < 4 else 9
            acc = 0.0
            for c in range(9):
                acc += hz[i, blk + c] * J[blk + c, r]
            HJ[i, r] = acc
    for r in range(8):
        blk = 0 if r < 4 else 9
        acc = 0.0
        for c in range(9):
            acc += gz[blk + c] * J[blk + c, r]
        g8[r] = acc
        for s in range(r, 8):
            acc = 0.0
            for c in range(9):
                acc += J[blk + c, r] * HJ[blk + c, s]
            h8[r, s] = acc
            h8[s, r] = acc
    for c in range(9):
        f = sign_a if (c < 3 or c >= 6) else 1.0
        fb = sign_b if (c < 3 or c >= 6) else 1.0
        ga = f * gz[c]
        gb = fb * gz[9 + c]
        for r in range(4):
            for s in range(4):
                h8[r, s] += ga * hess_a[c, r, s]
                h8[4 + r, 4 + s] += gb * hess_b[c, r, s]


# ---------------------------------------------------------------------------------------
# The pair energy straight in edge coordinates p = (e_a, theta_a, e_b, theta_b): every
# curvature and the twist are sums of dot and triple products of the six frame vectors
# [t_a, m1_a, m2_a, t_b, m1_b, m2_b] (blocks 0..5 of z). The energy's Hessian is
#   sum_f k_f (grad_p f grad_p f^T + (f - f_bar) J^T (d2 f / dz2) J) + sum_c (dE/dz_c) d2 z_c/dp2,
# and d2 f / dz2 is a combination of the bilinear forms' constant Hessians and of a few
# outer products of z-gradients; the bilinear parts of all three terms are added with their
# final coefficients, block by block from the frames' 3 x 4 Jacobians (never an 18 x 18
# matrix), the outer products in p (8 x 8).


@njit(cache=True)
def pair_edge_scratch():
    """Scratch arrays of `pair_terms_edges` (allocate once, reuse for every pair)."""
    return (np.empty(18), np.empty((24, 4)), np.empty((5, 18)), np.empty((5, 8)), np.empty(18),
            np.empty((8, 8)), np.empty(3), np.empty((4, 3)))


@njit(cache=True, inline="always")
def _jt(Jz, v, out):
    """out (8,) = J^T v for v (18,) w.r.t. z (block c reads edge c // 3)."""
    for o in range(2):
        for r in range(4):
            acc = 0.0
            for i in range(9):
                acc += Jz[9 * o + i, r] * v[9 * o + i]
            out[4 * o + r] = acc


@njit(cache=True, inline="always")
def _p_offset(A):
    """Offset in p of the edge block A reads: blocks 0-2 (and the combination 6) edge a,
    3-5 (and 7) edge b."""
    return 4 * (A // 3) if A < 6 else 4 * (A - 6)


@njit(cache=True, inline="always")
def _n_cols(A):
    """Columns of block A's Jacobian that can be non-zero: a tangent (blocks 0, 3) does not
    depend on the twist angle (its fourth column is exactly zero)."""
    return 3 if (A == 0 or A == 3) else 4


@njit(cache=True, inline="always")
def _dot_hess(Jz, A, B, coef, M):
    """M[p_A, p_B] += coef J_A^T J_B: one side of J^T d2(z_A . z_B)/dz2 J (the other side
    is M's transpose, added when M is symmetrised)."""
    pa = 3 * A
    pb = 3 * B
    oa = _p_offset(A)
    ob = _p_offset(B)
    for r in range(_n_cols(A)):
        for s in range(_n_cols(B)):
            M[oa + r, ob + s] += coef * (Jz[pa, r] * Jz[pb, s] + Jz[pa + 1, r] * Jz[pb + 1, s]
                                         + Jz[pa + 2, r] * Jz[pb + 2, s])


@njit(cache=True, inline="always")
def _cross_hess(Jz, P, Q, v, vo, coef, M, W):
    """M[p_P, p_Q] += coef J_P[:, r] . (J_Q[:, s] x v): one side of J^T d2 (z_P . (z_Q x v))
    / dz_P dz_Q J for a fixed vector v = v[vo:vo+3]. ``W`` (4, 3) scratch."""
    pp = 3 * P
    pq = 3 * Q
    op = _p_offset(P)
    oq = _p_offset(Q)
    v0 = v[vo]
    v1 = v[vo + 1]
    v2 = v[vo + 2]
    nq = _n_cols(Q)
    for s in range(nq):
        W[s, 0] = coef * (Jz[pq + 1, s] * v2 - Jz[pq + 2, s] * v1)
        W[s, 1] = coef * (Jz[pq + 2, s] * v0 - Jz[pq, s] * v2)
        W[s, 2] = coef * (Jz[pq, s] * v1 - Jz[pq + 1, s] * v0)
    for r in range(_n_cols(P)):
        for s in range(nq):
            M[op + r, oq + s] += (Jz[pp, r] * W[s, 0] + Jz[pp + 1, r] * W[s, 1]
                                  + Jz[pp + 2, r] * W[s, 2])


@njit(cache=True, inline="always")
def _cross_into(z, P, Q, out, o):
    """out[o:o+3] = z_P x z_Q."""
    p = 3 * P
    q = 3 * Q
    out[o] = z[p + 1] * z[q + 2] - z[p + 2] * z[q + 1]
    out[o + 1] = z[p + 2] * z[q] - z[p] * z[q + 2]
    out[o + 2] = z[p] * z[q + 1] - z[p + 1] * z[q]


@njit(cache=True)
def pair_terms_edges(val_a, jac_a, hess_a, sign_a, val_b, jac_b, hess_b, sign_b,
                     k1, k2, kt, kappa1_bar, kappa2_bar, psi_bar, g8, h8, ws):
    """Bending plus twisting energy (J) of a pair of edges with its gradient ``g8`` (8,) and
    Hessian ``h8`` (8, 8) w.r.t. p = (e_a, theta_a, e_b, theta_b), from the two frames'
    jets (`material_frame_jet`; sign -1: the edge enters against its direction). The same
    energy as `bending_terms` + `twist_terms` carried by `chain_pair`, without any 18 x 18
    matrix and without allocation (``ws``: `pair_edge_scratch`)."""
    z, Jz, gz, gp, G, M, U, W = ws
    # signed frame vectors and their derivatives: z = [t_a, m1_a, m2_a, t_b, m1_b, m2_b]
    for c in range(9):
        fa = sign_a if (c < 3 or c >= 6) else 1.0
        fb = sign_b if (c < 3 or c >= 6) else 1.0
        z[c] = fa * val_a[c]
        z[9 + c] = fb * val_b[c]
        for r in range(4):
            Jz[c, r] = fa * jac_a[c, r]
            Jz[9 + c, r] = fb * jac_b[c, r]
    # z-gradients (rows of gz): 0 D = 1 + t_a.t_b, 1 N1 = (m2_a + m2_b).(t_a x t_b),
    # 2 N2 = -(m1_a + m1_b).(t_a x t_b), 3 X = 1 + tr Q, 4 Y = t_a.(m1_a x m1_b + m2_a x m2_b)
    for i in range(5):
        for j in range(18):
            gz[i, j] = 0.0
    _cross_into(z, 0, 3, U, 0)  # U = t_a x t_b
    D = 1.0
    X = 1.0
    N1 = 0.0
    N2 = 0.0
    for k in range(3):
        ta = z[k]
        tb = z[9 + k]
        D += ta * tb
        X += z[3 + k] * z[12 + k] + z[6 + k] * z[15 + k]
        N1 += (z[6 + k] + z[15 + k]) * U[k]
        N2 -= (z[3 + k] + z[12 + k]) * U[k]
        gz[0, k] = tb
        gz[0, 9 + k] = ta
        gz[1, 6 + k] = U[k]
        gz[1, 15 + k] = U[k]
        gz[2, 3 + k] = -U[k]
        gz[2, 12 + k] = -U[k]
        gz[3, k] = tb
        gz[3, 9 + k] = ta
        gz[3, 3 + k] = z[12 + k]
        gz[3, 12 + k] = z[3 + k]
        gz[3, 6 + k] = z[15 + k]
        gz[3, 15 + k] = z[6 + k]
    X += D - 1.0
    # d N / d t_a = t_b x u, d N / d t_b = u x t_a (u the director sum of N1, N2)
    for k in range(3):
        k1_ = (k + 1) % 3
        k2_ = (k + 2) % 3
        u1a = z[6 + k1_] + z[15 + k1_]
        u1b = z[6 + k2_] + z[15 + k2_]
        u2a = -(z[3 + k1_] + z[12 + k1_])
        u2b = -(z[3 + k2_] + z[12 + k2_])
        gz[1, k] = z[9 + k1_] * u1b - z[9 + k2_] * u1a
        gz[1, 9 + k] = u1a * z[k2_] - u1b * z[k1_]
        gz[2, k] = z[9 + k1_] * u2b - z[9 + k2_] * u2a
        gz[2, 9 + k] = u2a * z[k2_] - u2b * z[k1_]
    # Y = t_a . (m1_a x m1_b) + t_a . (m2_a x m2_b)
    _cross_into(z, 1, 4, U, 0)
    Y = z[0] * U[0] + z[1] * U[1] + z[2] * U[2]
    for k in range(3):
        gz[4, k] = U[k]
    _cross_into(z, 2, 5, U, 0)
    Y += z[0] * U[0] + z[1] * U[1] + z[2] * U[2]
    for k in range(3):
        gz[4, k] += U[k]
    _cross_into(z, 4, 0, U, 0)  # d/dm1_a = m1_b x t_a
    for k in range(3):
        gz[4, 3 + k] = U[k]
    _cross_into(z, 0, 1, U, 0)  # d/dm1_b = t_a x m1_a
    for k in range(3):
        gz[4, 12 + k] = U[k]
    _cross_into(z, 5, 0, U, 0)
    for k in range(3):
        gz[4, 6 + k] = U[k]
    _cross_into(z, 0, 2, U, 0)
    for k in range(3):
        gz[4, 15 + k] = U[k]
    for i in range(5):
        _jt(Jz, gz[i], gp[i])
    # the three terms: kappa1 = N1 / D, kappa2 = N2 / D, psi = 2 atan2(Y, X)
    kap1 = N1 / D
    kap2 = N2 / D
    d1 = kap1 - kappa1_bar
    d2 = kap2 - kappa2_bar
    r2 = X * X + Y * Y
    psi = 2.0 * np.arctan2(Y, X)
    dt = psi - psi_bar
    energy = 0.5 * (k1 * d1 * d1 + k2 * d2 * d2 + kt * dt * dt)
    c1 = k1 * d1 / D
    c2 = k2 * d2 / D
    ct = kt * dt
    # dE/dz and dE/dp; gradients of kappa = (gN - kappa gD) / D, of psi = 2 (X gY - Y gX) / r2
    for j in range(18):
        G[j] = (c1 * (gz[1, j] - kap1 * gz[0, j]) + c2 * (gz[2, j] - kap2 * gz[0, j])
                + ct * 2.0 * (X * gz[4, j] - Y * gz[3, j]) / r2)
    for r in range(8):
        g1 = (gp[1, r] - kap1 * gp[0, r]) / D
        g2 = (gp[2, r] - kap2 * gp[0, r]) / D
        gt = 2.0 * (X * gp[4, r] - Y * gp[3, r]) / r2
        g8[r] = k1 * d1 * g1 + k2 * d2 * g2 + ct * gt
        gp[1, r] = g1  # gp rows now: 0 dD, 1 dkappa1, 2 dkappa2, 3 dX, 4 dY (p)
        gp[2, r] = g2
    # bilinear parts, one-sided into M (symmetrised below):
    # k d J^T(d2 kappa)J -> c (d2 N - kappa d2 D), k d J^T(d2 psi)J -> ct 2 (X d2 Y - Y d2 X)/r2
    for r in range(8):
        for s in range(8):
            M[r, s] = 0.0
    cy = ct * 2.0 * X / r2
    cx = -ct * 2.0 * Y / r2
    _dot_hess(Jz, 0, 3, cx - c1 * kap1 - c2 * kap2, M)
    _dot_hess(Jz, 1, 4, cx, M)
    _dot_hess(Jz, 2, 5, cx, M)
    # N1 + N2 = U . (t_a x t_b), U = c1 (m2_a + m2_b) - c2 (m1_a + m1_b) (coefficients in)
    for k in range(3):
        U[k] = c1 * (z[6 + k] + z[15 + k]) - c2 * (z[3 + k] + z[12 + k])
    _cross_hess(Jz, 0, 3, U, 0, 1.0, M, W)  # (t_a, t_b) with u
    # u's Jacobian on each edge, blocks 6 (edge a) and 7 (edge b) of Jz
    for k in range(3):
        for r in range(4):
            Jz[18 + k, r] = c1 * Jz[6 + k, r] - c2 * Jz[3 + k, r]
            Jz[21 + k, r] = c1 * Jz[15 + k, r] - c2 * Jz[12 + k, r]
    for P in (6, 7):
        _cross_hess(Jz, P, 0, z, 9, 1.0, M, W)  # u . (t_a x t_b): (u, t_a) with t_b
        _cross_hess(Jz, 3, P, z, 0, 1.0, M, W)  # (t_b, u) with t_a
    # Y: t_a . (m_a x m_b) for m = m1, m2
    for A in (1, 2):
        B = A + 3
        _cross_hess(Jz, 0, A, z, 3 * B, cy, M, W)
        _cross_hess(Jz, A, B, z, 0, cy, M, W)
        _cross_hess(Jz, B, 0, z, 3 * A, cy, M, W)
    # outer products in p, the frames' own curvature, symmetrisation
    c4 = ct * 2.0 / (r2 * r2)
    sym = c4 * (Y * Y - X * X)
    crs = c4 * 2.0 * X * Y
    for r in range(8):
        # reuse gz's first two rows for d psi/dp and c1 d kappa1/dp + c2 d kappa2/dp
        gz[0, r] = 2.0 * (X * gp[4, r] - Y * gp[3, r]) / r2
        gz[1, r] = c1 * gp[1, r] + c2 * gp[2, r]
    for r in range(8):
        a_r = gp[3, r]
        b_r = gp[4, r]
        g1_r = k1 * gp[1, r]
        g2_r = k2 * gp[2, r]
        gt_r = kt * gz[0, r]
        w_r = gz[1, r]
        dD_r = gp[0, r]
        for s in range(r, 8):
            a_s = gp[3, s]
            b_s = gp[4, s]
            h = (M[r, s] + M[s, r] + g1_r * gp[1, s] + g2_r * gp[2, s] + gt_r * gz[0, s]
                 - w_r * gp[0, s] - dD_r * gz[1, s]
                 + sym * (a_r * b_s + b_r * a_s) + crs * (a_r * a_s - b_r * b_s))
            h8[r, s] = h
    # the frames' own curvature sum_c (dE/dz_c) d2 z_c / dp2 (z_c = sign val_c)
    for c in range(9):
        ga = G[c] * (sign_a if (c < 3 or c >= 6) else 1.0)
        gb = G[9 + c] * (sign_b if (c < 3 or c >= 6) else 1.0)
        for r in range(4):
            for s in range(r, 4):
                h8[r, s] += ga * hess_a[c, r, s]
                h8[4 + r, 4 + s] += gb * hess_b[c, r, s]
    for r in range(8):
        for s in range(r + 1, 8):
            h8[s, r] = h8[r, s]
    return energy


@njit(cache=True)
def tip_moment_terms(e, moment, axis, grad, hess):
    """Potential (J) of a dead couple ``moment`` (N m) about the unit ``axis`` on an edge
    ``e`` (3,) m that turns in the plane normal to the axis: V = -M phi, phi = the edge's
    angle about the axis (atan2 in that plane, so valid for |phi| < pi from the plane's
    first basis vector). Writes grad (3,) (N) and hess (3, 3) (N/m) w.r.t. e."""
    # orthonormal basis (u, v) of the plane normal to the axis, v = axis x u
    if abs(axis[0]) < 0.9:
        u = np.array([1.0 - axis[0] * axis[0], -axis[1] * axis[0], -axis[2] * axis[0]])
    else:
        u = np.array([-axis[0] * axis[1], 1.0 - axis[1] * axis[1], -axis[2] * axis[1]])
    u /= np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    v = np.array([axis[1] * u[2] - axis[2] * u[1], axis[2] * u[0] - axis[0] * u[2],
                  axis[0] * u[1] - axis[1] * u[0]])
    p = e[0] * u[0] + e[1] * u[1] + e[2] * u[2]
    r = e[0] * v[0] + e[1] * v[1] + e[2] * v[2]
    rho2 = p * p + r * r
    phi = np.arctan2(r, p)
    # d phi / de = (p v - r u) / rho2
    for i in range(3):
        gi = p * v[i] - r * u[i]
        grad[i] = -moment * gi / rho2
        for j in range(3):
            dgi = u[j] * v[i] - v[j] * u[i]
            drho2 = 2.0 * (p * u[j] + r * v[j])
            hess[i, j] = -moment * (dgi / rho2 - gi * drho2 / (rho2 * rho2))
    return -moment * phi
