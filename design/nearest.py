"""The snap pattern of a given array closest to a target: branch and bound over its 2ⁿ states.

    from snapmorph.design import nearest_state
    r = nearest_state(units, "new_target.svg")         # units: a list of design.Unit
    r.state, r.deviation, r.placement, r.predicted     # '0110...', (max, rms) of the length

The search
----------
Every state of an array has the same base length, and unit i occupies the same stretch
[S_i, S_i+1] of it in every state (the base is inextensible), so a state can be compared with
the target point by point: the array's sample at arc length σ against the target's point at the
same fraction σ / Λ of its length. In a fixed frame (unit 1's start point and direction given)
the largest of these matched distances, c(p) = max_σ |x_p(σ) − q(σ)|, is decided unit by unit:
the first j units' states fix the first j units' positions, and the largest distance over them
can only grow as units are added. That makes c a branch-and-bound objective over the binary
tree of states (unit 1 at the root):

- bound: a node's cost c_j (its prefix's largest distance) and a tail bound — the array point
  at a later joint S_m is at most S_m − S_j from the prefix's end point z_j, so its distance to
  the target is at least |q(S_m) − z_j| − (S_m − S_j);
- incumbent: a greedy pass (each unit in the state closer to its stretch of the target)
  improved by single flips, before the tree is searched;
- search: depth first over vectorised chunks of nodes (children sorted by bound, best chunk
  first), pruning every node whose bound is not below the k-th best complete state found.

Within the frame this is exact for c (unless `max_nodes` stops it: `exact` says), and c bounds
the deviation of `design.targets.deviation` from above (a matched point is one candidate for
the nearest one). ``placement="clamped"`` fixes the frame: one search, exact.

With ``placement="best"`` the frame is not known in advance. Candidates come from two exact
searches: with unit 1 on the target's start (above) and with the last unit on the target's
end (the array walked backwards on the target walked backwards: a unit walked backwards is
the same unit with its arch on the other side). They are ranked by their largest matched
distance after the least-squares rigid fit (Kabsch, `kabsch_score`); the position search is
repeated in the winner's fitted frame until the winner stays (at most `rounds` times), single
and double flips polish it, and the winner is measured with the best rigid placement. What is
optimised is the fitted matched distance, a stand-in for the best placement's deviation: for
a target made from one of the array's states the state is found (tests, up to 20 units); for
a target that is no state of the array, brute force over all states found states with a 9-12 %
smaller deviation in the two cases checked (12 units: 6.89 against 7.57 %; 16 units: 2.00
against 2.27 %).

Cost: each expanded node costs O(P) work (P samples per unit); how many nodes depends on how
well the target's stretches tell the states apart: tens to thousands for a target made from
a state, up to about 10⁵ of the 2ⁿ⁺¹ − 1 tree nodes for an unrelated target at n = 20
(`NearestState.nodes`; `bench/bench_multishape.py` times n = 16 and 20: 0.15-0.4 s).
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from snapmorph.design.targets import Target, best_rigid_placement, deviation, place_rigid
from snapmorph.design.units import Unit

__all__ = ["NearestState", "PatternTable", "nearest_state", "measure", "pattern_table"]

PLACEMENTS = ("best", "clamped")
#: samples per unit compared with the target in the search (the unit's end among them)
SAMPLES = 8
#: at most this many arched units: states are held as bits of an int64
MAX_ARCHED = 62
_CHUNK = 4096
#: with placement "best", the runners-up of a search frame worth ranking: c below this many
#: times the best c (a frame that is off can make the best state second)
RUNNER_UP = 2.0


# --------------------------------------------------------------------------- the array's table
@dataclass(frozen=True)
class PatternTable:
    """What the search needs to know of an array (SI): for each unit i, the offsets of its P
    samples from its start in its own frame, unsnapped and snapped, `W[i, 0]` and `W[i, 1]`
    (complex (n, 2, P); the last sample is the unit's end), its end turns `turn[i]` (rad,
    (n, 2)), whether it can snap `arched[i]`, each sample's arc length from the array's start
    `sigma` (n, P) and the joints' `S` (n + 1,)."""

    W: np.ndarray
    turn: np.ndarray
    arched: np.ndarray
    sigma: np.ndarray
    S: np.ndarray

    @property
    def n(self) -> int:
        return len(self.arched)

    @property
    def length(self) -> float:
        return float(self.S[-1])


def pattern_table(snapped_xy, lengths, arched, end_turns, samples: int = SAMPLES) -> PatternTable:
    """A `PatternTable` from each unit's snapped base shape in its own frame: `snapped_xy[i]`
    complex (M,) or real (M, 2), m, from 0 heading +x, uniform in arc length (ignored for
    spacers), `lengths` (n,) m, `arched` (n,) bool, `end_turns` (n,) rad (side · θ)."""
    L = np.asarray(lengths, dtype=float)
    arched = np.asarray(arched, dtype=bool)
    n = len(L)
    frac = np.arange(1, samples + 1) / samples
    W = np.zeros((n, 2, samples), dtype=complex)
    W[:, 0] = L[:, None] * frac[None, :]
    W[:, 1] = W[:, 0]
    turn = np.zeros((n, 2))
    for i in np.flatnonzero(arched):
        z = np.asarray(snapped_xy[i])
        if z.ndim == 2:
            z = z[:, 0] + 1j * z[:, 1]
        z = z - z[0]
        M = len(z)
        idx = frac * (M - 1)
        W[i, 1] = np.interp(idx, np.arange(M), z.real) + 1j * np.interp(idx, np.arange(M), z.imag)
        turn[i, 1] = float(end_turns[i])
    S = np.concatenate([[0.0], np.cumsum(L)])
    sigma = S[:-1, None] + L[:, None] * frac[None, :]
    return PatternTable(W, turn, arched, sigma, S)


def _reference(table: PatternTable, target: Target, frame):
    """The target's matched points in the array's own frame (unit 1 starting at 0 heading +x)
    when unit 1 starts at frame = (x0, y0, angle): Q (n, P) complex at the samples and Qj
    (n + 1,) at the joints, each at the same fraction of the target's length."""
    x0, y0, a0 = frame
    rot = np.exp(-1j * a0)

    def at(s):
        p = target.at_fraction(np.clip(np.asarray(s) / table.length, 0.0, 1.0).ravel())
        return (((p[:, 0] - x0) + 1j * (p[:, 1] - y0)) * rot).reshape(np.shape(s))

    return at(table.sigma), at(table.S)


# --------------------------------------------------------------------------- costs and search
def matched_costs(table: PatternTable, Q, masks) -> np.ndarray:
    """c(p) for a batch of states given as int64 bit masks (bit i: unit i snapped): the largest
    matched distance (m) to the reference Q, all states at once."""
    masks = np.asarray(masks, dtype=np.int64)
    z = np.zeros(masks.shape, dtype=complex)
    e = np.ones(masks.shape, dtype=complex)
    c = np.zeros(masks.shape)
    for i in range(table.n):
        b = ((masks >> i) & 1).astype(int)
        pts = z[:, None] + e[:, None] * table.W[i, b]
        c = np.maximum(c, np.abs(pts - Q[i][None, :]).max(axis=1))
        z = pts[:, -1]
        e = e * np.exp(1j * table.turn[i, b])
    return c


def _tail_bound(table: PatternTable, Qj, i: int, z):
    """Lower bound of the largest matched distance at joints i + 2 .. n for prefixes ending at
    joint i + 1 in z: |q(S_m) − z| − (S_m − S_{i+1}), never below 0."""
    if i + 2 > table.n:
        return np.zeros(len(z))
    gap = table.S[i + 2:] - table.S[i + 1]
    lb = np.abs(Qj[None, i + 2:] - z[:, None]) - gap[None, :]
    return np.maximum(lb.max(axis=1), 0.0)


def _greedy(table: PatternTable, Q, Qj) -> int:
    """A first state: each unit in the state closer to its stretch of the target (tail bound
    breaking ties), front to back."""
    z, e, mask = 0j, 1 + 0j, 0
    for i in range(table.n):
        best = None
        for b in ((0, 1) if table.arched[i] else (0,)):
            pts = z + e * table.W[i, b]
            d = float(np.abs(pts - Q[i]).max())
            key = max(d, float(_tail_bound(table, Qj, i, np.array([pts[-1]]))[0]))
            if best is None or key < best[0]:
                best = (key, b, pts[-1], e * np.exp(1j * table.turn[i, b]))
        _, b, z, e = best
        mask |= b << i
    return mask


def _improve(table: PatternTable, Q, mask: int, cost: float):
    """Single-flip descent from `mask`: flip the unit that lowers c most, until none does."""
    flips = np.array([1 << i for i in np.flatnonzero(table.arched)], dtype=np.int64)
    if flips.size == 0:
        return mask, cost
    for _ in range(4 * table.n):
        trial = np.int64(mask) ^ flips
        c = matched_costs(table, Q, trial)
        k = int(np.argmin(c))
        if not c[k] < cost * (1 - 1e-12):
            break
        mask, cost = int(trial[k]), float(c[k])
    return mask, cost


@dataclass
class _Best:
    """The k best complete states found (cost ascending) and the pruning bound they give."""

    k: int
    cap: float
    ratio: float = math.inf
    items: list = field(default_factory=list)

    def offer(self, costs, masks):
        for c, m in zip(np.asarray(costs, float), np.asarray(masks, np.int64)):
            m = int(m)
            if c >= self.bound or any(m == mm for _, mm in self.items):
                continue
            self.items.append((float(c), m))
            self.items.sort()
            del self.items[self.k:]
            while self.items and self.items[-1][0] >= self.ratio * self.items[0][0]:
                self.items.pop()

    @property
    def bound(self) -> float:
        kth = self.items[-1][0] if len(self.items) >= self.k else self.cap
        near = self.ratio * self.items[0][0] if self.items else math.inf
        return min(kth, near, self.cap)


def branch_and_bound(table: PatternTable, Q, Qj, top: int = 1, seeds=(), cap: float = math.inf,
                     ratio: float = math.inf, max_nodes: int = 2_000_000):
    """The `top` states of smallest c in the frame of Q (see the module docstring).

    seeds: states (bit masks) tried first; cap: only states with c < cap are of interest;
    ratio: only states with c < ratio × the best c (the runners-up worth measuring).
    Returns ([(c, mask)] ascending, nodes expanded, exact)."""
    if int(np.count_nonzero(table.arched)) > MAX_ARCHED:
        raise ValueError(f"the search holds states as 64-bit masks: at most {MAX_ARCHED} arched "
                         f"units, got {int(np.count_nonzero(table.arched))}")
    best = _Best(int(top), float(cap), float(ratio))
    first = _greedy(table, Q, Qj)
    c0 = float(matched_costs(table, Q, [first])[0])
    first, c0 = _improve(table, Q, first, c0)
    starts = [first] + [int(s) for s in seeds]
    best.offer(matched_costs(table, Q, starts), starts)
    n = table.n
    stack = [(0, np.zeros(1, complex), np.ones(1, complex), np.zeros(1), np.zeros(1, np.int64),
              np.zeros(1))]
    nodes, exact = 0, True
    while stack:
        i, z, e, c, m, key = stack.pop()
        keep = key < best.bound
        if not np.any(keep):
            continue
        z, e, c, m = z[keep], e[keep], c[keep], m[keep]
        if nodes >= max_nodes:
            exact = False
            break
        kids = []
        for b in ((0, 1) if table.arched[i] else (0,)):
            pts = z[:, None] + e[:, None] * table.W[i, b][None, :]
            c2 = np.maximum(c, np.abs(pts - Q[i][None, :]).max(axis=1))
            z2 = pts[:, -1]
            kids.append((z2, e * np.exp(1j * table.turn[i, b]), c2, m | np.int64(b << i),
                         np.maximum(c2, _tail_bound(table, Qj, i, z2))))
        nodes += len(z) * len(kids)
        z, e, c, m, key = (np.concatenate(a) for a in zip(*kids))
        keep = key < best.bound
        z, e, c, m, key = z[keep], e[keep], c[keep], m[keep], key[keep]
        if not len(z):
            continue
        if i + 1 == n:
            best.offer(c, m)
            continue
        order = np.argsort(-key, kind="stable")  # worst first: the best chunk is pushed last
        for s in range(0, len(order), _CHUNK):
            sel = order[s:s + _CHUNK]
            stack.append((i + 1, z[sel], e[sel], c[sel], m[sel], key[sel]))
    return best.items, nodes, exact


def sample_points(table: PatternTable, mask: int) -> np.ndarray:
    """The array's samples (n P + 1,) complex, m, in its own frame, in state `mask`."""
    pts, z, e = [0j], 0j, 1 + 0j
    for i in range(table.n):
        b = (int(mask) >> i) & 1
        p = z + e * table.W[i, b]
        pts.extend(p)
        z, e = p[-1], e * np.exp(1j * table.turn[i, b])
    return np.array(pts)


def kabsch_score(table: PatternTable, target: Target, mask: int):
    """(largest matched distance, m, placement (x0, y0, angle)) of state `mask` after the
    least-squares rigid fit (Kabsch) of its samples onto the matched target points: a cheap
    stand-in for the best placement when ranking candidates."""
    a = sample_points(table, mask)
    s = np.concatenate([[0.0], table.sigma.ravel()])
    q = target.at_fraction(np.clip(s / table.length, 0.0, 1.0))
    b = q[:, 0] + 1j * q[:, 1]
    ca, cb = a.mean(), b.mean()
    rot = np.exp(1j * np.angle(np.sum(np.conj(a - ca) * (b - cb))))
    start = cb - rot * ca
    d = float(np.abs(rot * a + start - b).max())
    return d, (float(start.real), float(start.imag), float(np.angle(rot)))


def _descend(table: PatternTable, target: Target, mask: int, scored: dict) -> int:
    """Flip one or two units of `mask` while that lowers `kabsch_score` (first improvement,
    at most 4 n sweeps); `scored` caches the scores."""
    arched = [int(i) for i in np.flatnonzero(table.arched)]
    moves = [1 << i for i in arched] + [(1 << i) | (1 << j) for k, i in enumerate(arched)
                                        for j in arched[k + 1:]]

    def score(m):
        if m not in scored:
            scored[m] = kabsch_score(table, target, m)
        return scored[m][0]

    current = score(mask)
    for _ in range(4 * table.n):
        for mv in moves:
            if score(mask ^ mv) < current * (1 - 1e-9):
                mask ^= mv
                current = scored[mask][0]
                break
        else:
            break
    return mask


# --------------------------------------------------------------------------- deviations
def measure(local_xy, target, start=None, angle=None, maxiter: int = 400, kabsch: bool = True):
    """Deviations of a base polyline given in its own frame (from (0, 0) heading +x) from a
    target (a `Target`), both ways as `inverse_design` reports them: ({"best": (max, rms),
    "clamped": ...}, {"best": (x0, y0, angle), "clamped": ...}); the best placement searched
    from (start, angle) (default the target's start and tangent) and a Kabsch fit, never worse
    than the clamped one (kabsch=False: from (start, angle) only)."""
    target_xy = target.xy
    t_start, t_angle = tuple(target.start), target.start_angle
    clamped = place_rigid(local_xy, t_start, t_angle)
    s0 = t_start if start is None else start
    a0 = t_angle if angle is None else angle
    bs, ba = best_rigid_placement(local_xy, target_xy, start=s0, angle=a0, maxiter=maxiter,
                                  kabsch=kabsch)
    devs = {"clamped": deviation(clamped, target_xy),
            "best": deviation(place_rigid(local_xy, bs, ba), target_xy)}
    if devs["best"][0] > devs["clamped"][0]:
        devs["best"], bs, ba = devs["clamped"], t_start, t_angle
    places = {"clamped": (float(t_start[0]), float(t_start[1]), float(t_angle)),
              "best": (float(bs[0]), float(bs[1]), float(ba))}
    return devs, places


# --------------------------------------------------------------------------- the public API
@dataclass
class NearestState:
    """The snap pattern of an array closest to a target (SI; deviations as fractions of the
    target's length, placements (x0, y0, angle) in m, m, rad of unit 1's start).

    pattern: one bool per unit (True = snapped); state: the same as a '0'/'1' string;
    deviation: (max, rms) with `placement_mode`; deviations/placements: both ways;
    predicted: the base polyline placed as `placement` says; matched: c of the pattern (its
    largest arc-length-matched distance, m) with that placement; candidates: [(state, largest
    matched distance after a least-squares rigid fit, fraction of the length)] ranked; nodes:
    tree nodes expanded in all rounds; exact: no round was stopped by max_nodes."""

    units: list
    pattern: tuple
    state: str
    deviation: tuple
    deviations: dict
    placement: tuple
    placements: dict
    placement_mode: str
    predicted: np.ndarray
    target: np.ndarray
    target_length: float
    array_length: float
    matched: float
    candidates: list
    nodes: int
    rounds: int
    exact: bool
    time: float
    notes: list = field(default_factory=list)

    def __repr__(self):
        n = sum(not u.is_spacer for u in self.units)
        return (f"NearestState(state {self.state}, deviation max {100 * self.deviation[0]:.3g} % "
                f"/ RMS {100 * self.deviation[1]:.3g} % of {self.target_length * 1e3:.1f} mm "
                f"({self.placement_mode}), {n} arched units, {self.nodes} nodes, "
                f"{self.time:.2f} s)")


def _check_units(units) -> list:
    if units is None or isinstance(units, (str, bytes, Unit)):
        raise ValueError(f"units must be a sequence of design.Unit (at least one); got {units!r}")
    try:
        units = list(units)
    except TypeError:
        raise ValueError(f"units must be a sequence of design.Unit (at least one); got "
                         f"{units!r}") from None
    if not units:
        raise ValueError("units must hold at least one design.Unit; got an empty sequence")
    for i, u in enumerate(units):
        if not isinstance(u, Unit):
            raise ValueError(f"units[{i}] is not a design.Unit: {u!r}")
    return units


def table_for_units(units, lookup, state: str = "released", samples: int = SAMPLES) -> PatternTable:
    """The `PatternTable` of design units, their snapped shapes from the map (`MapLookup`)."""
    from snapmorph.design.shapes import snapped_shape

    shapes, turns = [None] * len(units), np.zeros(len(units))
    for i, u in enumerate(units):
        if not u.is_spacer:
            try:
                s = snapped_shape(u, source="map", lookup=lookup, state=state)
            except ValueError as exc:
                raise ValueError(f"unit {i + 1}: {exc}") from None
            shapes[i], turns[i] = s.xy, s.end_angle
    return pattern_table(shapes, [u.L for u in units], [not u.is_spacer for u in units], turns,
                         samples)


def _from_the_end(units, lookup, state, samples, target: Target, top, max_nodes):
    """The position search with the array's end on the target's end: the array walked from its
    last unit (a unit walked backwards is the same unit with its arch on the other side: the
    unit is symmetric) against the target walked backwards, in their start frame. Returns
    ([(c, mask of the original array)], nodes, exact)."""
    n = len(units)
    back = [u if u.is_spacer else Unit(L=u.L, h=u.h, t=u.t, w=u.w, side=-u.side, b=u.b)
            for u in units[::-1]]
    table = table_for_units(back, lookup, state, samples)
    rev = Target.from_polyline(target.xy[::-1])
    Q, Qj = _reference(table, rev, (float(rev.start[0]), float(rev.start[1]), rev.start_angle))
    found, nodes, exact = branch_and_bound(table, Q, Qj, top=top, ratio=RUNNER_UP,
                                           max_nodes=max_nodes)
    flip = [(c, sum(1 << (n - 1 - i) for i in range(n) if (m >> i) & 1)) for c, m in found]
    return flip, nodes, exact


def _mask_to_pattern(mask: int, n: int) -> tuple:
    return tuple(bool((mask >> i) & 1) for i in range(n))


def _pattern_to_mask(pattern) -> int:
    return sum(1 << i for i, p in enumerate(pattern) if p)


def nearest_state(units, target, *, design_map=None, placement: str = "best",
                  state: str = "released", top: int = 4, samples: int = SAMPLES,
                  max_nodes: int = 2_000_000, rounds: int = 3) -> NearestState:
    """The snap pattern of `units` whose base (design-map forward kinematics) is closest to
    `target`, with its deviation.

    target: (N, 2) points in m, a .csv/.svg/.dxf file (mm) or a `design.Target`; matched by
        fraction of length (a target whose length differs from the array's by more than 2 %
        is still searched, with a warning: the base does not stretch).
    placement: "best" (the deviation after the best rigid placement; the search frame is
        iterated, see the module docstring) or "clamped" (unit 1 on the target's start and
        tangent: the search is exact for the matched distance).
    top: candidates measured per round; samples: points per unit in the search; max_nodes:
        node budget per round (`exact` False when it stops a round); rounds: frame iterations.
    """
    from snapmorph.design.kinematics import chain
    from snapmorph.design.lookup import MapLookup, check_state, default_map
    from snapmorph.design.target_input import as_target

    t0 = time.perf_counter()
    units = _check_units(units)
    if placement not in PLACEMENTS:
        raise ValueError(f"placement must be 'best' or 'clamped', got {placement!r}")
    check_state(state)
    for name, value, lo in (("top", top, 1), ("samples", samples, 2), ("max_nodes", max_nodes, 1),
                            ("rounds", rounds, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
            raise ValueError(f"{name} must be an integer >= {lo}, got {value!r}")
    tgt = as_target(target)
    lookup = MapLookup(design_map if design_map is not None else default_map())
    table = table_for_units(units, lookup, state, samples)
    n = len(units)
    notes = []
    gap = abs(table.length - tgt.length) / tgt.length
    if gap > 0.02:
        msg = (f"the target is {tgt.length * 1e3:.1f} mm long, the array {table.length * 1e3:.1f} "
               f"mm ({100 * gap:.1f} % apart): the base does not stretch, so no state matches it "
               "closer than that allows; states compared by fraction of length")
        notes.append(msg)
        warnings.warn(msg, UserWarning, stacklevel=2)
    local_cache: dict = {}

    def local(mask):
        if mask not in local_cache:
            local_cache[mask] = chain(units, _mask_to_pattern(mask, n), lookup=lookup,
                                      state=state).xy
        return local_cache[mask]

    scored: dict = {}  # mask -> (largest matched distance after the Kabsch fit, its frame)
    frame = (float(tgt.start[0]), float(tgt.start[1]), tgt.start_angle)
    winner, nodes, exact, done = None, 0, True, 0
    for done in range(1, rounds + 1):
        Q, Qj = _reference(table, tgt, frame)
        seeds = [] if winner is None else [winner]
        found, k_nodes, k_exact = branch_and_bound(table, Q, Qj, top=top, seeds=seeds,
                                                   ratio=RUNNER_UP, max_nodes=max_nodes)
        nodes += k_nodes
        exact &= k_exact
        if placement == "clamped":
            winner = found[0][1]
            break
        if done == 1:  # candidates from the other end: the reversed array on the reversed target
            extra, k_nodes, k_exact = _from_the_end(units, lookup, state, samples, tgt, top,
                                                    max_nodes)
            nodes += k_nodes
            exact &= k_exact
            found = found + extra
        for _, mask in found:
            if mask not in scored:
                scored[mask] = kabsch_score(table, tgt, mask)
        new = min((m for _, m in found), key=lambda m: scored[m][0])
        if new == winner:
            break
        winner = new
        frame = scored[winner][1]
    if placement == "best":  # polish: single and double flips while the fitted distance drops
        winner = _descend(table, tgt, winner, scored)
    guess = scored[winner][1] if winner in scored else frame
    devs, places = measure(local(winner), tgt, start=guess[:2], angle=guess[2],
                           kabsch=winner not in scored)
    x0, y0, a0 = places[placement]
    Q, _ = _reference(table, tgt, places[placement])
    matched = float(matched_costs(table, Q, [winner])[0])
    pattern = _mask_to_pattern(winner, n)
    cands = sorted(((_state_string(_mask_to_pattern(m, n)), c / tgt.length)
                    for m, (c, _) in scored.items()), key=lambda c: c[1])
    return NearestState(units=units, pattern=pattern, state=_state_string(pattern),
                        deviation=devs[placement], deviations=devs, placement=places[placement],
                        placements=places, placement_mode=placement,
                        predicted=place_rigid(local(winner), (x0, y0), a0), target=tgt.xy,
                        target_length=tgt.length, array_length=table.length, matched=matched,
                        candidates=cands, nodes=nodes, rounds=done, exact=exact,
                        time=time.perf_counter() - t0, notes=notes)


def _state_string(pattern) -> str:
    return "".join("1" if p else "0" for p in pattern)
