"""The two stable base shapes of one unit, in the unit's own frame.

A shape is `UnitShape(xy, end_angle)`: the base polyline in m starting at (0, 0) heading +x,
and the direction of its end tangent (rad, counter-clockwise from +x). Unsnapped units and
spacers are straight: ((0, 0), (L, 0)), end angle 0. A snapped unit's shape is the state-(iii)
base shape per unit length times L, mirrored in z for side -1; its end angle is side * θ.

Sources: ``"map"`` (interpolated in a design map, the default) or ``"simulate"`` (a direct
simulation with `solver.unit.simulate_unit`, normalised the way the map is).

States: ``state="released"`` (default: state (iii) with the actuator and rollers removed, the
unit as used in an array) or ``"actuated"`` (the actuator still glued, the paper's state (iii)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from snapmorph.design.lookup import MapLookup, check_state
from snapmorph.design.units import Unit

SOURCES = ("map", "simulate")
E_DEFAULT = 2.2e9  # Pa, PETG (only the simulation needs it: the shape does not depend on E)


@dataclass(frozen=True)
class UnitShape:
    """Base polyline (K, 2) in m in the unit frame, and its end-tangent angle (rad)."""

    xy: np.ndarray
    end_angle: float


def straight(L: float) -> UnitShape:
    """An unsnapped unit or a spacer: a straight base of length L (m)."""
    return UnitShape(np.array([[0.0, 0.0], [L, 0.0]]), 0.0)


def snapped_shape(unit: Unit, source: str = "map", lookup: MapLookup | None = None,
                  E: float = E_DEFAULT, nodes=None, state: str | None = None) -> UnitShape:
    """The snapped (state iii) base of `unit` in its own frame (m); straight for a spacer.
    ``state``: "released" (None: the default) or "actuated"."""
    if state is not None:
        check_state(state)
    if unit.is_spacer:
        return straight(unit.L)
    if source == "map":
        lookup = lookup or MapLookup()
        bL = _check_b(unit, lookup)
        hL, tL, wL = unit.h / unit.L, unit.t / unit.L, unit.w / unit.L
        theta, S = lookup.theta_S(hL, tL, wL, state=state, b_over_L=bL)
        xy = conform(np.array(lookup.base_shape(hL, tL, wL, state=state, b_over_L=bL)),
                     theta, S) * unit.L
    elif source == "simulate":
        xy, theta = _simulated(unit.L, unit.h, unit.t, unit.w, unit.b, float(E), nodes,
                               state or "released")
        xy = xy * unit.L
    else:
        raise ValueError(f"source must be one of {SOURCES}, got {source!r}")
    xy = xy - xy[0]
    if unit.side < 0:
        xy[:, 1] *= -1.0
    return UnitShape(xy, unit.side * math.radians(theta))


def unit_shape(unit: Unit, snapped: bool, **kw) -> UnitShape:
    """The unit's base shape in the given state."""
    return snapped_shape(unit, **kw) if snapped else straight(unit.L)


def conform(xy: np.ndarray, theta_deg: float, S: float) -> np.ndarray:
    """Map a base shape by a similarity about its start so that its chord is S long at θ/2.

    Shapes and scalars are interpolated separately in the map, so the chord of an interpolated
    shape differs from the interpolated S and θ by the interpolation error (~1e-4 relative on
    a fine grid). Conforming the shape to the scalars makes forward kinematics agree exactly
    with inverse design, which works from S and θ.
    """
    xy = xy - xy[0]
    chord = complex(*xy[-1])
    want = S * complex(math.cos(math.radians(theta_deg) / 2), math.sin(math.radians(theta_deg) / 2))
    z = (xy[:, 0] + 1j * xy[:, 1]) * (want / chord)
    return np.stack([z.real, z.imag], axis=-1)


def normalise_base(xy: np.ndarray, theta_deg: float, L: float) -> np.ndarray:
    """A simulated state-(iii) base (m, any frame) as the map stores it: per unit length, from
    (0, 0), start tangent +x, arch side +z.

    The unit is symmetric, so its chord makes θ/2 with the start tangent: rotating the chord to
    +θ/2 sets the start tangent along +x without differentiating the polyline.
    """
    xy = np.asarray(xy, dtype=float)
    xy = xy - xy[0]
    chord = xy[-1]
    phi = math.atan2(chord[1], chord[0])
    rot = math.radians(theta_deg) / 2.0 - phi
    c, s = math.cos(rot), math.sin(rot)
    return (xy @ np.array([[c, s], [-s, c]])) / L


@lru_cache(maxsize=256)
def _simulated(L, h, t, w, b, E, nodes, state="released"):
    """Direct simulation of one unit: (normalised base shape, θ in degrees) of ``state``."""
    try:
        from snapmorph.units import UnitGeometry, simulate_unit
    except ImportError as exc:
        raise ValueError(f"source='simulate' needs solver.unit ({exc})") from None
    result = simulate_unit(UnitGeometry(L=L, h=h, t=t, w=w, b=b, E=E), nodes=nodes,
                           check_self_standing=(state == "released"))
    what = (f"unit L = {L * 1e3:.4g} mm, h = {h * 1e3:.4g} mm, t = {t * 1e3:.4g} mm, "
            f"w = {w * 1e3:.4g} mm")
    if not result.bistable or not math.isfinite(result.theta_deg):
        raise ValueError(f"{what} is not bistable in a direct simulation ({result.status})")
    if state == "released":
        if not result.released:
            raise ValueError(f"{what} is bistable only with its actuator glued: released, it "
                             "does not stay snapped (use state='actuated' for the held state)")
        base, theta = result.released["base_shape"], result.released["theta_deg"]
    else:
        base, theta = result.base_shape, result.theta_deg
    xy = normalise_base(base, theta, L)
    xy.setflags(write=False)
    return xy, float(theta)


def _check_b(unit: Unit, lookup: MapLookup):
    """The b/L to look the unit up at: its own on a map with a b/L axis, else None (the map's
    own, which must be the unit's)."""
    if lookup.has_b_axis:
        bL, bounds = unit.b / unit.L, lookup.bounds("b_over_L")
        if bounds is not None and not bounds[0] - 1e-12 <= bL <= bounds[1] * (1 + 1e-9):
            raise ValueError(
                f"unit b = {unit.b * 1e3:.4g} mm (b/L = {bL:.4g}) is outside the design map's b "
                f"range: b/L in [{bounds[0]:.4g}, {bounds[1]:.4g}], b in "
                f"[{bounds[0] * unit.L * 1e3:.4g}, {bounds[1] * unit.L * 1e3:.4g}] mm at its "
                f"L = {unit.L * 1e3:.4g} mm; or use source='simulate'")
        return bL
    b_map = lookup.b_over_L
    if abs(unit.b / unit.L - b_map) > 1e-6:
        raise ValueError(
            f"unit b/L = {unit.b / unit.L:.4g} but the design map was built at b/L = {b_map:.4g}; "
            "use a map built at that b/L, or source='simulate'")
