"""The design map as inverse design sees it: in one unit state, and vectorised.

`StateMap` hands every lookup the unit state (released or actuated) and, with the paper's angle
convention, answers h/L for θ by the map's theta_end = θ/2. `map_at_b` hands every lookup the
b/L of units with flat ends b (m) and strip width w (m): b/L = (b / w) w/L, a function of the
query's w/L alone, so that the callers (which know only h/L, t/L, w/L) need not change. `FastModel` computes the
all-snapped base of a sequence of units straight from the map's interpolants, vectorised over
a batch of parameter sets (the numbers of `design.kinematics.chain`); `chain_fast` is one such
base as a `Chain`.
"""

from __future__ import annotations

import math

import numpy as np


def _map_states(dm) -> tuple:
    return tuple(getattr(dm, "states", ("actuated",)))


def map_state_kw(dm, state: str) -> tuple[dict, str]:
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


class StateMap:
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


def check_b(b) -> float:
    """``b`` (extra flat length of the arch ends, m) as a float >= 0, or ValueError naming it."""
    value = math.nan
    if not isinstance(b, (bool, str, bytes)):
        try:
            value = float(b)
        except (TypeError, ValueError):
            pass
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"b (extra flat length of the arch ends, m) must be a finite number "
                         f">= 0; got {b!r}")
    return value


def map_at_b(dm, b: float, w: float):
    """The design map `dm` seen by units of flat-end length ``b`` and strip width ``w`` (m):
    every lookup gets ``b_over_L = (b / w) w_over_L``. A map without a b/L axis (its
    ``fixed_b_over_L``) is returned as it is when its b/L is that of every such unit (b = 0 on
    a b/L = 0 map); otherwise ValueError naming b and the map's b/L."""
    b = check_b(b)
    fixed = getattr(dm, "fixed_b_over_L", None)
    has_axis = "b_over_L" in tuple(getattr(dm, "dims", ()))
    if not has_axis:
        fixed = 0.0 if fixed is None else float(fixed)
        if b == 0.0 and fixed == 0.0:
            return dm
        where = getattr(dm, "path", None) or "the design map"
        raise ValueError(f"b = {b * 1e3:.6g} mm (extra flat length of the arch ends): {where} has "
                         f"no b/L axis (it was built at the one b/L = {fixed:g}); leave b out, or "
                         f"use a map with a b/L axis (schema 3, `make maps`)")
    return BMap(dm, b / w)


def b_length_min(dm, w: float) -> float:
    """The shortest unit length (m) the map's b/L range allows to units of strip width ``w``
    (m) seen through `map_at_b` (b/L = (b / w) w/L <= the map's largest b/L): 0 for a map that
    is not such a view, or at b = 0."""
    b_over_w = getattr(dm, "b_over_w", None)
    rng = getattr(dm, "ranges", None) or {}
    if not b_over_w or "b_over_L" not in rng:
        return 0.0
    return float(b_over_w) * float(w) / rng["b_over_L"][1]


class BMap:
    """A design map whose lookups get ``b_over_L = b_over_w * w_over_L`` (see `map_at_b`);
    everything else is the wrapped map's."""

    #: method -> position of its w/L argument
    _W_AT = {"at": 2, "value": 3, "base_shape": 2, "force_newtons": 2, "h_over_L_for_theta": 2,
             "h_over_L_for_theta_end": 2, "theta_range": 1, "bistable_boundary": 1}

    def __init__(self, dm, b_over_w: float):
        self._dm, self.b_over_w = dm, float(b_over_w)

    def __getattr__(self, name):
        import functools

        attr = getattr(self._dm, name)
        pos = self._W_AT.get(name)
        if pos is None or not callable(attr):
            return attr

        @functools.wraps(attr)
        def call(*args, **kw):
            w = kw["w_over_L"] if "w_over_L" in kw else args[pos]
            kw.setdefault("b_over_L", self.b_over_w * np.asarray(w, dtype=float))
            return attr(*args, **kw)
        return call


def chain_fast(units, dm, state_kw, start=(0.0, 0.0), angle: float = 0.0):
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
        model = FastModel(dm, t, w, [1] * len(arched), state_kw)
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


class FastModel:
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
