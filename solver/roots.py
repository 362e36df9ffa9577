"""The one bracketing root finder: regula falsi with the Illinois modification.

Every search for a sign change the solver makes goes through `illinois`: the zero-force
states of a push (`solver.states.zero_force_displacement`) and the bifurcation points on a
path step (`solver.branching`). Each evaluation is an equilibrium solve, so the search works
on *samples* the caller makes (its solved state travels with the abscissa) and asks the
caller for each new one.
"""

from __future__ import annotations

import numpy as np


def illinois(lo, hi, evaluate, value, tol_x, tol_f, max_eval, same_side=None, restart=None):
    """A root of a test function on the bracket [lo, hi] of samples, by regula falsi with
    the Illinois modification (the value of an end kept twice in a row is halved).

    A sample is a tuple whose first entry is its abscissa x; the caller's other entries
    (a solved state, say) travel with it. ``value(s)``: its signed test value (of opposite
    signs at lo and hi). ``evaluate(x, lo, hi)``: the sample at x, made from the current
    bracket's samples (e.g. a solve started from them), or None when it cannot be made
    (then the bracket's midpoint is tried, and the search ends if that fails too).
    ``same_side(s)``: does s lie on lo's side of the root? (default: ``value(s)`` has the
    sign of lo's value.) ``restart(s)``: called after s replaced hi; True when the test
    function changed with the smaller bracket (e.g. fewer eigenvalues cross in it), which
    starts the weights afresh.

    Stops when the bracket is at most ``tol_x`` long, when |value| of the better end is at
    most ``tol_f``, or after ``max_eval`` evaluations. Returns (the end with the smallest
    |value| (hi before any evaluation), converged: whether |value| got within tol_f)."""
    if same_side is None:
        sign0 = np.sign(value(lo))

        def same_side(s):
            return np.sign(value(s)) == sign0

    weights = [1.0, 1.0]  # the halved values of ends kept twice in a row
    side = 0  # which end was replaced last: 1 lo, -1 hi
    best = hi
    for _ in range(max_eval):
        if abs(hi[0] - lo[0]) <= tol_x or abs(value(best)) <= tol_f:
            break
        f_lo, f_hi = weights[0] * value(lo), weights[1] * value(hi)
        x = (lo[0] * f_hi - hi[0] * f_lo) / (f_hi - f_lo)
        if not min(lo[0], hi[0]) < x < max(lo[0], hi[0]):
            x = 0.5 * (lo[0] + hi[0])
        s = evaluate(x, lo, hi) or evaluate(0.5 * (lo[0] + hi[0]), lo, hi)
        if s is None:
            break
        if same_side(s):
            lo, weights[0] = s, 1.0
            if side == 1:
                weights[1] *= 0.5
            side = 1
        else:
            hi, weights[1] = s, 1.0
            if side == -1:
                weights[0] *= 0.5
            side = -1
            if restart is not None and restart(hi):
                weights, side = [1.0, 1.0], 0
        best = min((lo, hi), key=lambda e: abs(value(e)))
    return best, abs(value(best)) <= tol_f
