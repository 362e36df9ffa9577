"""Single equilibrium states under a prescribed displacement of one node.

Used to pin down the special states of a path exactly — the force maximum (a limit point
under load control is a regular point under displacement control) and zero-force states
when a load-controlled Newton from a rough guess would wander off to another equilibrium.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize

from snapmorph.solver.newton import TOL_DISP, newton
from snapmorph.solver.problem import ConvergenceError, make_control, state_from
from snapmorph.solver.roots import illinois


#: `DisplacementProbe.solve`: the numbers of equal steps in which the prescribed displacement
#: is approached, tried in turn (1: Newton straight from the guess)
SUBSTEPS = (1, 4, 16)


class DisplacementProbe:
    """Equilibria of ``structure`` with ``node``'s displacement along an axis-aligned
    ``direction`` prescribed; every other constraint kept. Forces in N, lengths in m."""

    def __init__(self, structure, node, direction=(0.0, -1.0), tol=1e-9, max_iter=30):
        self.structure = structure
        self.length, self.fscale = structure.scales()
        self.control = make_control(structure, node, direction, 1e-3 * self.length,
                                    "displacement")
        self.system = structure.reduced_system(extra_fixed=[(self.control.node, self.control.axis)])
        self.q0 = structure.initial_state()
        self.X = structure.positions_of(self.q0)  # (n_nodes, dim) stress-free positions, m
        self.tol = tol
        self.max_iter = max_iter

    def solve(self, guess, d):
        """Equilibrium at displacement ``d`` (m) from ``guess`` ((n_nodes, dim) positions or
        a full state vector).

        Returns (positions (n_nodes, dim), force along the direction, negative eigenvalues
        with the displacement held). Raises ConvergenceError."""
        c = self.control
        start = state_from(self.structure, guess, "guess")
        held = c.member_dofs[:, c.axis]
        sign = c.direction[c.axis]
        d_start = float((start[held[0]] - self.q0[held[0]]) * sign)
        self.system.reset_frames()  # 3-D rods: read q's twists as canonical
        # Newton straight to d first; if it fails, march the held displacement there from
        # the guess's own in 4, then 16 steps: near a bifurcation of the held structure (at
        # a force maximum, docs/path-following.md) K is nearly singular and a Newton started
        # a whole path step away can take a wild first step
        for n_sub in SUBSTEPS:
            q = start.copy()
            for k in range(1, n_sub + 1):
                q[held] = self.q0[held] + sign * (d_start + (d - d_start) * k / n_sub)
                it = newton(self.system, q, 0.0, None, self.tol * self.fscale,
                            TOL_DISP * self.length, self.max_iter, 0.25 * self.length)
                if it < 0:
                    break
            if it >= 0:
                break
        if it < 0:
            raise ConvergenceError(f"no equilibrium found at prescribed d = {d:.6g} m")
        self.system.accept(q)
        self.last_state = q  # the full state solved last (3-D rods: with the twists)
        return self.structure.positions_of(q), c.force(self.system), self.system.negative_eigenvalues


def refine_maximum(probe, d, F, positions, i, tol_d=None):
    """Maximum of F(d) near path sample ``i`` (a local maximum of F): Brent's bounded search
    (golden section with parabolic steps, `scipy.optimize.minimize_scalar`) on d in
    [d[i-1], d[i+1]] with displacement-controlled solves. Returns (F_max, d_max), and leaves
the full state at d_max in ``probe.last_state``.

    Each solve starts from the path's own states, interpolated to the solve's d by the
    parabola through the three samples (the state is a smooth function of d on the branch,
    so the guess is off by O(spacing^3)), not from an earlier solve: with the node held,
    the force maximum is close to a bifurcation of the held structure (an asymmetric mode;
    docs/path-following.md), where K is nearly singular and a Newton started there takes a
    wild first step."""
    a, b = float(d[i - 1]), float(d[i + 1])
    if not a < b:
        raise ConvergenceError("the path is not monotone in d around the maximum")
    tol_d = (b - a) * 1e-4 if tol_d is None else tol_d
    cache, states = {}, {}
    ds, Fs = np.asarray(d[i - 1:i + 2], dtype=float), np.asarray(F[i - 1:i + 2], dtype=float)
    # F is smooth on the branch between the samples: a solve that lands further from the
    # samples' line than twice their own variation has jumped to another equilibrium (its
    # force can be 50 % off), and the search is abandoned (the caller falls back)
    spread = float(np.max(np.abs(np.diff(Fs)))) + 1e-9 * float(np.max(np.abs(Fs)))
    samples = [np.asarray(positions[j], dtype=float) for j in range(i - 1, i + 2)]

    def f(x):
        x = float(x)
        if x not in cache:
            Fx = probe.solve(_on_parabola(ds, samples, x), x)[1]
            if not abs(Fx - float(np.interp(x, ds, Fs))) <= 2.0 * spread:
                raise ConvergenceError(
                    f"the solve at d = {x:.6g} m left the path's branch (F = {Fx:.6g} N against "
                    f"{float(np.interp(x, ds, Fs)):.6g} N on the path)")
            cache[x] = Fx
            states[x] = getattr(probe, "last_state", None)
        return cache[x]

    res = scipy.optimize.minimize_scalar(lambda x: -f(x), bounds=(a, b), method="bounded",
                                         options={"xatol": 0.5 * tol_d, "maxiter": 60})
    x = float(res.x)
    F_max = f(x)
    probe.last_state = states[x]  # the state at the maximum, for the caller
    return F_max, x


def _on_parabola(ds, values, x):
    """The Lagrange parabola through (ds[k], values[k]), k = 0, 1, 2, at x (any shape)."""
    d0, d1, d2 = (float(v) for v in ds)
    w0 = (x - d1) * (x - d2) / ((d0 - d1) * (d0 - d2))
    w1 = (x - d0) * (x - d2) / ((d1 - d0) * (d1 - d2))
    w2 = (x - d0) * (x - d1) / ((d2 - d0) * (d2 - d1))
    return w0 * values[0] + w1 * values[1] + w2 * values[2]


def zero_force_displacement(probe, d0, d1, pos0, pos1, F0, F1, tol_F, max_steps=40):
    """Displacement in [d0, d1] where F changes sign (F0, F1 N at the ends, whose states
    ``pos0``, ``pos1`` are (n_nodes, dim) positions or full states): regula falsi
    (`solver.roots.illinois`) on displacement-controlled solves, each started from the
    state of the nearer end of the bracket, until |F| <= ``tol_F``. Returns (d,
    positions), and leaves the full state there in ``probe.last_state``. Raises
    ConvergenceError."""
    if not F0 * F1 <= 0.0:
        raise ConvergenceError("the bracket does not contain a zero of the force")
    st = probe.structure

    def evaluate(x, lo, hi):
        near = lo if abs(x - lo[0]) < abs(x - hi[0]) else hi
        try:
            p, fx, _ = probe.solve(near[3], x)
        except ConvergenceError:
            return None
        return (x, fx, p, probe.last_state)

    ends = [(d, F, pos, state_from(st, pos)) for d, F, pos in ((d0, F0, pos0), (d1, F1, pos1))]
    best, found = illinois(ends[0], ends[1], evaluate, lambda s: s[1], 0.0, tol_F, max_steps)
    if not found:
        raise ConvergenceError("the zero-force state was not located")
    probe.last_state = best[3]
    return best[0], best[2]
