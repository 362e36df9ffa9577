"""Morphing between two snap patterns of one array: which units to snap, which to push back
(from the other face), in what order, and the shape after each step.

    from snapmorph.design.reconfigure import morph_plan
    plan = morph_plan(units, "0101", "1100")       # or md.morph_plan(0, 1) of a MultiDesign
    print(plan.table()); plan.plot("build/morph.png")

Every unit is bistable and, released, units do not interact (`design/arrays.py` explains why),
so every intermediate state of a reconfiguration is one of the array's 2ⁿ stable states:
the array can be let go after any step and its shape there is forward kinematics of that
state. A unit that is snapped in the start pattern and not in the end one is pushed back: its
arch, inverted through the base's hole, is pressed from the other face. A unit unsnapped at
the start and snapped at the end is snapped as usual, its arch pressed from its own face.

Order: push-backs first (they straighten the array), then snaps; within each group from the
held end (unit 1) outwards. If an intermediate base would cross itself, the order is searched
instead (depth first over the remaining steps, push-backs tried first, dead ends remembered):
the first order whose every intermediate base is free of crossings; when none exists the
default order is kept and the crossing steps are flagged (`MorphStep.crossing`).

Only forward kinematics is used: pushing a unit back is not simulated (`simulate_array`
snaps units but does not unsnap them).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snapmorph.design.targets import resample

__all__ = ["MorphPlan", "MorphStep", "morph_plan"]

ACTIONS = ("snap", "push back")
#: reordering searches at most this many partial orders before keeping the default order
_MAX_VISITS = 20000


@dataclass
class MorphStep:
    """One step: `unit` (0-based) is snapped or pushed back (`action`), pressed from `face`;
    `state` is the array's state after it, `xy` its base (m, placed), `crossing` whether that
    base crosses itself."""

    unit: int
    action: str
    face: str
    state: str
    xy: np.ndarray
    crossing: bool

    def describe(self, units) -> str:
        u = units[self.unit]
        label = f"{self.unit + 1}{'+' if u.side > 0 else '-'}"
        what = ("snap: press its arch through the base" if self.action == "snap"
                else "push back: press the inverted arch back through the base")
        return f"unit {label} {what}, from the {self.face}"


@dataclass
class MorphPlan:
    """A reconfiguration from pattern `start` to pattern `end` (tuples of bools, True =
    snapped) of `units`: `steps` in order, `start_xy` the base before the first step; every
    shape placed with unit 1's start at `placement` (x0, y0, angle; m, m, rad)."""

    units: list
    start: tuple
    end: tuple
    steps: list
    start_xy: np.ndarray
    placement: tuple
    reordered: bool = False
    notes: list = field(default_factory=list)

    @property
    def states(self) -> list:
        """The state strings from the start to the end, one per step plus the start."""
        return [_string(self.start)] + [s.state for s in self.steps]

    @property
    def shapes(self) -> list:
        """The bases (m) from the start to the end, one per step plus the start."""
        return [self.start_xy] + [s.xy for s in self.steps]

    @property
    def crossing_free(self) -> bool:
        return not any(s.crossing for s in self.steps)

    def table(self) -> str:
        """The steps as text: number, unit, action, face, state after, end point (mm)."""
        lines = [f"from {_string(self.start)} to {_string(self.end)}: {len(self.steps)} steps"
                 + (" (reordered to avoid a base crossing itself)" if self.reordered else "")]
        for k, s in enumerate(self.steps, start=1):
            end = s.xy[-1] * 1e3
            lines.append(f"{k:>3}. {s.describe(self.units)}; state {s.state}, free end at "
                         f"({end[0]:.1f}, {end[1]:.1f}) mm"
                         + ("  CROSSES ITSELF" if s.crossing else ""))
        if not self.steps:
            lines.append("  nothing to do: the patterns are the same")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def __repr__(self):
        snaps = sum(s.action == "snap" for s in self.steps)
        return (f"MorphPlan({_string(self.start)} -> {_string(self.end)}: {snaps} snaps, "
                f"{len(self.steps) - snaps} push-backs"
                f"{'' if self.crossing_free else ', a base crosses itself'})")

    def plot(self, path, title: str | None = None):
        """One panel per shape (start, then after each step), the unit acted on and the side
        it is pressed from marked; returns the path."""
        from snapmorph.design.multishape_plots import plot_morph_plan

        return plot_morph_plan(self, path, title=title)


def _string(pattern) -> str:
    return "".join("1" if p else "0" for p in pattern)


def _pattern(value, units, what: str) -> tuple:
    n = len(units)
    if isinstance(value, str):
        s = value.strip()
        if len(s) != n or any(c not in "01" for c in s):
            raise ValueError(f"{what} must be {n} characters 0/1 (one per unit, 1 = snapped); "
                             f"got {value!r}")
        flags = [c == "1" for c in s]
    else:
        try:
            flags = [bool(v) for v in value]
        except TypeError:
            raise ValueError(f"{what} must be a '0'/'1' string or one bool per unit; got "
                             f"{value!r}") from None
        if len(flags) != n:
            raise ValueError(f"{what} must have one entry per unit ({n}); got {len(flags)}")
    bad = [i + 1 for i, (f, u) in enumerate(zip(flags, units)) if f and u.is_spacer]
    if bad:
        raise ValueError(f"{what}: unit(s) {', '.join(map(str, bad))} are spacers (one state "
                         "only) and cannot be snapped")
    return tuple(flags)


def _face(unit, action: str) -> str:
    """The face to press from: a unit of side +1 has its arch on the engraved face ("n+" in
    the drawings); snapping presses the arch from its own face, pushing back from the other."""
    own = "engraved face" if unit.side > 0 else "other (not engraved) face"
    other = "other (not engraved) face" if unit.side > 0 else "engraved face"
    return own if action == "snap" else other


def _crosses(xy, n: int = 300) -> bool:
    """True when two non-adjacent segments of the base (resampled to n points) cross properly.
    Unlike `design.targets.self_intersects` (meant for drawn targets) it ignores orientation
    tests within round-off of zero, so that a straight base (collinear segments) never
    counts as crossing itself."""
    p = resample(np.asarray(xy, dtype=float), n)
    a, b = p[:-1], p[1:]
    eps = 1e-9 * float(np.sum(np.hypot(*np.diff(p, axis=0).T))) ** 2
    i, j = np.triu_indices(len(a), k=2)

    def orient(o, q, r):
        return (q[..., 0] - o[..., 0]) * (r[..., 1] - o[..., 1]) - \
               (q[..., 1] - o[..., 1]) * (r[..., 0] - o[..., 0])

    o1, o2 = orient(a[i], b[i], a[j]), orient(a[i], b[i], b[j])
    o3, o4 = orient(a[j], b[j], a[i]), orient(a[j], b[j], b[i])
    proper = (o1 * o2 < 0) & (o3 * o4 < 0)
    clear = (np.abs(o1) > eps) & (np.abs(o2) > eps) & (np.abs(o3) > eps) & (np.abs(o4) > eps)
    return bool(np.any(proper & clear))


def morph_plan(units, start, end, *, design_map=None, placement=(0.0, 0.0, 0.0),
               state: str = "released", reorder: bool = True) -> MorphPlan:
    """The steps from pattern `start` to pattern `end` of `units` (each a '0'/'1' string or
    one bool per unit): see the module docstring. `placement`: (x0, y0, angle) of unit 1's
    start (m, m, rad) for the shapes; `reorder`: search another order when an intermediate
    base crosses itself."""
    from snapmorph.design.kinematics import chain
    from snapmorph.design.lookup import MapLookup
    from snapmorph.design.nearest import _check_units

    units = _check_units(units)
    a = _pattern(start, units, "start")
    b = _pattern(end, units, "end")
    try:
        x0, y0, a0 = (float(v) for v in placement)
    except (TypeError, ValueError):
        raise ValueError(f"placement must be (x0, y0, angle) in m, m, rad; got "
                         f"{placement!r}") from None
    lookup = MapLookup(design_map) if design_map is not None else None
    cache = {}

    def shape(flags):
        key = tuple(flags)
        if key not in cache:
            cache[key] = chain(units, list(key), lookup=lookup, start=(x0, y0), start_angle=a0,
                               state=state).xy
        return cache[key]

    backs = [i for i in range(len(units)) if a[i] and not b[i]]
    snaps = [i for i in range(len(units)) if b[i] and not a[i]]
    default = [(i, "push back") for i in backs] + [(i, "snap") for i in snaps]

    def run(order):
        flags, steps = list(a), []
        for i, action in order:
            flags[i] = action == "snap"
            xy = shape(flags)
            steps.append(MorphStep(i, action, _face(units[i], action), _string(flags), xy,
                                   _crosses(xy)))
        return steps

    steps = run(default)
    reordered, notes = False, []
    if reorder and any(s.crossing for s in steps):
        found = _search_order(default, a, shape)
        if found is not None and found != default:
            steps, reordered = run(found), True
        elif found is None:
            notes.append("no order of these steps keeps every intermediate base free of "
                         "crossings: the flagged steps need the array supported off its plane "
                         "or a detour through other states")
    return MorphPlan(units=units, start=a, end=b, steps=steps, start_xy=shape(a),
                     placement=(x0, y0, a0), reordered=reordered, notes=notes)


def _search_order(actions, start, shape):
    """An order of `actions` whose every intermediate base is crossing-free, depth first
    (push-backs before snaps, as listed), or None; partial orders reaching the same set of
    done actions are equivalent (the state depends only on that set), so dead sets are
    remembered."""
    dead, visits = set(), [0]

    def state_of(done):
        flags = list(start)
        for k in done:
            i, action = actions[k]
            flags[i] = action == "snap"
        return flags

    def dfs(done, order):
        if len(order) == len(actions):
            return order
        key = frozenset(done)
        if key in dead or visits[0] > _MAX_VISITS:
            return None
        visits[0] += 1
        for k in range(len(actions)):
            if k in done:
                continue
            nxt = done | {k}
            if _crosses(shape(state_of(nxt))):
                continue
            got = dfs(nxt, order + [actions[k]])
            if got is not None:
                return got
        dead.add(key)
        return None

    return dfs(frozenset(), [])
