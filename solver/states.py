"""Single equilibrium states under a prescribed displacement of one node.

Used to pin down the special states of a path exactly — the force maximum (a limit point
under load control is a regular point under displacement control) and zero-force states
when a load-controlled Newton from a rough guess would wander off to another equilibrium.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize
from numba import njit

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
        with the displacement held: of K at the last Newton iterate, within the displacement
        tolerance of the state, `solver.newton.newton`'s ``settle``). Raises
        ConvergenceError."""
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
                            TOL_DISP * self.length, self.max_iter, 0.25 * self.length,
                            settle=True)
                if it < 0:
                    break
            if it >= 0:
                break
        if it < 0:
            raise ConvergenceError(f"no equilibrium found at prescribed d = {d:.6g} m")
        self.system.accept(q)
        self.last_state = q  # the full state solved last (3-D rods: with the twists)
        return self.structure.positions_of(q), c.force(self.system), self.system.negative_eigenvalues


def refine_maximum(probe, d, F, positions, i, tol_d=None, rates=None):
    """Maximum of F(d) near path sample ``i`` (a local maximum of F) on d in [d[i-1], d[i+1]]
    with displacement-controlled solves: the maxima of polynomials through the samples and
    the solves (`_interpolated_maximum`), Brent's bounded search (golden section with parabolic steps,
    `scipy.optimize.minimize_scalar`) where they do not close in. ``tol_d`` (m): how close
    d_max is located. Returns (F_max, d_max), and leaves the full state at d_max in
    ``probe.last_state``.

    Each solve starts from the path's own states interpolated to the solve's d (`between`:
    with the samples' ``rates`` dq/dd where the path gives them, else the parabola through
    the three samples; the state is a smooth function of d on the branch), not from an
    earlier solve alone: with the node held, the force maximum is close to a bifurcation of
    the held structure (an asymmetric mode; docs/path-following.md), where K is nearly
    singular and a Newton started from a state at another d takes a wild first step. A solve
    closer to an earlier solve than to any sample starts from that solve's state moved by
    the interpolant's change between the two (the interpolant's error, smooth in d, then
    cancels to first order: one or two corrections where the samples lie far apart)."""
    a, b = float(d[i - 1]), float(d[i + 1])
    if not a < b:
        raise ConvergenceError("the path is not monotone in d around the maximum")
    tol_d = (b - a) * 1e-4 if tol_d is None else tol_d
    cache, states = {}, {}
    ds, Fs = np.asarray(d[i - 1:i + 2], dtype=float), np.asarray(F[i - 1:i + 2], dtype=float)
    # F is smooth on the branch between the samples: a solve that lands further from the
    # samples' line than twice their own variation has jumped to another equilibrium (its
    # force can be 50 % off), and the search is abandoned (the caller falls back)
    F0, F1, F2 = (float(v) for v in Fs)  # (three numbers: no array passes)
    spread = max(abs(F1 - F0), abs(F2 - F1)) + 1e-9 * max(abs(F0), abs(F1), abs(F2))
    samples = [np.asarray(positions[j], dtype=float) for j in range(i - 1, i + 2)]
    slopes = None if rates is None else [np.asarray(rates[j], dtype=float)
                                          for j in range(i - 1, i + 2)]
    if slopes is not None:  # a row not known (NaN) is None: `between` goes without it
        slopes = [r if np.isfinite(r).all() else None for r in slopes]

    solved = {}  # d -> the solve's positions, when they are of the samples' kind
    interpolated = {}  # d -> the interpolant there (the guess of the solve at d)

    def guess(x):
        g = interpolated[x] = between(ds, samples, slopes, x)
        if solved:
            x0 = min(solved, key=lambda v: abs(v - x))
            if abs(x - x0) < min(abs(float(v) - x) for v in ds):
                g0 = interpolated.get(x0)
                g0 = between(ds, samples, slopes, x0) if g0 is None else g0
                return solved[x0] + (g - g0)
        return g

    def f(x):
        x = float(x)
        if x not in cache:
            pos, Fx = probe.solve(guess(x), x)[:2]
            pos = np.asarray(pos, dtype=float)
            if pos.shape == samples[0].shape:
                solved[x] = pos.copy()
            if not abs(Fx - float(np.interp(x, ds, Fs))) <= 2.0 * spread:
                raise ConvergenceError(
                    f"the solve at d = {x:.6g} m left the path's branch (F = {Fx:.6g} N against "
                    f"{float(np.interp(x, ds, Fs)):.6g} N on the path)")
            cache[x] = Fx
            states[x] = getattr(probe, "last_state", None)
        return cache[x]

    x = _interpolated_maximum(f, ds, Fs, tol_d)
    if x is None:  # the polynomials do not close in: Brent's safeguarded search
        res = scipy.optimize.minimize_scalar(lambda x: -f(x), bounds=(a, b), method="bounded",
                                             options={"xatol": 0.5 * tol_d, "maxiter": 60})
        x = float(res.x)
    F_max = f(x)
    probe.last_state = states[x]  # the state at the maximum, for the caller
    return F_max, x


#: `_interpolated_maximum`: the most estimates it solves at before it gives up
INTERPOLATION_STEPS = 8


def _interpolated_maximum(f, ds, Fs, tol_d):
    """d of the maximum of f by interpolation from the three path samples (ds, Fs) that
    bracket it: the maximum of the polynomial through the (up to) four points nearest the
    highest is solved at (``f``), until an estimate lies within ``tol_d`` of the one
    before; it is solved at too. The first estimate is the vertex of the samples' parabola,
    the later ones a cubic's maximum, which follows a lopsided peak (a parabola over the
    samples' width does not). Returns the d of the highest solve, or None when an estimate
    leaves the bracket or is not a maximum, or when the slope between the last two solves
    puts the maximum further than ``tol_d`` from them (`_settled`): the caller takes Brent's
    search then. Where F is smooth on the branch it solves three times, where the bounded
    Brent search, which starts on golden sections, solves eight to ten."""
    lo, hi = float(ds[0]), float(ds[2])
    pts = sorted((float(x), float(v)) for x, v in zip(ds, Fs))
    solved, last = [], None
    for _ in range(INTERPOLATION_STEPS):
        best = max(pts, key=lambda p: p[1])[0]
        near = sorted(sorted(pts, key=lambda p: abs(p[0] - best))[:4])
        estimate = _polynomial_maximum(near, lo, hi)
        if estimate is None:
            return None
        close = last is not None and abs(estimate - last) <= tol_d
        solved.append((f(estimate), estimate))
        if close:
            # two estimates agree; the slope between their solves must agree too, or the
            # samples' wide polynomial misled both (a sharp peak between far samples)
            return max(solved)[1] if _settled(solved[-2:], near, tol_d) else None
        pts = sorted(pts + [(estimate, solved[-1][0])])
        last = estimate
    return None


def _settled(pair, near, tol_d):
    """Does the maximum lie within ``tol_d`` of the last two solves ``pair`` ((F, d), their
    d within tol_d)? The Newton step -F' / F'' from their midpoint, F' their chord's slope
    and F'' the curvature of the parabola through the points ``near`` (the last estimate's
    polynomial points) nearest to them."""
    (Fa, xa), (Fb, xb) = sorted(pair, key=lambda p: p[1])
    if xb - xa <= 0.0:
        return True
    xm = 0.5 * (xa + xb)
    three = sorted(sorted(near, key=lambda p: abs(p[0] - xm))[:3])
    (x0, y0), (x1, y1), (x2, y2) = three
    if not x0 < x1 < x2:
        return False
    curvature = 2.0 * ((y2 - y1) / (x2 - x1) - (y1 - y0) / (x1 - x0)) / (x2 - x0)
    if not curvature < 0.0:
        return False
    return abs((Fb - Fa) / (xb - xa) / curvature) <= tol_d


def _polynomial_maximum(pts, lo, hi):
    """d in (lo, hi) of the interior maximum of the polynomial through the (d, F) points
    (three or four, distinct d) nearest the highest of them; None when it has none. In
    closed form (Newton's divided differences; p' a quadratic) on d centred and scaled."""
    x0 = pts[0][0]
    scale = pts[-1][0] - x0
    if not scale > 0.0:
        return None
    u = [(p[0] - x0) / scale for p in pts]
    y = [p[1] for p in pts]
    if any(b <= a for a, b in zip(u, u[1:])):
        return None
    # divided differences a1, a2, a3 of p(u) = y0 + a1 u + a2 u (u - u1) + a3 u (u - u1)(u - u2)
    d1 = [(y[k + 1] - y[k]) / (u[k + 1] - u[k]) for k in range(len(u) - 1)]
    d2 = [(d1[k + 1] - d1[k]) / (u[k + 2] - u[k]) for k in range(len(d1) - 1)]
    a1, a2 = d1[0], d2[0]
    a3 = (d2[1] - d2[0]) / (u[3] - u[0]) if len(u) == 4 else 0.0
    u1, u2 = u[1], (u[2] if len(u) == 4 else 0.0)
    s1, s2 = u1 + u2, u1 * u2  # of the nodes 0, u1, u2
    # p'(u) = A u^2 + B u + C, p''(u) = 2 A u + B
    A, B, C = 3.0 * a3, 2.0 * a2 - 2.0 * a3 * s1, a1 - a2 * u1 + a3 * s2
    if A == 0.0 or abs(A) <= 1e-12 * (abs(B) + abs(C)):
        roots = [] if B == 0.0 else [-C / B]
    else:
        disc = B * B - 4.0 * A * C
        if disc < 0.0:
            return None
        q = -0.5 * (B + math.copysign(math.sqrt(disc), B))
        roots = [q / A] + ([C / q] if q != 0.0 else [])
    top = (pts[max(range(len(y)), key=y.__getitem__)][0] - x0) / scale
    maxima = [r for r in roots if 2.0 * A * r + B < 0.0 and lo < x0 + r * scale < hi]
    if not maxima:
        return None
    return x0 + min(maxima, key=lambda r: abs(r - top)) * scale


def between(ds, values, slopes, x):
    """The state at displacement ``x`` between three path samples (``ds`` increasing,
    ``values`` their states): `hermite` on the pair of samples that brackets x, with the
    samples' ``slopes`` (dq/dd, `solver.path.Path.rates`); where they are None or not
    finite (a critical point's row), the parabola through the three samples, off by
    O(spacing^3). Newton solves started from it take one or two corrections instead of
    three to eight after a snap."""
    j = 0 if x <= float(ds[1]) else 1
    if slopes is not None:
        guess = hermite(ds[j], ds[j + 1], values[j], values[j + 1], slopes[j], slopes[j + 1], x)
        if guess is not None:
            return guess
    return _on_parabola(ds, values, x)


def hermite(d0, d1, q0, q1, r0, r1, x):
    """The cubic Hermite interpolant at ``x`` of a state known at d0 and d1 (q0, q1) with
    its slopes dq/dd there (r0, r1): off by O((d1 - d0)^4) on a smooth branch; None where a
    slope is None or not finite (or d0 = d1)."""
    h = float(d1) - float(d0)
    if h == 0.0 or r0 is None or r1 is None:
        return None
    t = (float(x) - float(d0)) / h
    h00, h01 = (1.0 + 2.0 * t) * (1.0 - t) ** 2, t * t * (3.0 - 2.0 * t)
    h10, h11 = t * (1.0 - t) ** 2 * h, t * t * (t - 1.0) * h
    q0, q1, r0, r1 = (np.asarray(v, dtype=float) for v in (q0, q1, r0, r1))
    if not q0.shape == q1.shape == r0.shape == r1.shape:
        if not math.isfinite(float(np.sum(r0) + np.sum(r1))):
            return None
        return h00 * q0 + h10 * r0 + h01 * q1 + h11 * r1
    out = np.empty(q0.shape)
    flat = [np.ascontiguousarray(v).reshape(-1) for v in (q0, r0, q1, r1)]
    if not _combine4(*flat, h00, h10, h01, h11, out.reshape(-1)):
        return None
    return out


@njit(cache=True)
def _combine4(a, b, c, e, wa, wb, wc, we, out):
    """out = wa a + wb b + wc c + we e, term by term in that order (the bits of the same
    numpy expression, without its three temporaries); False (out unfinished) where b or e
    holds a value that is not finite (a slope not known)."""
    for i in range(b.shape[0]):
        if not (abs(b[i]) < np.inf and abs(e[i]) < np.inf):
            return False
    for i in range(a.shape[0]):
        out[i] = wa * a[i] + wb * b[i] + wc * c[i] + we * e[i]
    return True


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
