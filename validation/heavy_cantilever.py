"""A clamped cantilever under its own weight against the exact heavy elastica.

Heavy elastica (inextensible, clamped horizontally at s = 0, free at s = L, weight q per
length, theta = the tangent's angle below the horizontal): the moment at s is
EI theta'(s) = int_s^L q (x(xi) - x(s)) dxi, so

    theta'' = -(q / EI) (L - s) cos(theta),   theta(0) = 0,   theta'(L) = 0,

tip deflection delta = int_0^L sin(theta) ds, tip rotation theta(L). With s in units of L it
depends on alpha = q L^3 / EI only. Solved here by shooting on theta'(0) in (0, alpha / 2]
(the moment at the clamp is at most q L^2 / 2) with a tight-tolerance ODE integrator and
Brent's root finder: about 1e-11 relative.

The DER model: `Structure.clamp` at node 0 (the clamp exactly at the node, O(N^-2)),
self-weight from `add_gravity` (each edge's weight half on each of its nodes), followed to
load factor 1 with `follow_load`; the 3-D strip (`Structure3D`, face normal along z: the
easy way in the x-z plane) is the same model.
"""

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from snapmorph.solver import Structure, Structure3D

L, T, W = 1.0, 5e-4, 1e-2
E = 12.0 / (W * T**3)  # EI = 1 N m^2
EI = 1.0
G = 9.81
NU = 0.38


def heavy_elastica(alpha):
    """(delta / L, x_tip / L, theta_tip rad) of the exact heavy elastica, alpha = q L^3 / EI."""

    def shoot(c):
        sol = solve_ivp(lambda s, y: [y[1], -alpha * (1.0 - s) * np.cos(y[0]),
                                      np.sin(y[0]), np.cos(y[0])],
                        [0.0, 1.0], [0.0, c, 0.0, 0.0], method="DOP853", rtol=1e-13,
                        atol=1e-15)
        return sol.y[:, -1]

    c = brentq(lambda c: shoot(c)[1], 1e-15, 0.5 * alpha, xtol=1e-15, rtol=1e-15)
    theta, _, delta, x = shoot(c)
    return delta, x, theta


def density_for(alpha, area=W * T):
    """The density (kg/m^3) that gives q L^3 / EI = alpha under g = 9.81 m/s^2."""
    return alpha * EI / L**3 / (area * G)


def heavy_cantilever(n_nodes, alpha, three_d=False):
    """The cantilever of ``n_nodes`` nodes from s = 0 to L along x, clamped at node 0, with
    its self-weight set to q L^3 / EI = ``alpha`` (along -z; 0: weightless). Returns the
    structure (its tip is node n_nodes - 1)."""
    s = np.linspace(0.0, L, n_nodes)
    if three_d:
        st = Structure3D()
        rod = st.add_rod(np.stack([s, 0 * s, 0 * s], 1), width=W, thickness=T, E=E, nu=NU,
                         normal=(0.0, 0.0, 1.0))
    else:
        st = Structure()
        rod = st.add_rod(np.stack([s, 0 * s], 1), width=W, thickness=T, E=E)
    st.clamp(rod.nodes[0], toward=rod.nodes[1])
    if alpha:
        st.add_gravity(density_for(alpha), g=G)
    return st


def tip_errors(n_nodes, alpha, three_d=False, **options):
    """Relative errors of the DER tip deflection and tip rotation at load factor 1 against
    the exact heavy elastica, and the path. Returns (deflection error, rotation error, path)."""
    st = heavy_cantilever(n_nodes, alpha, three_d)
    path = st.follow_load(1.0, **options)
    tip = path.positions[-1][-1]
    prev = path.positions[-1][-2]
    delta = -tip[-1]
    theta = np.arctan2(prev[-1] - tip[-1], tip[0] - prev[0])  # the last edge's angle
    exact_delta, _, exact_theta = heavy_elastica(alpha)
    # the last edge's angle is the tangent at its midpoint: compare it with the exact
    # tangent there (theta(s) near the free end: theta(L) - theta''(L) (ds/2)^2 / 2 with
    # theta''(L) = 0, so the midpoint angle equals theta(L) to O(ds^3))
    return (abs(delta - exact_delta * L) / (exact_delta * L),
            abs(theta - exact_theta) / exact_theta, path)
