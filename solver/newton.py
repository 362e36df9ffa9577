"""The one Newton: equilibrium of a `System` under a fixed load, used by every caller.

Converged when the residual is below ``tol_force`` or the last correction moved no DOF by
more than ``tol_disp``: the residual of very stiff stretching terms cannot drop below
round-off, positions can. Corrections longer than ``max_move`` are damped to it. The MGDC
corrector (`solver.mgdc`) has its own iteration but shares the convergence rule here
(`settled`, `counted`).
"""

from __future__ import annotations

import numpy as np

# The drivers' displacement tolerance, as a fraction of the structure's size (see above).
TOL_DISP = 1e-11

# The MGDC corrector has also converged when the next correction, estimated from the last
# two (du_k^2 / du_(k-1): quadratic convergence), falls below the displacement tolerance
# while the last one is within this factor of it: an iteration that would only confirm
# digits already there is skipped (`settled`). Step control still counts it (`counted`),
# so a path keeps the steps it had: its sampling, and the branches its steps can reach, do
# not change. Not for `newton` at a held displacement: there the force is read off the
# reaction, which the stiff stretching terms make sensitive to the last digits of the
# positions (a skipped iteration leaves it off by ~1e-10 relative).
SETTLE_FACTOR = 1e3


def newton(system, q, lam, P, tol_force, tol_disp, max_iter, max_move, fused=True,
           settle=False):
    """Newton at the fixed load ``lam P`` (P None: no load); ``q`` is updated in place.

    Returns the iterations used, or -1 when it failed. On success the system holds the
    assembled and factorised state at the converged q; with ``settle``, once the
    corrections are below ``tol_disp``, its energy and gradients at q with K factorised at
    the iterate before, within ``tol_disp`` of it (`System.settle`: no last assembly and
    factorisation; for a caller that reads the state's force, not its inertia).

    ``fused``: iterate with the system's compiled one-call iteration (`System.fused_newton`)
    while it can, the general path (assemble, factorise, solve apart; a dense pivoting
    solve when LDL^T without pivoting fails) taking over where it cannot. Both do the same
    arithmetic, except for a correction longer than ``max_move``: the fused iteration has
    applied it already, and it is undone (q + du - du) before the general path damps it;
    ``fused=False`` damps it from q itself.
    """
    du_max = np.inf
    if P is None:
        P = np.zeros(system.n)
    start = 0
    looped = system.newton_loop(q, lam, P, tol_force, tol_disp, max_iter, max_move,
                                settle) if fused else None
    if looped is not None:  # the fused iterations in one call (planar rods)
        status, start, du_max = looped
        if status == 0:
            return start
    for it in range(start, max_iter + 1):
        if fused and it < max_iter and (looped is None or it > start):
            if settle and du_max <= tol_disp and system.settle(q, lam, P) is not None:
                return it  # converged on the displacements: K stays factorised one step back
            fstat, r_max, du_step = system.fused_newton(
                q, lam, P, tol_force if du_max > tol_disp else np.inf)
            if fstat == 0:
                return it
            if fstat == 2 and du_step <= max_move:
                du_max = du_step
                continue
            if fstat == 2:  # undo the too-long step and damp it below
                system.increment(q, system.last_correction, -1.0)
        system.evaluate(q)
        R = system.grad - lam * P
        if not np.all(np.isfinite(R)):
            return -1
        ok = system.factor()
        r_max = float(np.max(np.abs(R))) if R.size else 0.0
        if r_max <= tol_force or du_max <= tol_disp:
            return it if ok else -1
        if not ok or it == max_iter:
            return -1
        du = system.solve(-R)
        if not np.all(np.isfinite(du)):
            return -1
        du_max = float(np.max(np.abs(du)))
        scale = min(1.0, max_move / du_max) if du_max > 0 else 1.0
        system.increment(q, du, scale)
    return -1


def settled(du_max, du_prev, tol_disp):
    """Has an iteration converged on the displacements? The last correction (``du_max``)
    is below ``tol_disp``, or it is within SETTLE_FACTOR of it and the next one, estimated
    as du_max^2 / du_prev, is below it (quadratic convergence: that correction would change
    no digit that matters)."""
    return du_max <= tol_disp or (du_max <= SETTLE_FACTOR * tol_disp
                                  and du_max * du_max <= tol_disp * du_prev)


def counted(it, is_settled, du_max, tol_disp, r_max, tol_force):
    """The iterations a converged corrector reports to step control: ``it``, plus the one
    skipped when it stopped on the estimate of `settled` alone (neither the last correction
    ``du_max`` nor the residual ``r_max`` was below its tolerance yet)."""
    early = is_settled and not du_max <= tol_disp and not r_max <= tol_force
    return it + 1 if early else it
