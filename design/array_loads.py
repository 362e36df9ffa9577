"""A morphed array under its own weight and external loads: sag, whether every unit keeps
its state, and the load at which the first unit snaps back (issue 23, part B).

    from snapmorph.design.arrays import simulate_array
    r = simulate_array(units, gravity=True, orientation="upright", material="petg",
                       loads=[ArrayLoad(unit=2, where="apex", force=(0.0, -0.05))])
    r.loaded.sag, r.loaded.holds, r.loaded.limit_factor, r.loaded.strain_max

The frame is the array's (`ArrayResult.base`): the first base edge clamped at the origin
heading +x, z normal to it in the array's plane. Orientation says where gravity points in
that frame:

- "upright": the array stands in a vertical plane, its clamped edge horizontal, gravity
  (0, -1) in its plane (in-plane bending; the paper could not test this);
- an angle a (degrees): the array turned about the clamp, gravity (sin a, -cos a) -- 0 is
  upright, 90 hangs from the clamp, -90 stands on it;
- "sideways": the paper's lay-flat array, gravity normal to its plane. The planar model
  carries no load from it (sag 0, nothing changes); out-of-plane sag and the table's
  friction are not modelled. External loads (in the plane) still act.

External loads are `ArrayLoad(unit, where, force)`: a force (fx, fz) in N in the array
frame on unit ``unit`` (0-based) at its apex ("apex", the arch's top node) or the end of
its base ("end"; the free end for the last unit). Loads and self-weight are dead loads of
the clamped array (`solver.Structure.add_gravity`, `add_load`, docs/loads.md), followed
from the unloaded morphed state by `Structure.follow_load`: to factor 1 (the sag, the
states held, the strain), then on to ``max_factor`` to find the factor at which the first
unit snaps back (the first limit point of the load factor, or the first change of a unit's
state without one). A unit's state is the side of its support chord its apex is on
(`apex_heights`): above on its arch's side in state (i), through the base when snapped.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.design.strains import unit_strains

__all__ = ["ArrayLoad", "LoadedArray", "apex_heights", "gravity_direction", "load_array",
           "resolve_material", "ORIENTATIONS", "DEFAULT_MAX_FACTOR"]

ORIENTATIONS = ("upright", "sideways")
#: how far past the loads (factor 1) the snap-back is looked for, by default
DEFAULT_MAX_FACTOR = 10.0
G = 9.81  # m/s^2


@dataclass(frozen=True)
class ArrayLoad:
    """A dead load on the array: ``force`` (fx, fz) N in the array frame on unit ``unit``
    (0-based) at ``where`` = "apex" (its arch's top node) or "end" (the end of its base)."""

    unit: int
    where: str = "apex"
    force: tuple = (0.0, 0.0)


def gravity_direction(orientation) -> np.ndarray | None:
    """Unit vector of gravity in the array frame for ``orientation`` ("upright", "sideways"
    or an angle in degrees; module doc); None for "sideways" (normal to the plane)."""
    if isinstance(orientation, str):
        if orientation not in ORIENTATIONS:
            raise ValueError(f"orientation must be 'upright', 'sideways' or an angle in degrees "
                             f"(-360 to 360); got {orientation!r}")
        return None if orientation == "sideways" else np.array([0.0, -1.0])
    if isinstance(orientation, (bool, np.bool_)) or not isinstance(orientation, (int, float, np.number)):
        raise ValueError(f"orientation must be 'upright', 'sideways' or an angle in degrees "
                         f"(-360 to 360); got {orientation!r}")
    a = float(orientation)
    if not (math.isfinite(a) and -360.0 <= a <= 360.0):
        raise ValueError(f"orientation (an angle) must be in degrees, -360 to 360; got {orientation!r}")
    a = math.radians(a)
    return np.array([math.sin(a), -math.cos(a)])


def resolve_material(material):
    """A `solver.materials.Material` from itself or a preset name; None stays None."""
    if material is None:
        return None
    from snapmorph.solver.materials import material as lookup

    return lookup(material)


def check_gravity(gravity) -> float:
    """g (m/s^2) from ``gravity``: None/False 0, True 9.81, or a number >= 0."""
    if gravity is None or gravity is False:
        return 0.0
    if gravity is True:
        return G
    if isinstance(gravity, (np.bool_,)) or not isinstance(gravity, (int, float, np.number)):
        raise ValueError(f"gravity must be True, False or g in m/s^2 (>= 0, e.g. 9.81); "
                         f"got {gravity!r}")
    g = float(gravity)
    if not (math.isfinite(g) and 0.0 <= g <= 1e4):
        raise ValueError(f"gravity (g) must be in m/s^2, 0 <= g <= 1e4; got {gravity!r}")
    return g


def check_loads(loads, units) -> list:
    """The loads as a list of `ArrayLoad`, checked against the array's ``units`` (ValueError
    naming the entry and the valid range)."""
    if loads is None:
        return []
    if isinstance(loads, ArrayLoad):
        loads = [loads]
    out = []
    n = len(units)
    for k, ld in enumerate(loads):
        if not isinstance(ld, ArrayLoad):
            raise ValueError(f"loads[{k}] must be an ArrayLoad(unit, where, force); got {ld!r}")
        if isinstance(ld.unit, bool) or not isinstance(ld.unit, (int, np.integer)) \
                or not 0 <= ld.unit < n:
            raise ValueError(f"loads[{k}].unit must be a unit index 0 .. {n - 1} (0-based); "
                             f"got {ld.unit!r}")
        if ld.where not in ("apex", "end"):
            raise ValueError(f"loads[{k}].where must be 'apex' or 'end'; got {ld.where!r}")
        if ld.where == "apex" and units[ld.unit].is_spacer:
            raise ValueError(f"loads[{k}]: unit {ld.unit + 1} is a spacer (no apex); use "
                             "where='end'")
        f = np.asarray(ld.force, dtype=float) if not isinstance(ld.force, str) else None
        if f is None or f.shape != (2,) or not np.all(np.isfinite(f)):
            raise ValueError(f"loads[{k}].force must be (fx, fz), two finite numbers in N; "
                             f"got {ld.force!r}")
        out.append(ld)
    return out


def load_node(model, load: ArrayLoad) -> int:
    """The node of ``model`` a load acts on."""
    m = model.meshes[load.unit]
    return int(m.apex if load.where == "apex" else m.base[-1])


def apex_heights(model, positions) -> np.ndarray:
    """(n_units,) each arched unit's apex height above the chord of its two support nodes,
    towards its arch's side, over h (about +1 in state (i), negative when snapped; NaN for a
    spacer)."""
    P = np.asarray(positions, float)
    out = np.full(len(model.units), np.nan)
    for i, (u, m) in enumerate(zip(model.units, model.meshes)):
        if u.is_spacer:
            continue
        s0, s1 = P[m.supports[0]], P[m.supports[1]]
        ex = (s1 - s0) / np.hypot(*(s1 - s0))
        out[i] = u.side * float(np.array([-ex[1], ex[0]]) @ (P[m.apex] - s0)) / u.h
    return out


@dataclass
class LoadedArray:
    """The array under its dead loads (SI; module doc). status: "held" (factor 1 carried,
    every unit in its state, stable), "lost: ..." (a unit changed state, or the array does
    not carry its loads), "sideways: ..." (no in-plane load), "no loads" or a path failure
    ("not converged: ..."); holds: status "held" or "sideways"/"no loads"; positions:
    (n_nodes, 2) at factor 1 (or the last state reached); sag: (2,) m, the free end's
    displacement from the unloaded morphed shape; held: (n_units,) each unit kept its state
    (spacers True); heights: apex heights / h unloaded and loaded (`apex_heights`);
    strains: [(strain, where)] per unit at factor 1 and ``strains_unloaded``;
    limit_factor: the load factor at which the first unit snaps back (None: none up to
    ``max_factor``), limit_unit (0-based), limit_load = limit_factor x total_load (N);
    total_load: sum of |f| of the dead loads at factor 1 (N; the weight plus the loads);
    path, search: the `solver.Path` to factor 1 and on to max_factor."""

    orientation: object
    gravity: np.ndarray | None
    g: float
    material: object
    loads: list
    status: str
    positions: np.ndarray
    sag: np.ndarray
    held: np.ndarray
    heights: tuple
    strains: list
    strains_unloaded: list
    total_load: float = 0.0
    max_factor: float = DEFAULT_MAX_FACTOR
    limit_factor: float | None = None
    limit_unit: int | None = None
    limit_kind: str = ""
    path: object = None
    search: object = None
    time: float = 0.0
    notes: list = field(default_factory=list)

    @property
    def holds(self) -> bool:
        return self.status == "held" or self.status.startswith(("sideways", "no loads"))

    @property
    def sag_m(self) -> float:
        """|sag| (m)."""
        return float(np.hypot(*self.sag))

    @property
    def limit_load(self) -> float | None:
        """N: the limit load factor times the total dead load."""
        return None if self.limit_factor is None else self.limit_factor * self.total_load

    @property
    def strain_max(self) -> float:
        """The largest surface strain at factor 1 (dimensionless)."""
        return max((s for s, _ in self.strains), default=0.0)

    def strain_where(self) -> str:
        """"unit k: arch|base, start|middle|end" of `strain_max` (1-based unit)."""
        i = int(np.argmax([s for s, _ in self.strains]))
        return f"unit {i + 1}: {self.strains[i][1]}"

    def __repr__(self):
        lim = "none" if self.limit_factor is None else f"{self.limit_factor:.4g}"
        return (f"LoadedArray({self.status.split(':')[0]!r}, sag {self.sag_m * 1e3:.3f} mm, "
                f"limit factor {lim} (up to {self.max_factor:g}), strain "
                f"{100 * self.strain_max:.3f} %)")


def _changed(h0, h1) -> np.ndarray:
    """(n,) True where a unit's apex went to the other side of its chord."""
    return np.where(np.isnan(h0), False, np.sign(h0) != np.sign(h1))


def _first_snap(model, path, h0):
    """(factor, unit, kind) at which the first unit snaps back along ``path``: the first row
    where a unit changed state before the path's first limit point ("state changed"), else
    that limit point ("limit point"; the unit: the first to change state past it, or the one
    left furthest from its unloaded state at the path's end -- past a limit the path goes
    down the unstable branch, where the other units return to theirs); (None, None, "")
    when neither."""
    rows = [apex_heights(model, P) for P in path.positions]
    lim = path.limit_load_factor
    k_lim = len(rows) if lim is None else int(np.argmax(path.load_factor))
    for k in range(1, len(rows)):
        flipped = np.flatnonzero(_changed(h0, rows[k]))
        if flipped.size:
            if k < k_lim:
                return float(path.load_factor[k]), int(flipped[0]), "state changed"
            return float(lim), int(flipped[0]), "limit point"
    if lim is None:
        return None, None, ""
    away = np.nan_to_num(np.abs(rows[-1] - h0), nan=-1.0)
    return float(lim), int(np.argmax(away)), "limit point"


def load_array(model, positions, g: float | None = None, orientation="upright",
               material=None, loads=(), max_factor: float = DEFAULT_MAX_FACTOR) -> LoadedArray:
    """The morphed array ``positions`` (n_nodes, 2) m of ``model`` (`design.arrays`),
    clamped at its start, under self-weight (``g`` m/s^2, default 9.81 with a ``material``
    and 0 without; the density of ``material``; along ``orientation``) and ``loads``
    ([`ArrayLoad`]); module doc. ``max_factor`` (>= 1): how far past the loads the first
    snap-back is looked for (1: not looked for)."""
    t0 = time.perf_counter()
    direction = gravity_direction(orientation)
    mat = resolve_material(material)
    g = (G if mat is not None else 0.0) if g is None else check_gravity(g)
    loads = check_loads(loads, model.units)
    if not (isinstance(max_factor, (int, float, np.number)) and math.isfinite(max_factor)
            and 1.0 <= max_factor <= 1e6):
        raise ValueError(f"max_factor must be a load factor, 1 <= max_factor <= 1e6; got "
                         f"{max_factor!r}")
    if g > 0 and mat is None:
        raise ValueError("gravity needs a material (its density): material='petg', 'pla', "
                         "'paper' or a Material")
    Q = np.asarray(positions, float)
    h0 = apex_heights(model, Q)
    strains0 = unit_strains(model, Q)
    st = model.structure(clamp=True)
    if g > 0 and direction is not None:
        st.add_gravity(mat.density, g=g, direction=tuple(direction))
    for ld in loads:
        st.add_load(load_node(model, ld), tuple(float(v) for v in ld.force))
    out = LoadedArray(orientation, direction, g, mat, loads, "held", Q.copy(), np.zeros(2),
                      np.ones(len(model.units), bool), (h0, h0), strains0, strains0,
                      max_factor=float(max_factor))
    if direction is None and g > 0:
        out.notes.append("sideways: gravity is normal to the array's plane; the planar model "
                         "carries no load from it (out-of-plane sag and the table's friction "
                         "are not modelled)")
    total = st.total_dead_load() if st.has_dead_loads else 0.0
    out.total_load = float(total)
    if total == 0.0:  # nothing acts in the plane: the unloaded state is the answer
        out.status = "sideways: no in-plane load" if direction is None and g > 0 else "no loads"
        out.time = time.perf_counter() - t0
        return out
    path = out.path = st.follow_load(1.0, start=Q)
    end = int(model.base_nodes[-1])
    if path.status == "ok" or path.status.startswith("snapped"):
        P1 = path.positions[-1]
    elif path.status.startswith("limit"):
        P1 = path.positions[int(np.argmax(path.load_factor))]
    else:
        out.status = path.status
        out.time = time.perf_counter() - t0
        return out
    h1 = apex_heights(model, P1)
    out.positions, out.sag, out.heights = P1.copy(), P1[end] - Q[end], (h0, h1)
    out.held = ~_changed(h0, h1)
    out.strains = unit_strains(model, P1)
    if path.status == "ok" and out.held.all() and path.negative_eigenvalues[-1] == 0:
        search = None
        if max_factor > 1.0:
            search = out.search = st.follow_load(float(max_factor), start=Q)
            if not (search.status == "ok" or search.status.startswith(("snapped", "limit"))):
                out.notes.append(f"the search for the snap-back load ended {search.status!r}")
                search = None
        if search is not None:
            out.limit_factor, out.limit_unit, out.limit_kind = _first_snap(model, search, h0)
    else:
        out.limit_factor, out.limit_unit, out.limit_kind = _first_snap(model, path, h0)
        if out.limit_unit is None and path.negative_eigenvalues[-1] > 0:
            out.limit_kind = "unstable at factor 1"
        lost = [i for i in np.flatnonzero(~out.held)]
        if out.limit_unit is not None:
            lost = sorted(set(lost) | {out.limit_unit})
            out.held[out.limit_unit] = False
        where = ("; ".join(f"unit {i + 1}" for i in lost) or "the array")
        lim = ("" if out.limit_factor is None
               else f" (at load factor {out.limit_factor:.4g}, {out.limit_kind})")
        if path.status == "ok":
            out.status = f"lost: {where} does not keep its state under the loads{lim}"
        elif path.status.startswith("snapped"):
            out.status = f"lost: {where} snaps back before the loads are full{lim}"
        else:
            out.status = f"lost: the array does not carry its loads: {where} snaps back{lim}"
    out.time = time.perf_counter() - t0
    return out
