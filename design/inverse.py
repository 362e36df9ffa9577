"""Geometric inverse design (paper, Section 4): the units whose snapped array matches a target.

Steps, as in the paper:
1. A target given by points (x increasing) is interpolated by a cubic spline y(x); one given by
   control points with tangents (circular segments, like the paper's S) needs no spline.
2. Tangents at the control points; biarcs between consecutive control points.
3. Each arc turning by φ over a chord c becomes units: |φ| below the smallest θ the map reaches
   while bistable → a straight spacer (consecutive ones merged); |φ| above the largest θ → split
   into equal arcs; otherwise one unit: h/L from θ = |φ| by inverting the map at t/L, w/L, and
   L = c / (S/L), iterated to a fixed point since t/L and w/L depend on L. The arch goes on the
   side the arc turns to (+1 left, -1 right).
4. Verification: forward kinematics of the all-snapped array, started at the target's first
   point along its first tangent, against the target: max and RMS distance between the curves
   as fractions of the target length.

Automatic control points (spline targets): start with the ends and the middle (in arc length),
as the paper; then, while the deviation is above `tol`, add the midpoint of the interval whose
bisection lowers the deviation most (the paper added one point by hand where an arc was too flat
to be a unit). Optional least-squares refinement of every unit's (L, h/L) on the deviation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from design.biarcs import Arc, biarcs, sample_arcs
from design.kinematics import chain
from design.lookup import MapLookup
from design.targets import (arc_length, check_points, deviation, deviation_vector,
                            read_target_csv, resample, self_intersects)
from design.units import Unit


@dataclass
class Piece:
    """How one unit came out of the biarcs: its arc(s) of the target (a spacer may cover
    several merged flat arcs), and the turning (degrees) and chord (m) it was designed for."""

    arcs: list
    turn_deg: float
    chord: float


@dataclass
class Design:
    """An inverse design. Lengths in m; deviations as fractions of `target_length`."""

    units: list
    predicted: np.ndarray
    target: np.ndarray
    target_length: float
    max_deviation: float
    rms_deviation: float
    control_points: np.ndarray
    control_angles: np.ndarray
    arcs: list
    pieces: list
    t: float
    w: float
    points: np.ndarray | None = None
    refinement: dict | None = None
    history: list = field(default_factory=list)

    @property
    def joints(self) -> np.ndarray:
        """Unit end points of the predicted array (n + 1, 2), m."""
        return self._chain.joints

    def table(self) -> str:
        """The unit table as text (mm, degrees): each unit's snapped turning and chord (forward
        kinematics) and the turning of the target arc(s) it stands for."""
        ch = self._chain
        turn = np.degrees(np.diff(ch.angles))
        chord = np.hypot(*np.diff(ch.joints, axis=0).T)
        lines = [f"{'unit':>4} {'L_mm':>7} {'h_mm':>6} {'h/L':>6} {'side':>4} {'turn_deg':>8} "
                 f"{'S_mm':>7} {'target_deg':>10}"]
        for i, (u, p) in enumerate(zip(self.units, self.pieces)):
            hl = f"{u.h / u.L:6.3f}" if u.h > 0 else "     -"
            side = f"{u.side:+d}" if u.side else "0"
            lines.append(f"{i + 1:>4} {u.L * 1e3:7.1f} {u.h * 1e3:6.1f} {hl} {side:>4} "
                         f"{turn[i]:8.2f} {chord[i] * 1e3:7.1f} {p.turn_deg:10.2f}")
        return "\n".join(lines)

    def write(self, out_dir, bed_length_mm: float | None = None, colours: dict | None = None,
              drawings: bool = True) -> list:
        """Write units.csv, predicted.csv (mm), design.png, design.txt and (unless drawings is
        False) the DXF/SVG drawings into out_dir; returns the paths."""
        from pathlib import Path

        from design.plots import plot_design
        from design.units import write_units_csv

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [write_units_csv(self.units, out / "units.csv")]
        np.savetxt(out / "predicted.csv", self.predicted * 1e3, delimiter=",", fmt="%.4f",
                   header="x_mm,y_mm", comments="")
        paths.append(out / "predicted.csv")
        paths.append(plot_design(self, out / "design.png"))
        (out / "design.txt").write_text(self.summary() + "\n")
        paths.append(out / "design.txt")
        if drawings:
            from design.drawings import write_drawings

            paths += write_drawings(self.units, out, bed_length_mm=bed_length_mm, colours=colours)
        return paths

    def summary(self) -> str:
        """The table and the deviation, as printed by `snapmorph design`."""
        text = [self.table(),
                f"target length {self.target_length * 1e3:.1f} mm; all-snapped deviation: "
                f"max {100 * self.max_deviation:.2f} %, RMS {100 * self.rms_deviation:.2f} % of it "
                f"(max {self.max_deviation * self.target_length * 1e3:.2f} mm)"]
        if self.refinement:
            r = self.refinement
            text.append(f"least-squares refinement: max {100 * r['max_before']:.2f} % -> "
                        f"{100 * r['max_after']:.2f} %, RMS {100 * r['rms_before']:.2f} % -> "
                        f"{100 * r['rms_after']:.2f} % ({r['nfev']} evaluations"
                        f"{'' if r['accepted'] else '; not better, kept the biarc design'})")
        return "\n".join(text)


def inverse_design(points, t: float, w: float, *, tangents=None, controls=None,
                   design_map=None, tol: float = 0.01, max_controls: int = 9,
                   min_turn_deg: float | None = None, merge_deg: float = 0.5,
                   refine: bool = False, plot=None) -> Design:
    """Design an array whose all-snapped base matches a target (SI units).

    points: (N, 2) target points in m, or the path of a CSV in mm (x, y[, tangent_deg]).
        Without tangents they are target points, x strictly increasing (N >= 3).
    tangents: tangent direction at each point, degrees (N,) or vectors (N, 2): the points are
        then control points (N >= 2) and the target is the biarcs through them.
    controls: spline mode only: x (m) of the control points (ends added), or None (automatic).
    t, w: sheet thickness and strip width (m), the same for every unit.
    tol: automatic control points stop once the max deviation is below tol (fraction).
    min_turn_deg: arcs turning less become straight spacers; default the map's smallest θ.
    merge_deg: a biarc whose end points and tangents are co-circular within this angle (deg)
        is taken as one arc (one unit); the paper's S is made of such arcs.
    refine: also adjust each unit's (L, h) by least squares on the deviation.
    plot: a path: also draw target, control points, biarcs and the predicted shape there.
    """
    t, w = _positive("t", t), _positive("w", w)
    if isinstance(points, (str, bytes)) or hasattr(points, "__fspath__"):
        points, csv_tangents = read_target_csv(points)
        if tangents is None:
            tangents = csv_tangents
    lookup = MapLookup(design_map)
    designer = _Designer(lookup, t, w, min_turn_deg, merge_deg)

    if tangents is not None:
        pts = check_points(points, 2, "control points")
        angles = _angles(tangents, len(pts))
        arcs = biarcs(pts, angles)
        target = sample_arcs(arcs, 65)
        _check_not_crossing(target)
        design = designer.design(pts, angles, target)
    else:
        pts = check_points(points, 3, "target points")
        dx = np.diff(pts[:, 0])
        if not np.all(dx > 0):
            i = int(np.flatnonzero(dx <= 0)[0])
            raise ValueError(
                f"target x must increase from point to point (point {i + 2} is not right of point "
                f"{i + 1}): a spline y(x) cannot follow a target that folds back; give control "
                "points with their tangents instead (tangents=..., or a third CSV column)")
        design = _spline_design(designer, pts, controls, tol, max_controls)
    design.points = pts
    if refine:
        design = designer.refine(design)
    if plot is not None:
        from design.plots import plot_design

        plot_design(design, plot)
    return design


class _Designer:
    """Turns control points + tangents into units, and verifies them by forward kinematics."""

    def __init__(self, lookup: MapLookup, t: float, w: float, min_turn_deg, merge_deg):
        self.lookup, self.t, self.w = lookup, t, w
        self.min_turn = min_turn_deg
        self.merge_deg = float(merge_deg)

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
        turn = math.degrees(abs(arc.turn))
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


def _spline_design(designer: _Designer, pts, controls, tol, max_controls) -> Design:
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
            raise ValueError("control x must lie within the target's x range")
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


def _angles(tangents, n: int) -> np.ndarray:
    """Tangent directions in rad from degrees (n,) or vectors (n, 2)."""
    try:
        a = np.asarray(tangents, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("tangents must be numbers: degrees (N,) or vectors (N, 2)") from None
    if a.ndim == 2 and a.shape == (n, 2):
        if not np.all(np.isfinite(a)) or np.any(np.hypot(*a.T) == 0):
            raise ValueError("tangent vectors must be finite and non-zero")
        return np.unwrap(np.arctan2(a[:, 1], a[:, 0]))
    if a.shape != (n,):
        raise ValueError(f"tangents must be one angle (degrees) or vector per control point "
                         f"({n}), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("tangent angles must be finite (no NaN)")
    return np.unwrap(np.radians(a))  # 170°, -170° is a 20° turn, not 340°


def _positive(name, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number (m), got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive length in m, got {value!r}")
    return v


def _check_not_crossing(target) -> None:
    if self_intersects(resample(target, 400)):
        raise ValueError("the target crosses itself; an array's base cannot")
