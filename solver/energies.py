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


@njit(cache=True)
def stretch_terms(x, EA, rest_length, grad, hess):
    """Stretching energy of one edge; ``x`` = [xa, za, xb, zb] (m), EA (N), rest length (m).

    Writes d(E)/dx into ``grad`` (4,) and d2(E)/dx2 into ``hess`` (4, 4); returns E (J).
    """
    ex = x[2] - x[0]
    ez = x[3] - x[1]
    length = np.sqrt(ex * ex + ez * ez)
    k = EA / rest_length
    stretch = length - rest_length
    energy = 0.5 * k * stretch * stretch
    tx = ex / length
    tz = ez / length
    gx = k * stretch * tx
    gz = k * stretch * tz
    grad[0] = -gx
    grad[1] = -gz
    grad[2] = gx
    grad[3] = gz
    # d2E/de2 = k [t t^T + (1 - rest/length)(I - t t^T)]
    c = k * stretch / length
    hxx = k * tx * tx + c * (1.0 - tx * tx)
    hzz = k * tz * tz + c * (1.0 - tz * tz)
    hxz = k * tx * tz - c * tx * tz
    for a in range(2):
        for b in range(2):
            sign = 1.0 if a == b else -1.0
            hess[2 * a, 2 * b] = sign * hxx
            hess[2 * a + 1, 2 * b + 1] = sign * hzz
            hess[2 * a, 2 * b + 1] = sign * hxz
            hess[2 * a + 1, 2 * b] = sign * hxz
    return energy


@njit(cache=True, inline="always")
def _block(h, bi, bj, a00, a01, a10, a11):
    """Write the 2x2 block (bi, bj) of a symmetric 6x6 matrix and its transpose."""
    r = 2 * bi
    c = 2 * bj
    h[r, c] = a00
    h[r, c + 1] = a01
    h[r + 1, c] = a10
    h[r + 1, c + 1] = a11
    h[c, r] = a00
    h[c + 1, r] = a01
    h[c, r + 1] = a10
    h[c + 1, r + 1] = a11


@njit(cache=True, inline="always")
def _kappa_ee(i, j, f, inv_g, fe, ge, gee, fee):
    """d2(kappa)/de_i de_j of kappa = 2 f / g (quotient rule, twice)."""
    return 2.0 * inv_g * (
        fee[i][j]
        - (fe[i] * ge[j] + ge[i] * fe[j]) * inv_g
        - f * gee[i][j] * inv_g
        + 2.0 * f * ge[i] * ge[j] * inv_g * inv_g
    )


@njit(cache=True)
def curvature_terms(x, dkappa, d2kappa):
    """Integrated curvature at the middle node of ``x`` = [x0, z0, x1, z1, x2, z2].

    kappa = 2 tan(phi/2) = 2 f / g with f = e0 x e1 and g = |e0||e1| + e0 . e1
    (dimensionless, positive for a counter-clockwise turn).
    Writes d(kappa)/dx (6,) and d2(kappa)/dx2 (6, 6); returns kappa.
    """
    # Derivatives are taken with respect to the edge vectors (a0, b0, a1, b1) first and then
    # mapped to the node coordinates; everything stays in registers (no allocation), since
    # this kernel runs once per node per Newton iteration.
    a0 = x[2] - x[0]
    b0 = x[3] - x[1]
    a1 = x[4] - x[2]
    b1 = x[5] - x[3]
    n0 = np.sqrt(a0 * a0 + b0 * b0)
    n1 = np.sqrt(a1 * a1 + b1 * b1)
    f = a0 * b1 - b0 * a1
    g = n0 * n1 + a0 * a1 + b0 * b1
    inv_g = 1.0 / g
    kappa = 2.0 * f * inv_g

    fe = (b1, -a1, -b0, a0)
    t0x = a0 / n0
    t0z = b0 / n0
    t1x = a1 / n1
    t1z = b1 / n1
    ge = (n1 * t0x + a1, n1 * t0z + b1, n0 * t1x + a0, n0 * t1z + b0)
    r01 = n1 / n0
    r10 = n0 / n1
    g00 = r01 * (1.0 - t0x * t0x)
    g11 = r01 * (1.0 - t0z * t0z)
    g01 = -r01 * t0x * t0z
    g22 = r10 * (1.0 - t1x * t1x)
    g33 = r10 * (1.0 - t1z * t1z)
    g23 = -r10 * t1x * t1z
    g02 = t0x * t1x + 1.0
    g03 = t0x * t1z
    g12 = t0z * t1x
    g13 = t0z * t1z + 1.0
    gee = (
        (g00, g01, g02, g03),
        (g01, g11, g12, g13),
        (g02, g12, g22, g23),
        (g03, g13, g23, g33),
    )
    # f is bilinear: its only second derivatives are d2f/da0 db1 = 1, d2f/db0 da1 = -1
    fee = (
        (0.0, 0.0, 0.0, 1.0),
        (0.0, 0.0, -1.0, 0.0),
        (0.0, -1.0, 0.0, 0.0),
        (1.0, 0.0, 0.0, 0.0),
    )
    ke = (
        2.0 * (fe[0] - f * ge[0] * inv_g) * inv_g,
        2.0 * (fe[1] - f * ge[1] * inv_g) * inv_g,
        2.0 * (fe[2] - f * ge[2] * inv_g) * inv_g,
        2.0 * (fe[3] - f * ge[3] * inv_g) * inv_g,
    )
    k00 = _kappa_ee(0, 0, f, inv_g, fe, ge, gee, fee)
    k01 = _kappa_ee(0, 1, f, inv_g, fe, ge, gee, fee)
    k02 = _kappa_ee(0, 2, f, inv_g, fe, ge, gee, fee)
    k03 = _kappa_ee(0, 3, f, inv_g, fe, ge, gee, fee)
    k11 = _kappa_ee(1, 1, f, inv_g, fe, ge, gee, fee)
    k12 = _kappa_ee(1, 2, f, inv_g, fe, ge, gee, fee)
    k13 = _kappa_ee(1, 3, f, inv_g, fe, ge, gee, fee)
    k22 = _kappa_ee(2, 2, f, inv_g, fe, ge, gee, fee)
    k23 = _kappa_ee(2, 3, f, inv_g, fe, ge, gee, fee)
    k33 = _kappa_ee(3, 3, f, inv_g, fe, ge, gee, fee)
    # gradient: d/dx0 = -k_e0, d/dx1 = k_e0 - k_e1, d/dx2 = k_e1
    dkappa[0] = -ke[0]
    dkappa[1] = -ke[1]
    dkappa[2] = ke[0] - ke[2]
    dkappa[3] = ke[1] - ke[3]
    dkappa[4] = ke[2]
    dkappa[5] = ke[3]
    # Hessian blocks from K00 = d2k/de0de0, K01 = d2k/de0de1, K11 = d2k/de1de1:
    # [[K00, K01 - K00, -K01], [., K00 - K01 - K10 + K11, K01 - K11], [., ., K11]]
    _block(d2kappa, 0, 0, k00, k01, k01, k11)
    _block(d2kappa, 0, 1, k02 - k00, k03 - k01, k12 - k01, k13 - k11)
    _block(d2kappa, 0, 2, -k02, -k03, -k12, -k13)
    _block(d2kappa, 1, 1, k00 - 2.0 * k02 + k22, k01 - k03 - k12 + k23,
           k01 - k12 - k03 + k23, k11 - 2.0 * k13 + k33)
    _block(d2kappa, 1, 2, k02 - k22, k03 - k23, k12 - k23, k13 - k33)
    _block(d2kappa, 2, 2, k22, k23, k23, k33)
    return kappa


@njit(cache=True)
def bending_terms(x, stiffness, kappa_bar, grad, hess):
    """Bending energy at the middle node of ``x`` (6,); stiffness = EI / l_bar (N m).

    Writes the gradient (6,) and Hessian (6, 6); returns E (J).
    """
    # grad and hess first receive d(kappa) and d2(kappa), then are scaled in place
    kappa = curvature_terms(x, grad, hess)
    dev = kappa - kappa_bar
    c = stiffness * dev
    for p in range(6):
        for q in range(6):
            hess[p, q] = c * hess[p, q] + stiffness * grad[p] * grad[q]
    for p in range(6):
        grad[p] *= c
    return 0.5 * stiffness * dev * dev


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


@njit(cache=True)
def turning_curvature(x):
    """Integrated curvature 2 tan(phi/2) at the middle of three nodes (no derivatives)."""
    a0 = x[2] - x[0]
    b0 = x[3] - x[1]
    a1 = x[4] - x[2]
    b1 = x[5] - x[3]
    g = np.sqrt(a0 * a0 + b0 * b0) * np.sqrt(a1 * a1 + b1 * b1) + a0 * a1 + b0 * b1
    return 2.0 * (a0 * b1 - b0 * a1) / g


@njit(cache=True, inline="always")
def dead_load_terms(x, force, x_ref):
    """Potential of a dead load on one coordinate: E = -f (x - X) (J) for a constant force
    ``force`` (N) on the coordinate ``x`` (m) whose stress-free value is ``x_ref``.

    Returns (E, dE/dx = -f); d2E/dx2 = 0: a dead load adds no stiffness. Measured from the
    stress-free state, so that the potential stays of the size of the work done and the
    energies the drivers compare keep their digits."""
    return -force * (x - x_ref), -force


# ---------------------------------------------------------------------------- gradients only
# The energy and gradient of each term without its Hessian: what a state that Newton has
# converged to needs (its force and energy), the stiffness being factorised already at the
# iterate before it (`solver.assembly.assemble_gradient`).

@njit(cache=True)
def stretch_gradient(x, EA, rest_length, grad):
    """`stretch_terms` without the Hessian: writes d(E)/dx (4,), returns E (J)."""
    ex = x[2] - x[0]
    ez = x[3] - x[1]
    length = np.sqrt(ex * ex + ez * ez)
    k = EA / rest_length
    stretch = length - rest_length
    gx = k * stretch * (ex / length)
    gz = k * stretch * (ez / length)
    grad[0] = -gx
    grad[1] = -gz
    grad[2] = gx
    grad[3] = gz
    return 0.5 * k * stretch * stretch


@njit(cache=True)
def bending_gradient(x, stiffness, kappa_bar, grad):
    """`bending_terms` without the Hessian: writes d(E)/dx (6,), returns E (J). The
    curvature kappa = 2 f / g and its derivatives with respect to the edge vectors as in
    `curvature_terms`."""
    a0 = x[2] - x[0]
    b0 = x[3] - x[1]
    a1 = x[4] - x[2]
    b1 = x[5] - x[3]
    n0 = np.sqrt(a0 * a0 + b0 * b0)
    n1 = np.sqrt(a1 * a1 + b1 * b1)
    f = a0 * b1 - b0 * a1
    inv_g = 1.0 / (n0 * n1 + a0 * a1 + b0 * b1)
    kappa = 2.0 * f * inv_g
    c = stiffness * (kappa - kappa_bar)
    # d(kappa)/d(a0, b0, a1, b1) = 2 (f_e - f g_e / g) / g
    s = 2.0 * c * inv_g
    fg = f * inv_g
    k0 = s * (b1 - fg * (n1 * a0 / n0 + a1))
    k1 = s * (-a1 - fg * (n1 * b0 / n0 + b1))
    k2 = s * (-b0 - fg * (n0 * a1 / n1 + a0))
    k3 = s * (a0 - fg * (n0 * b1 / n1 + b0))
    grad[0] = -k0
    grad[1] = -k1
    grad[2] = k0 - k2
    grad[3] = k1 - k3
    grad[4] = k2
    grad[5] = k3
    return 0.5 * c * (kappa - kappa_bar)


@njit(cache=True)
def spring_gradient(x, stiffness, rest_offset_x, rest_offset_z, grad):
    """`spring_terms` without the Hessian: writes d(E)/dx (4,), returns E (J)."""
    dx = x[0] - x[2] - rest_offset_x
    dz = x[1] - x[3] - rest_offset_z
    grad[0] = stiffness * dx
    grad[1] = stiffness * dz
    grad[2] = -stiffness * dx
    grad[3] = -stiffness * dz
    return 0.5 * stiffness * (dx * dx + dz * dz)
