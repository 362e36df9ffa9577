"""Forward kinematics of an array (paper, Section 3).

The base of an array in any snap pattern (which units are snapped: ``snapped=``, e.g. "101")
is the concatenation of its units' base shapes, each translated and rotated so that it starts
where the previous one ends, along the previous end tangent. Neighbouring units are assumed not
to interact (the paper's conjecture, validated on three units).

Every function takes the units' state ``state=``: "released" (default, None: the units as used,
actuators removed) or "actuated" (each snapped unit's state (iii) with its actuator still glued).
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass

import numpy as np

from snapmorph.design.lookup import MapLookup, check_state
from snapmorph.design.shapes import UnitShape, unit_shape
from snapmorph.design.units import Unit


@dataclass(frozen=True)
class Chain:
    """A placed array: `xy` (K, 2) base polyline in m; `pieces[i]` the (k_i, 2) polyline of
    unit i (sharing end points with its neighbours); `joints` (n + 1, 2) the unit end points;
    `angles` (n + 1,) the base tangent direction (rad) at each joint."""

    xy: np.ndarray
    pieces: tuple
    joints: np.ndarray
    angles: np.ndarray

    def __repr__(self):
        end = self.joints[-1]
        turn = float(np.degrees(self.angles[-1] - self.angles[0]))
        return (f"Chain({len(self.pieces)} units, {len(self.xy)} points, end at "
                f"({end[0] * 1e3:.2f}, {end[1] * 1e3:.2f}) mm, total turning {turn:.2f} deg)")


def chain(units, snapped, source: str = "map", lookup: MapLookup | None = None,
          start=(0.0, 0.0), start_angle: float = 0.0, state: str | None = None, **kw) -> Chain:
    """Place the units' base shapes end to end, from `start` (m) heading `start_angle` (rad);
    snapped units in ``state`` ("released" by default, or "actuated")."""
    units, snapped = _check(units, snapped)
    _check_start(start, start_angle)
    if state is not None:
        kw["state"] = check_state(state)
    if source == "map" and lookup is None and any(s and not u.is_spacer
                                                  for u, s in zip(units, snapped)):
        lookup = MapLookup()
    shapes = [unit_shape(u, s, source=source, lookup=lookup, **kw)
              for u, s in zip(units, snapped)]
    return place(shapes, start, start_angle)


def place(shapes: list[UnitShape], start=(0.0, 0.0), start_angle: float = 0.0) -> Chain:
    """Concatenate unit-frame shapes, matching end points and end tangents; from `start` (m)
    heading `start_angle` (rad)."""
    pos, ang = _check_start(start, start_angle)
    pieces, joints, angles = [], [pos.copy()], [ang]
    for shape in shapes:
        c, s = math.cos(ang), math.sin(ang)
        rot = np.array([[c, -s], [s, c]])
        piece = shape.xy @ rot.T + pos
        piece[0] = pos  # exact shared joint
        pieces.append(piece)
        pos = piece[-1].copy()
        ang = ang + shape.end_angle
        joints.append(pos.copy())
        angles.append(ang)
    xy = np.vstack([pieces[0]] + [p[1:] for p in pieces[1:]]) if pieces else pos[None, :]
    return Chain(xy, tuple(pieces), np.array(joints), np.array(angles))


def forward_kinematics(units, snapped=None, source: str = "map", design_map=None,
                       start=(0.0, 0.0), start_angle: float = 0.0, state: str | None = None,
                       **kw) -> np.ndarray:
    """Base polyline (K, 2) in m of `units` with unit i snapped when `snapped[i]`.

    `snapped`: booleans, a '0'/'1' string, or None (all snapped). Starts at `start` heading
    `start_angle` (rad; default (0, 0) and +x). `source`: "map" (design map, `design_map` or the
    default one) or "simulate" (direct simulation; keyword `E`, `nodes` passed on).
    `state`: "released" (default: the units with their actuators removed, as used) or
    "actuated" (state (iii) with the actuators still glued).
    """
    lookup = MapLookup(design_map) if (source == "map" and design_map is not None) else None
    return chain(units, snapped, source=source, lookup=lookup, start=start,
                 start_angle=start_angle, state=state, **kw).xy


def parse_snapped(snapped, n: int) -> list[bool]:
    """A snap pattern as n booleans, from a '0'/'1' string (char i: unit i + 1 snapped) or a
    sequence; None: all snapped."""
    if snapped is None:
        return [True] * n
    if isinstance(snapped, str):
        s = snapped.strip()
        if len(s) != n or any(ch not in "01" for ch in s):
            raise ValueError(f"snapped must be a string of {n} characters 0/1 (one per unit, "
                             f"1 = snapped), got {snapped!r}")
        return [ch == "1" for ch in s]
    flags = list(snapped)
    if len(flags) != n:
        raise ValueError(f"snapped must have one entry per unit ({n}), got {len(flags)}")
    out = []
    for f in flags:
        if f not in (0, 1, True, False):
            raise ValueError(f"snapped entries must be booleans, got {f!r}")
        out.append(bool(f))
    return out


def all_snap_patterns(units, source: str = "map", design_map=None, chains: bool = False,
                      state: str | None = None, **kw) -> dict:
    """Every stable state of the array: {snap pattern: (K, 2) base polyline in m} (or
    {snap pattern: Chain} with chains=True).

    Units that are spacers have one state only, so there are 2ⁿ snap patterns for n arched
    units; their characters in the pattern are always '0'. Ordered from all unsnapped upwards,
    unit 1 being the most significant character. `state` (the units' state, released or
    actuated): as in `forward_kinematics`.
    """
    units, _ = _check(units, None)
    arched = [i for i, u in enumerate(units) if not u.is_spacer]
    lookup = MapLookup(design_map) if source == "map" else None
    out = {}
    for bits in itertools.product((False, True), repeat=len(arched)):
        snapped = [False] * len(units)
        for i, b in zip(arched, bits):
            snapped[i] = b
        key = "".join("1" if s else "0" for s in snapped)
        ch = chain(units, snapped, source=source, lookup=lookup, state=state, **kw)
        out[key] = ch if chains else ch.xy
    return out


def parse_state(state, n: int) -> list[bool]:
    """Deprecated name (snapmorph 0.1) of `parse_snapped`."""
    _renamed("parse_state", "parse_snapped")
    return parse_snapped(state, n)


def all_states(units, *args, **kw) -> dict:
    """Deprecated name (snapmorph 0.1) of `all_snap_patterns`."""
    _renamed("all_states", "all_snap_patterns")
    return all_snap_patterns(units, *args, **kw)


def _renamed(old: str, new: str) -> None:
    warnings.warn(f"design.{old} is deprecated (a snap pattern is not a unit state); use "
                  f"design.{new}", DeprecationWarning, stacklevel=3)


def _check(units, snapped):
    """(list of units, list of snapped flags), or ValueError naming `units` or `snapped`."""
    if units is None or isinstance(units, (str, bytes, Unit)):
        raise ValueError(f"units must be a sequence of design.Unit (the array's units, in "
                         f"order; at least one); got {units!r}")
    try:
        units = list(units)
    except TypeError:
        raise ValueError(f"units must be a sequence of design.Unit (the array's units, in "
                         f"order; at least one); got {units!r}") from None
    if not units:
        raise ValueError("units must hold at least one design.Unit (an array needs at least one "
                         "unit); got an empty sequence")
    for i, u in enumerate(units):
        if not isinstance(u, Unit):
            raise ValueError(f"unit {i + 1} is not a design.Unit: {u!r}")
    flags = parse_snapped(snapped, len(units))
    if snapped is not None:  # None: every arched unit snapped (a spacer has one state only)
        for i, (u, f) in enumerate(zip(units, flags)):
            if f and u.is_spacer:
                raise ValueError(f"snapped: unit {i + 1} is a spacer (h = 0, one state only) and "
                                 f"cannot be snapped; give 0 (or False) for it; got {snapped!r}")
    return units, flags


def _check_start(start, start_angle):
    """(start as a float array (2,) in m, start_angle as a float in rad), or ValueError
    naming the parameter, its unit and what is valid."""
    bad = (f"start (the array's first joint (x, y), m) must be two finite real numbers; "
           f"got {start!r}")
    if start is None or isinstance(start, (str, bytes)):
        raise ValueError(bad)
    try:
        raw = np.asarray(start)
    except (TypeError, ValueError):
        raise ValueError(bad) from None
    if raw.shape != (2,) or raw.dtype.kind not in "iufO":
        raise ValueError(bad)
    try:
        pos = np.array(start, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(bad) from None
    if not np.all(np.isfinite(pos)):
        raise ValueError(bad)
    bad = (f"start_angle (heading of the first unit's base, rad, counter-clockwise from +x) "
           f"must be a finite real number; got {start_angle!r}")
    if start_angle is None or isinstance(start_angle, (str, bytes, bool, np.bool_, complex,
                                                       np.complexfloating)):
        raise ValueError(bad)
    try:
        ang = float(start_angle)
    except (TypeError, ValueError):
        raise ValueError(bad) from None
    if not math.isfinite(ang):
        raise ValueError(bad)
    return pos, ang
