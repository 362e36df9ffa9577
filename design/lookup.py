"""What design needs from a design map, behind one small adapter.

`MapLookup` wraps a `maps.DesignMap` (the only reader of the map files) and adds the few things
inverse design asks that the map does not answer directly: θ and S/L of a unit as plain floats,
the θ range in which units are bistable at given t/L and w/L, and the unit whose snapped base
turns by a given angle over a given chord (the fixed point in L, since t/L and w/L depend on L).
Everything here is dimensionless except `unit_for_arc` (SI).

Every lookup takes ``state=``: "released" (state (iii) with the actuator and rollers removed,
the unit as used in an array; the default) or "actuated" (the actuator still glued, the
paper's definition); None means the lookup's own default (`MapLookup(dm, state=...)`), and
when that is None too the map's default (released) — the state is then not passed to the map,
so a wrapped map may set it.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

_DEFAULT = {}


def default_map():
    """The committed default design map, loaded once (`maps.DesignMap.load()`)."""
    if "map" not in _DEFAULT:
        try:
            from snapmorph.maps import DesignMap
        except ImportError as exc:  # maps/ not built yet
            raise ValueError(f"no design map available (maps.DesignMap: {exc})") from None
        try:
            _DEFAULT["map"] = DesignMap.load()
        except OSError as exc:
            raise ValueError(f"no design map available: {exc}") from None
    return _DEFAULT["map"]


def load_map(path=None):
    """A design map from `path` (None: the default map); ValueError when it cannot be read."""
    if path is None:
        return default_map()
    from pathlib import Path

    if not Path(path).is_file():
        raise ValueError(f"design map not found: {path}")
    try:
        from snapmorph.maps import DesignMap
    except ImportError as exc:
        raise ValueError(f"cannot read design maps (maps.DesignMap: {exc})") from None
    try:
        return DesignMap.load(path)
    except OSError as exc:
        raise ValueError(f"cannot read design map {path}: {exc}") from None


STATES = ("released", "actuated")


def check_state(state) -> str:
    """``state`` if it is "released" or "actuated", else ValueError."""
    if not isinstance(state, str) or state not in STATES:
        raise ValueError(f"state must be 'released' (the unit with its actuator removed, the "
                         f"default) or 'actuated' (actuator still glued); got {state!r}")
    return state


class MapLookup:
    """Scalar lookups on a design map, cached; `dm` follows the `maps.DesignMap` API.

    ``state``: the default state of every lookup ("released" or "actuated"; None: the map's
    default, released)."""

    def __init__(self, dm=None, state: str | None = None):
        self.state = None if state is None else check_state(state)
        self.dm = default_map() if dm is None else dm
        self._scalar = lru_cache(maxsize=65536)(self._scalar_uncached)
        self._shape = lru_cache(maxsize=4096)(self._shape_uncached)
        self._range = lru_cache(maxsize=1024)(self._theta_range_uncached)
        self._arc = lru_cache(maxsize=16384)(self._unit_for_arc_uncached)

    # --- map metadata -----------------------------------------------------------------------
    @property
    def b_over_L(self) -> float:
        """The b/L the map answers at when a lookup names none: the one it was built at (0
        when the map does not say; 0 on a map with a b/L axis, `maps.DEFAULT_B_OVER_L`)."""
        value = _attrs(self.dm).get("b_over_L", 0.0)
        return float(value)

    @property
    def has_b_axis(self) -> bool:
        """Whether the map interpolates in b/L (a lookup may then name any b/L in its range)."""
        return "b_over_L" in tuple(getattr(self.dm, "dims", ()))

    def grid(self, name: str):
        """The coordinate values of `name` (h_over_L, t_over_L, w_over_L) or None if unknown."""
        for holder in ("ds", "dataset", "_ds", "data"):
            ds = getattr(self.dm, holder, None)
            if ds is not None and hasattr(ds, "coords") and name in ds.coords:
                return np.asarray(ds.coords[name].values, dtype=float)
        value = getattr(self.dm, name, None)
        if value is not None:
            try:
                return np.asarray(value, dtype=float).ravel()
            except (TypeError, ValueError):
                return None
        return None

    def bounds(self, name: str):
        """(min, max) of a map coordinate, or None if the map does not expose it."""
        g = self.grid(name)
        if g is None or g.size == 0:
            return None
        return float(np.min(g)), float(np.max(g))

    def _st(self, state):
        return self.state if state is None else check_state(state)

    @staticmethod
    def _kw(state) -> dict:
        return {} if state is None else {"state": state}

    # --- lookups ----------------------------------------------------------------------------
    def theta_S(self, h_over_L: float, t_over_L: float, w_over_L: float, state=None,
                b_over_L=None):
        """(θ in degrees, S/L) of the snapped unit in ``state``; ValueError outside the map or
        if not bistable there (for the released state: if the released unit is not).
        ``b_over_L``: None for the map's own (`b_over_L`), else a map with a b/L axis."""
        return self._scalar(_r(h_over_L), _r(t_over_L), _r(w_over_L), self._st(state),
                            _rb(b_over_L))[:2]

    def theta_end(self, h_over_L: float, t_over_L: float, w_over_L: float, state=None) -> float:
        """θ_end in degrees (angle between the base's start tangent and its chord, θ/2 for a
        symmetric base) of the snapped unit in ``state``."""
        value = self._scalar(_r(h_over_L), _r(t_over_L), _r(w_over_L), self._st(state))[2]
        if not math.isfinite(value):
            raise ValueError(f"the design map has no theta_end at h/L = {h_over_L:.4g}, "
                             f"t/L = {t_over_L:.4g}, w/L = {w_over_L:.4g} (a schema-1 map?)")
        return value

    def base_shape(self, h_over_L: float, t_over_L: float, w_over_L: float,
                   state=None, b_over_L=None) -> np.ndarray:
        """Snapped base shape per unit length, (M, 2), from (0, 0) heading +x, arch side +z."""
        return self._shape(_r(h_over_L), _r(t_over_L), _r(w_over_L), self._st(state),
                           _rb(b_over_L))

    def h_over_L_for_theta(self, theta_deg: float, t_over_L: float, w_over_L: float,
                           state=None, angle: str = "theta") -> float:
        """h/L of the unit turning by θ (degrees, > 0) at the given t/L and w/L in ``state``;
        ``angle="theta_end"``: of the unit whose θ_end is ``theta_deg``."""
        state = self._st(state)
        kw = self._kw(state)
        if angle != "theta":
            kw["angle"] = angle
        value = self.dm.h_over_L_for_theta(theta_deg=float(theta_deg), t_over_L=float(t_over_L),
                                           w_over_L=float(w_over_L), **kw)
        value = float(np.asarray(value))
        if not math.isfinite(value):
            raise ValueError(f"{angle} = {theta_deg:.3g}° is not reached by any bistable unit of "
                             f"the map at t/L = {t_over_L:.4g}, w/L = {w_over_L:.4g} ({state or 'released'})")
        return value

    def h_over_L_for_theta_end(self, theta_end_deg: float, t_over_L: float, w_over_L: float,
                               state=None) -> float:
        """h/L of the unit whose θ_end (end tangent to chord, degrees) is ``theta_end_deg``."""
        return self.h_over_L_for_theta(theta_end_deg, t_over_L, w_over_L, state=state,
                                       angle="theta_end")

    def theta_range(self, t_over_L: float, w_over_L: float, state=None):
        """(θ_min, θ_max, h/L at θ_min, h/L at θ_max) over the bistable units of the map at
        t/L, w/L: θ_min is where units stop being bistable. ValueError if there are none."""
        return self._range(_r(t_over_L, 5), _r(w_over_L, 5), self._st(state))

    # --- uncached implementations -----------------------------------------------------------
    def _scalar_uncached(self, h, t, w, state, b=None):
        try:
            res = self.dm.at(h_over_L=h, t_over_L=t, w_over_L=w, **self._kw(state), **_kw_b(b))
        except (ValueError, KeyError, IndexError) as exc:
            raise ValueError(f"unit h/L = {h:.4g}, t/L = {t:.4g}, w/L = {w:.4g}: {exc}") from None
        theta, S = _get(res, "theta"), _get(res, "S")
        try:
            theta_end = _get(res, "theta_end")
        except (AttributeError, KeyError):
            theta_end = math.nan
        if not (math.isfinite(theta) and math.isfinite(S)):
            raise ValueError(f"unit h/L = {h:.4g}, t/L = {t:.4g}, w/L = {w:.4g} is not bistable "
                             f"in the design map ({state or 'released'} state)")
        return theta, S, theta_end

    def _shape_uncached(self, h, t, w, state, b=None):
        try:
            xy = self.dm.base_shape(h_over_L=h, t_over_L=t, w_over_L=w, **self._kw(state),
                                    **_kw_b(b))
        except (ValueError, KeyError, IndexError) as exc:
            raise ValueError(f"unit h/L = {h:.4g}, t/L = {t:.4g}, w/L = {w:.4g}: {exc}") from None
        xy = np.array(np.asarray(xy, dtype=float), copy=True)
        if xy.ndim != 2 or xy.shape[1] != 2 or not np.all(np.isfinite(xy)):
            raise ValueError(f"unit h/L = {h:.4g}, t/L = {t:.4g}, w/L = {w:.4g}: the map has no "
                             "base shape there (monostable or failed point)")
        xy.setflags(write=False)
        return xy

    def _theta_range_uncached(self, t, w, state):
        # Interpolation cells touching a monostable grid point are undefined, so the bistable
        # range is bounded by grid nodes: scanning the nodes is enough.
        self._check_b(w)
        hs = self.grid("h_over_L")
        if hs is None or hs.size < 2:
            hs = np.linspace(0.01, 0.6, 119)
        ok = []
        for h in hs:
            try:
                theta, _ = self.theta_S(h, t, w, state=state)
            except ValueError:
                continue
            if theta > 0:
                ok.append((theta, h))
        if not ok:
            raise ValueError(f"the design map has no bistable unit at t/L = {t:.4g}, w/L = {w:.4g}"
                             + _range_hint(self, t, w))
        lo = min(ok)
        hi = max(ok)
        return lo[0], hi[0], lo[1], hi[1]

    # --- a unit for a circular arc -----------------------------------------------------------
    def unit_for_arc(self, theta_deg: float, chord: float, t: float, w: float, state=None):
        """(L, h) in m of the unit whose snapped base turns by |θ| (degrees) over chord S (m);
        see `_unit_for_arc_uncached`."""
        return self._arc(_r(abs(theta_deg)), _r(chord), _r(t), _r(w), self._st(state))

    def _unit_for_arc_uncached(self, theta_deg: float, chord: float, t: float, w: float,
                               state: str | None = None, tol: float = 1e-10, max_iter: int = 50):
        """(L, h) in m of the unit whose snapped base turns by |θ| (degrees) over chord S (m).

        θ → h/L by inverting the map at t/L, w/L; L = S / (S/L). t/L and w/L depend on L, so the
        two steps are repeated until L stops changing (a contraction: S/L and θ barely depend on
        t/L and w/L).
        """
        theta = abs(float(theta_deg))
        L = float(chord)  # S/L is 0.5-1: the chord is a good first guess
        for _ in range(max_iter):
            t_L, w_L = t / L, w / L
            self._check_tw(t_L, w_L, L)
            h_L = self.h_over_L_for_theta(theta, t_L, w_L, state=state)
            _, S_L = self.theta_S(h_L, t_L, w_L, state=state)
            L_new = chord / S_L
            if abs(L_new - L) <= tol * L:
                L = L_new
                break
            L = L_new
        else:
            raise ValueError(f"no fixed point for the unit turning {theta:.3g}° over "
                             f"{chord * 1e3:.4g} mm (L did not settle)")
        h_L = self.h_over_L_for_theta(theta, t / L, w / L, state=state)
        return L, h_L * L

    def _check_tw(self, t_L, w_L, L):
        for name, value, what in (("t_over_L", t_L, "t"), ("w_over_L", w_L, "w")):
            b = self.bounds(name)
            if b is not None and not (b[0] * (1 - 1e-9) <= value <= b[1] * (1 + 1e-9)):
                raise ValueError(
                    f"a unit of L = {L * 1e3:.4g} mm has {what}/L = {value:.4g}, outside the map's "
                    f"{what}/L range [{b[0]:.4g}, {b[1]:.4g}]; change {what} or the target's size")
        self._check_b(w_L, L)

    def _check_b(self, w_L, L=None):
        """On a map seen at flat ends b (`map_model.map_at_b`: b/L = (b / w) w/L), ValueError
        naming b when the b/L of a unit of this w/L (and length L, m) is outside the map's."""
        b_over_w = getattr(self.dm, "b_over_w", None)
        bounds = self.bounds("b_over_L")
        if not b_over_w or bounds is None:
            return
        value = b_over_w * w_L
        if bounds[0] - 1e-12 <= value <= bounds[1] * (1 + 1e-9):
            return
        unit = "a unit" if L is None else f"a unit of L = {L * 1e3:.4g} mm"
        raise ValueError(
            f"{unit} (w/L = {w_L:.4g}) has b/L = {value:.4g} with its flat ends b, outside the "
            f"map's b/L range [{bounds[0]:.4g}, {bounds[1]:.4g}] (units need L >= "
            f"b / {bounds[1]:.4g}); give a smaller b or scale the target up")


def _r(x, digits=12):
    """Round a key for caching (12 significant digits: no effect on the numbers)."""
    return float(f"{float(x):.{digits}g}")


def _rb(b):
    """A b/L cache key: None (the map's own b/L) or the rounded value."""
    return None if b is None else _r(b)


def _kw_b(b) -> dict:
    """The map keyword of a lookup's b/L (none for the map's own)."""
    return {} if b is None else {"b_over_L": b}


def _get(res, name) -> float:
    """A scalar variable from whatever `DesignMap.at` returns (mapping, Dataset or object)."""
    try:
        value = res[name]
    except (TypeError, KeyError, IndexError):
        value = getattr(res, name)
    value = getattr(value, "values", value)
    return float(np.asarray(value, dtype=float).reshape(-1)[0])


def _attrs(dm) -> dict:
    for holder in ("attrs",):
        a = getattr(dm, holder, None)
        if isinstance(a, dict):
            return a
    for holder in ("ds", "dataset", "_ds", "data"):
        ds = getattr(dm, holder, None)
        if ds is not None and isinstance(getattr(ds, "attrs", None), dict):
            return ds.attrs
    return {}


def _range_hint(lookup, t, w) -> str:
    parts = []
    for name, value in (("t_over_L", t), ("w_over_L", w)):
        b = lookup.bounds(name)
        if b is not None:
            parts.append(f"{name} range [{b[0]:.4g}, {b[1]:.4g}]")
    return f" (map {', '.join(parts)})" if parts else ""
