"""Simulate one bistable unit and report its snap-through metrics.

    >>> from solver.unit import UnitGeometry, simulate_unit
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
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from solver.continuation import ConvergenceError
from solver.stability import state_stability
from solver.states import DisplacementProbe, refine_maximum, zero_force_displacement
from solver.unit_model import DEFAULT_NODES, UnitGeometry, build_unit

__all__ = ["UnitGeometry", "UnitResult", "simulate_unit", "STATUS_CODES"]

STATUS_CODES = {"ok": 0, "monostable": 1, "not_converged": 2, "invalid_geometry": 3}
NAN = float("nan")


@dataclass
class UnitResult:
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
    energy_barrier: float = NAN
    energy_stored: float = NAN
    self_standing: bool | None = None
    #: state (iii) with the actuator and rollers removed (what an array without actuators
    #: holds): {"base_shape", "S" (chord, m), "theta_deg", "arch"}; empty when not stable
    released: dict = field(default_factory=dict)
    bifurcation: bool | None = None
    curve: tuple = (np.zeros(0), np.zeros(0))
    base_shape: np.ndarray = field(default_factory=lambda: np.full((0, 2), np.nan))
    shapes: dict = field(default_factory=dict)
    stability: dict = field(default_factory=dict)
    solve_time: float = NAN
    n_nodes: int = 0

    @property
    def status_code(self) -> int:
        """0 ok, 1 monostable, 2 not converged (the design-map codes)."""
        if self.status in STATUS_CODES:
            return STATUS_CODES[self.status]
        return STATUS_CODES["not_converged"]

    def summary(self) -> dict:
        """The scalar metrics as a plain dict (SI)."""
        keys = ("status", "bistable", "F_cr", "d_cr", "d_unstable", "d_second", "S",
                "theta_deg", "energy_barrier", "energy_stored", "self_standing",
                "bifurcation", "solve_time", "n_nodes")
        return {k: getattr(self, k) for k in keys}


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
) -> UnitResult:
    """Simulate the push test of one unit and extract F_cr, S, theta and the shapes.

    ``nodes``: resolution (about the number of base nodes; None = the converged default);
    ``method``: "mgdc" (load control, the paper's) or "displacement";
    ``tie``: "exact" or "spring" bonds; ``steps``: first-step size as a fraction of 3 h;
    ``branch``: at a bifurcation "follow" the branch the unit takes (default) or stay on the
    "primary" (symmetric) path; ``critical``: detect critical points and report stability
    (False: the bare path, no ``bifurcation`` flag and no per-state stability).
    Never raises for a geometry that can be built: failures come back in ``status``.

    ``stability`` holds, besides the per-step counts, ``critical_points`` (the path's
    `solver.stability.CriticalPoint` records) and ``states``: {"i", "ii", "iii"} ->
    `solver.stability.StateStability` (negative eigenvalues under force and displacement
    control; (i) is a force maximum, i.e. marginal under force control).
    ``bifurcation``: True when the path met a bifurcation before the force peak F_cr
    (before snap-through), False when not, None when ``critical`` is False.
    """
    if not isinstance(g, UnitGeometry):
        raise ValueError(f"g must be a UnitGeometry; got {type(g).__name__}")
    nodes = DEFAULT_NODES if nodes is None else nodes
    t0 = time.perf_counter()
    if g.h == 0.0:
        straight = np.stack([np.linspace(0, g.L, 3), np.zeros(3)], 1)
        return UnitResult(g, "monostable", base_shape=np.full((0, 2), np.nan),
                          shapes={"i": {"base": straight}}, solve_time=0.0)
    model = build_unit(g, nodes=nodes, tie=tie, tie_stiffness=tie_stiffness)
    try:
        push = dict(method=method, steps=steps, branch=branch, critical=critical)
        result = _simulate(g, model, push, check_self_standing, nodes, tie, tie_stiffness)
    except ConvergenceError as exc:
        result = UnitResult(g, f"not converged: {exc}")
    except (FloatingPointError, np.linalg.LinAlgError) as exc:
        result = UnitResult(g, f"not converged: numerical failure ({exc})")
    result.solve_time = time.perf_counter() - t0
    result.n_nodes = model.structure.n_nodes
    return result


def _stop_after_second_crossing(rows):
    F = rows["F"]
    if len(F) < 3 or F[-1] <= 0.0:
        return False
    return bool(np.any(np.asarray(F[:-1]) < 0.0))


def _simulate(g, model, push, check_self_standing, nodes, tie, tie_stiffness):
    st = model.structure
    distance = 3.0 * g.h
    path = st.push(model.apex, (0.0, -1.0), distance, stop=_stop_after_second_crossing, **push)
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

    probe = DisplacementProbe(st, model.apex, (0.0, -1.0))
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
    j = _first_crossing(F, start=(i_pk or 0), downward=True)
    k = _first_crossing(F, start=j, downward=False) if j is not None else None
    if k is None:
        if path.status != "ok" and not path.status.startswith("stopped"):
            result.status = path.status
        elif j is None or path.status == "ok":
            result.status = "monostable"
        else:
            result.status = path.status
        return result

    X = st.reference_positions
    pos_ii = _solve_zero_force(st, path, j, probe)
    pos_iii = _solve_zero_force(st, path, k, probe)
    result.d_unstable = float(X[model.apex, 1] - pos_ii[model.apex, 1])
    result.d_second = float(X[model.apex, 1] - pos_iii[model.apex, 1])
    result.bistable = True
    base_pos = pos_iii[base]
    result.base_shape = base_pos.copy()
    result.S = float(base_pos[-1, 0] - base_pos[0, 0])
    result.theta_deg = _end_tangent_angle(base_pos)
    result.energy_barrier = st.energy(pos_ii)
    result.energy_stored = st.energy(pos_iii)
    result.shapes["ii"] = shape(pos_ii)
    result.shapes["iii"] = shape(pos_iii)
    if critical:
        result.stability["states"]["ii"] = _state_stability(st, model, pos_ii, force_system)
        result.stability["states"]["iii"] = _state_stability(st, model, pos_iii, force_system)
    if check_self_standing:
        result.self_standing, released = _self_standing(g, model, pos_iii, nodes, tie,
                                                         tie_stiffness)
        if released is not None:
            rb = released[base]
            result.released = {
                "base_shape": rb.copy(),
                "S": float(np.hypot(*(rb[-1] - rb[0]))),
                "theta_deg": _end_tangent_angle(rb),
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


def _first_crossing(F, start, downward):
    for i in range(max(start, 0) + 1, len(F)):
        if downward and F[i - 1] >= 0.0 > F[i]:
            return i
        if not downward and F[i - 1] <= 0.0 < F[i]:
            return i
    return None


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
