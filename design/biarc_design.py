"""The paper's procedure (Section 4): biarcs through control points, one unit per arc.

A spline y(x) through the target points (or control points with tangents), biarcs between the
control points, one unit per arc: h/L from the arc's turning θ by inverting the map, L = chord /
(S/L) iterated to a fixed point; flat arcs become spacers, large arcs are split. Control points
are given or found by a discrete search (`_auto_controls`); `BiarcDesigner.refine` is the
optional least-squares refinement of (L, h/L). With the paper's angle convention the map is
entered with theta_end = θ/2 (`theta_scale` 2), which reproduces the paper's Table 3 and
over-curves about twice.
"""

from __future__ import annotations

import math

import numpy as np

from snapmorph.design.biarcs import Arc, biarcs
from snapmorph.design.inverse_result import Design, Piece
from snapmorph.design.kinematics import chain
from snapmorph.design.lookup import MapLookup
from snapmorph.design.targets import (arc_length, check_points, deviation, deviation_vector,
                                      resample, self_intersects)
from snapmorph.design.units import Unit


def finite_control_points(points):
    from snapmorph.design.targets import _finite_points

    return check_points(_finite_points(points, "control points"), 2, "control points")


class BiarcDesigner:
    """Turns control points + tangents into units, and verifies them by forward kinematics."""

    def __init__(self, lookup: MapLookup, t: float, w: float, min_turn_deg, merge_deg,
                 theta_scale: float = 1.0):
        self.lookup, self.t, self.w = lookup, t, w
        #: 2 for the paper's convention: an arc turning φ gets the unit with theta_end = φ
        self.theta_scale = float(theta_scale)
        self.min_turn = min_turn_deg
        self.merge_deg = float(merge_deg)
        #: called with "refine" at each least-squares evaluation (a progress bar's tick)
        self.progress = lambda stage: None

    # --- one arc -> units -------------------------------------------------------------------
    def theta_limits(self, L: float):
        """(θ_min, θ_max) in degrees for units of length about L."""
        tL, wL = self._clamped(self.t / L, "t_over_L"), self._clamped(self.w / L, "w_over_L")
        lo, hi, _, _ = self.lookup.theta_range(float(f"{tL:.3g}"), float(f"{wL:.3g}"))
        if self.min_turn is not None:
            lo = max(lo, float(self.min_turn))
        return lo, hi

    def h_limits(self, L: float):
        """(h/L at θ_min, h/L at θ_max) for units of length about L."""
        tL, wL = self._clamped(self.t / L, "t_over_L"), self._clamped(self.w / L, "w_over_L")
        _, _, h_lo, h_hi = self.lookup.theta_range(float(f"{tL:.3g}"), float(f"{wL:.3g}"))
        return h_lo, h_hi

    def _clamped(self, value, name):
        b = self.lookup.bounds(name)
        return value if b is None else min(max(value, b[0]), b[1])

    def units_for_arc(self, arc: Arc):
        """[(Unit or None for straight, sub-arc)] for one biarc arc."""
        turn = math.degrees(abs(arc.turn)) * self.theta_scale  # θ the unit must turn
        lo, hi = self.theta_limits(arc.chord)
        if turn < lo:
            return [(None, arc)]
        n = max(1, math.ceil(turn / hi - 1e-9))
        for _ in range(8):
            subs = arc.split(n) if n > 1 else [arc]
            try:
                sub = subs[0]
                L, h = self.lookup.unit_for_arc(turn / n, sub.chord, self.t, self.w)
            except ValueError as exc:
                lo_n, hi_n = self.theta_limits(sub.chord)
                if turn / n > hi_n * 0.999:
                    n += 1
                    continue
                if turn / n < lo_n * 1.001 and n == 1:
                    return [(None, arc)]
                raise ValueError(f"the target needs a unit turning {turn / n:.2f}° over "
                                 f"{sub.chord * 1e3:.1f} mm: {exc}") from None
            side = 1 if arc.turn > 0 else -1
            u = Unit(L=L, h=h, t=self.t, w=self.w, side=side, b=self.lookup.b_over_L * L)
            return [(u, s) for s in subs]
        raise ValueError(f"cannot split an arc turning {turn:.1f}° into units of the map")

    # --- control points -> design ------------------------------------------------------------
    def design(self, ctrl, angles, target) -> Design:
        arcs = biarcs(ctrl, angles, self.merge_deg)
        units, pieces = [], []
        flat = []  # consecutive straight arcs, merged into one spacer
        for arc in arcs:
            for unit, sub in self.units_for_arc(arc):
                if unit is None:
                    flat.append(sub)
                    continue
                if flat:
                    units.append(self._spacer(flat))
                    pieces.append(Piece(flat, math.degrees(sum(a.turn for a in flat)),
                                        sum(a.chord for a in flat)))
                    flat = []
                units.append(unit)
                pieces.append(Piece([sub], math.degrees(sub.turn), sub.chord))
        if flat:
            units.append(self._spacer(flat))
            pieces.append(Piece(flat, math.degrees(sum(a.turn for a in flat)),
                                sum(a.chord for a in flat)))
        return self.verify(units, pieces, ctrl, angles, arcs, target)

    def _spacer(self, flat) -> Unit:
        return Unit(L=sum(a.chord for a in flat), h=0.0, t=self.t, w=self.w, side=0)

    def verify(self, units, pieces, ctrl, angles, arcs, target) -> Design:
        ch = chain(units, None, source="map", lookup=self.lookup, start=tuple(ctrl[0]),
                   start_angle=float(angles[0]))
        dmax, drms = deviation(ch.xy, target)
        d = Design(units=units, predicted=ch.xy, target=target, target_length=arc_length(target),
                   max_deviation=dmax, rms_deviation=drms, control_points=np.asarray(ctrl),
                   control_angles=np.asarray(angles), arcs=arcs, pieces=pieces, t=self.t, w=self.w)
        d._chain = ch
        return d

    # --- least squares ------------------------------------------------------------------------
    def refine(self, design: Design) -> Design:
        """Adjust (L, h/L) of every unit (L of spacers) by least squares on the deviation."""
        from scipy.optimize import least_squares

        units = design.units
        x0, lo, hi = [], [], []
        for u in units:
            x0.append(1.0)
            lo.append(0.7)
            hi.append(1.3)
            if not u.is_spacer:
                h_lo, h_hi = self.h_limits(u.L)
                x0.append(u.h / u.L)
                lo.append(min(h_lo * 1.01, u.h / u.L))
                hi.append(max(h_hi * 0.99, u.h / u.L))
        x0, lo, hi = np.array(x0), np.array(lo), np.array(hi)
        lo, hi = np.minimum(lo, x0 - 1e-9), np.maximum(hi, x0 + 1e-9)
        start, a0 = tuple(design.control_points[0]), float(design.control_angles[0])
        n_res = 2 * 120
        penalty = np.full(n_res, 1.0)
        target = resample(design.target, 301)  # fine enough: the residuals are smooth in it

        def build(x):
            out, k = [], 0
            for u in units:
                L = u.L * x[k]
                k += 1
                if u.is_spacer:
                    out.append(Unit(L=L, h=0.0, t=u.t, w=u.w, side=0))
                else:
                    out.append(Unit(L=L, h=x[k] * L, t=u.t, w=u.w, side=u.side,
                                    b=self.lookup.b_over_L * L))
                    k += 1
            return out

        def residuals(x):
            self.progress("refine")
            try:
                xy = chain(build(x), None, source="map", lookup=self.lookup, start=start,
                           start_angle=a0).xy
            except ValueError:
                return penalty
            return deviation_vector(xy, target, 120)

        r0 = residuals(x0)
        sol = least_squares(residuals, x0, bounds=(lo, hi), diff_step=1e-5, x_scale="jac",
                            max_nfev=30 * len(x0), xtol=1e-6, ftol=1e-6)
        better = sol.cost < 0.5 * float(r0 @ r0) * (1 - 1e-6)
        new = self.verify(build(sol.x) if better else units, design.pieces,
                          design.control_points, design.control_angles, design.arcs,
                          design.target)
        new.points, new.history = design.points, design.history
        new.refinement = {"max_before": design.max_deviation, "rms_before": design.rms_deviation,
                          "max_after": new.max_deviation, "rms_after": new.rms_deviation,
                          "nfev": int(sol.nfev), "accepted": bool(better),
                          "units_before": list(units)}
        return new


def spline_design(designer: BiarcDesigner, pts, controls, tol, max_controls) -> Design:
    """Spline target; given control points, or automatic ones (see `_auto_controls`)."""
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(pts[:, 0], pts[:, 1])
    xs = np.linspace(pts[0, 0], pts[-1, 0], 801)
    target = np.stack([xs, spline(xs)], axis=-1)

    def design_at(xc):
        xc = np.asarray(sorted(xc), dtype=float)
        return designer.design(np.stack([xc, spline(xc)], axis=-1), np.arctan(spline(xc, 1)),
                               target)

    if controls is not None:
        xc = np.unique(np.concatenate([[pts[0, 0], pts[-1, 0]], np.asarray(controls, float)]))
        if xc[0] < pts[0, 0] or xc[-1] > pts[-1, 0]:
            raise ValueError("controls (x of the control points, m) must lie within the "
                             "target's x range")
        return design_at(xc)
    return _auto_controls(design_at, target, pts, tol, max_controls)


def _auto_controls(design_at, target, pts, tol, max_controls, n_candidates: int = 24) -> Design:
    """Automatic control points on a spline target.

    Candidates: the interior target points and n_candidates points evenly spread in arc length.
    Start as the paper with the ends and the middle; add, one at a time, the candidate that
    gives the smallest max deviation (kept even when it does not help at once: an added point
    can turn a flat arc into a unit only together with the next); then move each interior
    point to a neighbouring candidate while that helps. The best design seen is returned; the
    search stops once it is within tol or has max_controls points. The deviation is not smooth
    in the control points (an arc crossing the smallest θ becomes a spacer), hence a discrete
    search rather than an optimiser.
    """
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(target, axis=0).T))])
    even = np.interp(np.linspace(0, s[-1], n_candidates + 2)[1:-1], s, target[:, 0])
    cand = np.unique(np.round(np.concatenate([even, pts[1:-1, 0]]), 12))
    x0, x1 = float(pts[0, 0]), float(pts[-1, 0])
    cache, errors = {}, []

    def evaluate(xc):
        key = tuple(sorted(xc))
        if key not in cache:
            try:
                cache[key] = design_at(key)
            except ValueError as exc:
                errors.append(exc)
                cache[key] = None
        return cache[key]

    def score(d):
        return (math.inf, math.inf) if d is None else (d.max_deviation, d.rms_deviation)

    mid = float(cand[np.argmin(np.abs(np.interp(cand, target[:, 0], s) - s[-1] / 2))])
    current = (x0, mid, x1)
    best = evaluate(current)
    history = [(list(current), score(best)[0])]
    while score(best)[0] > tol and len(current) < max_controls:
        trials = [tuple(sorted(current + (c,))) for c in cand if c not in current]
        if not trials:
            break
        current = min(trials, key=lambda xc: score(evaluate(xc)))
        d = evaluate(current)
        history.append((list(current), score(d)[0]))
        if score(d) < score(best):
            best = d
    # local moves of the interior points of the best set
    if best is not None and score(best)[0] > tol:
        xc = list(best.control_points[:, 0])
        improved = True
        while improved:
            improved = False
            for i in range(1, len(xc) - 1):
                j = int(np.argmin(np.abs(cand - xc[i])))
                for k in (j - 2, j - 1, j + 1, j + 2):
                    if 0 <= k < len(cand) and cand[k] not in xc:
                        trial = sorted(xc[:i] + [float(cand[k])] + xc[i + 1:])
                        d = evaluate(trial)
                        if score(d) < score(best):
                            best, xc, improved = d, trial, True
                            history.append((list(trial), score(d)[0]))
                            break
    if best is None:
        raise errors[0]
    best.history = history
    return best


def tangent_angles(tangents, n: int) -> np.ndarray:
    """Tangent directions in rad from degrees (n,) or vectors (n, 2)."""
    try:
        a = np.asarray(tangents, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("tangents must be numbers: degrees (N,) or vectors (N, 2)") from None
    if a.ndim == 2 and a.shape == (n, 2):
        if not np.all(np.isfinite(a)) or np.any(np.hypot(*a.T) == 0):
            raise ValueError("tangents given as vectors (N, 2) must be finite and non-zero")
        return np.unwrap(np.arctan2(a[:, 1], a[:, 0]))
    if a.shape != (n,):
        raise ValueError(f"tangents must be one angle (degrees) or vector per control point "
                         f"({n}), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"tangents must be finite angles in degrees (no NaN); got {tangents!r}")
    return np.unwrap(np.radians(a))  # 170°, -170° is a 20° turn, not 340°


def check_not_crossing(target) -> None:
    if self_intersects(resample(target, 400)):
        raise ValueError("the target crosses itself; an array's base cannot")
