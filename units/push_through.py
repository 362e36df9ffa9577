"""The push-through experiment, once for every unit model: the planar unit (`units.planar`),
the 3-D and 2-D units (`units.push3d`) and each unit of a whole array (`design.arrays`).

The apex is pushed towards the base until the force F has fallen through zero and risen
through it again; from the F-d samples: F_cr, d_cr, the first force maximum (refined by
displacement-controlled solves, `solver.states.refine_maximum`); the zero crossings of F
classified (`classify_crossings`); the zero-force states (ii) and (iii) solved as equilibria
(Newton from the bracketing samples, else the one root finder `solver.roots.illinois` on
displacement-controlled solves, `solver.states.zero_force_displacement`); their stability
with the actuator unloaded; and the outcome worded with a name of `units.status`.

One driver, `push_through(model, rules)`, over a duck-typed model (pacopy's style), which
supplies what differs between the units (`PushModel`): how it pushes, its states, how d is
read, how it solves an equilibrium at F = 0 and checks a state's stability. `Rules` holds
what the experiment decides: the stop test, the classification of the crossings and the
steps the models take or skip. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Protocol

import numpy as np

# (the solver is imported where it is used: `design.arrays` imports this module and stays light)

NAN = float("nan")

#: a sampled local minimum of F after the peak below this fraction of F_cr (and above 0)
#: is refined (`refine_dips`): the path's steps may stride over a shallow dip below zero (a
#: marginally bistable unit) that decides whether there is a state (iii)
DIP_FRACTION = 0.2


class PushFailed(Exception):
    """The push itself failed; its message is the outcome's status ("not converged: ...")."""


class PushModel(Protocol):
    """What a unit model supplies to `push_through` (duck-typed; nothing is subclassed).

    ``failures``: the exceptions of its solves that mean "no solution here" (others
    propagate); ``probe``: displacement-controlled solves of the pushed node
    (`solver.states.DisplacementProbe`: ``solve(guess, d) -> (positions, F, negative
    eigenvalues)`` and ``last_state``), or None (then F_cr is read from the samples and a
    zero-force state from Newton only); set by `push`. Optional ``force_counts(path)``:
    the samples' negative-eigenvalue counts under force control ((K,) ints; the zero
    crossings are classified by them, `zero_crossings`), or None (the slope rule); a model
    that gives them passes them to its stop test as ``rows["neg_force"]``."""

    failures: tuple
    probe: object

    def push(self, stop: Callable[[dict], bool]):
        """Push the apex; ``stop(rows)`` (rows {"d": [...], "F": [...]}) ends the push. A
        path: ``displacement`` (K,) m, ``force`` (K,) N, ``positions`` (K, n, dim),
        ``status``. Raises `PushFailed` when the push fails."""

    def states(self, path) -> np.ndarray:
        """(K, ...) the samples' states, as `solve_unloaded` and the probe take them."""

    def positions(self, state) -> np.ndarray:
        """Node positions of a state."""

    def displacement(self, positions) -> float:
        """d (m) of the pushed node in a state, towards the base, from the stress-free state."""

    def solve_unloaded(self, guess):
        """(positions, state) of the equilibrium with the actuator on and F = 0 next to
        ``guess``; raises one of ``failures``."""

    def stability(self, state):
        """`solver.stability.StateStability` of a state with the actuator unloaded; None when
        its tangent stiffness is singular."""

    def checkpoint(self, stage: str) -> None:
        """Called between the stages (a wall-time limit may end the experiment here)."""


# ---------------------------------------------------------------------------- the samples
def first_peak(F):
    """Index of the first local maximum of F with F > 0 (None if there is none)."""
    F = F.tolist() if isinstance(F, np.ndarray) else F  # (a loop over floats, not scalars)
    for i in range(1, len(F) - 1):
        if F[i] > 0 and F[i] >= F[i - 1] and F[i] > F[i + 1]:
            return i
    return None


def largest_force(F):
    """Index of the largest F."""
    return int(np.argmax(F))


def zero_crossings(d, F, start=0, neg=None):
    """Zero crossings of F along the path after sample ``start``, in path order:
    [(i, kind)] where samples i-1 and i bracket the zero; kind -1: an unstable equilibrium
    at F = 0 such as (ii), +1: a candidate stable state such as (iii).

    ``neg``: the samples' negative-eigenvalue counts under force control (the drivers'
    inertia counts of the tangent stiffness with the pushed node loaded, not held): a zero
    of F is a state of the unit with its actuator unloaded, so the count at the bracketing
    sample nearer the zero classifies it (0: stable, +1; more: unstable, -1). A count below
    0 (unknown, e.g. a sample inserted by a displacement-controlled search) and ``neg`` None
    fall back on the sign of dF/dd between the two samples (a path running backwards in d
    flips it): right while d increases, but on a path that snaps back (d decreasing) past a
    turning point of d the chord's slope misreads an unstable state as a stable one. Counts
    that differ while d increases mean a force extremum between the samples, on either side
    of the zero: the nearer sample can be on the wrong side (a unit whose F_min lies just
    before its second zero, stepped over in one step, read its stable state (iii) as a
    second unstable one and was called monostable), and the chord's slope, which is the
    slope at the zero there, decides."""
    out = []
    for i in range(max(start, 0) + 1, len(F)):
        if i == 1 and F[0] == 0.0:
            continue  # the unloaded start is not a crossing
        if (F[i - 1] >= 0.0 > F[i]) or (F[i - 1] <= 0.0 < F[i]):
            count = -1
            if neg is not None and neg[i - 1] >= 0 and neg[i] >= 0 and (
                    neg[i - 1] == neg[i] or d[i] <= d[i - 1]):
                count = neg[i] if abs(F[i]) < abs(F[i - 1]) else neg[i - 1]
            if count >= 0:
                out.append((i, -1 if count > 0 else 1))
                continue
            dF = F[i] - F[i - 1]
            dd = d[i] - d[i - 1]
            slope = np.sign(dF) * (np.sign(dd) if dd != 0 else 1.0)
            out.append((i, int(slope)))
    return out


def classify_crossings(crossings, depth=None):
    """(j, k) of the zero crossings [(i, kind)] after the peak: j the first unstable one
    (the state (ii)), k the next stable one (the candidate second stable state (iii)) that
    lies deeper than (ii) (``depth[i]``: the d of crossing i, when given: a stable zero
    behind (ii) is the path come back to the first state, not a second one); None where
    there is none. The one classification rule."""
    j = next((i for i, kind in crossings if kind < 0), None)
    k = next((i for i, kind in crossings if kind > 0 and j is not None and i > j
              and (depth is None or depth[i] > depth[j])), None)
    return j, k


def snap_crossings(d, F, neg=None):
    """(i_pk, j, k) of a push's F-d samples: i_pk the first force maximum (None if none), j
    and k the crossings of (ii) and (iii) after it (`classify_crossings`); a crossing is
    between samples i-1 and i, and (iii) lies deeper (larger d, interpolated) than (ii).
    ``neg``: the samples' force-control inertia counts, which classify the crossings
    (`zero_crossings`; None: the slope between the samples).""" 
    # (as Python floats: the stop test asks at every state, and float arithmetic on them is
    # the same IEEE arithmetic as on numpy scalars, at a tenth of the cost)
    d, F = np.asarray(d, float).tolist(), np.asarray(F, float).tolist()
    i_pk = first_peak(F)
    crossings = zero_crossings(d, F, start=(i_pk or 0),
                               neg=None if neg is None else np.asarray(neg).tolist())
    depth = {i: d[i - 1] + F[i - 1] / (F[i - 1] - F[i]) * (d[i] - d[i - 1])
             for i, _ in crossings}
    return (i_pk, *classify_crossings(crossings, depth))


def second_state_passed(rows) -> bool:
    """The push's stop test: the path has passed a candidate (iii) (`snap_crossings`, with
    the rows' force-control counts ``rows["neg_force"]`` when the model gives them)."""
    F = rows["F"]
    # (ii) and (iii) need F below zero and then not below it again: a path whose samples
    # have all stayed below zero since the first one that went there has no crossing
    # after (ii) (cheap tests first, at C speed where they can be: the test runs at every
    # state, and most states of a push are above zero)
    if len(F) < 3 or not min(F) < 0.0:
        return False
    below = next(i for i, f in enumerate(F) if f < 0.0)  # (there is one: min(F) < 0)
    if all(f < 0.0 for f in F[below:]):
        return False
    return snap_crossings(rows["d"], F, rows.get("neg_force"))[2] is not None


def parabola_peak(d, F, i):
    """Vertex of the parabola through samples i-1, i, i+1 (F_max, d_max), or sample i (at
    an end of the samples, or where d is not increasing there)."""
    if 0 < i < len(F) - 1:
        x, y = np.asarray(d[i - 1: i + 2], float), np.asarray(F[i - 1: i + 2], float)
        if x[0] < x[1] < x[2]:
            a, b, c = np.polyfit(x - x[1], y, 2)
            if a < 0:
                xv = -b / (2 * a)
                if x[0] - x[1] <= xv <= x[2] - x[1]:
                    return float(c - b * b / (4 * a)), float(x[1] + xv)
    return float(F[i]), float(d[i])


def refine_peak(probe, d, F, Q, i, failures, tol=2e-3, rates=None):
    """F_cr, d_cr and whether they were solved: the force maximum near path sample i by
    displacement-controlled solves (a limit point under load control is regular under
    displacement control); the vertex of the parabola through three samples when that
    fails (one of ``failures``) or there is no probe. ``tol``: the search stops when the
    bracket is below this fraction of the samples' spacing (F is flat at its maximum: an
    error e in d costs ~ F'' e^2 / 2 in F_cr). A search whose best solve stays below the
    sample itself (the sample lies at the maximum, closer than the search's tolerance)
    returns the sample: an equilibrium of the path, not the parabola's vertex (which between
    coarse samples can overshoot the maximum by 1e-4 of F_cr). ``rates``: the samples'
    dq/dd (`solver.path.Path.rates`, aligned with ``Q``), the solves' guesses, or None."""
    if probe is not None and 0 < i < len(d) - 1 and d[i - 1] < d[i] < d[i + 1]:
        from snapmorph.solver.states import refine_maximum

        try:
            F_max, d_max = refine_maximum(probe, d, F, Q, i, tol_d=tol * (d[i + 1] - d[i - 1]),
                                          rates=rates)
        except failures:
            return (*parabola_peak(d, F, i), False)
        if F_max >= F[i]:
            return float(F_max), float(d_max), True
        return float(F[i]), float(d[i]), False
    return (*parabola_peak(d, F, i), False)


def refine_dips(probe, d, F, P, Q, i_pk, failures=(Exception,), tol=2e-3, neg=None):
    """Samples with the minimum of every shallow dip of F (a local minimum after the peak
    with 0 < F < DIP_FRACTION F_cr between two path samples) inserted, located by Brent's
    search on displacement-controlled solves from the nearest sample; returns (d, F, P, Q)
    (the inputs when nothing was inserted), and the counts ``neg`` with -1 (unknown) at the
    inserted samples when given. Only a dip the search takes below zero is inserted: it
    makes the zero crossings of a marginally bistable unit visible."""
    if probe is None or i_pk is None or len(F) < 3:
        return (d, F, P, Q) if neg is None else (d, F, P, Q, neg)
    F_cr = F[i_pk]
    inserts = []
    for m in range(i_pk + 1, len(F) - 1):
        if not (0.0 < F[m] < DIP_FRACTION * F_cr and F[m] <= F[m - 1] and F[m] < F[m + 1]):
            continue
        if not d[m - 1] < d[m] < d[m + 1]:
            continue
        cache = {}

        def f(x, m=m, cache=cache):
            x = float(x)
            if x not in cache:
                near = m - 1 + int(np.argmin(np.abs(d[m - 1:m + 2] - x)))
                pos, Fx, _ = probe.solve(Q[near], x)
                cache[x] = (Fx, np.asarray(pos).copy(), probe.last_state.copy())
            return cache[x][0]

        try:
            import scipy.optimize

            res = scipy.optimize.minimize_scalar(
                f, bounds=(float(d[m - 1]), float(d[m + 1])), method="bounded",
                options={"xatol": 0.5 * tol * (d[m + 1] - d[m - 1]), "maxiter": 60})
            x = float(res.x)
            Fx, pos, q = cache[x] if x in cache else (f(x), *cache[x][1:])
        except failures:  # the samples stand
            continue
        if Fx < 0.0:
            inserts.append((m + 1 if x > d[m] else m, x, Fx, pos, q))
    if not inserts:
        return (d, F, P, Q) if neg is None else (d, F, P, Q, neg)
    d, F, P, Q = list(d), list(F), list(P), list(Q)
    neg = None if neg is None else list(neg)
    for at, x, Fx, pos, q in sorted(inserts, key=lambda t: -t[0]):
        d.insert(at, x)
        F.insert(at, Fx)
        P.insert(at, pos)
        Q.insert(at, q)
        if neg is not None:
            neg.insert(at, -1)  # a displacement-controlled solve: no force-control count
    out = np.asarray(d), np.asarray(F), np.asarray(P), np.asarray(Q)
    return out if neg is None else (*out, np.asarray(neg))


def zero_force_state(model, d, F, P, Q, i, rates=None):
    """The equilibrium at F = 0 between samples i-1 and i (which bracket a zero of F):
    Newton with the actuator unloaded from the interpolated state (between the samples'
    states at the d where the chord of F crosses zero; with the samples' ``rates`` dq/dd,
    `solver.path.Path.rates`, a cubic Hermite guess, else the states' chord); if it fails or leaves the
    bracket (it can wander to another equilibrium), the zero located first by regula falsi
    on the probe's displacement-controlled solves (`solver.states.zero_force_displacement`)
    and Newton from there. Returns (positions, state, error): error None when solved, else
    why not (the interpolated state is returned then)."""
    from snapmorph.solver.problem import ConvergenceError
    from snapmorph.solver.states import zero_force_displacement

    s = F[i - 1] / (F[i - 1] - F[i])
    guess = (1 - s) * Q[i - 1] + s * Q[i]
    if rates is not None and d[i] > d[i - 1]:
        from snapmorph.solver.states import hermite

        smooth = hermite(d[i - 1], d[i], Q[i - 1], Q[i], rates[i - 1], rates[i],
                         (1 - s) * d[i - 1] + s * d[i])
        guess = guess if smooth is None else smooth
    lo, hi = min(d[i - 1], d[i]), max(d[i - 1], d[i])
    pad = 1e-6 * (hi - lo) + 1e-12

    def inside(pos):
        return lo - pad <= model.displacement(pos) <= hi + pad

    error = ConvergenceError("the zero-force state left its path bracket")
    try:
        pos, q = model.solve_unloaded(guess)
        if inside(pos):
            return pos, q, None
    except model.failures as exc:
        error = exc
    if model.probe is not None:
        try:
            tol_F = 1e-9 * max(abs(F[i - 1]), abs(F[i]))
            zero_force_displacement(model.probe, d[i - 1], d[i], Q[i - 1], Q[i], F[i - 1], F[i],
                                    tol_F)
            # from the full state of the last solve (3-D rods: its twists too)
            pos, q = model.solve_unloaded(model.probe.last_state.copy())
            if inside(pos):
                return pos, q, None
            error = ConvergenceError("the zero-force state left its path bracket")
        except model.failures as exc:
            error = exc
    return (1 - s) * P[i - 1] + s * P[i], guess, error


# ---------------------------------------------------------------------------- the wording
def no_second_state(path_status: str, j, d_end: float):
    """(status, reason) of a push on which no state (iii) was found: "monostable" only when
    the path ran its course (``path_status`` "ok": it reached its distance or its model's
    stop test ended it; "ok: ..." says where it ended); a path that stopped before ("stopped: ...", "not converged: ...",
    "timeout: ...") gives its failure as a "not converged" or "timeout" status."""
    if path_status == "ok" or path_status.startswith("ok: "):
        reason = ("no snap-through: F does not fall below zero" if j is None else
                  "F crosses zero downwards but does not rise through zero again "
                  f"before d = {d_end:.4g} m")
        if path_status.startswith("ok: "):  # how far the path went (a stated limit)
            reason += f" ({path_status[4:]})"
        return "monostable", reason
    # a path cut before its distance (step cap, wandering, underflow, time) answers nothing
    status = (path_status if path_status.startswith(("not converged", "timeout"))
              else f"not converged: {path_status}")
    return status, status


def _not_found(state, model, positions) -> str:
    return (f"not converged: {state} was not found as an equilibrium near "
            f"d = {model.displacement(positions):.4g} m")


def unstable_reason(stab, d_second) -> str:
    """The status of a second state (iii) that is not stable with the actuator unloaded."""
    why = ("its tangent stiffness is singular (a critical state)" if stab is None else
           f"{stab.negative_force} negative eigenvalue(s) of the tangent stiffness with the "
           f"actuator unloaded")
    return f"second state unstable: state (iii) at d = {d_second:.4g} m has {why}"


# ---------------------------------------------------------------------------- the driver
@dataclass(frozen=True)
class Rules:
    """What the experiment does; each model takes the defaults or says what it skips.

    stop: the push's stop test on its rows; peak: the sample F_cr is read at (`first_peak`;
    `largest_force` for an array's unit); refine_peak: F_cr by displacement-controlled solves
    (else the samples' parabola); peak_stability: also the stability of the peak sample;
    refine_dips: look for a shallow dip below zero the steps strode over (`refine_dips`);
    unstable_state: solve state (ii); exact: the states that must be found as equilibria
    (one that is not ends the experiment: "not converged"); stability: check (ii) and (iii)
    (else (iii) found is the answer); peak_tol: the peak search's bracket, a fraction of the
    samples' spacing."""

    stop: Callable = second_state_passed
    peak: Callable = first_peak
    refine_peak: bool = True
    peak_stability: bool = False
    refine_dips: bool = False
    unstable_state: bool = True
    exact: tuple = ("ii", "iii")
    stability: bool = True
    peak_tol: float = 2e-3


@dataclass
class PushOutcome:
    """What the push found (SI). status: "ok", "monostable", "second state unstable: ..." or
    "not converged: ..." (`units.status`); reason: why not bistable ("" when it is);
    states / full_states: "i", "ii", "iii" -> positions / full state vectors; peak: the
    path sample of F_cr; exact_states: (ii), (iii) solved as equilibria (not interpolated);
    stability: "i", "ii", "iii" -> `solver.stability.StateStability` (None: singular);
    error: the failure of a state that was not found (None); crossings: the samples of the
    crossings of (ii) and (iii)."""

    status: str
    path_status: str = ""
    curve: tuple = (np.zeros(0), np.zeros(0))
    F_cr: float = NAN
    d_cr: float = NAN
    d_unstable: float = NAN
    d_second: float = NAN
    bistable: bool = False
    states: dict = field(default_factory=dict)
    exact_states: bool = False
    path: object = None
    reason: str = ""
    full_states: dict = field(default_factory=dict)
    stability: dict = field(default_factory=dict)
    peak: int | None = None
    error: Exception | None = None
    #: (j, k): the curve samples that end the zero crossings of (ii) and (iii) (None: none)
    crossings: tuple = (None, None)


def push_through(model, rules: Rules = Rules()) -> PushOutcome:
    """Push ``model`` (a `PushModel`) through: F_cr, the zero crossings, states (ii) and
    (iii), their stability and the status (module docstring)."""
    try:
        path = model.push(rules.stop)
    except PushFailed as exc:
        return PushOutcome(status=str(exc), reason=str(exc))
    d, F = np.asarray(path.displacement), np.asarray(path.force)
    out = PushOutcome("ok", path_status=str(path.status), curve=(d.copy(), F.copy()), path=path)
    P, Q = np.asarray(path.positions), model.states(path)
    # the samples' dq/dd, the searches' guesses (planar paths, whose states are positions)
    rates = path.rates if getattr(path, "rates", None) is not None and Q is path.positions \
        else None
    probe = model.probe
    counts = getattr(model, "force_counts", None)
    neg = None if counts is None else counts(path)
    _, j, k = snap_crossings(d, F, neg)
    if k is None and rules.refine_dips:  # a shallow dip the steps strode over may go below 0
        refined = refine_dips(probe, d, F, P, Q, first_peak(F), model.failures, neg=neg)
        if len(refined[0]) > len(d):
            d, F, P, Q = refined[:4]
            neg = None if neg is None else refined[4]
            rates = None  # (no rates at the inserted samples)
            out.curve = (d.copy(), F.copy())
            _, j, k = snap_crossings(d, F, neg)
    out.crossings = (j, k)
    i_pk = out.peak = rules.peak(F)
    if i_pk is not None:
        if rules.refine_peak:
            out.F_cr, out.d_cr, exact = refine_peak(probe, d, F, Q, i_pk, model.failures,
                                                    rules.peak_tol, rates)
        else:
            (out.F_cr, out.d_cr), exact = parabola_peak(d, F, i_pk), False
        out.states["i"], out.full_states["i"] = np.asarray(P[i_pk]).copy(), Q[i_pk].copy()
        if exact:  # state (i) at the maximum itself, whatever the path's sampling
            out.full_states["i"] = probe.last_state.copy()
            out.states["i"] = np.asarray(model.positions(out.full_states["i"])).copy()
        if rules.peak_stability:
            out.stability["i"] = model.stability(Q[i_pk])
    model.checkpoint("after the path")
    if k is None:
        out.status, out.reason = no_second_state(str(path.status), j, float(d[-1]))
        return out

    pos_ii = q_ii = err_ii = None
    if rules.unstable_state:
        pos_ii, q_ii, err_ii = zero_force_state(model, d, F, P, Q, j, rates)
        if err_ii is not None and "ii" in rules.exact:
            out.error = err_ii
            out.status = out.reason = _not_found("the unstable state (ii)", model, pos_ii)
            return out
    pos_iii, q_iii, err_iii = zero_force_state(model, d, F, P, Q, k, rates)
    out.exact_states = err_ii is None and err_iii is None
    if pos_ii is not None:
        out.d_unstable = model.displacement(pos_ii)
        out.states["ii"], out.full_states["ii"] = pos_ii, q_ii
    out.d_second = model.displacement(pos_iii)
    out.states["iii"], out.full_states["iii"] = pos_iii, q_iii
    if err_iii is not None and "iii" in rules.exact:
        out.error = err_iii
        out.status = out.reason = _not_found("the second state (iii)", model, pos_iii)
        return out
    model.checkpoint("after the zero-force states")
    if rules.stability:
        if pos_ii is not None and err_ii is None:
            out.stability["ii"] = model.stability(q_ii)
        stab = out.stability["iii"] = model.stability(q_iii)
        if stab is None or not stab.stable_force:
            out.status = out.reason = unstable_reason(stab, out.d_second)
            return out
    out.bistable = True
    return out
