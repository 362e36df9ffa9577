"""Inverse design: the units whose all-snapped array matches a target.

`inverse_design` has two procedures (design/README.md has the details):

- **Tolerance-driven, any open planar curve** (the default for points): the target is a curve
  parametrised by arc length (`design.targets.Target`); initial layouts cut it where its
  turning changes direction and give each run units by an equal share of its turning; then
  least squares over every unit's (L, h/L), every spacer's L and the placement at once, through
  the map's interpolants (`_FastModel`, vectorised), until the predicted all-snapped base is
  within tol × the target's length; fewest units first; otherwise the best design and a
  warning. Deviations after the best rigid placement and with unit 1 clamped on the target's
  start and tangent; `verify_design` simulates the designed array as a whole.
- **The paper's procedure** (Section 4; `controls=`, `tangents=`, `theta_convention="paper"`):
  spline y(x) or control points with tangents, biarcs, one unit per arc (h/L from θ by
  inverting the map, L = chord / (S/L) iterated to a fixed point), flat arcs → spacers, large
  arcs split; optional least-squares refinement of (L, h/L). With the paper's convention the
  map is entered with theta_end = θ/2, which reproduces the paper's Table 3 and over-curves
  about twice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from snapmorph.design.biarcs import Arc, biarcs, sample_arcs
from snapmorph.design.kinematics import chain
from snapmorph.design.lookup import MapLookup
from snapmorph.design.targets import (Target, arc_length, best_rigid_placement, check_points, deviation,
                            deviation_vector, place_rigid, resample, self_intersects)
from snapmorph.design.units import Unit


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
    #: the tolerance asked for (fraction of target_length) and whether the selected deviation
    #: meets it
    tol: float | None = None
    met: bool | None = None
    #: "best" (best rigid placement) or "clamped" (unit 1 on the target's start and tangent):
    #: which of `deviations` is `max_deviation` / `rms_deviation` and where `predicted` sits
    placement_mode: str = "clamped"
    #: (x0, y0, angle) m, m, rad: unit 1's start point and start direction in the target frame
    placement: tuple | None = None
    deviations: dict = field(default_factory=dict)
    placements: dict = field(default_factory=dict)
    #: the unit state the map was entered with ("released" or "actuated")
    state: str = "actuated"
    theta_convention: str = "ours"
    #: whole-array simulation (`verify_design`), None until verified
    verification: dict | None = None
    notes: list = field(default_factory=list)
    limits: object | None = None
    time: float = 0.0

    def __repr__(self):
        # short: the arrays (target, predicted, arcs) would print about 10 kB
        n_arched = sum(not u.is_spacer for u in self.units)
        met = "" if self.met is None else f", tol {100 * self.tol:.3g} % {'met' if self.met else 'MISSED'}"
        return (f"Design({n_arched} arched units + {len(self.units) - n_arched} spacers, target "
                f"{self.target_length * 1e3:.1f} mm, max deviation {100 * self.max_deviation:.3g} % "
                f"({self.placement_mode}){met}, t={self.t * 1e3:.3g} mm, w={self.w * 1e3:.3g} mm, "
                f"state {self.state})")

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

        from snapmorph.design.plots import plot_design
        from snapmorph.design.units import write_units_csv

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [write_units_csv(self.units, out / "units.csv", placement=self.placement)]
        if self.met is False:
            _mark_missed(out / "units.csv", self)
        np.savetxt(out / "predicted.csv", self.predicted * 1e3, delimiter=",", fmt="%.4f",
                   header="x_mm,y_mm", comments="")
        paths.append(out / "predicted.csv")
        if self.verification is not None:
            np.savetxt(out / "simulated.csv", self.verification["xy"] * 1e3, delimiter=",",
                       fmt="%.4f", header="x_mm,y_mm", comments="")
            paths.append(out / "simulated.csv")
        paths.append(plot_design(self, out / "design.png"))
        (out / "design.txt").write_text(self.summary() + "\n")
        paths.append(out / "design.txt")
        if drawings:
            from snapmorph.design.drawings import write_drawings

            paths += write_drawings(self.units, out, bed_length_mm=bed_length_mm, colours=colours)
        return paths

    def summary(self) -> str:
        """The table and the deviations, as printed by `snapmorph design`."""
        L = self.target_length
        text = [self.table(),
                f"target length {L * 1e3:.1f} mm; {sum(not u.is_spacer for u in self.units)} "
                f"arched units, {sum(u.is_spacer for u in self.units)} spacers; map state: "
                f"{self.state}; angle convention: {self.theta_convention}"]
        rows = [("predicted (map)", self.deviations)]
        if self.verification is not None:
            v = self.verification
            rows.append((f"simulated array ({v['status']}, {v['time']:.1f} s)", v["deviations"]))
        text.append("deviation from the target, % of its length (max / RMS, max in mm):")
        for name, devs in rows:
            for mode, what in (("best", "best rigid placement"),
                               ("clamped", "start clamped on the target")):
                if mode in devs:
                    mx, rms = devs[mode]
                    sel = " <- tol" if mode == self.placement_mode and name.startswith("pred") else ""
                    text.append(f"  {name:<34} {what:<29} {100 * mx:6.2f} / {100 * rms:5.2f} "
                                f"({mx * L * 1e3:.2f} mm){sel}")
        if not self.deviations:
            text.append(f"  all-snapped deviation: max {100 * self.max_deviation:.2f} %, RMS "
                        f"{100 * self.rms_deviation:.2f} % (max "
                        f"{self.max_deviation * L * 1e3:.2f} mm)")
        if self.tol is not None:
            if self.met:
                text.append(f"tolerance {100 * self.tol:.2f} % ({self.placement_mode} placement): "
                            f"met ({100 * self.max_deviation:.2f} %)")
            else:
                text.append(f"TOLERANCE MISSED: {100 * self.max_deviation:.2f} % > "
                            f"{100 * self.tol:.2f} % ({self.placement_mode} placement); this is "
                            "the best design found")
        if self.placement is not None:
            x0, y0, a = self.placement
            text.append(f"placement of unit 1's start: x0 = {x0 * 1e3:.2f} mm, y0 = {y0 * 1e3:.2f} "
                        f"mm, direction {math.degrees(a):.2f} deg")
        if self.refinement and "quantum_deg" not in self.refinement:
            r = self.refinement
            text.append(f"least-squares refinement: max {100 * r['max_before']:.2f} % -> "
                        f"{100 * r['max_after']:.2f} %, RMS {100 * r['rms_before']:.2f} % -> "
                        f"{100 * r['rms_after']:.2f} % ({r['nfev']} evaluations"
                        f"{'' if r['accepted'] else '; not better, kept the biarc design'})")
        text += [f"note: {n}" for n in self.notes]
        return "\n".join(text)


def _mark_missed(path, design) -> None:
    """Add a comment line to a written units.csv saying the tolerance was missed."""
    from pathlib import Path

    path = Path(path)
    lines = path.read_text().splitlines(keepends=True)
    note = (f"# TOLERANCE MISSED: best design found, deviation {100 * design.max_deviation:.2f} % > "
            f"tol {100 * design.tol:.2f} % of the target length ({design.placement_mode} "
            "placement)\n")
    k = 1 if lines and lines[0].startswith("# placement") else 0
    path.write_text("".join(lines[:k] + [note] + lines[k:]))


def inverse_design(points, t: float, w: float, *, tangents=None, controls=None,
                   design_map=None, tol: float = 0.01, max_controls: int = 9,
                   min_turn_deg: float | None = None, merge_deg: float = 0.5,
                   refine: bool | None = None, plot=None, placement: str = "best",
                   L_range=None, hL_range=None, min_barrier: float = 0.5,
                   state: str = "released", max_units: int = 40,
                   theta_convention: str = "ours", verify: bool = False,
                   progress=None) -> Design:
    """Design an array whose all-snapped base matches a target within `tol` (SI units).

    points: the target: (N, 2) points in m in any orientation (N >= 2; a smooth parametric
        spline through them, parametrised by arc length), or a file: CSV in mm
        (x, y[, tangent_deg]; splined the same way), SVG (the first path's `d`, mm) or DXF (the
        first polyline, mm); drawn curves are sampled densely and taken as drawn.
    tangents: tangent direction at each point, degrees (N,) or vectors (N, 2): the points are
        then control points and the target is the biarcs through them (the paper's S).
    tol: the largest deviation allowed, a fraction of the target's arc length (0 < tol < 1).
        The design picks the number of units, their (L, h), sides and spacers, refined by least
        squares over all of them at once through the map, until the predicted all-snapped base
        is within tol; if it cannot, it warns (`UserWarning`) and returns the best design found
        (`met` False).
    placement: "best" (the deviation after the best rigid placement of the array on the
        target; unit 1's start is then `placement` of the result) or "clamped" (unit 1's start
        held on the target's start point and tangent). Both are always reported.
    L_range: (min, max) unit length in m (default: what the map covers at t and w).
    hL_range: (min, max) h/L (default: the map's h/L where every unit is bistable with an
        energy barrier of at least `min_barrier`, in units of E I_arch / L).
    state: "released" (the unit with its actuator removed, as used) or "actuated" (state (iii));
        a map without released states has only "actuated": `state` of the result says which.
    max_units: at most this many arched units.
    theta_convention: "ours" (θ is the total turning between the end tangents) or "paper": the
        paper's procedure (biarcs through control points, one unit per arc, no refinement)
        entering the map with theta_end = θ/2, which reproduces the paper's Table 3; such
        designs over-curve about twice (said in `notes` and by a warning).
    verify: also simulate the designed array as a whole (`verify_design`).
    controls, max_controls, min_turn_deg, merge_deg, refine: the paper-style procedure for
        points with x increasing (`controls`: x in m of the control points; `refine`: least
        squares on its (L, h/L)); with `controls` (or theta_convention="paper") that procedure
        is used instead of the tolerance-driven one. With tangents, the biarc design is refined
        by the tolerance-driven one when it misses tol (refine=None) or always (True), never
        with refine=False (the paper's procedure as it is).
    plot: a path: also draw target, predicted (and simulated) shapes there.
    progress: None or a callable progress(stage) called with "design", "refine" (once per
        least-squares evaluation), "verify" and "plot" as the work goes on (for a progress bar).
    """
    import warnings

    t, w = _positive("t", t), _positive("w", w)
    tol = _fraction("tol", tol)
    placement = _choice("placement", placement, PLACEMENTS)
    theta_convention = _choice("theta_convention", theta_convention, THETA_CONVENTIONS)
    state = _choice("state", state, STATES)
    if isinstance(max_units, bool) or not isinstance(max_units, (int, np.integer)) or max_units < 1:
        raise ValueError(f"max_units must be an integer >= 1, got {max_units!r}")
    try:
        min_barrier = float(min_barrier)
    except (TypeError, ValueError):
        raise ValueError(f"min_barrier must be a number (E I_arch / L), got {min_barrier!r}") from None
    if not (math.isfinite(min_barrier) and min_barrier >= 0):
        raise ValueError(f"min_barrier must be >= 0 (E I_arch / L), got {min_barrier!r}")
    max_controls = _max_controls(max_controls)
    min_turn_deg = None if min_turn_deg is None else _angle_deg("min_turn_deg", min_turn_deg)
    merge_deg = _angle_deg("merge_deg", merge_deg)
    if controls is not None:
        controls = _controls_x(controls)
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(stage); got {progress!r}")
    tick = progress if progress is not None else (lambda stage: None)
    drawn = False  # a curve read from a drawing (SVG, DXF) is taken as drawn, not splined
    if isinstance(points, (str, bytes)) or hasattr(points, "__fspath__"):
        from pathlib import Path

        from snapmorph.design.target_io import read_target

        drawn = Path(points).suffix.lower() in (".svg", ".dxf")
        points, file_tangents = read_target(points)
        if tangents is None:
            tangents = file_tangents
    raw = design_map if design_map is not None else _default_dm()
    state_kw, state_used = _map_state_kw(raw, state)
    paper = theta_convention == "paper"
    dm = _StateMap(raw, state_kw)
    lookup = MapLookup(_StateMap(raw, state_kw, paper=paper))
    designer = _Designer(lookup, t, w, min_turn_deg, merge_deg, theta_scale=2.0 if paper else 1.0)
    designer.progress = tick
    tick("design")

    if tangents is not None:
        pts = _finite_control_points(points)
        angles = _angles(tangents, len(pts))
        arcs = biarcs(pts, angles)
        target_xy = sample_arcs(arcs, 65)
        _check_not_crossing(target_xy)
        design = designer.design(pts, angles, target_xy)
        design.points = pts
        design = _assess(design, target_xy, dm, state_kw, placement, tol)
        if theta_convention == "ours" and (refine or (refine is None and not design.met)):
            curve = _curve_design(Target.from_polyline(target_xy), t, w, dm, tol, placement,
                                  L_range, hL_range, min_barrier, state, max_units, lookup,
                                  progress=tick)
            if curve.max_deviation < design.max_deviation:
                curve.points = pts
                design = curve
    elif controls is not None or theta_convention == "paper":
        pts = check_points(points, 3, "target points")
        dx = np.diff(pts[:, 0])
        if not np.all(dx > 0):
            i = int(np.flatnonzero(dx <= 0)[0])
            raise ValueError(
                f"target x must increase from point to point (point {i + 2} is not right of point "
                f"{i + 1}) for the paper's procedure (controls=..., or theta_convention='paper'): "
                "a spline y(x) cannot follow a target that folds back; leave controls out for the "
                "tolerance-driven design of any curve")
        if controls is not None:
            x0, x1 = float(pts[0, 0]), float(pts[-1, 0])
            bad = controls[(controls < x0) | (controls > x1)]
            if bad.size:
                raise ValueError(f"controls (x of the control points, m) must lie within the "
                                 f"target's x range {x0:.6g} to {x1:.6g} m; got {bad[0]:.6g} m")
        design = _spline_design(designer, pts, controls, tol, max_controls)
        design.points = pts
        if refine and theta_convention == "ours":
            design = designer.refine(design)
        design = _assess(design, design.target, dm, state_kw, placement, tol)
    else:
        target = Target.from_polyline(points) if drawn else Target.from_points(points)
        design = _curve_design(target, t, w, dm, tol, placement, L_range, hL_range, min_barrier,
                               state, max_units, lookup, progress=tick)
        design.points = target.points
    design.state = state_used
    design.theta_convention = theta_convention
    if theta_convention == "paper":
        msg = ("theta_convention='paper' enters the map with theta_end (the angle between one end "
               "tangent and the chord, θ/2) as the paper's maps most likely do: each unit turns "
               "about twice its arc, so this design over-curves about 2x (predicted deviation "
               f"{100 * design.max_deviation:.0f} % of the target length)")
        design.notes.append(msg)
        warnings.warn(msg, UserWarning, stacklevel=2)
    if state_used != state:
        design.notes.append(f"the map has no {state} state; used {state_used}")
    if verify:
        tick("verify")
        verify_design(design)
    if not design.met and theta_convention == "ours":
        warnings.warn(f"tolerance missed: the best design deviates {100 * design.max_deviation:.2f} % "
                      f"of the target length > tol {100 * tol:.2f} % ({placement} placement)",
                      UserWarning, stacklevel=2)
    if plot is not None:
        tick("plot")
        from snapmorph.design.plots import plot_design

        plot_design(design, plot)
    return design


def _default_dm():
    from snapmorph.design.lookup import default_map

    return default_map()


def _fraction(name, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, a fraction of the target length, got "
                         f"{value!r}") from None
    if not (math.isfinite(v) and 0 < v < 1):
        raise ValueError(f"{name} must be a fraction of the target's arc length, 0 < {name} < 1 "
                         f"(0.01 is 1 %), got {value!r}")
    return v


def _max_controls(value) -> int:
    """The control-point budget of the automatic search: an integer >= 3 (it starts with the two
    ends and the middle)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 3:
        raise ValueError(f"max_controls (number of control points, the two ends included) must be "
                         f"an integer >= 3; got {value!r}")
    return int(value)


def _angle_deg(name, value) -> float:
    """An angle threshold in degrees, 0 <= value < 180."""
    if isinstance(value, bool):
        raise ValueError(f"{name} must be an angle in degrees, 0 <= {name} < 180; got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an angle in degrees, 0 <= {name} < 180; got "
                         f"{value!r}") from None
    if not (math.isfinite(v) and 0 <= v < 180):
        raise ValueError(f"{name} must be an angle in degrees, 0 <= {name} < 180; got {value!r}")
    return v


def _controls_x(value) -> np.ndarray:
    """Interior control x (m), a 1-D sequence of finite numbers."""
    what = "controls must be the x of the control points in m, a sequence of finite numbers"
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{what}; got {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what}; got {value!r}") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"{what} (1-D); got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what}; got {value!r}")
    return arr


def _choice(name, value, allowed):
    if value not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(repr(a) for a in allowed)}, got "
                         f"{value!r}")
    return value


def _finite_control_points(points):
    from snapmorph.design.targets import _finite_points

    return check_points(_finite_points(points, "control points"), 2, "control points")


class _Designer:
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


def _angles(tangents, n: int) -> np.ndarray:
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


# =============================================================================================
# Tolerance-driven design of any planar curve (issue 10)
# =============================================================================================
PLACEMENTS = ("best", "clamped")
THETA_CONVENTIONS = ("ours", "paper")
STATES = ("released", "actuated")
#: correspondence points of the least-squares residual (each gives an x and a y residual)
_N_FIT = 160
#: spacers shorter than this (m) are dropped from an initial layout (they are glue joints)
_MIN_SPACER = 1e-3
#: relative margin kept from the fabrication limits (see `_Fit.bounds`)
_EDGE = 1e-5


def _map_states(dm) -> tuple:
    return tuple(getattr(dm, "states", ("actuated",)))


def _map_state_kw(dm, state: str) -> tuple[dict, str]:
    """Keyword arguments selecting `state` in the map's lookups, and the state actually used:
    a map without released states (schema 1) only has the actuated state (iii)."""
    import inspect

    try:
        params = inspect.signature(dm.at).parameters
    except (TypeError, ValueError):
        params = {}
    if "state" not in params:
        return {}, "actuated"
    used = state if state in _map_states(dm) else "actuated"
    return {"state": used}, used


class _StateMap:
    """A design map seen in one state: every lookup gets ``state=`` (unless given), and with
    the paper's convention `h_over_L_for_theta(θ)` answers by the map's theta_end = θ/2 (a
    schema-1 map has no theta_end: θ itself, the same for a symmetric unit). Everything else is
    the wrapped map's."""

    _STATEFUL = ("at", "value", "base_shape", "theta_range", "bistable_boundary",
                 "h_over_L_for_theta", "h_over_L_for_theta_end")

    def __init__(self, dm, state_kw: dict, paper: bool = False):
        self._dm, self._kw, self._paper = dm, dict(state_kw), paper

    def __getattr__(self, name):
        attr = getattr(self._dm, name)
        if name in self._STATEFUL and self._kw and callable(attr):
            def call(*args, **kw):
                for k, v in self._kw.items():
                    kw.setdefault(k, v)
                return attr(*args, **kw)
            return call
        return attr

    def h_over_L_for_theta(self, theta_deg, t_over_L, w_over_L, **kw):
        if (self._paper and hasattr(self._dm, "h_over_L_for_theta_end")
                and getattr(self._dm, "schema_version", 1) >= 2):
            for k, v in self._kw.items():
                kw.setdefault(k, v)
            return self._dm.h_over_L_for_theta_end(np.asarray(theta_deg, float) / 2.0,
                                                   t_over_L, w_over_L, **kw)
        return self.__getattr__("h_over_L_for_theta")(theta_deg, t_over_L, w_over_L, **kw)


def _chain_fast(units, dm, state_kw, start=(0.0, 0.0), angle: float = 0.0):
    """`design.kinematics.chain` of the all-snapped units, its shapes from one vectorised map
    lookup (the same numbers: conformed map shape, scaled, mirrored, placed)."""
    from snapmorph.design.kinematics import place
    from snapmorph.design.shapes import UnitShape, straight

    arched = [i for i, u in enumerate(units) if not u.is_spacer]
    t, w = units[0].t, units[0].w
    shapes = [None] * len(units)
    if arched:
        L = np.array([units[i].L for i in arched])
        hL = np.array([units[i].h / units[i].L for i in arched])
        model = _FastModel(dm, t, w, [1] * len(arched), state_kw)
        shp, th = model.shapes(L, hL)
        if not (np.all(np.isfinite(shp)) and np.all(np.isfinite(th))):
            bad = arched[int(np.flatnonzero(~np.isfinite(th))[0])] if not np.all(np.isfinite(th)) \
                else arched[0]
            u = units[bad]
            raise ValueError(f"unit {bad + 1} (L = {u.L * 1e3:.1f} mm, h = {u.h * 1e3:.1f} mm) is "
                             "not bistable in the design map")
        for j, i in enumerate(arched):
            xy = shp[j] * units[i].L
            if units[i].side < 0:
                xy = xy * np.array([1.0, -1.0])
            shapes[i] = UnitShape(xy, units[i].side * float(th[j]))
    for i, u in enumerate(units):
        if shapes[i] is None:
            shapes[i] = straight(u.L)
    return place(shapes, start, angle)


class _FastModel:
    """The all-snapped base of a sequence of units straight from the map, vectorised over a
    batch of parameter sets (the same numbers as `design.kinematics.chain`: map shape conformed
    to the interpolated θ and S, scaled by L, mirrored for side -1, placed end to end).
    Shapes are complex numbers x + iy."""

    def __init__(self, dm, t, w, sides, state_kw):
        self.dm, self.t, self.w, self.kw = dm, t, w, state_kw
        self.sides = np.asarray(sides, dtype=int)
        self.arched = np.flatnonzero(self.sides != 0)
        self.M = int(getattr(dm, "samples", 65))

    def shapes(self, L, hL):
        """Arched units of lengths L and h/L (any equal shapes): conformed unit-length shapes
        (..., M, 2) and θ (...) in rad; NaN where the map has no bistable unit."""
        L, hL = np.asarray(L, float), np.asarray(hL, float)
        tL, wL = self.t / L, self.w / L
        r = self.dm.at(hL, tL, wL, allow_nan=True, **self.kw)
        theta = np.radians(np.asarray(r["theta"], dtype=float))
        S = np.asarray(r["S"], dtype=float)
        xy = np.asarray(self.dm.base_shape(hL, tL, wL, allow_nan=True, **self.kw), dtype=float)
        z = (xy[..., 0] - xy[..., :1, 0]) + 1j * (xy[..., 1] - xy[..., :1, 1])
        want = S * np.exp(0.5j * theta)
        with np.errstate(invalid="ignore", divide="ignore"):
            z = z * (want / z[..., -1])[..., None]
        return np.stack([z.real, z.imag], axis=-1), theta

    def unit_frames(self, idx, L, hL):
        """Units `idx` (k,) with lengths L (k,) and h/L (k,): their shapes in their own frames,
        complex (k, M) in m, and end turns (k,) in rad."""
        idx = np.asarray(idx, dtype=int)
        z = np.empty((len(idx), self.M), dtype=complex)
        turn = np.zeros(len(idx))
        sides = self.sides[idx]
        flat = sides == 0
        if np.any(flat):
            z[flat] = np.asarray(L)[flat][:, None] * np.linspace(0.0, 1.0, self.M)[None, :]
        arch = ~flat
        if np.any(arch):
            shp, th = self.shapes(np.asarray(L)[arch], np.asarray(hL)[arch])
            zz = (shp[..., 0] + 1j * shp[..., 1]) * np.asarray(L)[arch][:, None]
            neg = sides[arch] < 0
            zz[neg] = np.conj(zz[neg])
            z[arch] = zz
            turn[arch] = sides[arch] * th
        return z, turn

    @staticmethod
    def assemble(z, turn, start, angle):
        """Place unit shapes z (B, n, M) with end turns (B, n) from start (B,) complex heading
        angle (B,): (B, n (M - 1) + 1) complex polylines."""
        B, n, M = z.shape
        out = np.empty((B, n * (M - 1) + 1), dtype=complex)
        out[:, 0] = start
        pos, ang = np.array(start, dtype=complex), np.array(angle, dtype=float)
        for i in range(n):
            piece = z[:, i, 1:] * np.exp(1j * ang)[:, None] + pos[:, None]
            out[:, 1 + i * (M - 1):1 + (i + 1) * (M - 1)] = piece
            pos = piece[:, -1]
            ang = ang + turn[:, i]
        return out


def _resample_batch(z: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(B, K) complex polylines sampled at arc-length fractions u: (B, len(u)) complex."""
    seg = np.abs(np.diff(z, axis=1))
    s = np.concatenate([np.zeros((z.shape[0], 1)), np.cumsum(seg, axis=1)], axis=1)
    out = np.empty((z.shape[0], len(u)), dtype=complex)
    for b in range(z.shape[0]):
        q = u * s[b, -1]
        out[b] = np.interp(q, s[b], z[b].real) + 1j * np.interp(q, s[b], z[b].imag)
    return out


@dataclass
class Limits:
    """Fabrication bounds of a design (SI): unit length range, h/L range (bistable with the
    energy-barrier margin), the θ (deg) those units reach, and the shortest spacer."""

    L_min: float
    L_max: float
    hL_min: float
    hL_max: float
    theta_min: float
    theta_max: float
    spacer_min: float = _MIN_SPACER


def _limits(dm, t, w, L_range, hL_range, min_barrier, state_kw) -> Limits:
    """Fabrication bounds from the user's ranges, intersected with what the map covers: t/L and
    w/L inside the map, h/L where every unit of the L range is bistable with an energy barrier
    of at least `min_barrier` (E I_arch / L units)."""
    rng = getattr(dm, "ranges", None) or {}
    lo, hi = 0.0, math.inf
    for name, v in (("t_over_L", t), ("w_over_L", w)):
        if name in rng:
            a, b = rng[name]
            lo, hi = max(lo, v / b), min(hi, v / a)
    map_L = (lo, hi)
    if L_range is not None:
        try:
            a, b = (float(v) for v in L_range)
        except (TypeError, ValueError):
            raise ValueError(f"L_range must be (L_min, L_max) in m, got {L_range!r}") from None
        if not (math.isfinite(a) and math.isfinite(b) and 0 < a < b):
            raise ValueError(f"L_range must be (L_min, L_max) in m with 0 < L_min < L_max, got "
                             f"{L_range!r}")
        lo, hi = max(lo, a), min(hi, b)
    if not lo < hi:
        raise ValueError(
            f"no valid unit: the map covers unit lengths {map_L[0] * 1e3:.1f} to "
            f"{map_L[1] * 1e3:.1f} mm at t = {t * 1e3:g} mm, w = {w * 1e3:g} mm"
            + (f", L_range is {L_range[0] * 1e3:g} to {L_range[1] * 1e3:g} mm"
               if L_range is not None else "") + "; they do not overlap")
    hs = np.asarray(dm.h_over_L, dtype=float)
    Ls = np.linspace(lo, hi, 5)
    ok = np.ones(hs.size, dtype=bool)
    for L in Ls:
        r = dm.at(hs, np.full_like(hs, t / L), np.full_like(hs, w / L), allow_nan=True, **state_kw)
        th = np.asarray(r["theta"], float)
        barrier = np.asarray(r["energy_barrier"], float)
        ok &= np.isfinite(th) & (th > 0) & np.isfinite(barrier) & (barrier >= min_barrier)
    if hL_range is not None:
        try:
            a, b = (float(v) for v in hL_range)
        except (TypeError, ValueError):
            raise ValueError(f"hL_range must be (h/L min, h/L max), got {hL_range!r}") from None
        if not (math.isfinite(a) and math.isfinite(b) and 0 < a < b):
            raise ValueError(f"hL_range must be (min, max) with 0 < min < max, got {hL_range!r}")
        ok &= (hs >= a - 1e-12) & (hs <= b + 1e-12)
    # the longest run of consecutive valid grid nodes: interpolation inside it is defined
    best, i = None, 0
    while i < hs.size:
        if ok[i]:
            j = i
            while j + 1 < hs.size and ok[j + 1]:
                j += 1
            if best is None or j - i > best[1] - best[0]:
                best = (i, j)
            i = j + 1
        else:
            i += 1
    if best is None or best[1] == best[0]:
        raise ValueError(
            f"no valid unit: no h/L of the map is bistable with an energy barrier >= "
            f"{min_barrier:g} (E I/L) for every unit length {lo * 1e3:.1f} to {hi * 1e3:.1f} mm"
            + (f" within hL_range {tuple(hL_range)}" if hL_range is not None else "")
            + "; widen hL_range or L_range, or lower min_barrier")
    hL_min, hL_max = float(hs[best[0]]), float(hs[best[1]])
    if hL_range is not None:
        hL_min, hL_max = max(hL_min, float(hL_range[0])), min(hL_max, float(hL_range[1]))
    Lmid = math.sqrt(lo * hi)
    th = np.asarray(dm.at(np.array([hL_min, hL_max]), np.full(2, t / Lmid), np.full(2, w / Lmid),
                          allow_nan=True, **state_kw)["theta"], float)
    return Limits(lo, hi, hL_min, hL_max, float(np.min(th)), float(np.max(th)))


def _hL_for_turn(dm, turn_deg, L, t, w, lim: Limits, state_kw, scale=1.0) -> float:
    """h/L of the unit of length L turning by |turn_deg| × scale (deg), clamped to the limits."""
    want = float(np.clip(abs(turn_deg) * scale, lim.theta_min, lim.theta_max))
    hs = np.linspace(lim.hL_min, lim.hL_max, 200)
    th = np.asarray(dm.at(hs, np.full_like(hs, t / L), np.full_like(hs, w / L), allow_nan=True,
                          **state_kw)["theta"], float)
    good = np.isfinite(th)
    if not np.any(good):
        return 0.5 * (lim.hL_min + lim.hL_max)
    hs, th = hs[good], th[good]
    order = np.argsort(th)
    return float(np.interp(want, th[order], hs[order]))


def _turn_runs(target: Target, hysteresis: float) -> list:
    """Sample intervals [(i0, i1)] of the target on which its tangent turns one way: split at
    the extrema of the tangent angle, ignoring wiggles smaller than `hysteresis` (rad)."""
    phi = target.angle
    breaks, direction, ext = [0], 0, 0
    for i in range(1, len(phi)):
        if direction == 0:
            if abs(phi[i] - phi[0]) > hysteresis:
                direction, ext = (1 if phi[i] > phi[0] else -1), i
        elif direction > 0:
            if phi[i] >= phi[ext]:
                ext = i
            elif phi[ext] - phi[i] > hysteresis:
                breaks.append(ext)
                direction, ext = -1, i
        else:
            if phi[i] <= phi[ext]:
                ext = i
            elif phi[i] - phi[ext] > hysteresis:
                breaks.append(ext)
                direction, ext = 1, i
    breaks.append(len(phi) - 1)
    breaks = sorted(set(breaks))
    return [(a, b) for a, b in zip(breaks[:-1], breaks[1:]) if b > a]


def _initial_layout(target: Target, quantum_deg: float, lim: Limits, dm, t, w, state_kw,
                    theta_scale: float = 1.0, share: float = 1.0):
    """A first guess: (sides, L, h/L). The target is cut where its turning changes direction;
    each run turning Φ gets round(|Φ| / quantum) units (at least enough not to exceed θ_max, none
    when it turns less than half the smallest θ: a spacer), each covering an equal share of the
    turning; a unit whose share of the curve is longer than L_max (or than `share` times it)
    sits at its middle (in turning) between two spacers."""
    s, phi = target.s, target.angle
    runs = _turn_runs(target, math.radians(0.25 * lim.theta_min))
    items = []  # (side, L, hL)

    def spacer(length):
        if length > 0:
            items.append((0, float(length), 0.0))

    for i0, i1 in runs:
        Phi = math.degrees(phi[i1] - phi[i0])
        ell = s[i1] - s[i0]
        if abs(Phi) < 0.5 * lim.theta_min:
            spacer(ell)
            continue
        n = max(1, int(round(abs(Phi) / quantum_deg)), math.ceil(abs(Phi) / lim.theta_max - 1e-9))
        side = 1 if Phi > 0 else -1
        levels = phi[i0] + (phi[i1] - phi[i0]) * np.arange(n + 1) / n
        seg_phi = phi[i0:i1 + 1] * side
        cuts = np.interp(levels * side, np.maximum.accumulate(seg_phi), s[i0:i1 + 1])
        cuts[0], cuts[-1] = s[i0], s[i1]
        for k in range(n):
            a, b = cuts[k], cuts[k + 1]
            length = b - a
            L = float(np.clip(share * length, lim.L_min, lim.L_max))
            mid_level = 0.5 * (levels[k] + levels[k + 1]) * side
            centre = float(np.interp(mid_level, np.maximum.accumulate(seg_phi), s[i0:i1 + 1]))
            left = max(0.0, min(centre - L / 2 - a, length - L))
            right = max(0.0, length - L - left)
            spacer(left)
            hL = _hL_for_turn(dm, abs(Phi) / n, L, t, w, lim, state_kw, theta_scale)
            items.append((side, L, hL))
            spacer(right)
    # merge neighbouring spacers; drop slivers
    merged = []
    for it in items:
        if it[0] == 0 and merged and merged[-1][0] == 0:
            merged[-1] = (0, merged[-1][1] + it[1], 0.0)
        else:
            merged.append(it)
    merged = [it for it in merged if it[0] != 0 or it[1] >= lim.spacer_min]
    if not merged:
        merged = [(0, target.length, 0.0)]
    sides = [it[0] for it in merged]
    return sides, np.array([it[1] for it in merged]), np.array([it[2] for it in merged])


class _Fit:
    """Least squares over every unit's (L, h/L), every spacer's L and, for the best placement,
    the start point and direction: residuals are the distances between arc-length-matched points
    of the predicted all-snapped base and the target (over its length). Jacobians by forward
    differences, all perturbed arrays evaluated in one vectorised map lookup."""

    def __init__(self, model: _FastModel, target: Target, lim: Limits, placement: str):
        self.m, self.target, self.lim, self.placement = model, target, lim, placement
        self.u = np.linspace(0.0, 1.0, _N_FIT)
        self.ref = target.at_fraction(self.u)
        self.ref_c = self.ref[:, 0] + 1j * self.ref[:, 1]
        self.n = len(model.sides)
        self.Lref = target.length

    def pack(self, L, hL, start, angle):
        v = []
        for i in range(self.n):
            v.append(L[i] / self.Lref)
            if self.m.sides[i] != 0:
                v.append(hL[i])
        if self.placement == "best":
            v += [start[0] / self.Lref, start[1] / self.Lref, angle]
        return np.array(v)

    def bounds(self):
        lo, hi = [], []
        for i in range(self.n):
            if self.m.sides[i] != 0:
                # a hair inside the limits: a unit on the map's edge must stay inside it after
                # units.csv rounds it to mm
                lo += [self.lim.L_min * (1 + _EDGE) / self.Lref, self.lim.hL_min * (1 + _EDGE)]
                hi += [self.lim.L_max * (1 - _EDGE) / self.Lref, self.lim.hL_max * (1 - _EDGE)]
            else:
                lo.append(self.lim.spacer_min / self.Lref)
                hi.append(2.0)
        if self.placement == "best":
            lo += [-np.inf] * 3
            hi += [np.inf] * 3
        return np.array(lo), np.array(hi)

    def unpack(self, V):
        """(B, p) → L (B, n), hL (B, n), start (B,) complex, angle (B,)."""
        V = np.atleast_2d(V)
        B = V.shape[0]
        L, hL = np.zeros((B, self.n)), np.zeros((B, self.n))
        k = 0
        for i in range(self.n):
            L[:, i] = V[:, k] * self.Lref
            k += 1
            if self.m.sides[i] != 0:
                hL[:, i] = V[:, k]
                k += 1
        if self.placement == "best":
            start = (V[:, k] + 1j * V[:, k + 1]) * self.Lref
            angle = V[:, k + 2]
        else:
            start = np.full(B, complex(*self.target.start))
            angle = np.full(B, self.target.start_angle)
        return L, hL, start, angle

    def _index(self):
        """For each parameter: (unit index or -1 for placement, what)."""
        out = []
        for i in range(self.n):
            out.append((i, "L"))
            if self.m.sides[i] != 0:
                out.append((i, "hL"))
        if self.placement == "best":
            out += [(-1, "x"), (-1, "y"), (-1, "a")]
        return out

    def _residual(self, z):
        p = _resample_batch(z, self.u)
        d = (p - self.ref_c[None]) / self.Lref
        r = np.stack([d.real, d.imag], axis=-1).reshape(len(z), -1)
        return np.where(np.isfinite(r), r, 1.0)

    def residuals(self, v):
        L, hL, start, angle = self.unpack(v[None])
        z, turn = self.m.unit_frames(np.arange(self.n), L[0], hL[0])
        return self._residual(self.m.assemble(z[None], turn[None], start, angle))[0]

    def jac(self, v):
        """Forward differences; only the perturbed unit is looked up again (one vectorised
        lookup for all of them), the others reuse the unperturbed shapes."""
        lo, hi = self.bounds()
        step = 1e-6 * np.maximum(1.0, np.abs(v))
        sgn = np.where(v + step > hi, -1.0, 1.0)
        h = sgn * step
        L, hL, start, angle = self.unpack(v[None])
        L, hL, start, angle = L[0], hL[0], start[0], angle[0]
        z0, t0 = self.m.unit_frames(np.arange(self.n), L, hL)
        index = self._index()
        P = len(v)
        Z = np.repeat(z0[None], P + 1, axis=0)
        T = np.repeat(t0[None], P + 1, axis=0)
        S = np.full(P + 1, start, dtype=complex)
        A = np.full(P + 1, angle)
        units, Ls, hLs, rows = [], [], [], []
        for k, (i, what) in enumerate(index):
            if i < 0:
                if what == "x":
                    S[k + 1] += h[k] * self.Lref
                elif what == "y":
                    S[k + 1] += 1j * h[k] * self.Lref
                else:
                    A[k + 1] += h[k]
                continue
            Li, hLi = L[i], hL[i]
            if what == "L":
                Li = Li + h[k] * self.Lref
            else:
                hLi = hLi + h[k]
            units.append(i)
            Ls.append(Li)
            hLs.append(hLi)
            rows.append(k + 1)
        if units:
            zp, tp = self.m.unit_frames(np.array(units), np.array(Ls), np.array(hLs))
            Z[rows, units] = zp
            T[rows, units] = tp
        R = self._residual(self.m.assemble(Z, T, S, A))
        return ((R[1:] - R[0]) / h[:, None]).T

    def solve(self, v0, weights=None, max_nfev=25):
        from scipy.optimize import least_squares

        lo, hi = self.bounds()
        v0 = np.clip(v0, lo + 1e-12, hi - 1e-12)
        if weights is None:
            fun, jac = self.residuals, self.jac
        else:
            fun = lambda v: weights * self.residuals(v)  # noqa: E731
            jac = lambda v: weights[:, None] * self.jac(v)  # noqa: E731
        # the residuals are distances of ~1e-3 of the length: 1e-6 relative is plenty
        sol = least_squares(fun, v0, jac=jac, bounds=(lo, hi), x_scale="jac", xtol=1e-7,
                            ftol=1e-6, gtol=1e-8, max_nfev=max_nfev, method="trf")
        return sol.x, int(sol.nfev)


def _units_from(sides, L, hL, t, w, b_over_L) -> list:
    out = []
    for sd, Li, hi in zip(sides, L, hL):
        if sd == 0:
            out.append(Unit(L=float(Li), h=0.0, t=t, w=w, side=0))
        else:
            out.append(Unit(L=float(Li), h=float(hi * Li), t=t, w=w, side=int(sd),
                            b=b_over_L * float(Li)))
    return out


def _pieces_for(units, target: Target) -> list:
    """Each unit's share of the target (by arc length, scaled to the target's length): the
    turning (deg) and chord (m) of that stretch of the target."""
    total = sum(u.L for u in units)
    edges = np.concatenate([[0.0], np.cumsum([u.L for u in units])]) / total * target.length
    ang = np.interp(edges, target.s, target.angle)
    pts = np.stack([np.interp(edges, target.s, target.xy[:, 0]),
                    np.interp(edges, target.s, target.xy[:, 1])], axis=-1)
    return [Piece([], math.degrees(ang[i + 1] - ang[i]), float(np.hypot(*(pts[i + 1] - pts[i]))))
            for i in range(len(units))]


def _assess(design: Design, target_xy: np.ndarray, dm, state_kw: dict, placement: str,
            tol: float, start=None, angle=None, quick: int | None = None) -> Design:
    """Fill in the deviations of a design's predicted all-snapped base, both ways: start
    clamped on the target's start point and tangent, and best rigid placement; select the one
    `placement` names for `predicted`, `max_deviation`, `rms_deviation` and `placement`.
    quick: search the best placement from (start, angle) only, in at most `quick` iterations
    (while comparing candidates; the chosen design is assessed in full)."""
    t_start = target_xy[0]
    seg = np.diff(resample(target_xy, 2001)[:2], axis=0)[0]
    t_angle = (float(design.control_angles[0]) if len(design.control_angles)
               else math.atan2(seg[1], seg[0]))
    local = _chain_fast(design.units, dm, state_kw).xy
    clamped = place_rigid(local, t_start, t_angle)
    s0 = start if start is not None else t_start
    a0 = angle if angle is not None else t_angle
    best_start, best_angle = best_rigid_placement(local, target_xy, start=s0, angle=a0,
                                                  kabsch=quick is None, maxiter=quick or 400)
    best = place_rigid(local, best_start, best_angle)
    design.deviations = {"clamped": deviation(clamped, target_xy), "best": deviation(best, target_xy)}
    if design.deviations["best"][0] > design.deviations["clamped"][0]:
        best, best_start, best_angle = clamped, tuple(t_start), t_angle  # never worse
        design.deviations["best"] = design.deviations["clamped"]
    design.placements = {"clamped": (float(t_start[0]), float(t_start[1]), t_angle),
                         "best": (float(best_start[0]), float(best_start[1]), float(best_angle))}
    design.placement_mode = placement
    design.placement = design.placements[placement]
    x0, y0, a = design.placement
    ch = _chain_fast(design.units, dm, state_kw, start=(x0, y0), angle=a)
    design.predicted = ch.xy
    design._chain = ch
    design.max_deviation, design.rms_deviation = design.deviations[placement]
    design.tol = tol
    design.met = bool(design.max_deviation <= tol)
    return design


def verify_design(design: Design, nodes: int | None = None) -> dict:
    """Simulate the designed array as a whole (`design.arrays.simulate_array`, every arched unit
    snapped in order, actuators removed) and measure its base against the target both ways.
    Returns (and stores as `design.verification`) {"status", "time", "xy" (placed as the design
    says), "deviations": {"best": (max, rms), "clamped": (max, rms)}, "placements": ...}."""
    import time

    from snapmorph.design.arrays import simulate_array

    t0 = time.perf_counter()
    r = simulate_array(design.units, None, nodes=nodes)
    target_xy = design.target
    local = r.base
    out = {"status": r.status, "time": time.perf_counter() - t0}
    seg = np.diff(resample(target_xy, 2001)[:2], axis=0)[0]
    t_angle = math.atan2(seg[1], seg[0])
    clamped = place_rigid(local, target_xy[0], t_angle)
    x0, y0, a0 = design.placement if design.placement is not None else (*target_xy[0], t_angle)
    bs, ba = best_rigid_placement(local, target_xy, start=(x0, y0), angle=a0)
    best = place_rigid(local, bs, ba)
    out["deviations"] = {"clamped": deviation(clamped, target_xy), "best": deviation(best, target_xy)}
    if out["deviations"]["best"][0] > out["deviations"]["clamped"][0]:
        out["deviations"]["best"] = out["deviations"]["clamped"]
        bs, ba = tuple(target_xy[0]), t_angle
    out["placements"] = {"clamped": (*target_xy[0], t_angle), "best": (*bs, ba)}
    out["xy"] = place_rigid(local, (x0, y0), a0)
    out["xy_best"] = place_rigid(local, bs, ba)
    out["max_deviation"], out["rms_deviation"] = out["deviations"][design.placement_mode]
    design.verification = out
    return out


def _curve_design(target: Target, t, w, dm, tol, placement, L_range, hL_range, min_barrier,
                  state, max_units, lookup, progress=None) -> Design:
    """Tolerance-driven design of any planar curve (see `inverse_design`); progress("layouts")
    is called once per layout tried."""
    import time

    t0 = time.perf_counter()
    state_kw, state_used = {}, state  # dm is a _StateMap: it adds the state itself
    lim = _limits(dm, t, w, L_range, hL_range, min_barrier, state_kw)
    b_over_L = lookup.b_over_L
    fractions = (0.95, 0.8, 0.65, 0.5, 0.4, 0.3, 0.22)
    quanta = sorted({round(max(lim.theta_min, f * lim.theta_max), 6) for f in fractions}
                    | {round(lim.theta_min, 6)}, reverse=True)
    best, tried, seen = None, [], set()
    # fewest units first; for each count, units covering their whole share of the curve, then
    # units of 60 % of it between spacers (curvature concentrated, as a unit's is)
    for q, share in ((q, s) for q in quanta for s in (1.0, 0.6)):
        sides, L, hL = _initial_layout(target, q, lim, dm, t, w, state_kw, share=share)
        key = (tuple(sides), share if any(s == 0 for s in sides) else 1.0)
        if key in seen:
            continue
        seen.add(key)
        if progress is not None:
            progress("layouts")
        if sum(1 for s in sides if s) > max_units:
            tried.append((q, len(sides), f"the layout needs {sum(1 for s in sides if s)} arched "
                                         f"units > max_units = {max_units}"))
            break
        model = _FastModel(dm, t, w, sides, state_kw)
        fit = _Fit(model, target, lim, placement)
        v0 = fit.pack(L, hL, target.start, target.start_angle)
        r0 = fit.residuals(v0)
        v, nfev = fit.solve(v0)
        # minimax polish (Lawson): reweight towards the largest distances, unless the
        # arc-length-matched distances (an upper bound of the deviation, nearly) are already
        # well inside tol
        weights = np.ones_like(r0)
        for _ in range(3):
            r = fit.residuals(v)
            d = np.hypot(r[0::2], r[1::2])
            if not np.all(np.isfinite(d)) or d.max() <= 0.5 * tol:
                break
            weights = weights * np.repeat(np.maximum(d / d.max(), 0.05), 2)
            weights = weights / np.sqrt(np.mean(weights ** 2))
            v2, n2 = fit.solve(v, weights=np.sqrt(weights), max_nfev=20)
            nfev += n2
            if np.max(np.hypot(*fit.residuals(v2).reshape(-1, 2).T)) < d.max():
                v = v2
        Lf, hLf, start_c, angle = (a[0] for a in fit.unpack(v))
        start = (float(start_c.real), float(start_c.imag))
        units = _units_from(sides, Lf, hLf, t, w, b_over_L)
        try:
            d = Design(units=units, predicted=None, target=target.xy, target_length=target.length,
                       max_deviation=math.inf, rms_deviation=math.inf,
                       control_points=np.empty((0, 2)), control_angles=np.array([target.start_angle]),
                       arcs=[], pieces=_pieces_for(units, target), t=t, w=w)
            d = _assess(d, target.xy, dm, state_kw, placement, tol, start=start, angle=angle,
                        quick=80)
        except ValueError as exc:
            tried.append((q, len(sides), str(exc)))
            continue
        # the initial layout's deviation, as placed on the target's start and tangent
        try:
            units0 = _units_from(sides, L, hL, t, w, b_over_L)
            before = deviation(_chain_fast(units0, dm, state_kw, tuple(target.start),
                                           target.start_angle).xy, target.xy)
        except ValueError:
            before = (math.inf, math.inf)
        d.refinement = {"max_before": before[0], "rms_before": before[1],
                        "max_after": d.max_deviation, "rms_after": d.rms_deviation,
                        "nfev": nfev, "accepted": True, "quantum_deg": q, "share": share}
        tried.append((q, len(sides), d.max_deviation))
        if best is None or d.max_deviation < best.max_deviation:
            best = d
        if best.max_deviation <= tol:
            break
    if best is None:
        raise ValueError("no design: " + "; ".join(str(e) for _, _, e in tried if isinstance(e, str))
                         + "; raise max_units or L_range")
    x0, y0, a0 = best.placements["best"]
    best = _assess(best, target.xy, dm, state_kw, placement, tol, start=(x0, y0), angle=a0)
    best.history = tried
    best.state = state_used
    best.limits = lim
    best.time = time.perf_counter() - t0
    return best
