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
formed straight in the edge coordinates through the frames' angular velocities (no 18 x 18
matrix, no allocation; tested equal to the reference kernels to round-off and against
finite differences).
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


@njit(cache=True, inline="always")
def _curvature_inputs(z, which, y):
    """The 9 numbers kappa1 (``which`` = 1) or kappa2 (2) of the frame pair ``z`` depends
    on, into ``y``: t_a, t_b and the signed sum of a director of each frame. Returns (ua,
    ub, sign): where in z the two directors start, and the sum's sign."""
    ua = _CURV_U[which - 1, 0]
    ub = _CURV_U[which - 1, 1]
    sgn = 1.0 if which == 1 else -1.0
    for k in range(3):
        y[k] = z[k]
        y[3 + k] = z[9 + k]
        y[6 + k] = sgn * (z[ua + k] + z[ub + k])
    return ua, ub, sgn


@njit(cache=True)
def material_curvature(z, which, grad, hess):
    """kappa1 (``which`` = 1) or kappa2 (2) of the frame pair ``z`` (18,); writes its gradient
    (18,) and Hessian (18, 18) w.r.t. z."""
    y = np.empty(9)
    g9 = np.empty(9)
    h9 = np.empty((9, 9))
    zi = np.empty(9, dtype=np.int64)  # z index of each y component (u: the first director)
    ua, ub, sgn = _curvature_inputs(z, which, y)
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
        ua, ub, sgn = _curvature_inputs(z, which, y)
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
# The pair energy straight in edge coordinates p = (e_a, theta_a, e_b, theta_b). Every
# derivative of a frame is a rotation, dz_A/dp_r = omega_r x z_A for the three vectors z_A
# of the edge's frame, with omega_r = t x dt/dp_r + (dm1/dp_r . m2) t read off its jet
# (Omega: 3 x 4 per edge). So J^T (d2E/dz2) J = Omega^T Psi Omega, with Psi's three 3 x 3
# blocks (aa, ab, bb) summed from the terms of E (every one a dot or triple product of the
# six frame vectors, or an outer product of two gradients):
#   - c x.y, x in frame a, y in frame b:  Psi_ab += c ((x.y) I - y x^T);
#   - u.(x cross y), the slots x, y:  Psi_xy += (x cross y) u^T - (u.y) [x]_cross (Psi_yx its
#     transpose; the skew part cancels on a diagonal block);
#   - grad f grad g^T:  Psi_aa = Psi_bb += tau_f tau_g^T, Psi_ab -= tau_f tau_g^T, with the
#     torque tau_f = sum_A z_A x df/dz_A over frame a (frame b's is -tau_f: f is invariant
#     under a common rotation of both frames).
# Every block costs a few 3-vector products instead of a 4 x 4 product per pair of frame
# vectors. Terms proportional to t . m (zero: the frames are orthonormal) are left out.
# The frames' own curvature sum_c (dE/dz_c) d2z_c/dp2 is added from the jets' Hessians.
#
# The scratch is one flat array of 4-wide rows addressed by constant offsets (no strides to
# multiply, no per-call allocation or reference counting): the signed frame vectors, the
# frames' Omega, dE/dz, the Psi blocks, Psi Omega, then 3-vectors of the kernel.
_TA, _M1A, _M2A, _TB, _M1B, _M2B = 0, 1, 2, 3, 4, 5
_OMA, _OMB = 6, 9               # 3 rows of 4 each
_GZ = 12                        # 6 rows: dE/dz per frame vector (unsigned frames)
_PAA, _PAB, _PBB, _PO = 18, 21, 24, 27
_W, _V, _U1, _U2, _UA, _UB, _U, _S = 30, 31, 32, 33, 34, 35, 36, 37
_TBUA, _TBUB, _UATA, _UBTA, _M1BTA, _M2BTA, _TAM1A, _TAM2A = 38, 39, 40, 41, 42, 43, 44, 45
_TN1, _TN2, _TY = 46, 47, 48
_O1A, _O1B, _O2A, _O2B, _O3A, _O3B, _SK, _XT = 49, 50, 51, 52, 53, 54, 55, 56
_PAIR_ROWS = 57
# the cross products `pair_terms_edges` forms, (i, j, k): row k = row i x row j; of the
# frame vectors (w = t_a x t_b, and V = m1_a x m1_b + m2_a x m2_b with S), and of the
# gradient's vectors with the frames
_FRAME_CROSSES = ((_TA, _TB, _W), (_M1A, _M1B, _V), (_M2A, _M2B, _S))
_GRADIENT_CROSSES = ((_TB, _UA, _TBUA), (_TB, _UB, _TBUB), (_UA, _TA, _UATA),
                     (_UB, _TA, _UBTA), (_M1B, _TA, _M1BTA), (_M2B, _TA, _M2BTA),
                     (_TA, _M1A, _TAM1A), (_TA, _M2A, _TAM2A))


@njit(cache=True)
def pair_edge_scratch():
    """Scratch of `pair_terms_edges` (allocate once, reuse for every pair)."""
    return np.empty(4 * _PAIR_ROWS)


@njit(cache=True, inline="always")
def _vcross(W, i, j, k):
    """Row k of W = row i x row j (3-vectors of the flat scratch)."""
    a = 4 * i
    b = 4 * j
    c = 4 * k
    W[c] = W[a + 1] * W[b + 2] - W[a + 2] * W[b + 1]
    W[c + 1] = W[a + 2] * W[b] - W[a] * W[b + 2]
    W[c + 2] = W[a] * W[b + 1] - W[a + 1] * W[b]


@njit(cache=True, inline="always")
def _vcrosses(W, table):
    """`_vcross` for every (i, j, k) of ``table``, in order."""
    for i, j, k in table:
        _vcross(W, i, j, k)


@njit(cache=True, inline="always")
def _vdot(W, i, j):
    """Row i . row j of the flat scratch."""
    a = 4 * i
    b = 4 * j
    return W[a] * W[b] + W[a + 1] * W[b + 1] + W[a + 2] * W[b + 2]


@njit(cache=True, inline="always")
def _omega(val, jac, W, row):
    """Rows row..row+2 of W: the frame's angular velocity per p_r (1/m, 1/rad),
    omega_r = t x dt/dp_r + (dm1/dp_r . m2) t (zero for a clamp frame's zero jet)."""
    o = 4 * row
    for r in range(4):
        d0 = jac[0, r]
        d1 = jac[1, r]
        d2 = jac[2, r]
        mu = jac[3, r] * val[6] + jac[4, r] * val[7] + jac[5, r] * val[8]
        W[o + r] = val[1] * d2 - val[2] * d1 + mu * val[0]
        W[o + 4 + r] = val[2] * d0 - val[0] * d2 + mu * val[1]
        W[o + 8 + r] = val[0] * d1 - val[1] * d0 + mu * val[2]


@njit(cache=True, inline="always")
def _psi_block(W, oa, pr, ob, h8, ra, rb, full):
    """h8[ra:ra+4, rb:rb+4] = Omega_a^T Psi Omega_b (Omega_a, Psi, Omega_b: rows oa, pr, ob
    of W); only the upper triangle unless ``full``."""
    for k in range(3):
        for s in range(4):
            W[4 * (_PO + k) + s] = (W[4 * (pr + k)] * W[4 * ob + s]
                                    + W[4 * (pr + k) + 1] * W[4 * (ob + 1) + s]
                                    + W[4 * (pr + k) + 2] * W[4 * (ob + 2) + s])
    for r in range(4):
        for s in range(4):
            if full or s >= r:
                h8[ra + r, rb + s] = (W[4 * oa + r] * W[4 * _PO + s]
                                      + W[4 * (oa + 1) + r] * W[4 * (_PO + 1) + s]
                                      + W[4 * (oa + 2) + r] * W[4 * (_PO + 2) + s])


@njit(cache=True, inline="always")
def _own_curvature(W, g, hess, h8, o):
    """h8[o:o+4, o:o+4] (upper triangle) += sum_c (dE/dz_c) d2z_c/dp2 of one frame (dE/dz of
    its unsigned vectors in rows g..g+2 of W)."""
    a00 = 0.0
    a01 = 0.0
    a02 = 0.0
    a03 = 0.0
    a11 = 0.0
    a12 = 0.0
    a13 = 0.0
    a22 = 0.0
    a23 = 0.0
    a33 = 0.0
    for c in range(9):
        gc = W[4 * (g + c // 3) + c % 3]
        a00 += gc * hess[c, 0, 0]
        a01 += gc * hess[c, 0, 1]
        a02 += gc * hess[c, 0, 2]
        a03 += gc * hess[c, 0, 3]
        a11 += gc * hess[c, 1, 1]
        a12 += gc * hess[c, 1, 2]
        a13 += gc * hess[c, 1, 3]
        a22 += gc * hess[c, 2, 2]
        a23 += gc * hess[c, 2, 3]
        a33 += gc * hess[c, 3, 3]
    h8[o, o] += a00
    h8[o, o + 1] += a01
    h8[o, o + 2] += a02
    h8[o, o + 3] += a03
    h8[o + 1, o + 1] += a11
    h8[o + 1, o + 2] += a12
    h8[o + 1, o + 3] += a13
    h8[o + 2, o + 2] += a22
    h8[o + 2, o + 3] += a23
    h8[o + 3, o + 3] += a33



@njit(cache=True)
def pair_terms_edges(val_a, jac_a, hess_a, sign_a, val_b, jac_b, hess_b, sign_b,
                     k1, k2, kt, kappa1_bar, kappa2_bar, psi_bar, g8, h8, ws):
    """Bending plus twisting energy (J) of a pair of edges with its gradient ``g8`` (8,) and
    Hessian ``h8`` (8, 8) w.r.t. p = (e_a, theta_a, e_b, theta_b), from the two frames'
    jets (`material_frame_jet`; sign -1: the edge enters against its direction). The same
    energy as `bending_terms` + `twist_terms` carried by `chain_pair`, without any 18 x 18
    matrix and without allocation (``ws``: `pair_edge_scratch`)."""
    W = ws
    # signed frame vectors z = [t_a, m1_a, m2_a, t_b, m1_b, m2_b]; a reversed edge enters as
    # (-t, m1, -m2), which rotates with the same omega
    for k in range(3):
        W[4 * _TA + k] = sign_a * val_a[k]
        W[4 * _M1A + k] = val_a[3 + k]
        W[4 * _M2A + k] = sign_a * val_a[6 + k]
        W[4 * _TB + k] = sign_b * val_b[k]
        W[4 * _M1B + k] = val_b[3 + k]
        W[4 * _M2B + k] = sign_b * val_b[6 + k]
    _omega(val_a, jac_a, W, _OMA)
    _omega(val_b, jac_b, W, _OMB)
    # D = 1 + t_a.t_b, N1 = u1.w, N2 = -u2.w (w = t_a x t_b, u1 = m2_a + m2_b,
    # u2 = m1_a + m1_b), X = 1 + tr Q, Y = t_a.V (V = m1_a x m1_b + m2_a x m2_b)
    _vcrosses(W, _FRAME_CROSSES)
    for k in range(3):
        W[4 * _V + k] += W[4 * _S + k]
        W[4 * _U1 + k] = W[4 * _M2A + k] + W[4 * _M2B + k]
        W[4 * _U2 + k] = W[4 * _M1A + k] + W[4 * _M1B + k]
    tab = _vdot(W, _TA, _TB)
    D = 1.0 + tab
    X = D + _vdot(W, _M1A, _M1B) + _vdot(W, _M2A, _M2B)
    N1 = _vdot(W, _U1, _W)
    N2 = -_vdot(W, _U2, _W)
    Y = _vdot(W, _TA, _V)
    # kappa1 = N1 / D, kappa2 = N2 / D, psi = 2 atan2(Y, X)
    kap1 = N1 / D
    kap2 = N2 / D
    d1 = kap1 - kappa1_bar
    d2 = kap2 - kappa2_bar
    r2 = X * X + Y * Y
    psi = 2.0 * np.arctan2(Y, X)
    dt = psi - psi_bar
    energy = 0.5 * (k1 * d1 * d1 + k2 * d2 * d2 + kt * dt * dt)
    # dE = c1 (dN1 - kappa1 dD) + c2 (dN2 - kappa2 dD) + cy dY + cx dX
    c1 = k1 * d1 / D
    c2 = k2 * d2 / D
    ctw = kt * dt
    cx = -2.0 * ctw * Y / r2
    cy = 2.0 * ctw * X / r2
    cD = cx - c1 * kap1 - c2 * kap2  # of t_a.t_b, in D and in X
    # c1 N1 + c2 N2 = U.w, U = Ua + Ub = c1 u1 - c2 u2 (linear in the directors)
    for k in range(3):
        W[4 * _UA + k] = c1 * W[4 * _M2A + k] - c2 * W[4 * _M1A + k]
        W[4 * _UB + k] = c1 * W[4 * _M2B + k] - c2 * W[4 * _M1B + k]
        W[4 * _U + k] = W[4 * _UA + k] + W[4 * _UB + k]
    _vcrosses(W, _GRADIENT_CROSSES)
    # dE/dz, carried to the unsigned frames (t and m2 of a reversed edge flip)
    for k in range(3):
        w = W[4 * _W + k]
        W[4 * _GZ + k] = sign_a * (cD * W[4 * _TB + k] + W[4 * _TBUA + k] + W[4 * _TBUB + k]
                                   + cy * W[4 * _V + k])
        W[4 * _GZ + 4 + k] = cx * W[4 * _M1B + k] - c2 * w + cy * W[4 * _M1BTA + k]
        W[4 * _GZ + 8 + k] = sign_a * (cx * W[4 * _M2B + k] + c1 * w + cy * W[4 * _M2BTA + k])
        W[4 * _GZ + 12 + k] = sign_b * (cD * W[4 * _TA + k] + W[4 * _UATA + k]
                                        + W[4 * _UBTA + k])
        W[4 * _GZ + 16 + k] = cx * W[4 * _M1A + k] - c2 * w + cy * W[4 * _TAM1A + k]
        W[4 * _GZ + 20 + k] = sign_b * (cx * W[4 * _M2A + k] + c1 * w + cy * W[4 * _TAM2A + k])
    # dE/dp = J^T dE/dz
    for r in range(4):
        acc_a = 0.0
        acc_b = 0.0
        for A in range(3):
            for k in range(3):
                acc_a += W[4 * (_GZ + A) + k] * jac_a[3 * A + k, r]
                acc_b += W[4 * (_GZ + 3 + A) + k] * jac_b[3 * A + k, r]
        g8[r] = acc_a
        g8[4 + r] = acc_b
    # torques on frame a of N1 = t_a x (t_b x u1) + m2_a x w, N2 = -(t_a x (t_b x u2)
    # + m1_a x w), Y = t_a x V + m1_a x (m1_b x t_a) + m2_a x (m2_b x t_a); D: w; X: w + V
    _vcross(W, _TB, _U1, _S)
    _vcross(W, _TA, _S, _TN1)
    _vcross(W, _M2A, _W, _S)
    for k in range(3):
        W[4 * _TN1 + k] += W[4 * _S + k]
    _vcross(W, _TB, _U2, _S)
    _vcross(W, _TA, _S, _TN2)
    _vcross(W, _M1A, _W, _S)
    for k in range(3):
        W[4 * _TN2 + k] = -(W[4 * _TN2 + k] + W[4 * _S + k])
    _vcross(W, _TA, _V, _TY)
    _vcross(W, _M1A, _M1BTA, _S)
    for k in range(3):
        W[4 * _TY + k] += W[4 * _S + k]
    _vcross(W, _M2A, _M2BTA, _S)
    for k in range(3):
        W[4 * _TY + k] += W[4 * _S + k]
    # The outer products, as sum_m (a_m b_m^T + b_m a_m^T) in torques:
    # k1 g1 g1^T - c1 (g1 gD^T + gD g1^T) (g1 = grad kappa1), the same for kappa2, and
    # 4 kt beta beta^T - 2 kt (psi - psi_bar) (alpha beta^T + beta alpha^T) from the Hessian
    # of psi, 2 (X HY - Y HX) / r2 - 2 (alpha beta^T + beta alpha^T), with
    # beta = (X gY - Y gX) / r2 = grad psi / 2, alpha = (X gX + Y gY) / r2.
    iD = 1.0 / D
    ir2 = 1.0 / r2
    s_u = -_vdot(W, _U, _TB)
    s_1 = -cy * _vdot(W, _TA, _M1B)
    s_2 = -cy * _vdot(W, _TA, _M2B)
    for k in range(3):
        w = W[4 * _W + k]
        g1 = (W[4 * _TN1 + k] - kap1 * w) * iD
        g2 = (W[4 * _TN2 + k] - kap2 * w) * iD
        gX = w + W[4 * _V + k]
        gY = W[4 * _TY + k]
        beta = (X * gY - Y * gX) * ir2
        alpha = (X * gX + Y * gY) * ir2
        W[4 * _O1A + k] = g1
        W[4 * _O1B + k] = 0.5 * k1 * g1 - c1 * w
        W[4 * _O2A + k] = g2
        W[4 * _O2B + k] = 0.5 * k2 * g2 - c2 * w
        W[4 * _O3A + k] = beta
        W[4 * _O3B + k] = 2.0 * kt * beta - 2.0 * ctw * alpha
        W[4 * _SK + k] = (s_u * W[4 * _TA + k] + tab * W[4 * _UB + k] + s_1 * W[4 * _M1A + k]
                          + s_2 * W[4 * _M2A + k])
        W[4 * _XT + k] = cy * W[4 * _V + k] - cD * W[4 * _TB + k]
    # Psi blocks, sym(M) = M + M^T, [v] = the cross-product matrix of v:
    # - dot products cD t_a.t_b + cx (m1_a.m1_b + m2_a.m2_b): Psi_ab += tr(S) I - S,
    #   S = cD t_b t_a^T + cx (m1_b m1_a^T + m2_b m2_a^T);
    # - U.(t_a x t_b): Psi_ab += w U^T - (U.t_b) [t_a] + t_a (t_b x Ua)^T + t_b (Ub x t_a)^T
    #   + (t_a.t_b) [Ub], Psi_aa += sym((Ua x t_a) t_b^T), Psi_bb += sym((t_b x Ub) t_a^T);
    # - cy t_a.(m_a x m_b), m = m1, m2: Psi_ab += cy (V t_a^T - (t_a.m_b) [m_a]
    #   + m_a (m_b x t_a)^T), Psi_aa += cy sym((t_a x m_a) m_b^T);
    # the skew parts are gathered in [SK], the terms x t_a^T in XT t_a^T
    trS = cD * tab + cx * (X - D)
    for k in range(3):
        for l in range(3):
            o = (W[4 * _O1A + k] * W[4 * _O1B + l] + W[4 * _O1B + k] * W[4 * _O1A + l]
                 + W[4 * _O2A + k] * W[4 * _O2B + l] + W[4 * _O2B + k] * W[4 * _O2A + l]
                 + W[4 * _O3A + k] * W[4 * _O3B + l] + W[4 * _O3B + k] * W[4 * _O3A + l])
            W[4 * (_PAB + k) + l] = (
                W[4 * _W + k] * W[4 * _U + l] + W[4 * _TA + k] * W[4 * _TBUA + l]
                + W[4 * _TB + k] * W[4 * _UBTA + l] + W[4 * _XT + k] * W[4 * _TA + l]
                + cy * (W[4 * _M1A + k] * W[4 * _M1BTA + l] + W[4 * _M2A + k] * W[4 * _M2BTA + l])
                - cx * (W[4 * _M1B + k] * W[4 * _M1A + l] + W[4 * _M2B + k] * W[4 * _M2A + l])
                - o)
            if l >= k:
                paa = (o + W[4 * _UATA + k] * W[4 * _TB + l] + W[4 * _TB + k] * W[4 * _UATA + l]
                       + cy * (W[4 * _TAM1A + k] * W[4 * _M1B + l]
                               + W[4 * _M1B + k] * W[4 * _TAM1A + l]
                               + W[4 * _TAM2A + k] * W[4 * _M2B + l]
                               + W[4 * _M2B + k] * W[4 * _TAM2A + l]))
                pbb = o + W[4 * _TBUB + k] * W[4 * _TA + l] + W[4 * _TA + k] * W[4 * _TBUB + l]
                W[4 * (_PAA + k) + l] = paa
                W[4 * (_PAA + l) + k] = paa
                W[4 * (_PBB + k) + l] = pbb
                W[4 * (_PBB + l) + k] = pbb
    for k in range(3):
        W[4 * (_PAB + k) + k] += trS
    W[4 * _PAB + 1] -= W[4 * _SK + 2]
    W[4 * _PAB + 2] += W[4 * _SK + 1]
    W[4 * (_PAB + 1)] += W[4 * _SK + 2]
    W[4 * (_PAB + 1) + 2] -= W[4 * _SK]
    W[4 * (_PAB + 2)] -= W[4 * _SK + 1]
    W[4 * (_PAB + 2) + 1] += W[4 * _SK]
    # Omega^T Psi Omega, block by block (upper triangle of the diagonal blocks)
    _psi_block(W, _OMA, _PAA, _OMA, h8, 0, 0, False)
    _psi_block(W, _OMA, _PAB, _OMB, h8, 0, 4, True)
    _psi_block(W, _OMB, _PBB, _OMB, h8, 4, 4, False)
    # the frames' own curvature
    _own_curvature(W, _GZ, hess_a, h8, 0)
    _own_curvature(W, _GZ + 3, hess_b, h8, 4)
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
