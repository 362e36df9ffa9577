"""Every state of an array simulated whole, against forward kinematics (issue 6).

    from snapmorph.design.array_study import paper_three_units, run_study
    study = run_study(paper_three_units(), name="three units")
    print(study.table())

For each state the simulated base (`design.arrays.simulate_array`) is compared with two
concatenations of single-unit shapes:

- ``fk``: `design.forward_kinematics(..., source="simulate")` (or ``source="map"``), the
  paper's conjecture as this project uses it — each snapped unit's state (iii) from
  `simulate_unit` or the design map, released by default (actuator and rollers removed), or
  with ``state="actuated"`` the paper's state (iii) with the actuator still on;
- ``fk_free``: the same concatenation of each unit's *released* state (iii) (one-unit array,
  actuator and rollers removed, same mesh as the array): what the conjecture predicts when the
  units do not interact.

Deviations are curve-to-curve (largest distance between the two polylines, both ways) and of the
tip, as fractions of the array length (sum of L). States are computed along a tree (each from
the state with its last snapped unit unsnapped: 2^n - 1 snaps for n arched units); the
all-snapped state is also computed in several snapping orders.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.design.arrays import PETG_E, ArrayResult, build_array, rigid_residual, simulate_array
from snapmorph.design.units import Unit
from snapmorph.units.shapes import end_tangent_angle

__all__ = ["ArrayStudy", "all_array_states", "curve_deviation", "fk_released",
           "paper_three_units", "released_shapes", "run_study", "shape_change", "table3_M_units",
           "table3_S_units", "scaled_units"]

T, W = 0.5e-3, 5e-3
#: Table 3 of the paper, M: (L, h) mm of the four arched units, the 67.3 mm spacer between
#: units 2 and 3; sides: the paper says only that units 3 and 4 are on opposite sides; these
#: follow the M's turns walking from its left end (right, right, straight, left, right)
TABLE3_M = ((72.6, 6.9, -1), (73.8, 11.3, -1), (67.3, 0.0, 0), (129.4, 21.1, 1), (133.2, 31.3, -1))


def paper_three_units(b: float | None = None) -> list:
    """The paper's three identical units (t 0.5, h 20, w 5, L 100 mm), arches on +z; b (m)
    defaults to w, as the specimens of the forward-kinematics experiment."""
    b = W if b is None else b
    return [Unit(L=0.1, h=0.02, t=T, w=W, side=1, b=b)] * 3


def table3_M_units(b_over_L: float = 0.0) -> list:
    """The paper's inverse-designed M (Table 3): four arched units of different sizes on both
    sides and a spacer; b = b_over_L L (0: the parametric study's, and the design maps')."""
    out = []
    for L, h, side in TABLE3_M:
        L, h = L * 1e-3, h * 1e-3
        out.append(Unit(L=L, h=h, t=T, w=W, side=side, b=b_over_L * L if h > 0 else 0.0))
    return out


#: Table 3 of the paper, S: eight units of (L, h) = (106.7, 25.8) mm, four on each side of the
#: base, one arm per side; the paper's S has a straight between its arms, of a length it does
#: not give: 100 mm, as `design.paper.S_STRAIGHT` (our S target)
TABLE3_S = (106.7, 25.8)
TABLE3_S_STRAIGHT = 100.0


def table3_S_units(b_over_L: float = 0.0, straight: bool = True) -> list:
    """The paper's inverse-designed S (Table 3): four units (106.7, 25.8) mm with arches on
    +z, a 100 mm spacer (``straight``), four with arches on -z; t 0.5, w 5 mm, b = b_over_L L."""
    L, h = TABLE3_S[0] * 1e-3, TABLE3_S[1] * 1e-3
    arm = [Unit(L=L, h=h, t=T, w=W, side=s, b=b_over_L * L) for s in (1, -1)]
    middle = [Unit(L=TABLE3_S_STRAIGHT * 1e-3, h=0.0, t=T, w=W, side=0, b=0.0)] if straight else []
    return [arm[0]] * 4 + middle + [arm[1]] * 4


def scaled_units(units, factor: float) -> list:
    """``units`` with every length (L, h, t, w, b) times ``factor``: the same shapes, the
    weight per length ~ factor^2 against EI ~ factor^4, so self-weight counts factor times
    more (q L^3 / EI ~ factor)."""
    return [Unit(L=u.L * factor, h=u.h * factor, t=u.t * factor, w=u.w * factor, side=u.side,
                 b=u.b * factor) for u in units]


# ---------------------------------------------------------------------------- comparisons
def curve_deviation(a, b, length: float, n: int = 2000) -> float:
    """Largest distance between polylines a and b (m), both ways, over ``length`` (m): n points
    spread evenly along each are measured against the other polyline."""
    from snapmorph.design.targets import distances_to_polyline, resample

    da = distances_to_polyline(resample(np.asarray(a, float), n), np.asarray(b, float))
    db = distances_to_polyline(resample(np.asarray(b, float), n), np.asarray(a, float))
    return float(max(da.max(), db.max())) / length


def released_shapes(units, nodes=None, E: float = PETG_E, coincident_ties: bool = True):
    """{unit index: (UnitShape of the released state iii, SnapRecord)} for every arched unit,
    from one-unit arrays (one simulation per distinct unit). Raises ValueError when a unit does
    not stay snapped alone."""
    from snapmorph.design.shapes import UnitShape

    cache, out = {}, {}
    for i, u in enumerate(units):
        if u.is_spacer:
            continue
        if u not in cache:
            model = build_array([u], nodes=nodes, E=E, coincident_ties=coincident_ties)
            r = simulate_array([u], [True], model=model)
            if r.status != "ok":
                raise ValueError(f"unit {i + 1} alone: {r.status}")
            cache[u] = (UnitShape(r.base.copy(), float(r.angles[-1])), r.snaps[0])
        out[i] = cache[u]
    return out


def fk_released(units, snapped, shapes) -> np.ndarray:
    """Concatenation (K, 2) m of straight unsnapped units and the released shapes of the
    snapped ones (`released_shapes`), from (0, 0) heading +x."""
    from snapmorph.design.kinematics import place
    from snapmorph.design.shapes import straight

    return place([shapes[i][0] if s else straight(u.L)
                  for i, (u, s) in enumerate(zip(units, snapped))]).xy


def all_array_states(units, nodes=None, E: float = PETG_E, coincident_ties: bool = True,
                     model=None) -> dict:
    """{state string: ArrayResult} of every state, each from its parent state (the same state
    with its last snapped unit unsnapped): one snap per state. Spacers stay '0'."""
    model = model or build_array(units, nodes=nodes, E=E, coincident_ties=coincident_ties)
    n = len(model.units)
    arched = [i for i, u in enumerate(model.units) if not u.is_spacer]
    out = {}
    for bits in itertools.product((0, 1), repeat=len(arched)):
        flags = [False] * n
        for i, b in zip(arched, bits):
            flags[i] = bool(b)
        key = "".join("1" if f else "0" for f in flags)
        on = [i for i in arched if flags[i]]
        if not on:
            out[key] = simulate_array(model.units, flags, model=model)
            continue
        parent = list(flags)
        parent[on[-1]] = False
        pkey = "".join("1" if f else "0" for f in parent)
        out[key] = simulate_array(model.units, flags, model=model, start=out[pkey])
        out[key].time += out[pkey].time
    return out


def _orders(arched, limit=6):
    """Snapping orders of the all-snapped state: every permutation up to 3 arched units, else
    ascending, descending, evens first, odds first (and at most ``limit``)."""
    if len(arched) <= 3:
        return [tuple(p) for p in itertools.permutations(arched)]
    cand = [tuple(arched), tuple(reversed(arched)), tuple(arched[0::2] + arched[1::2]),
            tuple(arched[1::2] + arched[0::2])]
    seen = []
    for c in cand:
        if c not in seen:
            seen.append(c)
    return seen[:limit]


# ---------------------------------------------------------------------------- the study
@dataclass
class StateRow:
    """One state: deviations of the simulated base from fk / fk_free as fractions of the array
    length (curve: largest curve-to-curve distance; tip: end point), end-direction difference
    (deg), wall time of the snaps that made it (s, cumulative along the tree)."""

    state: str
    status: str
    dev_fk: float
    tip_fk: float
    angle_fk_deg: float
    dev_free: float
    tip_free: float
    time: float


@dataclass
class ArrayStudy:
    """Result of `run_study` (SI; deviations as fractions of `length`)."""

    name: str
    units: list
    length: float
    states: dict
    fk: dict
    fk_free: dict
    rows: list
    units_table: list
    orders: dict
    order_spread: float  # m, largest node distance between the all-snapped results of the orders
    neighbour_change: float  # m, largest change of a unit's shape when another one snapped
    neighbour_change_peak: float  # m, the same at the actuator's peak force
    times: dict = field(default_factory=dict)

    def __repr__(self):
        bad = sum(r.status != "ok" for r in self.rows)
        worst = max((r.dev_fk for r in self.rows if np.isfinite(r.dev_fk)), default=float("nan"))
        return (f"ArrayStudy({self.name!r}: {len(self.units)} units, {len(self.rows)} states, "
                f"{bad} not ok, largest deviation from FK {worst:.2e} of the length)")

    @property
    def ok(self) -> bool:
        return all(r.status == "ok" for r in self.rows) and all(
            r.status == "ok" for r in self.orders.values())

    def table(self) -> str:
        """Markdown: units, states, orders, timings."""
        L = self.length
        lines = [f"### {self.name}: {len(self.units)} units, array length {L * 1e3:.1f} mm", "",
                 "| unit | L mm | h mm | b mm | side | θ of the FK unit (°) "
                 "| θ held, array mesh (°) | θ released (°) | F_cr (N) |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for r in self.units_table:
            lines.append(f"| {r['unit']} | {r['L'] * 1e3:.1f} | {r['h'] * 1e3:.1f} | "
                         f"{r['b'] * 1e3:.1f} | {r['side']:+d} | {r['theta_simulate']:.3f} | "
                         f"{r['theta_held']:.3f} | {r['theta_released']:.3f} | {r['F_cr']:.4f} |")
        lines += ["", "| state | status | vs FK: curve | tip | end angle (°) | "
                  "vs released-unit FK: curve | tip | time from flat (s) |",
                  "|---|---|---|---|---|---|---|---|"]
        for r in self.rows:
            lines.append(f"| {r.state} | {r.status} | {r.dev_fk:.2e} | {r.tip_fk:.2e} | "
                         f"{r.angle_fk_deg:+.3f} | {r.dev_free:.1e} | {r.tip_free:.1e} | "
                         f"{r.time:.2f} |")
        lines += ["", f"Snapping orders of the all-snapped state ({len(self.orders)}): "
                  + ", ".join("-".join(str(k) for k in o) for o in self.orders)
                  + f" (0-based); largest distance between their bases' nodes: "
                  f"{self.order_spread:.1e} m ({self.order_spread / L:.1e} of the length).",
                  f"Largest change of another unit's shape (base and arch nodes, rigid motion "
                  f"removed) when a unit snaps: {self.neighbour_change:.1e} m after the release, "
                  f"{self.neighbour_change_peak:.1e} m at the actuator's peak force.",
                  "Wall time: " + ", ".join(f"{k} {v:.2f} s" for k, v in self.times.items())
                  + "."]
        return "\n".join(lines)

    def summary(self) -> dict:
        """Plain numbers (JSON-ready)."""
        return {
            "name": self.name,
            "length_m": self.length,
            "units": self.units_table,
            "states": [r.__dict__ for r in self.rows],
            "max_dev_fk": max(r.dev_fk for r in self.rows),
            "max_dev_free": max(r.dev_free for r in self.rows),
            "orders": [list(o) for o in self.orders],
            "order_spread_m": self.order_spread,
            "neighbour_change_m": self.neighbour_change,
            "neighbour_change_peak_m": self.neighbour_change_peak,
            "times_s": self.times,
        }


def run_study(units, name: str = "array", nodes=None, E: float = PETG_E, orders=None,
              coincident_ties: bool = True, fk: bool = True, source: str = "simulate",
              state: str = "released", design_map=None) -> ArrayStudy:
    """Simulate every state of ``units`` and compare with forward kinematics; also the
    all-snapped state in several ``orders`` (tuples of 0-based indices; default `_orders`).
    ``fk=False`` skips forward kinematics (NaN deviations); ``source``: "simulate" (each unit
    by `simulate_unit` at the array's resolution) or "map" (``design_map``, default map);
    ``state``: "released" (default) or "actuated" single units."""
    from snapmorph.design.kinematics import chain
    from snapmorph.design.lookup import MapLookup

    units = list(units)
    t_all = time.perf_counter()
    model = build_array(units, nodes=nodes, E=E, coincident_ties=coincident_ties)
    length = model.length
    t0 = time.perf_counter()
    states = all_array_states(units, model=model)
    t_states = time.perf_counter() - t0

    t0 = time.perf_counter()
    shapes = released_shapes(units, nodes=nodes, E=E, coincident_ties=coincident_ties)
    t_single = time.perf_counter() - t0
    t0 = time.perf_counter()
    fk_xy, thetas = {}, {}
    fk_kw = (dict(source="simulate", nodes=model.nodes, E=E, state=state) if source == "simulate"
             else dict(source="map", state=state,
                       lookup=None if design_map is None else MapLookup(design_map)))
    if fk:
        full = chain(units, [not u.is_spacer for u in units], **fk_kw)
        turns = np.degrees(np.diff(full.angles))
        thetas = {i: abs(float(turns[i])) for i in shapes}
    rows, free_xy = [], {}
    for key, res in states.items():
        flags = [c == "1" for c in key]
        free_xy[key] = fk_released(units, flags, shapes)
        nan = float("nan")
        dev_fk = tip_fk = ang = nan
        if fk:
            ch = chain(units, flags, **fk_kw)
            fk_xy[key] = ch.xy
            dev_fk = curve_deviation(res.base, ch.xy, length)
            tip_fk = float(np.hypot(*(res.base[-1] - ch.xy[-1]))) / length
            ang = math.degrees(float(res.angles[-1] - ch.angles[-1]))
        rows.append(StateRow(key, res.status, dev_fk, tip_fk, ang,
                             curve_deviation(res.base, free_xy[key], length),
                             float(np.hypot(*(res.base[-1] - free_xy[key][-1]))) / length,
                             res.time))
    t_fk = time.perf_counter() - t0

    t0 = time.perf_counter()
    arched = [i for i, u in enumerate(units) if not u.is_spacer]
    all_on = "".join("0" if u.is_spacer else "1" for u in units)
    orders = [tuple(o) for o in (orders or _orders(arched))]
    by_order = {}
    for o in orders:
        by_order[o] = (states[all_on] if list(o) == arched
                       else simulate_array(units, all_on, order=o, model=model))
    spread = 0.0
    ref = states[all_on].positions
    for r in by_order.values():
        spread = max(spread, float(np.max(np.hypot(*(r.positions - ref).T))))
    t_orders = time.perf_counter() - t0

    snaps = [s for r in list(states.values()) + list(by_order.values()) for s in r.snaps]
    change = max((float(np.nanmax(s.neighbour_change)) for s in snaps
                  if s.neighbour_change is not None and len(units) > 1), default=0.0)
    change_peak = max((float(np.nanmax(s.neighbour_change_peak)) for s in snaps
                       if s.neighbour_change_peak is not None and len(units) > 1), default=0.0)

    table = []
    for i, (shape, rec) in shapes.items():
        u = units[i]
        table.append(dict(unit=i + 1, L=u.L, h=u.h, b=u.b, side=u.side,
                          theta_simulate=thetas.get(i, float("nan")),
                          # a one-unit array numbers its base nodes first
                          theta_held=abs(end_tangent_angle(rec.held[:len(shape.xy)])),
                          theta_released=abs(rec.turn_deg), F_cr=rec.F_cr))
    times = {"states": t_states, "single units": t_single, "forward kinematics": t_fk,
             "orders": t_orders, "total": time.perf_counter() - t_all}
    return ArrayStudy(name, units, length, states, fk_xy, free_xy, rows, table, by_order,
                      spread, change, change_peak, times)


def shape_change(a: ArrayResult, b: ArrayResult, unit: int) -> float:
    """Change (m) of unit ``unit``'s shape between two results of the same model, rigid motion
    removed."""
    m = a.model.meshes[unit]
    idx = np.concatenate([m.base, m.arch])
    return rigid_residual(a.positions[idx], b.positions[idx])
