"""Inverse design: the units whose all-snapped array matches a target.

`inverse_design` checks its arguments, reads the target and runs one of two procedures
(design/README.md has the details):

- the tolerance-driven fit of any open planar curve (`design.curve_fit`; the default for
  points);
- the paper's procedure (Section 4; `controls=`, `tangents=`, `theta_convention="paper"`):
  biarcs through control points, one unit per arc (`design.biarc_design`).

Both return a `Design` (`design.inverse_result`), measured the same way (`design.verification`:
the deviation with unit 1 clamped on the target's start and tangent, and after the best rigid
placement; `verify_design` simulates the designed array as a whole).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from snapmorph.design.biarc_design import (BiarcDesigner, check_not_crossing,
                                           finite_control_points, spline_design, tangent_angles)
from snapmorph.design.biarcs import biarcs, sample_arcs
from snapmorph.design.curve_fit import curve_design
from snapmorph.design.inverse_result import Design
from snapmorph.design.lookup import MapLookup
from snapmorph.design.map_model import StateMap, map_at_b, map_state_kw
from snapmorph.design.target_io import TargetFile, target_file_of
from snapmorph.design.targets import Target, arc_length, check_points
from snapmorph.design.targets_frame import DrawingFrame
from snapmorph.design.targets_scale import check_points_scale
from snapmorph.design.unit_margins import verify_loads
from snapmorph.design.verification import assess, verify_design

PLACEMENTS = ("best", "clamped")
THETA_CONVENTIONS = ("ours", "paper")
STATES = ("released", "actuated")


def inverse_design(points, t: float, w: float, *, tangents=None, controls=None,
                   design_map=None, tol: float = 0.01, tol_abs: float | None = None,
                   select=None, units=None, max_controls: int = 9,
                   min_turn_deg: float | None = None, merge_deg: float = 0.5,
                   refine: bool | None = None, plot=None, placement: str = "best",
                   L_range=None, hL_range=None, min_barrier: float = 0.5,
                   state: str = "released", max_units: int = 40,
                   theta_convention: str = "ours", verify: bool = False,
                   progress=None, material=None, orientation=None, max_strain=None,
                   min_backload=None, b: float | None = None) -> Design:
    """Design an array whose all-snapped base matches a target within `tol` (SI units).

    points: the target: (N, 2) points in m in any orientation (N >= 2; a smooth parametric
        spline through them, parametrised by arc length), a file (`target_io.read_target_file`
        with `select` and `units`: CSV, splined the same way; SVG and DXF curves, taken as
        drawn), or a `target_io.TargetFile` already read. A target from a file shorter than
        the shortest unit the map allows at (t, w), or far longer than the longest array, is
        refused (`targets_scale.check_scale`: the likely unit slip, in mm); points given as
        numbers get the best design, a warning and ``met = False``.
    tangents: tangent direction at each point, degrees (N,) or vectors (N, 2): the points are
        then control points and the target is the biarcs through them (the paper's S).
    tol: the largest deviation allowed, a fraction of the target's arc length (0 < tol < 1).
        The design picks the number of units, their (L, h), sides and spacers, refined by least
        squares over all of them at once through the map, until the predicted all-snapped base
        is within tol; if it cannot, it warns (`UserWarning`) and returns the best design found
        (`met` False).
    tol_abs: also the largest deviation allowed in m (None: none); the design meets both, so
        the stricter one governs (`tol` of the result is the fraction used, `tol_governs`
        says which). A whole-array verification that fails (`verify`) also makes `met` False.
    select, units: read a target file with these (`target_io.read_target_file`).
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
    material, orientation, max_strain, min_backload: does the design hold? With any of them
        the designed array is simulated under its own weight (`material`: a Material or
        "petg", "pla", "paper", default the paper's; `orientation`: "upright" (default),
        "sideways" or an angle, deg), every unit's strain must stay below `max_strain`
        (default the material's allowable strain) and its snap-back load above
        `min_backload` (N), and no parts may overlap (`design.unit_margins.verify_loads`);
        when not, `met` is False, `verification_failure` and `load_check` say why, and a
        UserWarning is given.
    b: extra flat length of every arched unit's ends, m (the paper's specimens: b = w); the
        map is read at b/L = b / L of each unit (it needs a b/L axis, unless b is 0 on a map
        built at b/L = 0), so units are at least b / (the map's largest b/L) long. None: today's behaviour, the map's own b/L (0 on the committed
        maps), every unit's b = that b/L times its L.
    """
    import warnings

    t, w = check_positive("t", t), check_positive("w", w)
    tol = check_fraction("tol", tol)
    placement = check_choice("placement", placement, PLACEMENTS)
    theta_convention = check_choice("theta_convention", theta_convention, THETA_CONVENTIONS)
    state = check_choice("state", state, STATES)
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
    tol_abs = None if tol_abs is None else check_positive("tol_abs", tol_abs)
    source = target_file_of(points, select=select, units=units)
    drawn = False  # a curve read from a drawing (SVG, DXF) is taken as drawn, not splined
    if source is not None:
        drawn, points = source.drawn, source.points
        if tangents is None:
            tangents = source.tangents
    raw = design_map if design_map is not None else _default_dm()
    if b is not None:
        raw = map_at_b(raw, b, w)
    state_kw, state_used = map_state_kw(raw, state)
    paper = theta_convention == "paper"
    dm = StateMap(raw, state_kw)
    lookup = MapLookup(StateMap(raw, state_kw, paper=paper))
    designer = BiarcDesigner(lookup, t, w, min_turn_deg, merge_deg, theta_scale=2.0 if paper else 1.0)
    designer.progress = tick
    if source is not None:  # a file's length may be a unit slip; raw points keep the old
        # contract (the best design, a warning and met = False: test_out_of_reach_says_so)
        check_points_scale(points, t, w, design_map=raw, L_range=L_range, max_units=max_units)
    tick("design")

    if tangents is not None:
        pts = finite_control_points(points)
        angles = tangent_angles(tangents, len(pts))
        arcs = biarcs(pts, angles)
        target_xy = sample_arcs(arcs, 65)
        check_not_crossing(target_xy)
        tol_used = effective_tol(tol, tol_abs, arc_length(target_xy))
        design = designer.design(pts, angles, target_xy)
        design.points = pts
        design = assess(design, target_xy, dm, state_kw, placement, tol_used)
        if theta_convention == "ours" and (refine or (refine is None and not design.met)):
            curve = curve_design(Target.from_polyline(target_xy), t, w, dm, tol_used, placement,
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
        tol_used = effective_tol(tol, tol_abs, Target.from_points(pts).length)
        design = spline_design(designer, pts, controls, tol_used, max_controls)
        design.points = pts
        if refine and theta_convention == "ours":
            design = designer.refine(design)
        design = assess(design, design.target, dm, state_kw, placement,
                        effective_tol(tol, tol_abs, design.target_length))
    else:
        target = Target.from_polyline(points) if drawn else Target.from_points(points)
        design = curve_design(target, t, w, dm, effective_tol(tol, tol_abs, target.length),
                              placement, L_range, hL_range, min_barrier, state, max_units,
                              lookup, progress=tick)
        design.points = target.points
    if b is not None:
        design.units = [u if u.is_spacer else replace(u, b=float(b)) for u in design.units]
    design.tol_rel, design.tol_abs = tol, tol_abs
    design.source = source if source is not None else TargetFile(
        np.asarray(points, dtype=float), None, DrawingFrame("csv"), source="points")
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
    verify_loads(design, material, orientation, max_strain, min_backload)
    if design.max_deviation > design.tol and theta_convention == "ours":
        warnings.warn(f"tolerance missed: the best design deviates {100 * design.max_deviation:.2f} % "
                      f"of the target length > tol {100 * design.tol:.2f} % ({placement} "
                      "placement)", UserWarning, stacklevel=2)
    if design.verification_failure:
        warnings.warn(f"verification failed: {design.verification_failure}", UserWarning,
                      stacklevel=2)
    if plot is not None:
        tick("plot")
        from snapmorph.design.plots import plot_design

        plot_design(design, plot)
    return design


def effective_tol(tol: float, tol_abs: float | None, length: float) -> float:
    """The fraction of the target's length a design must meet: `tol`, or `tol_abs` (m) over
    `length` (m) when that is stricter."""
    return tol if tol_abs is None else min(tol, tol_abs / length)


def _default_dm():
    from snapmorph.design.lookup import default_map

    return default_map()


def check_fraction(name, value) -> float:
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


def check_choice(name, value, allowed):
    if value not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(repr(a) for a in allowed)}, got "
                         f"{value!r}")
    return value


def check_positive(name, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number (m), got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive length in m, got {value!r}")
    return v
