"""Simulate one bistable unit and report its snap-through metrics.

    >>> from units import UnitGeometry, simulate_unit      # or from solver.unit
    >>> r = simulate_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3))
    >>> r.bistable, r.F_cr, r.S, r.theta_deg

The apex is pushed down with MGDC from d = 0 until the force has crossed zero twice; the
unstable state (ii) and the second stable state (iii) are then solved exactly at F = 0 by
Newton from the bracketing path states, and S, theta and the base shape come from (iii).
The path is the one a displacement-controlled rig makes the unit follow: where another
equilibrium branch crosses it (a bifurcation), the push leaves along the critical mode
(`solver.branching`); ``bifurcation`` records whether that happened before snap-through.
Energies are the elastic energies of the exact states, which equal the work of F along the
path (the supports do no work), i.e. the integrals of F dd. SI units throughout.

The experiment is `units.push_through`, the one the 3-D and 2-D units and the units of a
whole array go through: zero crossings of F(d) are classified by the sign of the slope dF/dd
between the path samples that bracket them, not by their order along d: (ii) is the first
crossing after the force peak with dF/dd < 0, (iii) the next one with dF/dd > 0. The unit is
bistable only when (iii) is stable with the actuator unloaded (no negative eigenvalue of the
tangent stiffness); when it is not, ``status`` is "second state unstable: ..." and ``reason``
says why.

Scale: the model is linear elastic, so its displacements do not depend on E and scale with
the lengths, and its forces scale as E L^2. Every unit is therefore solved at the reference
L = 0.1 m, E = 2.2 GPa and the results are scaled back: E = 1e200 Pa or lengths in any unit
take exactly the same steps as the reference.
"""

from __future__ import annotations

import dataclasses
import inspect
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.solver.problem import ConvergenceError
from snapmorph.solver.stability import state_stability
from snapmorph.solver.states import DisplacementProbe
from snapmorph.units import status as statuses
from snapmorph.units.geometry import (DEFAULT_NODES, PETG_E, SUPPORT_OFFSET, UnitGeometry,
                                      build_unit, check_nodes, check_real)
from snapmorph.units.metrics import (largest_strain, most_negative_force, snap_back,
                                     strain_on_path, strain_place)
from snapmorph.units.push_through import Rules, push_through, snap_crossings
# the one crossing rule of every unit, under the names the tests check
from snapmorph.units.push_through import (  # noqa: F401
    first_peak as _first_peak,
    zero_crossings as _zero_crossings,
)
from snapmorph.units.result import UnitResultBase
from snapmorph.units.shapes import chord_angle, end_tangent_angle

__all__ = ["UnitGeometry", "UnitResult", "simulate_unit", "STATUS_CODES", "DEFAULT_NODES"]

#: status -> design-map status code (`units.status`, without "pending")
STATUS_CODES = {name: code for name, code in statuses.CODE.items() if code >= 0}
NAN = float("nan")
#: the reference unit every simulation is solved at (results are scaled back)
L_INTERNAL = 0.1  # m
E_INTERNAL = PETG_E  # Pa
DOWN = (0.0, -1.0)  # the apex is pushed towards the base
METHODS = ("mgdc", "displacement")
#: the default ``steps`` of an MGDC push: its steps adapt to the path (up to 8 x the first);
#: F_cr and F_min come from displacement-controlled searches and S, theta from the exact
#: state (iii), so a coarser path moves them by ~1e-9 (F) and ~1e-12 (S, theta) against 60
MGDC_STEPS = 20
#: the MGDC push's corrections converge to this fraction of the unit's size (the drivers'
#: default is 1e-11): the path's samples only guide the searches, which solve F_cr, F_min
#: and states (ii), (iii) again at their own displacements to the drivers' default; it saves
#: about a tenth of the push's iterations and moves no metric by more than ~1e-9 (1e-8
#: saves a quarter, but the thinnest units of the domain, t/L ~ 4e-5, then lose their
#: zero-force state)
PATH_TOL_DISP = 1e-9
#: the default ``steps`` of a displacement-controlled push (its steps are where it samples)
RIG_STEPS = 60
#: the MGDC predictor of the unit's pushes (`solver.mgdc.follow_mgdc`): with the path's
#: curvature term the corrector takes 3 iterations a step where the tangent's takes 4-5
PATH_PREDICTOR = "second-order"
#: the peak searches' bracket (F_cr, F_min), a fraction of the path's spacing at 60 steps
PEAK_TOL = 2e-3
TIES = ("exact", "spring")
BRANCHES = ("follow", "primary")


@dataclass(repr=False)
class UnitResult(UnitResultBase):
    """Metrics of one unit (SI: N, m, J, degrees for angles). NaN where a field does not exist.

    The fields of `units.result.UnitResultBase` and: S, theta_deg (state (iii)'s chord and
    turning); theta_end_deg; the energies; bifurcation; base_shape (state (iii)). released:
    state (iii) with the actuator and rollers removed (what an array without actuators
    holds): {"base_shape", "S" (chord, m), "theta_deg", "theta_end_deg", "arch"}; empty
    when the released unit is not stable (then ``self_standing`` is False). reason: no
    snap-through, no second crossing, state (iii) unstable (with its negative-eigenvalue
    count), a failed or timed-out solve."""

    geometry: UnitGeometry
    S: float = NAN
    theta_deg: float = NAN
    base_shape: np.ndarray = field(default_factory=lambda: np.full((0, 2), np.nan))
    #: angle between the base's start tangent and its chord in state (iii), degrees, signed as
    #: theta (theta / 2 for a symmetric base; the convention the paper's maps most likely use)
    theta_end_deg: float = NAN
    energy_barrier: float = NAN
    energy_stored: float = NAN
    bifurcation: bool | None = None
    F_min: float = NAN
    """N: the most negative force on the snap path (after F_cr, up to state (iii)), by
    displacement-controlled solves; NaN when F does not fall below zero"""
    d_Fmin: float = NAN
    """m: the apex displacement d at F_min"""
    F_back: float = NAN
    """N (> 0): the snap-back load: the released state (iii) on the rig's rollers, its apex
    pushed back up (+z), the force peak that returns it to (i); NaN when there is no
    released state or no peak"""
    stiffness_released: float = NAN
    """N/m: the released state (iii)'s tangent stiffness against an apex force, 1 / (e^T K^-1
    e), on the rollers; NaN when there is no released state"""
    strain_max: float = NAN
    """dimensionless: the largest surface strain |eps| + |kappa - kappa_bar| t / 2 over the
    snap path's states (d = 0 to state (iii)) and its exact states, arch and base"""
    strain_max_released: float = NAN
    """dimensionless: the same in the released state (iii); NaN when there is none"""
    strain_where: str = ""
    """where strain_max sits: "arch" or "base", its part and x / L
    (`units.metrics.strain_place`)"""

    STATE_KEYS = ("theta_end_deg", "energy_barrier", "energy_stored")
    MORE_KEYS = ("bifurcation", "F_min", "d_Fmin", "F_back", "stiffness_released",
                 "strain_max", "strain_max_released", "strain_where")


def _check_choice(name, value, choices):
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}; got {value!r}")
    return value


def check_flag(name: str, value) -> bool:
    """A simulation's flag (every unit's ``critical``, ``check_self_standing``): ``value`` as
    a bool (True, False or a numpy bool), or ValueError naming ``name``."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False; got {value!r}")
    return bool(value)


def check_steps(steps):
    """Every unit's ``steps`` (the push's first step is 3 h / steps) if an integer in
    [1, 100000], or ValueError."""
    if isinstance(steps, (bool, np.bool_)) or not isinstance(steps, (int, np.integer)) \
            or not 1 <= steps <= 100000:
        raise ValueError(f"steps (first step = 3 h / steps) must be an integer in [1, 100000]; "
                         f"got {steps!r}")
    return steps


def simulate_unit(
    g: UnitGeometry,
    nodes: int | None = None,
    method: str = "mgdc",
    tie: str = "exact",
    tie_stiffness: float | None = None,
    check_self_standing: bool = True,
    steps: int | None = None,
    branch: str = "follow",
    critical: bool = True,
    time_limit: float | None = None,
) -> UnitResult:
    """Simulate the push test of one unit and extract F_cr, S, theta and the shapes.

    ``nodes``: resolution (about the number of base nodes; None = the converged default);
    ``method``: "mgdc" (load control, the paper's) or "displacement";
    ``tie``: "exact" or "spring" bonds (``tie_stiffness`` N/m, None = 1e3 x the stiffest
    adjacent edge); ``steps``: first-step size as a fraction of 3 h (None: `MGDC_STEPS`
    for "mgdc", `RIG_STEPS` for "displacement");
    ``branch``: at a bifurcation "follow" the branch the unit takes (default) or stay on the
    "primary" (symmetric) path; ``critical``: detect critical points and report stability
    (False: the bare path, no ``bifurcation`` flag and no per-state stability; state (iii)'s
    stability is always checked); ``time_limit``: wall time (s) after which the simulation
    stops with status "timeout: ..." (None: no limit).
    Arguments are validated (ValueError naming the parameter); after that it never raises
    for a geometry that can be built: failures come back in ``status`` and ``reason``.

    ``stability`` holds, besides the per-step counts, ``critical_points`` (the path's
    `solver.stability.CriticalPoint` records) and ``states``: {"i", "ii", "iii"} ->
    `solver.stability.StateStability` (negative eigenvalues under force and displacement
    control; (i) is a force maximum, i.e. marginal under force control).
    ``bifurcation``: True when the path met a bifurcation before the force peak F_cr
    (before snap-through), False when not, None when ``critical`` is False.
    """
    if not isinstance(g, UnitGeometry):
        raise ValueError(f"g must be a UnitGeometry; got {type(g).__name__}")
    nodes = DEFAULT_NODES if nodes is None else check_nodes(nodes)
    _check_choice("method", method, METHODS)
    _check_choice("tie", tie, TIES)
    _check_choice("branch", branch, BRANCHES)
    check_self_standing = check_flag("check_self_standing", check_self_standing)
    critical = check_flag("critical", critical)
    steps = (MGDC_STEPS if method == "mgdc" else RIG_STEPS) if steps is None else \
        check_steps(steps)
    if tie_stiffness is not None:
        tie_stiffness = check_real("tie_stiffness", tie_stiffness, "N/m", "bond spring stiffness")
        if tie_stiffness <= 0:
            raise ValueError(f"tie_stiffness (bond spring stiffness, N/m) must be > 0; "
                             f"got {tie_stiffness!r}")
    if time_limit is not None:
        time_limit = check_real("time_limit", time_limit, "s", "wall-time limit")
        if time_limit <= 0:
            raise ValueError(f"time_limit (wall-time limit, s) must be > 0 (None: no limit); "
                             f"got {time_limit!r}")
    t0 = time.perf_counter()
    if g.h == 0.0:
        straight = np.stack([np.linspace(0, g.L, 3), np.zeros(3)], 1)
        return UnitResult(g, "monostable", base_shape=np.full((0, 2), np.nan),
                          shapes={"i": {"base": straight}}, solve_time=0.0,
                          reason="no arch (h = 0)")
    # Solve the reference-scale unit (see the module docstring) and scale the results back.
    length = g.L / L_INTERNAL
    force = (g.E / E_INTERNAL) * length**2
    gi = _reference_geometry(g, length)
    k_int = None if tie_stiffness is None else tie_stiffness * length / force
    deadline = None if time_limit is None else t0 + time_limit
    model = build_unit(gi, nodes=nodes, tie=tie, tie_stiffness=k_int)
    try:
        push = dict(method=method, steps=steps, branch=branch, critical=critical)
        result = _simulate(gi, model, push, check_self_standing, deadline)
    except _Timeout as exc:
        result = UnitResult(gi, f"timeout: {exc}", reason=f"timeout: {exc}")
    except ConvergenceError as exc:
        result = UnitResult(gi, f"not converged: {exc}", reason=f"not converged: {exc}")
    except (FloatingPointError, np.linalg.LinAlgError, ZeroDivisionError, OverflowError,
            ValueError) as exc:
        # the arguments are valid: an exception from inside the solve is a failed solve
        msg = f"not converged: numerical failure ({type(exc).__name__}: {exc})"
        result = UnitResult(gi, msg, reason=msg)
    result = _rescale(result, g, length, force)
    result.solve_time = time.perf_counter() - t0
    result.n_nodes = model.structure.n_nodes
    return result


def _reference_geometry(g: UnitGeometry, length: float) -> UnitGeometry:
    """``g`` at the reference scale (lengths / ``length``, E = `E_INTERNAL`): ``g`` itself
    when it is already there (no second validation of the same numbers, 70 us)."""
    if length == 1.0 and g.E == E_INTERNAL:
        return g
    return dataclasses.replace(g.scaled(1.0 / length) if length != 1.0 else g, E=E_INTERNAL)


class _Timeout(Exception):
    """The wall-time limit passed (internal: becomes status "timeout: ...")."""


class _DeadlineProbe(DisplacementProbe):
    """A `DisplacementProbe` whose every solve first checks the wall-time limit (the peak and
    zero-force searches call it many times)."""

    def __init__(self, *args, deadline=None, **kw):
        super().__init__(*args, **kw)
        self.deadline = deadline

    def solve(self, guess, d):
        _check_deadline(self.deadline, "while locating F_cr or a zero-force state")
        return super().solve(guess, d)


def _rescale(r: UnitResult, g: UnitGeometry, length: float, force: float) -> UnitResult:
    """The reference-scale result ``r`` in the units of ``g``: lengths x ``length``, forces
    x ``force``, energies x force * length. Angles and counts do not change."""
    r.geometry = g
    if length == 1.0 and force == 1.0:
        return r
    energy = force * length
    for name in ("d_cr", "d_unstable", "d_second", "S"):
        setattr(r, name, getattr(r, name) * length)
    r.F_cr *= force
    r.F_min *= force
    r.d_Fmin *= length
    r.F_back *= force
    r.stiffness_released *= force / length
    r.energy_barrier *= energy
    r.energy_stored *= energy
    d, F = r.curve
    r.curve = (np.asarray(d) * length, np.asarray(F) * force)
    r.base_shape = np.asarray(r.base_shape) * length
    r.shapes = {k: {n: np.asarray(v) * length for n, v in s.items()} for k, s in r.shapes.items()}
    if r.released:
        r.released = {k: (v * length if k in ("base_shape", "arch", "S") else v)
                      for k, v in r.released.items()}
    cps = r.stability.get("critical_points")
    if cps:
        out = []
        for c in cps:
            try:
                pos = None if c.positions is None else np.asarray(c.positions) * length
                out.append(dataclasses.replace(c, d=c.d * length, F=c.F * force, positions=pos,
                                               eigenvalue=c.eigenvalue * force / length))
            except (TypeError, ValueError, AttributeError):
                out.append(c)
        r.stability["critical_points"] = out
    if r.status == "ok" and not np.all(np.isfinite([r.F_cr, r.S, r.energy_stored])):
        r.status = "not converged: the forces overflow float64 at this E and L"
        r.reason = r.status
        r.bistable = False
    return r


def _push_options(structure, push, deadline):
    """``push`` plus a wall-time bound: the drivers' ``time_limit`` when they take it; a
    per-step stop test otherwise."""
    if deadline is None:
        return push, None
    from snapmorph.solver.displacement import follow_displacement
    from snapmorph.solver.mgdc import follow_mgdc

    driver = follow_mgdc if push["method"] == "mgdc" else follow_displacement
    if "time_limit" in inspect.signature(driver).parameters:
        return dict(push, time_limit=max(deadline - time.perf_counter(), 1e-3)), None
    return push, (lambda: time.perf_counter() > deadline)


def _check_deadline(deadline, stage):
    if deadline is not None and time.perf_counter() > deadline:
        raise _Timeout(f"wall-time limit reached {stage}")


class _PlanarPush:
    """The planar unit at the reference scale as the model of `units.push_through`: its apex
    pushed down by a path follower (``push``: the drivers' options), displacement-controlled
    probes that check the wall-time limit, states as node positions (n, 2)."""

    failures = (ConvergenceError,)

    def __init__(self, model, push, distance, deadline, limit=np.inf):
        self.model, self.st = model, model.structure
        self.options, self.distance, self.deadline = push, distance, deadline
        self.limit = limit  # m, the geometric limit the push may go on to (`push_limit`)
        self.X = self.st.reference_positions
        self.probe = self.system = self.counts = None
        self._solved = []  # (positions, system factorised there) of the last unloaded solves

    def push(self, stop):
        st = self.st
        options, late = _push_options(st, self.options, self.deadline)
        mgdc = options["method"] == "mgdc"
        rule = stop

        limited = []

        def stop(rows):  # the same test on the force-control counts, the deadline, the limit
            if late is not None and late():
                return True
            if rule({"d": rows["d"], "F": rows["F"], "neg_force": rows["neg"] if mgdc else None}):
                return True
            # a tall arch's limit lies below 3 h: past it the push only stretches the rods
            limited.append(rows["d"][-1] >= self.limit)
            return limited[-1]
        if mgdc:
            options = dict(options, tol_disp=PATH_TOL_DISP, predictor=PATH_PREDICTOR)
        path = st.push(self.model.apex, DOWN, self.distance, stop=stop, **options)
        if path.status.startswith("timeout") or (late is not None and late()):
            raise _Timeout(f"while following the path ({len(path.force)} steps)")
        self.counts = path.negative_eigenvalues if mgdc else None
        if path.status == "ok" and limited and limited[-1]:
            path = dataclasses.replace(path, status=self._limit_status())
        elif path.status == "ok" and _goes_on(path, self.counts):
            path = self._push_on(path, rule, late)
        elif mgdc and path.status != "ok":
            path = self._as_a_rig(path, rule, late)
        self.system = st.reduced_system()  # force control: the actuator unloaded
        self.probe = _DeadlineProbe(st, self.model.apex, DOWN, deadline=self.deadline)
        return path

    def _as_a_rig(self, path, rule, late):
        """MGDC stopped before its distance (a step cap, a path that wanders or turns back
        at a snap-back, a step-size underflow): the push again as a displacement-controlled
        rig makes it, from d = 0 to the geometric limit `push_limit` (it jumps where the
        rig's unit jumps, and passes regular points MGDC's steps failed at). Its path is
        taken when it ran its course or passed a state (iii); else MGDC's stands (its
        failure is the status)."""
        options, _ = _push_options(self.st, self.options, self.deadline)
        options = dict(options, method="displacement", steps=max(options["steps"], RIG_STEPS))

        def stop(rows):
            if late is not None and late():
                return True
            return rule({"d": rows["d"], "F": rows["F"], "neg_force": None})
        rig = self.st.push(self.model.apex, DOWN, self.limit, stop=stop, **options)
        if rig.status.startswith("timeout") or (late is not None and late()):
            raise _Timeout(f"while following the path as a rig ({len(rig.force)} steps)")
        j = snap_crossings(path.displacement, path.force, self.counts)[1]
        counts = None  # displacement control: d only grows, the slope rule holds
        if j is not None:
            # (ii) on MGDC's path, which follows the unstable branch a rig cannot; the rig's
            # path beyond the deepest d MGDC reached (where the rig jumps on) after it
            deepest = float(np.max(path.displacement[:j + 1]))
            beyond = np.flatnonzero(rig.displacement > deepest)
            if len(beyond):
                rig = _joined(_head(path, j + 1), _head(rig, None, beyond[0] - 1), rig.status)
                counts = np.concatenate([self.counts[:j + 1],
                                         np.full(len(rig) - j - 1, -1)])
        found = snap_crossings(rig.displacement, rig.force, counts)[2] is not None
        if not (found or rig.status == "ok"):
            return path
        self.counts = counts
        status = rig.status
        if status == "ok" and not found:
            status = self._limit_status()
        rig.info["mgdc_status"] = path.status
        return dataclasses.replace(rig, status=status)

    def _limit_status(self):
        limit = self.limit
        return (f"ok: the apex reached the geometric limit d = {limit:.6g} m "
                f"({limit / (self.distance / 3.0):.4g} h = {LIMIT_TEXT})")

    def force_counts(self, path):
        """The samples' negative-eigenvalue counts under force control (MGDC's own), -1 on
        the displacement-controlled part past 3 h (`_push_on`); None for a
        displacement-controlled push (the slope rule: d only grows there)."""
        return self.counts

    def _push_on(self, path, rule, late):
        """The push ran 3 h with F below zero (or falling) and no state (iii): on by
        displacement control from its last state to the geometric limit `push_limit` (the
        stop test sees the whole path). Returns the joined path; its status names the
        limit when it is reached without state (iii)."""
        limit = self.limit
        head = {"d": list(path.displacement), "F": list(path.force),
                "neg_force": None if self.counts is None else list(self.counts)}

        def stop(rows):
            if late is not None and late():
                return True
            neg = None if head["neg_force"] is None else \
                head["neg_force"] + [-1] * (len(rows["d"]) - 1)
            whole = {"d": head["d"] + rows["d"][1:], "F": head["F"] + rows["F"][1:],
                     "neg_force": neg}
            return rule(whole) or _turned_up(rows)
        options, _ = _push_options(self.st, self.options, self.deadline)
        options = {k: v for k, v in options.items() if k in ("critical", "time_limit")}
        more = self.st.push(self.model.apex, DOWN, limit, method="displacement", stop=stop,
                            start=path.positions[-1],
                            steps=max(self.options["steps"], RIG_STEPS), **options)
        if more.status.startswith("timeout") or (late is not None and late()):
            raise _Timeout(f"while following the path past 3 h ({len(more.force)} steps)")
        status = more.status
        if status == "ok" and not more.displacement[-1] < limit:
            status = self._limit_status()
        if self.counts is not None:
            self.counts = np.concatenate([self.counts, np.full(len(more) - 1, -1)])
        return _joined(path, more, status)

    def states(self, path):
        return path.positions

    def positions(self, state):
        return self.st.positions_of(state)

    def displacement(self, positions) -> float:
        apex = self.model.apex
        return float(self.X[apex, 1] - positions[apex, 1])

    def solve_unloaded(self, guess):
        pos, info = self.st.solve_equilibrium(guess, node=None)
        # its Newton's system holds K factorised at the state: `stability` reads it there
        self._solved.append((pos, info["system"]))
        del self._solved[:-2]  # (states (ii) and (iii))
        return pos, pos

    def stability(self, positions):
        for pos, system in self._solved:
            if pos is positions:
                return _state_stability(self.st, self.model, positions, system, True)
        return _state_stability(self.st, self.model, positions, self.system)

    def checkpoint(self, stage):
        _check_deadline(self.deadline, stage)


#: how `push_limit` bounds the push (quoted in the status of a push that reaches it)
LIMIT_TEXT = ("h + the arch's arc length from its bond's inner end to the apex + the base's "
              "length from that end to the roller: the inextensible unit cannot push further")


def push_limit(g: UnitGeometry) -> float:
    """The farthest (m) the apex of an inextensible unit can be pushed towards the base: the
    bond's inner end B lies within the base's length |x_B - x_roller| of its roller (at
    z = 0), the apex within the arch's arc length s_BA of B, so d <= h + s_BA + |x_B -
    x_roller|. A push that passes it must stretch the rods: a push that reaches it without
    state (iii) has none to find."""
    x_b = g.bond
    s_ba = (g.flat_length - x_b) + 0.5 * g.arch_length
    return g.h + s_ba + abs(x_b - SUPPORT_OFFSET * g.L)


def _goes_on(path, counts) -> bool:
    """Should the push go on past its 3 h? Yes when no state (iii) was passed and, after
    the force peak, F has fallen below zero or is still falling at the end."""
    d, F = path.displacement, path.force
    i_pk, j, k = snap_crossings(d, F, counts)
    if k is not None or len(F) < 3:
        return False
    after = F[(i_pk or 0):]
    return bool(np.min(after) < 0.0 or (F[-1] < F[-2] and d[-1] > d[-2]))


def _turned_up(rows) -> bool:
    """The push past 3 h may end where F, still above zero, rises again (no snap-through
    ahead: F did not fall below zero)."""
    d, F = rows["d"], rows["F"]
    return len(F) > 2 and min(F) > 0.0 and F[-1] > F[-2] and d[-1] > d[-2]


def _head(path, stop, start=0):
    """Rows [start, stop) of a path (its critical points in that range of d kept)."""
    rows = slice(start, stop)
    d = path.displacement[rows]
    lo, hi = float(np.min(d)), float(np.max(d))
    return dataclasses.replace(
        path, displacement=d, force=path.force[rows], positions=path.positions[rows],
        energy=path.energy[rows], iterations=path.iterations[rows],
        negative_eigenvalues=path.negative_eigenvalues[rows],
        negative_eigenvalues_displacement=path.negative_eigenvalues_displacement[rows],
        critical_points=[c for c in path.critical_points if lo <= c.d <= hi],
        fields={k: v[rows] for k, v in path.fields.items()},
        rates=None if path.rates is None else path.rates[rows],
        stiffness=None if path.stiffness is None else path.stiffness[rows])


def _joined(path, more, status):
    """The path ``path`` followed by ``more`` (which starts at its last state), as one."""
    def cat(a, b):
        return np.concatenate([np.asarray(a), np.asarray(b)[1:]])

    info = dict(path.info)
    info["total_iterations"] = (path.info.get("total_iterations", 0)
                                + more.info.get("total_iterations", 0))
    info["pushed_on"] = {"from_d": float(path.displacement[-1]), "method": more.method,
                         "status": more.status}
    fields = {k: cat(v, more.fields[k]) for k, v in path.fields.items() if k in more.fields}
    def known(name, shape):  # a per-state array of both (NaN where one has none), or None
        a, b = getattr(path, name), getattr(more, name)
        if a is None and b is None:
            return None
        return cat(np.full(shape(path), np.nan) if a is None else a,
                   np.full(shape(more), np.nan) if b is None else b)

    rates = known("rates", lambda p: np.shape(p.positions))
    stiffness = known("stiffness", lambda p: np.shape(p.displacement))
    return dataclasses.replace(
        path, displacement=cat(path.displacement, more.displacement),
        force=cat(path.force, more.force), positions=cat(path.positions, more.positions),
        status=status, energy=cat(path.energy, more.energy),
        iterations=cat(path.iterations, more.iterations),
        negative_eigenvalues=cat(path.negative_eigenvalues, more.negative_eigenvalues),
        negative_eigenvalues_displacement=cat(path.negative_eigenvalues_displacement,
                                              more.negative_eigenvalues_displacement),
        info=info, critical_points=list(path.critical_points) + list(more.critical_points),
        fields=fields, rates=rates, stiffness=stiffness)


def _simulate(g, model, push, check_self_standing, deadline=None):
    st = model.structure
    critical = push["critical"]
    pusher = _PlanarPush(model, push, 3.0 * g.h, deadline, push_limit(g))
    # the peak search as fine in d as with 60 steps, whatever the path's spacing
    tol = PEAK_TOL * push["steps"] / RIG_STEPS
    out = push_through(pusher, Rules(peak_stability=critical, peak_tol=tol))
    if out.error is not None:  # a zero-force state not found: the simulation failed
        raise out.error
    path = out.path
    result = UnitResult(g, "ok", curve=out.curve)
    result.stability = {
        "negative_eigenvalues": path.negative_eigenvalues.copy(),
        "negative_eigenvalues_displacement": path.negative_eigenvalues_displacement.copy(),
    }
    if critical:
        result.stability["critical_points"] = list(path.critical_points)
        result.stability["states"] = {}
    arch, base = model.arch_nodes, model.base_nodes

    def shape(pos):
        return {"arch": pos[arch].copy(), "base": pos[base].copy()}

    i_pk = out.peak
    if i_pk is not None:
        result.F_cr, result.d_cr = out.F_cr, out.d_cr
        result.shapes["i"] = shape(path.positions[i_pk])
    if critical:
        d_snap = result.d_cr if i_pk is not None else np.inf
        result.bifurcation = any(c.d <= d_snap for c in path.bifurcations)
        if i_pk is not None:
            result.stability["states"]["i"] = out.stability["i"]
    # the snap path: from d = 0 to the crossing of state (iii) (the whole path without one)
    end = len(out.curve[1]) - 1 if out.crossings[1] is None else out.crossings[1]
    result.F_min, result.d_Fmin = most_negative_force(
        pusher.probe, *out.curve, path.positions, i_pk, end, _PlanarPush.failures, tol,
        path.rates)
    rods = {"arch": arch, "base": base}
    X = st.reference_positions
    # the snap path's samples with the states (i), (ii), (iii) in their places along it
    # (exact equilibria between two samples), for the largest strain
    d_path, states, rates = _with_states(out, path, end)
    top, rod, node, k, series = largest_strain(states, X, rods, g.t)
    # located between the samples by displacement-controlled solves
    result.strain_max = strain_on_path(pusher.probe, d_path, series, states, k, X, rods, g.t,
                                       _PlanarPush.failures, tol, rates)
    result.strain_where = strain_place(rod, X[rods[rod][node], 0], g.L)
    if "iii" not in out.states:  # no second state: monostable, or the path failed
        result.status, result.reason = out.status, out.reason
        return result

    pos_ii, pos_iii = out.states["ii"], out.states["iii"]
    result.d_unstable, result.d_second = out.d_unstable, out.d_second
    result.energy_barrier = st.energy(pos_ii)
    result.shapes["ii"] = shape(pos_ii)
    result.shapes["iii"] = shape(pos_iii)
    if critical:
        result.stability["states"]["ii"] = out.stability["ii"]
        result.stability["states"]["iii"] = out.stability["iii"]
    if not out.bistable:
        result.status, result.reason = out.status, out.reason
        return result
    result.bistable = True
    base_pos = pos_iii[base]
    result.base_shape = base_pos.copy()
    result.S = float(base_pos[-1, 0] - base_pos[0, 0])
    result.theta_deg = end_tangent_angle(base_pos)
    result.theta_end_deg = chord_angle(base_pos)
    result.energy_stored = st.energy(pos_iii)
    if check_self_standing:
        _check_deadline(deadline, "before the released state")
        result.self_standing, released = _self_standing(g, model, pos_iii)
        if released is not None:
            rb = released[base]
            result.released = {
                "base_shape": rb.copy(),
                "S": float(np.hypot(*(rb[-1] - rb[0]))),
                "theta_deg": end_tangent_angle(rb),
                "theta_end_deg": chord_angle(rb),
                "arch": released[arch].copy(),
            }
            result.strain_max_released = largest_strain(released, X, rods, g.t)[0]
            _check_deadline(deadline, "before the snap-back push")
            _snap_back(result, g, model, released, push["steps"], deadline)
    return result


def _with_states(out, path, end):
    """(d (K,), positions (K, n_nodes, 2), their dq/dd or None): the path's samples
    0..``end`` with the states (i), (ii) and (iii) of ``out`` (a `PushOutcome`) inserted
    where they lie: (i) next to the peak sample on the side of d_cr, (ii) and (iii) inside
    the sample brackets of their zero crossings (rates NaN there: not known). States not
    found are left out."""
    d = list(np.asarray(out.curve[0][:end + 1], float))
    P = list(np.asarray(path.positions[:end + 1], float))
    R = None if path.rates is None else list(np.asarray(path.rates[:end + 1], float))
    unknown = np.full(np.shape(P[0]), np.nan)
    places = []
    if "i" in out.states and out.peak is not None and np.isfinite(out.d_cr) \
            and out.d_cr != d[out.peak]:
        places.append((out.peak + (1 if out.d_cr > d[out.peak] else 0), out.d_cr, "i"))
    j, k = out.crossings
    for name, at, depth in (("ii", j, out.d_unstable), ("iii", k, out.d_second)):
        if name in out.states and at is not None and at <= end and np.isfinite(depth):
            places.append((at, depth, name))
    for at, depth, name in sorted(places, key=lambda p: -p[0]):
        state = np.asarray(out.states[name], float)
        # a state closer to a sample than a quarter of their bracket takes its place: a
        # near-double point leaves the searches between samples nothing to interpolate on
        lo, hi = d[at - 1], d[at] if at < len(d) else d[at - 1]
        near = at - 1 if abs(depth - lo) <= abs(depth - hi) else at
        if near < len(d) and abs(depth - d[near]) < 0.25 * abs(hi - lo):
            d[near], P[near] = float(depth), state
            if R is not None:
                R[near] = unknown
        else:
            d.insert(at, float(depth))
            P.insert(at, state)
            if R is not None:
                R.insert(at, unknown)
    return np.asarray(d), np.asarray(P), None if R is None else np.asarray(R)


def _snap_back(result, g, model, released, steps, deadline):
    """F_back and stiffness_released of a bistable, self-standing result (`units.metrics.
    snap_back`): the unit without its actuator on the rollers, its base middle held in x."""
    back = model.variant(actuator=False)
    back.structure.fix(back.base_mid, "x")
    # the main push's predictor and path tolerance (the peak is solved again exactly), and
    # its search as fine in d as with 60 steps (`PEAK_TOL`): 8 % fewer iterations than the
    # tangent at the drivers' tolerance with its own search (whose bracket was 2e-3 of the
    # samples' spacing: F_back moved by up to 2.5e-6 where the steps grew)
    options = dict(predictor=PATH_PREDICTOR, tol_disp=PATH_TOL_DISP)
    if deadline is not None:
        options["time_limit"] = max(deadline - time.perf_counter(), 1e-3)
    try:
        # a third of the push's steps: the peak is located by displacement-controlled
        # solves, not read off the samples (F_back moves by ~1e-10 relative against 60)
        F_back, _, k, path = snap_back(back, released, 3.0 * g.h, max(1, steps // 3),
                                       options, _PlanarPush.failures,
                                       PEAK_TOL * max(1, steps // 3) / RIG_STEPS)
    except ConvergenceError:
        return
    if path.status.startswith("timeout"):
        raise _Timeout("while pushing the released unit back")
    result.F_back, result.stiffness_released = F_back, k


def _state_stability(st, model, positions, system, factorised=False):
    """Negative-eigenvalue counts of a state with the apex loaded (force control) and held
    (displacement control); None when the state is exactly critical. ``factorised``: the
    system holds K factorised at the state already (`state_stability`)."""
    try:
        return state_stability(st, positions, model.apex, DOWN, system=system,
                               factorised=factorised)
    except ValueError:
        return None


def _self_standing(g, model, pos_iii):
    """Is state (iii) stable with the actuator and rollers removed (rigid-body motion held
    by a statically determinate set of constraints)? Returns (flag, released positions or
    None)."""
    free = model.variant(actuator=False, supports=False)
    st = free.structure
    st.fix(free.base_mid, "xz")
    st.fix(int(free.base_nodes[0]), "z")
    try:
        pos, info = st.solve_equilibrium(pos_iii, node=None)
    except ConvergenceError:
        return False, None
    moved = float(np.max(np.abs(pos - pos_iii)))
    ok = bool(info["negative_eigenvalues"] == 0 and moved < 0.25 * g.h)
    return ok, (pos if ok else None)
