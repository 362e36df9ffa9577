"""Scale sanity of a target: is it a length an array of units can have?

A unit slip (a drawing in metres or inches read as mm, mm read as metres) makes a target a
thousand times too short or too long, and the design then fails with a solver's complaint.
`check_scale` refuses such a target first, with one line in mm that names the likely slip:

    0.52 mm long: shorter than the shortest unit the map allows at t = 0.5 mm, w = 5 mm
    (50.0 mm): is the file in metres (520.0 mm)?

The bounds: the shortest unit the design map covers at (t, w) (every unit is at least that
long), and `LONG_FACTOR` times `max_units` units of the longest such length (arched units
with spacers as long between them): far longer than any array that can be designed and
verified.
"""

from __future__ import annotations

from snapmorph.design.targets_pieces import TargetError

#: a target longer than LONG_FACTOR × max_units × the longest unit is refused
LONG_FACTOR = 2.0
#: slips tried for a too short target: (unit word, its mm, the --units value)
SHORT_SLIPS = (("metres", 1000.0, "m"), ("inches", 25.4, "in"), ("cm", 10.0, "cm"))
#: and for a too long one: mm read as (unit word, its mm)
LONG_SLIPS = (("metres", 1000.0), ("inches", 25.4), ("cm", 10.0))
#: a slip is suggested only when the corrected length is at most this (mm) long
PLAUSIBLE_MM = 3000.0
#: `check_points_scale` bounds the length with at least this many units (the default
#: max_units), so that a smaller max_units is left to the design's own message about it
SLIP_MAX_UNITS = 40


def unit_length_range(t: float, w: float, design_map=None, L_range=None) -> tuple:
    """(L_min, L_max) in m: the unit lengths the design map covers at sheet thickness t and
    strip width w (m), i.e. t/L and w/L (and b/L, for a map seen at flat ends b:
    `map_model.map_at_b`) inside the map, intersected with L_range if given."""
    from snapmorph.design.map_model import b_length_min

    if design_map is None:
        from snapmorph.maps import DesignMap

        design_map = DesignMap.load()
    rng = design_map.ranges
    lo = max(t / rng["t_over_L"][1], w / rng["w_over_L"][1], b_length_min(design_map, w))
    hi = min(t / rng["t_over_L"][0], w / rng["w_over_L"][0])
    if L_range is not None:
        lo, hi = max(lo, float(L_range[0])), min(hi, float(L_range[1]))
    if not lo < hi:
        raise ValueError(f"no unit length: the map covers no unit at t = {t * 1e3:g} mm, "
                         f"w = {w * 1e3:g} mm" + (" within L_range" if L_range else ""))
    return lo, hi


def check_scale(length_m: float, t: float, w: float, *, design_map=None, L_range=None,
                max_units: int = 40) -> None:
    """Raise `TargetError` (a ValueError; reason "too-short", "probably-metres" or "too-long")
    with a one-line message in mm when a target of this length (m) cannot be an array of units
    of thickness t and width w (m): shorter than the shortest unit the map allows, or more than
    LONG_FACTOR × max_units × the longest unit."""
    lo, hi = unit_length_range(t, w, design_map, L_range)
    mm = length_m * 1e3
    b_over_w = getattr(design_map, "b_over_w", None)
    at = f"at t = {t * 1e3:g} mm, w = {w * 1e3:g} mm" + (
        f", b = {b_over_w * w * 1e3:g} mm" if b_over_w else "")
    if length_m < lo:
        slips = [(word, mm * f, flag) for word, f, flag in SHORT_SLIPS
                 if lo * 1e3 <= mm * f <= PLAUSIBLE_MM]
        hint = ""
        if slips:
            hint = ": is the file in " + " or ".join(f"{word} ({v:.1f} mm)" for word, v, _ in
                                                     slips) + "?"
        reason = "probably-metres" if slips and slips[0][0] == "metres" else "too-short"
        raise TargetError(f"target {_mm(mm)} mm long: shorter than the shortest unit the map "
                          f"allows {at} ({lo * 1e3:.1f} mm){hint}", reason)
    longest = LONG_FACTOR * max_units * hi
    if length_m > longest:
        slips = [(word, mm / f) for word, f in LONG_SLIPS if lo * 1e3 <= mm / f <= PLAUSIBLE_MM]
        hint = ""
        if slips:
            word, v = slips[0]
            hint = f": is the file in mm but read as {word} ({v:.1f} mm)?"
        raise TargetError(f"target {_mm(mm)} mm long: far longer than the longest array "
                          f"({longest * 1e3:.0f} mm: {max_units} units of at most "
                          f"{hi * 1e3:.1f} mm {at}, spacers between){hint}", "too-long")


def check_points_scale(points, t: float, w: float, **kw) -> None:
    """`check_scale` for a target given as (N, 2) points in m, once they can be measured:
    points that cannot (too few, not finite, zero length) are left to the design's own
    checks, bounds that leave no unit length to its message about them, and so is a max_units
    below `SLIP_MAX_UNITS`. `kw`: as `check_scale` takes them."""
    import math

    import numpy as np

    try:
        p = np.asarray(points, dtype=float)
        unit_length_range(t, w, kw.get("design_map"), kw.get("L_range"))
    except (TypeError, ValueError):
        return
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
        return
    length = float(np.sum(np.hypot(*np.diff(p, axis=0).T)))
    if math.isfinite(length) and length > 0:
        kw["max_units"] = max(int(kw.get("max_units", SLIP_MAX_UNITS)), SLIP_MAX_UNITS)
        check_scale(length, t, w, **kw)


def _mm(v: float) -> str:
    return f"{v:.3g}" if v < 10 else f"{v:.1f}"
