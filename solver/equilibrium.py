"""Newton equilibrium: one state under a fixed load (`Structure.solve_equilibrium`)."""

from __future__ import annotations

import numpy as np

from snapmorph.solver.newton import TOL_DISP, newton
from snapmorph.solver.problem import (ConvergenceError, check_options, load_vector, make_control,
                                      real_scalar, state_from)


def equilibrium(structure, positions, node, direction, force, tol=1e-9, max_iter=40):
    """Newton from ``positions`` ((n_nodes, dim) m or a full state) to the equilibrium under
    ``force`` (N) on ``node`` along ``direction`` (no load when ``node`` is None).

    Returns (positions (n_nodes, dim), info dict: "iterations", "energy" (J),
    "negative_eigenvalues", "state" (the full state), "system" (the reduced system, holding
    K assembled and factorised at that state)). Raises ConvergenceError when Newton
    fails."""
    q = state_from(structure, positions)
    force = real_scalar(force, "force", "N")
    if not np.isfinite(force):
        raise ValueError(f"force must be finite (N); got {force!r}")
    opts = check_options(tol=(tol, "pos", 0.0, 1e-1, "(relative)"),
                         max_iter=(max_iter, "int", 1, 10**4, ""))
    system = structure.reduced_system()
    length, fscale = structure.scales()
    P = None
    if node is not None:
        control = make_control(structure, node, direction, 1e-3 * length, "mgdc")
        P = load_vector(system, control)
    tol_force = opts["tol"] * max(fscale, abs(force))
    it = newton(system, q, force, P, tol_force, TOL_DISP * length, opts["max_iter"],
                0.25 * length)
    if it < 0:
        raise ConvergenceError(
            f"equilibrium not found within {max_iter} Newton iterations from the given state"
        )
    system.accept(q)
    info = {
        "iterations": it,
        "energy": system.energy,
        "negative_eigenvalues": system.negative_eigenvalues,
        "state": q,
        "system": system,
    }
    return structure.positions_of(q), info
