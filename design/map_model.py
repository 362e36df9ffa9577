"""The design map as inverse design sees it: in one unit state, and vectorised.

`StateMap` hands every lookup the unit state (released or actuated) and, with the paper's angle
convention, answers h/L for θ by the map's theta_end = θ/2. `FastModel` computes the
all-snapped base of a sequence of units straight from the map's interpolants, vectorised over
a batch of parameter sets (the numbers of `design.kinematics.chain`); `chain_fast` is one such
base as a `Chain`.
"""

from __future__ import annotations

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
