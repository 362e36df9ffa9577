"""Energy kernels of planar discrete elastic rods (paper, Appendix A).

Each kernel takes the local node coordinates of one element and its parameters, writes the
local gradient and Hessian into preallocated arrays and returns the element energy (J).
Local coordinates are ordered ``[x0, z0, x1, z1, ...]`` in metres.

- stretching, per edge:  ``E_s = 1/2 EA eps^2 |e_bar|``, ``eps = |e|/|e_bar| - 1``
- bending, per interior node: ``E_b = 1/2 (EI / l_bar) (kappa - kappa_bar)^2`` with the
  integrated curvature ``kappa = 2 tan(phi / 2) = 2 (e0 x e1) / (|e0||e1| + e0 . e1)``
  (phi = signed turning angle, l_bar = reference Voronoi length)
- tie spring, per node pair: ``E_k = 1/2 k |(x_a - x_b) - (X_a - X_b)|^2`` (zero-length
  spring on the relative displacement; the paper's "stiff springs")
- dead load, per loaded coordinate (any dimension): ``E_f = -f (x - X)`` (the potential of
  a constant force f on a coordinate x whose stress-free value is X; no stiffness)
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _stretch_jet(x, EA, rest_length):
    """(E (J), d(E)/d(xb) = (gx, gz) (N), the 2x2 block (hxx, hxz, hzz) (N/m)) of one edge;
    d(E)/d(xa) = -(gx, gz) and d2(E)/dx2 = [[H, -H], [-H, H]]."""
    return stretch_jet(x[0], x[1], x[2], x[3], EA, rest_length)


@njit(cache=True, inline="always")
def stretch_jet(xa, za, xb, zb, EA, rest_length):
    """`_stretch_jet` of the edge from (xa, za) to (xb, zb) (m), from scalars: what the
    assembler calls, with no array between the state and the element."""
    ex = xb - xa
    ez = zb - za
    length = np.sqrt(ex * ex + ez * ez)
    k = EA / rest_length
    stretch = length - rest_length
    energy = 0.5 * k * stretch * stretch
    tx = ex / length
    tz = ez / length
    # d2E/de2 = k [t t^T + (1 - rest/length)(I - t t^T)]
    c = k * stretch / length
    hxx = k * tx * tx + c * (1.0 - tx * tx)
    hzz = k * tz * tz + c * (1.0 - tz * tz)
    hxz = k * tx * tz - c * tx * tz
    return energy, k * stretch * tx, k * stretch * tz, hxx, hxz, hzz


@njit(cache=True, inline="always")
def stretch_force(q, nodes, EA, rest_length):
    """dE/dx_b = (gx, gz) (N) of the edge between ``nodes`` (a, b) in the flat state ``q``
    (`stretch_terms` without its Hessian: dE/dx_a = -(gx, gz), the same bits)."""
    a, b = 2 * nodes[0], 2 * nodes[1]
    ex = q[b] - q[a]
    ez = q[b + 1] - q[a + 1]
    length = np.sqrt(ex * ex + ez * ez)
    k = EA / rest_length
    stretch = length - rest_length
    return k * stretch * (ex / length), k * stretch * (ez / length)


@njit(cache=True)
def stretch_terms(x, EA, rest_length, grad, hess):
    """Stretching energy of one edge; ``x`` = [xa, za, xb, zb] (m), EA (N), rest length (m).

    Writes d(E)/dx into ``grad`` (4,) and d2(E)/dx2 into ``hess`` (4, 4); returns E (J).
    """
    energy, gx, gz, hxx, hxz, hzz = _stretch_jet(x, EA, rest_length)
    grad[0] = -gx
    grad[1] = -gz
    grad[2] = gx
    grad[3] = gz
    for a in range(2):
        for b in range(2):
            sign = 1.0 if a == b else -1.0
            hess[2 * a, 2 * b] = sign * hxx
            hess[2 * a + 1, 2 * b + 1] = sign * hzz
            hess[2 * a, 2 * b + 1] = sign * hxz
            hess[2 * a + 1, 2 * b] = sign * hxz
    return energy


@njit(cache=True, inline="always")
def _turning_jet(x):
    """kappa at the middle node of ``x`` (6,) and what its derivatives are made of.

    kappa = 2 tan(phi/2) depends on the node coordinates through the turning angle
    phi = theta1 - theta0 only (theta_i = direction of edge i), so
    d(kappa) = k1 d(phi), d2(kappa) = k2 d(phi) d(phi)^T + k1 d2(phi) with
    k1 = 1 + kappa^2/4, k2 = kappa k1 / 2. d(theta)/de = (-ez, ex)/|e|^2 for an edge e and
    d2(theta)/de2 = [[2 ex ez, ez^2 - ex^2], [., -2 ex ez]]/|e|^4: no cross-edge terms. Returns
    (kappa, k1, k2, P (6 node components of d(phi)), u0, v0, u1, v1) with
    d2(phi)/de_i^2 = [[u_i, v_i], [v_i, -u_i]] (1/m^2 and 1/m)."""
    return turning_jet(x[0], x[1], x[2], x[3], x[4], x[5])


@njit(cache=True, inline="always")
def turning_jet(x0, z0, x1, z1, x2, z2):
    """`_turning_jet` of the nodes (x0, z0), (x1, z1), (x2, z2) (m), from scalars: what the
    assembler calls, with no array between the state and the element."""
    a0 = x1 - x0
    b0 = z1 - z0
    a1 = x2 - x1
    b1 = z2 - z1
    return turning_jet_edges(a0, b0, edge_turn(a0, b0), a1, b1, edge_turn(a1, b1))


@njit(cache=True, inline="always")
def edge_turn(a, b):
    """What the turning angle's derivatives take from one edge e = (a, b): (|e|^2, |e|,
    p_x, p_z, u, v) with d(theta)/de = (p_x, p_z) = (-b, a)/|e|^2 and
    d2(theta)/de2 = [[u, v], [v, -u]] = [[-2 p_x p_z, p_x^2 - p_z^2], .]. Two bending
    stencils share an edge; the assembler computes this once for both (`turning_jet_edges`:
    the first edge takes it negated, exactly)."""
    s = a * a + b * b
    px = -b / s
    pz = a / s
    return s, np.sqrt(s), px, pz, -2.0 * px * pz, px * px - pz * pz


@njit(cache=True, inline="always")
def turning_jet_edges(a0, b0, t0, a1, b1, t1):
    """`_turning_jet` from the edges e0 = (a0, b0) = x1 - x0, e1 = (a1, b1) = x2 - x1 and
    their `edge_turn` ``t0``, ``t1``."""
    s0, r0, q0x, q0z, w0, y0 = t0
    s1, r1, p1x, p1z, u1, v1 = t1
    kappa = edge_turning(a0, b0, r0, a1, b1, r1)
    k1 = 1.0 + 0.25 * kappa * kappa
    k2 = 0.5 * kappa * k1
    # d(phi)/de0 = -d(theta0)/de0 = (b0, -a0)/|e0|^2, d(phi)/de1 = d(theta1)/de1; so
    # d2(phi)/de0^2 = [[2 p0x p0z, p0z^2 - p0x^2], .] = -d2(theta0)/de0^2 (the negations
    # are exact: these are the bits of the formulas written for e0)
    p0x = -q0x
    p0z = -q0z
    u0 = -w0
    v0 = -y0
    # nodes: e0 = x1 - x0, e1 = x2 - x1
    return (kappa, k1, k2, -p0x, -p0z, p0x - p1x, p0z - p1z, p1x, p1z, u0, v0, u1, v1)


@njit(cache=True, inline="always")
def _turning_lower(jet, alpha, beta, grad, hl):
    """grad = alpha d(phi) (6,) and the lower triangle of beta d(phi) d(phi)^T + alpha d2(phi)
    packed by rows into ``hl`` (21,) (row r, column c <= r at r (r + 1) / 2 + c)."""
    P = jet[3:9]
    for i in range(6):
        grad[i] = alpha * P[i]
    h = turning_lower(jet, alpha, beta)
    for k in range(21):
        hl[k] = h[k]


@njit(cache=True, inline="always")
def turning_lower(jet, alpha, beta):
    """The lower triangle of beta d(phi) d(phi)^T + alpha d2(phi) packed by rows (a tuple of
    21: row r, column c <= r at r (r + 1) / 2 + c), from the `_turning_jet` ``jet``.

    d2(phi) in the nodes from the edge blocks T_i = d2(phi)/de_i^2: [[T0, -T0, 0],
    [-T0, T0 + T1, -T1], [0, -T1, T1]]."""
    _, _, _, P0, P1, P2, P3, P4, P5, u0, v0, u1, v1 = jet
    a0 = alpha * u0
    b0 = alpha * v0
    a1 = alpha * u1
    b1 = alpha * v1
    q0 = beta * P0
    q1 = beta * P1
    q2 = beta * P2
    q3 = beta * P3
    q4 = beta * P4
    q5 = beta * P5
    return (q0 * P0 + a0,
            q1 * P0 + b0,
            q1 * P1 - a0,
            q2 * P0 - a0,
            q2 * P1 - b0,
            q2 * P2 + (a0 + a1),
            q3 * P0 - b0,
            q3 * P1 + a0,
            q3 * P2 + (b0 + b1),
            q3 * P3 - (a0 + a1),
            q4 * P0,
            q4 * P1,
            q4 * P2 - a1,
            q4 * P3 - b1,
            q4 * P4 + a1,
            q5 * P0,
            q5 * P1,
            q5 * P2 - b1,
            q5 * P3 + a1,
            q5 * P4 + b1,
            q5 * P5 - a1)


@njit(cache=True, inline="always")
def _unpack_lower(hl, n, h):
    """The symmetric (n, n) ``h`` from its lower triangle packed by rows in ``hl``."""
    k = 0
    for r in range(n):
        for c in range(r + 1):
            h[r, c] = hl[k]
            h[c, r] = hl[k]
            k += 1


@njit(cache=True)
def curvature_terms(x, dkappa, d2kappa):
    """Integrated curvature at the middle node of ``x`` = [x0, z0, x1, z1, x2, z2].

    kappa = 2 tan(phi/2) = 2 f / g with f = e0 x e1 and g = |e0||e1| + e0 . e1
    (dimensionless, positive for a counter-clockwise turn).
    Writes d(kappa)/dx (6,) and d2(kappa)/dx2 (6, 6); returns kappa.
    """
    jet = _turning_jet(x)
    hl = np.empty(21)
    _turning_lower(jet, jet[1], jet[2], dkappa, hl)
    _unpack_lower(hl, 6, d2kappa)
    return jet[0]


@njit(cache=True, inline="always")
def bending_lower(x, stiffness, kappa_bar, grad, hl):
    """`bending_terms` with the Hessian's lower triangle packed by rows into ``hl`` (21,)
    (row r, column c <= r at r (r + 1) / 2 + c): what the assembler scatters. Returns E (J)."""
    jet = _turning_jet(x)
    energy, alpha, beta = bending_scales(jet, stiffness, kappa_bar)
    _turning_lower(jet, alpha, beta, grad, hl)
    return energy


@njit(cache=True, inline="always")
def bending_scales(jet, stiffness, kappa_bar):
    """(E (J), dE/dphi, d2E/dphi2) of the bending energy at the `_turning_jet` ``jet``:
    E = S/2 (kappa - kappa_bar)^2, dE/dphi = c k1, d2E/dphi2 = S k1^2 + c k2 (c = S dev)."""
    kappa, k1, k2 = jet[0], jet[1], jet[2]
    dev = kappa - kappa_bar
    c = stiffness * dev
    return 0.5 * stiffness * dev * dev, c * k1, stiffness * k1 * k1 + c * k2


@njit(cache=True)
def bending_terms(x, stiffness, kappa_bar, grad, hess):
    """Bending energy at the middle node of ``x`` (6,); stiffness = EI / l_bar (N m).

    Writes the gradient (6,) and Hessian (6, 6); returns E (J).
    """
    hl = np.empty(21)
    energy = bending_lower(x, stiffness, kappa_bar, grad, hl)
    _unpack_lower(hl, 6, hess)
    return energy


@njit(cache=True)
def spring_terms(x, stiffness, rest_offset_x, rest_offset_z, grad, hess):
    """Zero-length tie spring between two nodes, ``x`` = [xa, za, xb, zb] (m), k (N/m).

    The spring resists the change of the offset x_a - x_b from its reference value, so
    nodes a few micrometres apart (as in the paper) carry no initial force.
    """
    dx = x[0] - x[2] - rest_offset_x
    dz = x[1] - x[3] - rest_offset_z
    grad[0] = stiffness * dx
    grad[1] = stiffness * dz
    grad[2] = -stiffness * dx
    grad[3] = -stiffness * dz
    for i in range(4):
        for j in range(4):
            hess[i, j] = 0.0
    for c in range(2):
        hess[c, c] = stiffness
        hess[c + 2, c + 2] = stiffness
        hess[c, c + 2] = -stiffness
        hess[c + 2, c] = -stiffness
    return 0.5 * stiffness * (dx * dx + dz * dz)


@njit(cache=True, inline="always")
def pair_lower(hxx, hxz, hzz, hl):
    """The lower triangle of [[H, -H], [-H, H]] (the Hessian of an edge or a tie spring in
    its 4 coordinates, H = [[hxx, hxz], [hxz, hzz]]) packed by rows into ``hl`` (10,)."""
    hl[0] = hxx
    hl[1] = hxz
    hl[2] = hzz
    hl[3] = -hxx
    hl[4] = -hxz
    hl[5] = hxx
    hl[6] = -hxz
    hl[7] = -hzz
    hl[8] = hxz
    hl[9] = hzz


@njit(cache=True, inline="always")
def stretch_lower(x, EA, rest_length, grad, hl):
    """`stretch_terms` with the Hessian's lower triangle packed by rows into ``hl`` (10,)
    (what the assembler scatters). Returns E (J)."""
    energy, gx, gz, hxx, hxz, hzz = _stretch_jet(x, EA, rest_length)
    grad[0] = -gx
    grad[1] = -gz
    grad[2] = gx
    grad[3] = gz
    pair_lower(hxx, hxz, hzz, hl)
    return energy


@njit(cache=True, inline="always")
def spring_lower(x, stiffness, rest_offset_x, rest_offset_z, grad, hl):
    """`spring_terms` with the Hessian's lower triangle packed by rows into ``hl`` (10,).
    Returns E (J)."""
    dx = x[0] - x[2] - rest_offset_x
    dz = x[1] - x[3] - rest_offset_z
    grad[0] = stiffness * dx
    grad[1] = stiffness * dz
    grad[2] = -stiffness * dx
    grad[3] = -stiffness * dz
    pair_lower(stiffness, 0.0, stiffness, hl)
    return 0.5 * stiffness * (dx * dx + dz * dz)


@njit(cache=True)
def turning_curvature(x):
    """Integrated curvature 2 tan(phi/2) at the middle of three nodes (no derivatives)."""
    a0 = x[2] - x[0]
    b0 = x[3] - x[1]
    a1 = x[4] - x[2]
    b1 = x[5] - x[3]
    return edge_turning(a0, b0, np.sqrt(a0 * a0 + b0 * b0), a1, b1, np.sqrt(a1 * a1 + b1 * b1))


@njit(cache=True, inline="always")
def edge_turning(a0, b0, r0, a1, b1, r1):
    """2 tan(phi/2) = 2 f / g of the turn from the edge e0 = (a0, b0) to e1 = (a1, b1) of
    lengths r0, r1: f = e0 x e1, g = |e0||e1| + e0 . e1 (the one formula of the bending
    energy, its derivatives' jet and the surface strain)."""
    return 2.0 * (a0 * b1 - b0 * a1) / (r0 * r1 + a0 * a1 + b0 * b1)


@njit(cache=True, inline="always")
def dead_load_terms(x, force, x_ref):
    """Potential of a dead load on one coordinate: E = -f (x - X) (J) for a constant force
    ``force`` (N) on the coordinate ``x`` (m) whose stress-free value is ``x_ref``.

    Returns (E, dE/dx = -f); d2E/dx2 = 0: a dead load adds no stiffness. Measured from the
    stress-free state, so that the potential stays of the size of the work done and the
    energies the drivers compare keep their digits."""
    return -force * (x - x_ref), -force
