"""The one energy descent: from a state that is not a stable equilibrium down to one.

Newton steps on the tangent stiffness K shifted to positive definite, ``du = -(K + mu I)^-1
g``, each accepted only when it lowers the energy (where K is positive definite no shift is
needed and the step is Newton's). Two rules choose the shift:

- ``"levenberg"`` (Levenberg–Marquardt on the banded K): a running multiplier, raised
  fourfold (from 1e-8 of K's largest diagonal entry) until LDL^T finds no negative pivot and
  the step, capped at ``max_move``, lowers the energy, and lowered fourfold after each
  success. Converged when the gradient is below ``tol_force`` or the last full Newton step
  below ``tol_disp``. For a released structure that must find its nearest minimum.
- ``"least"``: the smallest shift (within 5 %) that makes K + mu I positive definite, found
  by bisection on the LDL^T inertia, so that the unstable components grow about tenfold per
  step; the first step also pushes ``push`` m along the directions of negative curvature
  (`negative_curvature`), and a backtracking line search keeps the energy going down.
  Converged only where K itself is positive definite. For a rig that has just moved the
  pushed node on and must settle into a stable state with that node held.
"""

from __future__ import annotations

import numpy as np

from snapmorph.solver.banded import ldlt_factor, ldlt_solve
from snapmorph.solver.problem import ConvergenceError

SHIFTS = ("levenberg", "least")


def descend(system, q, tol_force, tol_disp, max_iter, *, shift="levenberg", max_move=np.inf,
            push=0.0, carry_frames=False):
    """Move ``q`` (full state, updated in place) down the energy of ``system`` to a stable
    equilibrium (rules above). Returns the iterations used; the system is left assembled
    and factorised at q (``"least"``) or assembled at it. ``carry_frames``: the system's
    reference frames follow every accepted step (`System.accept`). Raises
    ConvergenceError when no descent step is found or it does not converge."""
    if shift not in SHIFTS:
        raise ValueError(f"shift must be one of {SHIFTS}; got {shift!r}")
    n = system.n
    step = _levenberg_step if shift == "levenberg" else _least_shift_step
    rule = {"mu": 0.0, "diag": None, "kicked": False, "push": float(push),
            "max_move": float(max_move)}
    du_last = np.inf  # the size of the last step that counts for convergence, m
    for it in range(max_iter):
        energy = system.evaluate(q)
        g = np.array(system.grad[:n])
        if rule["diag"] is None:
            rule["diag"] = float(np.max(np.abs(system.band[0, :n])))
        du_last = step(system, q, energy, g, du_last, tol_force, tol_disp, rule)
        if du_last is None:
            return it
        if carry_frames:
            system.accept(q)
    raise ConvergenceError(f"descend did not converge in {max_iter} iterations")


def _levenberg_step(system, q, energy, g, du_last, tol_force, tol_disp, rule):
    """One Levenberg–Marquardt step from q (the system assembled there); None when q has
    converged, else the size of the step if it was a full Newton step (inf otherwise)."""
    if float(np.max(np.abs(g))) <= tol_force or du_last <= tol_disp:
        return None
    n, diag = system.n, rule["diag"]
    mu = rule["mu"]
    fresh = True  # the band holds K at q (assembled by the caller)
    while True:
        if not fresh:
            system.evaluate(q)
        fresh = False
        if mu:
            system.band[0, :n] += mu
        if system.factor() and system.negative_eigenvalues == 0:
            du = system.solve(-g)
            big = float(np.max(np.abs(du)))
            t = min(1.0, rule["max_move"] / big) if big > 0 else 1.0
            q_try = q.copy()
            system.increment(q_try, du, t)
            if system.evaluate(q_try) <= energy + 1e-12 * abs(energy):
                break
        mu = max(4.0 * mu, 1e-8 * diag)
        if mu > 1e12 * diag:
            raise ConvergenceError("descend: no energy decrease along the gradient")
    q[:] = q_try
    rule["mu"] = 0.25 * mu if mu > 1e-10 * diag else 0.0
    return big if (mu == 0.0 and t == 1.0) else np.inf


def _least_shift_step(system, q, energy, g, du_last, tol_force, tol_disp, rule):
    """One step of the least-shift rule from q (the system assembled there); None when q
    is a converged stable equilibrium (the system then factorised there), else the size of
    the step taken."""
    if not np.all(np.isfinite(g)):
        raise ConvergenceError("descend: the gradient is not finite")
    band = system.band.copy()
    status, negative, _ = ldlt_factor(system.band, 0.0)
    system.use_band_factor()  # solve() uses the band factor just made
    if status != 0:
        negative = -1
    if negative == 0:
        system.factor_ok, system.negative_eigenvalues = True, 0
        if float(np.max(np.abs(g))) <= tol_force or du_last <= tol_disp:
            return None
        du = system.solve(-g)
    else:
        kick = None
        if not rule["kicked"] and status == 0:
            kick = negative_curvature(system.band, system.solve)
            rule["kicked"] = True
        mu = definite_shift(band)
        if mu is None:
            raise ConvergenceError("descend: no shift makes the stiffness positive definite")
        shifted = band.copy()
        shifted[0] += mu
        ldlt_factor(shifted, 0.0)
        du = ldlt_solve(shifted, np.ascontiguousarray(-g.reshape(-1, 1))).ravel()
        if kick is not None:
            du += rule["push"] * kick
    if not np.all(np.isfinite(du)):
        raise ConvergenceError("descend: the step is not finite")
    t = 1.0
    q_base = q.copy()
    while True:
        system.increment(q, du, t)
        if negative == 0 or system.evaluate(q) < energy or t < 1e-6:
            break
        q[:] = q_base
        t *= 0.5
    return float(np.max(np.abs(du))) * t


def negative_curvature(factor, solve):
    """A unit direction of negative curvature from an LDL^T factor in band storage (row 0:
    D, rows k: L[j + k, j]) with negative pivots: the sum over negative pivots j of
    ``x_j = K^-1 L D e_j`` (``x_j^T K x_j = D_j < 0``, and the x_j are K-orthogonal, so their
    sum has negative curvature too; normalised, largest component positive), or None."""
    n = factor.shape[1]
    bw = factor.shape[0] - 1
    total = np.zeros(n)
    for j in np.flatnonzero(factor[0] < 0.0):
        y = np.zeros(n)
        y[j] = factor[0, j]
        k = min(bw, n - 1 - j)
        y[j + 1: j + 1 + k] = factor[0, j] * factor[1: 1 + k, j]
        x = solve(y)
        norm = float(np.linalg.norm(x))
        if norm > 0.0 and np.isfinite(norm):
            x = x / norm
            total += x if x[np.argmax(np.abs(x))] > 0 else -x
    norm = float(np.linalg.norm(total))
    return total / norm if norm > 0.0 else None


def definite_shift(band, rel=0.05):
    """The smallest mu (within ``rel``) that makes the banded symmetric K + mu I positive
    definite, by bisection on the inertia of LDL^T; None when none is found."""
    scale = float(np.max(np.abs(band[0])))
    if not scale > 0.0 or not np.isfinite(scale):
        return None

    def definite(mu):
        b = band.copy()
        b[0] += mu
        status, negative, _ = ldlt_factor(b, 0.0)
        return status == 0 and negative == 0

    hi = 1e-12 * scale
    while not definite(hi):
        hi *= 4.0
        if hi > 1e3 * scale:
            return None
    lo = 0.0
    while hi - lo > rel * hi:
        mid = 0.5 * (lo + hi)
        if definite(mid):
            hi = mid
        else:
            lo = mid
    return hi * (1.0 + rel)
