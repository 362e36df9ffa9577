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

Zero crossings of F(d) are classified by the sign of the slope dF/dd between the path samples
that bracket them, not by their order along d: (ii) is the first crossing after the force peak
with dF/dd < 0, (iii) the next one with dF/dd > 0. The unit is bistable only when (iii) is
stable with the actuator unloaded (no negative eigenvalue of the tangent stiffness); when it
is not, ``status`` is "second state unstable: ..." and ``reason`` says why.

Scale: the model is linear elastic, so its displacements do not depend on E and scale with
the lengths, and its forces scale as E L^2. Every unit is therefore solved at the reference
L = 0.1 m, E = 2.2 GPa and the results are scaled back: E = 1e200 Pa or lengths in any unit
take exactly the same steps as the reference.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

import dataclasses
import inspect

from snapmorph.solver.problem import ConvergenceError
from snapmorph.solver.stability import state_stability
from snapmorph.solver.states import DisplacementProbe, refine_maximum, zero_force_displacement
from snapmorph.units import status as statuses
from snapmorph.units.geometry import DEFAULT_NODES, PETG_E, UnitGeometry, build_unit, check_nodes, check_real

__all__ = ["UnitGeometry", "UnitResult", "simulate_unit", "STATUS_CODES", "DEFAULT_NODES"]

#: status -> design-map status code (`units.status`, without "pending")
STATUS_CODES = {name: code for name, code in statuses.CODE.items() if code >= 0}
NAN = float("nan")
#: the reference unit every simulation is solved at (results are scaled back)
L_INTERNAL = 0.1  # m
E_INTERNAL = PETG_E  # Pa
METHODS = ("mgdc", "displacement")
TIES = ("exact", "spring")
BRANCHES = ("follow", "primary")


class ReleasedMetrics:
    """S and theta of the released state (iii) (actuator removed), read from a result's
    ``released`` dict; shared by the planar, 3-D and 2-D units' results."""

    @property
    def S_released(self) -> float:
        """Chord (m) of the released state (iii); NaN when the released unit is not stable."""
        return float(self.released.get("S", NAN))

    @property
    def theta_released_deg(self) -> float:
        """Turning (degrees) of the released state (iii); NaN when it is not stable."""
        return float(self.released.get("theta_deg", NAN))


@dataclass
class UnitResult(ReleasedMetrics):
    """Metrics of one unit (SI: N, m, J, degrees for angles). NaN where a field does not exist."""

    geometry: UnitGeometry
    status: str
    bistable: bool = False
    F_cr: float = NAN
    d_cr: float = NAN
    d_unstable: float = NAN
    d_second: float = NAN
    S: float = NAN
    theta_deg: float = NAN
    #: angle between the base's start tangent and its chord in state (iii), degrees, signed as
    #: theta (theta / 2 for a symmetric base; the convention the paper's maps most likely use)
    theta_end_deg: float = NAN
    energy_barrier: float = NAN
    energy_stored: float = NAN
    self_standing: bool | None = None
    #: state (iii) with the actuator and rollers removed (what an array without actuators
    #: holds): {"base_shape", "S" (chord, m), "theta_deg", "theta_end_deg", "arch"}; empty
    #: when the released unit is not stable (then ``self_standing`` is False)
    released: dict = field(default_factory=dict)
    #: why the unit is not bistable ("" when it is): no snap-through, no second crossing,
    #: state (iii) unstable (with its negative-eigenvalue count), a failed or timed-out solve
    reason: str = ""
    bifurcation: bool | None = None
    curve: tuple = (np.zeros(0), np.zeros(0))
    base_shape: np.ndarray = field(default_factory=lambda: np.full((0, 2), np.nan))
    shapes: dict = field(default_factory=dict)
    stability: dict = field(default_factory=dict)
    solve_time: float = NAN
    n_nodes: int = 0

    @property
    def status_code(self) -> int:
        """The design-map code of ``status``: 0 ok, 1 monostable, 2 not converged,
        3 invalid geometry, 4 timeout, 5 second state unstable."""
        return statuses.status_code(self.status)

    def summary(self) -> dict:
        """The scalar metrics as a plain dict (SI)."""
        keys = ("status", "bistable", "F_cr", "d_cr", "d_unstable", "d_second", "S",
                "theta_deg", "theta_end_deg", "energy_barrier", "energy_stored",
                "self_standing", "S_released", "theta_released_deg", "bifurcation", "reason",
                "solve_time", "n_nodes")
        return {k: getattr(self, k) for k in keys}

    def __repr__(self) -> str:
        g = self.geometry
        head = (f"UnitResult({self.status.split(':')[0]!r}, L={g.L:.4g} m, h={g.h:.4g} m, "
                f"t={g.t:.4g} m, w={g.w:.4g} m, b={g.b:.4g} m")
        if self.bistable:
            rel = self.theta_released_deg
            return (f"{head}: bistable, F_cr={self.F_cr:.4g} N, S={self.S:.4g} m, "
                    f"theta={self.theta_deg:.4g} deg, released theta={rel:.4g} deg, "
                    f"{self.solve_time:.3g} s)")
        return f"{head}: not bistable ({self.reason or self.status}), F_cr={self.F_cr:.4g} N)"


def _check_choice(name, value, choices):
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}; got {value!r}")
    return value


def _check_flag(name, value):
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False; got {value!r}")
    return bool(value)


def simulate_unit(
    g: UnitGeometry,
    nodes: int | None = None,
    method: str = "mgdc",
    tie: str = "exact",
    tie_stiffness: float | None = None,
    check_self_standing: bool = True,
    steps: int = 60,
    branch: str = "follow",
    critical: bool = True,
    time_limit: float | None = None,
) -> UnitResult:
    """Simulate the push test of one unit and extract F_cr, S, theta and the shapes.

    ``nodes``: resolution (about the number of base nodes; None = the converged default);
    ``method``: "mgdc" (load control, the paper's) or "displacement";
    ``tie``: "exact" or "spring" bonds (``tie_stiffness`` N/m, None = 1e3 x the stiffest
    adjacent edge); ``steps``: first-step size as a fraction of 3 h;
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
    check_self_standing = _check_flag("check_self_standing", check_self_standing)
    critical = _check_flag("critical", critical)
    if isinstance(steps, (bool, np.bool_)) or not isinstance(steps, (int, np.integer)) \
            or not 1 <= steps <= 100000:
        raise ValueError(f"steps (first step = 3 h / steps) must be an integer in [1, 100000]; "
                         f"got {steps!r}")
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
    gi = dataclasses.replace(g.scaled(1.0 / length) if length != 1.0 else g, E=E_INTERNAL)
    k_int = None if tie_stiffness is None else tie_stiffness * length / force
    deadline = None if time_limit is None else t0 + time_limit
    model = build_unit(gi, nodes=nodes, tie=tie, tie_stiffness=k_int)
    try:
        push = dict(method=method, steps=steps, branch=branch, critical=critical)
        result = _simulate(gi, model, push, check_self_standing, nodes, tie, k_int, deadline)
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


def _stop_after_second_crossing(rows):
    F = rows["F"]
    if len(F) < 3 or F[-1] <= 0.0:
        return False
    return bool(np.any(np.asarray(F[:-1]) < 0.0))


def _simulate(g, model, push, check_self_standing, nodes, tie, tie_stiffness, deadline=None):
    st = model.structure
    distance = 3.0 * g.h
    push, late = _push_options(st, push, deadline)
    stop = _stop_after_second_crossing
    if late is not None:
        def stop(rows):  # noqa: F811 - the same test, and the deadline
            return late() or _stop_after_second_crossing(rows)
    path = st.push(model.apex, (0.0, -1.0), distance, stop=stop, **push)
    if path.status.startswith("timeout") or (late is not None and late()):
        raise _Timeout(f"while following the path ({len(path.force)} steps)")
    d, F = path.displacement, path.force
    result = UnitResult(g, "ok", curve=(d.copy(), F.copy()))
    result.stability = {
        "negative_eigenvalues": path.negative_eigenvalues.copy(),
        "negative_eigenvalues_displacement": path.negative_eigenvalues_displacement.copy(),
    }
    critical = push["critical"]
    if critical:
        result.stability["critical_points"] = list(path.critical_points)
        result.stability["states"] = {}
    force_system = st.reduced_system()
    arch, base = model.arch_nodes, model.base_nodes

    def shape(pos):
        return {"arch": pos[arch].copy(), "base": pos[base].copy()}

    probe = _DeadlineProbe(st, model.apex, (0.0, -1.0), deadline=deadline)
    i_pk = _first_peak(F)
    if i_pk is not None:
        result.F_cr, result.d_cr = _refine_peak(d, F, i_pk, probe, path.positions)
        result.shapes["i"] = shape(path.positions[i_pk])
    if critical:
        d_snap = result.d_cr if i_pk is not None else np.inf
        result.bifurcation = any(c.d <= d_snap for c in path.bifurcations)
        if i_pk is not None:
            result.stability["states"]["i"] = _state_stability(st, model, path.positions[i_pk],
                                                               force_system)
    _check_deadline(deadline, "after the path")
    crossings = _zero_crossings(d, F, start=(i_pk or 0))
    j = next((i for i, slope in crossings if slope < 0), None)
    k = next((i for i, slope in crossings if slope > 0 and j is not None and i > j), None)
    if k is None:
        if path.status != "ok" and not path.status.startswith("stopped"):
            result.status = path.status
            result.reason = path.status
        elif j is None or path.status == "ok":
            result.status = "monostable"
            result.reason = ("no snap-through: F does not fall below zero" if j is None else
                             "F crosses zero downwards but does not rise through zero again "
                             f"before d = {d[-1]:.4g} m")
        else:
            result.status = path.status
            result.reason = path.status
        return result

    X = st.reference_positions
    pos_ii = _solve_zero_force(st, path, j, probe)
    pos_iii = _solve_zero_force(st, path, k, probe)
    _check_deadline(deadline, "after the zero-force states")
    result.d_unstable = float(X[model.apex, 1] - pos_ii[model.apex, 1])
    result.d_second = float(X[model.apex, 1] - pos_iii[model.apex, 1])
    result.energy_barrier = st.energy(pos_ii)
    result.shapes["ii"] = shape(pos_ii)
    result.shapes["iii"] = shape(pos_iii)
    stab_ii = _state_stability(st, model, pos_ii, force_system)
    stab_iii = _state_stability(st, model, pos_iii, force_system)
    if critical:
        result.stability["states"]["ii"] = stab_ii
        result.stability["states"]["iii"] = stab_iii
    if stab_iii is None or not stab_iii.stable_force:
        why = ("its tangent stiffness is singular (a critical state)" if stab_iii is None else
               f"{stab_iii.negative_force} negative eigenvalue(s) of the tangent stiffness "
               f"with the actuator unloaded")
        result.status = f"second state unstable: state (iii) at d = {result.d_second:.4g} m has {why}"
        result.reason = result.status
        return result
    result.bistable = True
    base_pos = pos_iii[base]
    result.base_shape = base_pos.copy()
    result.S = float(base_pos[-1, 0] - base_pos[0, 0])
    result.theta_deg = _end_tangent_angle(base_pos)
    result.theta_end_deg = _chord_angle(base_pos)
    result.energy_stored = st.energy(pos_iii)
    if check_self_standing:
        _check_deadline(deadline, "before the released state")
        result.self_standing, released = _self_standing(g, model, pos_iii, nodes, tie,
                                                         tie_stiffness)
        if released is not None:
            rb = released[base]
            result.released = {
                "base_shape": rb.copy(),
                "S": float(np.hypot(*(rb[-1] - rb[0]))),
                "theta_deg": _end_tangent_angle(rb),
                "theta_end_deg": _chord_angle(rb),
                "arch": released[arch].copy(),
            }
    return result


def _state_stability(st, model, positions, system):
    """Negative-eigenvalue counts of a state with the apex loaded (force control) and held
    (displacement control); None when the state is exactly critical."""
    try:
        return state_stability(st, positions, model.apex, (0.0, -1.0), system=system)
    except ValueError:
        return None


def _first_peak(F):
    for i in range(1, len(F) - 1):
        if F[i] > 0 and F[i] >= F[i - 1] and F[i] > F[i + 1]:
            return i
    return None


def _refine_peak(d, F, i, probe, positions):
    """F_cr and d_cr: the maximum of F(d) located by displacement-controlled solves around
    path sample ``i`` (a force maximum is a regular point under displacement control); the
    vertex of the parabola through the three samples if the path is not monotone there."""
    x, y = d[i - 1: i + 2], F[i - 1: i + 2]
    if x[0] < x[1] < x[2]:
        try:
            F_max, d_max = refine_maximum(probe, d, F, positions, i, tol_d=2e-3 * (x[2] - x[0]))
            if F_max >= F[i]:
                return float(F_max), float(d_max)
        except ConvergenceError:
            pass
        a, b, c = np.polyfit(x - x[1], y, 2)
        xv = -b / (2 * a) if a < 0 else np.inf
        if x[0] - x[1] <= xv <= x[2] - x[1]:
            return float(c - b * b / (4 * a)), float(x[1] + xv)
    return float(F[i]), float(d[i])


def _zero_crossings(d, F, start=0):
    """Zero crossings of F along the path after sample ``start``, in path order:
    [(i, slope sign)] where samples i-1 and i bracket the zero and the sign is that of dF/dd
    between them (-1: an unstable equilibrium under displacement control, such as (ii);
    +1: a candidate stable state, such as (iii)). A path running backwards in d (snap-back)
    flips the sign: it is the slope that classifies a crossing, not the direction of F."""
    out = []
    for i in range(max(start, 0) + 1, len(F)):
        if i == 1 and F[0] == 0.0:
            continue  # the unloaded start is not a crossing
        if (F[i - 1] >= 0.0 > F[i]) or (F[i - 1] <= 0.0 < F[i]):
            dF = F[i] - F[i - 1]
            dd = d[i] - d[i - 1]
            slope = np.sign(dF) * (np.sign(dd) if dd != 0 else 1.0)
            out.append((i, int(slope)))
    return out


def _solve_zero_force(st, path, i, probe):
    """Equilibrium at F = 0 between the path states i-1 and i (which bracket a zero of F).

    Newton under load control from the interpolated state first; if it lands outside the
    bracket (it can wander to another equilibrium), the zero is located by regula falsi on
    displacement-controlled solves, and Newton finishes from there."""
    d, F, P = path.displacement, path.force, path.positions
    F0, F1 = F[i - 1], F[i]
    s = F0 / (F0 - F1)
    apex = probe.control.node
    z0 = probe.X[apex, 1]
    lo, hi = min(d[i - 1], d[i]), max(d[i - 1], d[i])
    pad = 1e-6 * (hi - lo) + 1e-12

    def inside(pos):
        return lo - pad <= z0 - pos[apex, 1] <= hi + pad

    guess = (1 - s) * P[i - 1] + s * P[i]
    try:
        pos, _ = st.solve_equilibrium(guess, node=None)
        if inside(pos):
            return pos
    except ConvergenceError:
        pass
    tol_F = 1e-9 * max(abs(F0), abs(F1))
    x, guess = zero_force_displacement(probe, d[i - 1], d[i], P[i - 1], P[i], F0, F1, tol_F)
    pos, _ = st.solve_equilibrium(guess, node=None)
    if not inside(pos):
        raise ConvergenceError("the zero-force state left its path bracket")
    return pos


def _end_tangent_angle(base_pos):
    """Signed angle (degrees) from the first to the last base edge; > 0 when the base curls
    toward +z, the side the arch started on."""
    e0 = base_pos[1] - base_pos[0]
    e1 = base_pos[-1] - base_pos[-2]
    a = math.atan2(e1[1], e1[0]) - math.atan2(e0[1], e0[0])
    a = (a + math.pi) % (2 * math.pi) - math.pi
    return math.degrees(a)


def _chord_angle(base_pos):
    """Signed angle (degrees) from the base's start tangent (first edge) to its chord (first
    to last node): theta_end, theta / 2 for a symmetric base."""
    e0 = base_pos[1] - base_pos[0]
    c = base_pos[-1] - base_pos[0]
    a = math.atan2(c[1], c[0]) - math.atan2(e0[1], e0[0])
    a = (a + math.pi) % (2 * math.pi) - math.pi
    return math.degrees(a)


def _self_standing(g, model, pos_iii, nodes, tie, tie_stiffness):
    """Is state (iii) stable with the actuator and rollers removed (rigid-body motion held
    by a statically determinate set of constraints)? Returns (flag, released positions or
    None)."""
    free = build_unit(g, nodes=nodes, tie=tie, tie_stiffness=tie_stiffness,
                      actuator=False, supports=False)
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
