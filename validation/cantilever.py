"""Cantilever with a vertical tip displacement against the exact large-deflection elastica.

Elastica (inextensible, clamped at s = 0, vertical dead load P at s = L, psi = slope angle):
    psi'' = -alpha cos(psi),  psi(0) = 0,  psi'(1) = 0,  alpha = P L^2 / EI,
    tip deflection delta / L = integral_0^1 sin(psi) ds.
Solved here by shooting on psi'(0) with a tight-tolerance ODE integrator.
"""

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from snapmorph.solver import Structure

L, T, W = 1.0, 5e-4, 1e-2
E = 12.0 / (W * T**3)  # EI = 1 N m^2
EI = 1.0


def clamped_rod_nodes(n_nodes, length):
    """Node abscissae of a rod whose clamp sits at the midpoint of its first edge.

    The clamped first edge straddles s = 0 (nodes at -ds/2 and +ds/2) and the last node is
    at s = length: the clamp then acts at s = 0 to second order in ds.
    """
    ds = length / (n_nodes - 1.5)
    return -0.5 * ds + ds * np.arange(n_nodes)


def elastica_deflection(alpha):
    """Tip deflection / L of the exact elastica for alpha = P L^2 / EI."""

    def shoot(c):
        sol = solve_ivp(
            lambda s, y: [y[1], -alpha * np.cos(y[0]), np.sin(y[0])],
            [0.0, 1.0],
            [0.0, c, 0.0],
            rtol=1e-12,
            atol=1e-14,
        )
        return sol.y[:, -1]

    c = brentq(lambda c: shoot(c)[1], 1e-12, alpha * (1 + 1e-9))
    return shoot(c)[2]


def cantilever_path(n_nodes, method="mgdc", **options):
    """The cantilever of ``n_nodes`` nodes (its first edge held, tip pushed down to
    alpha = 10 at delta / L = 0.8106): the `Path` of ``Structure.push``."""
    s = clamped_rod_nodes(n_nodes, L)
    st = Structure()
    rod = st.add_rod(np.stack([s, np.zeros_like(s)], 1), width=W, thickness=T, E=E)
    st.fix(0, "xz")
    st.fix(1, "xz")
    # tip: free horizontally and in rotation, pushed down; alpha = 10 at delta/L = 0.8106
    return st.push(rod.nodes[-1], (0.0, -1.0), 0.8106 * L, method=method, **options)


def max_relative_errors(path):
    """Max relative error of the deflection at the DER forces, and of the force at the DER
    deflections (via the local slope of the exact curve), over alpha in (0, 10]."""
    keep = (path.force > 0.05) & (path.force * L**2 / EI <= 10.0)
    d_err, f_err = [], []
    for F, d in zip(path.force[keep][::3], path.displacement[keep][::3]):
        alpha = F * L**2 / EI
        exact = elastica_deflection(alpha) * L
        slope = (elastica_deflection(alpha * 1.001) - elastica_deflection(alpha * 0.999)) * L / (
            0.002 * alpha
        )  # d(delta)/d(alpha)
        d_err.append(abs(d - exact) / exact)
        f_err.append(abs((d - exact) / slope) / alpha)
    return max(d_err), max(f_err)
