"""Load control: every dead load of a structure times one load factor, followed with MGDC.

`follow_load` hands the shared MGDC driver (`solver.mgdc`) the structure *without* its
dead loads (`ConstrainedStructure.without_dead_loads`) and a `LoadControl` in place of a
pushed node: its unit load is the dead-load pattern scaled to 1 N in all,

    P = W^T f / F_tot,   F_tot = sum over nodes of |f_i|  (N; the total weight under gravity),

so the driver's load F = lambda F_tot is the dead loads at factor lambda, and the path's
displacement is the work-conjugate one, d = f . (x - X) / F_tot (m): the load-weighted mean
displacement along the loads (under gravity, the descent of the centre of mass), F d the
loads' work. The drivers' stability counts, critical points (a limit point of the load
factor is a force limit, control "force") and branch switching carry over unchanged; the
rig of displacement control has nothing to hold (a distributed load has no single
displacement), so branches are switched by the tangent plane. Formulation and the
statuses: docs/loads.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snapmorph.solver.equilibrium import equilibrium
from snapmorph.solver.mgdc import follow_mgdc
from snapmorph.solver.problem import MAX_DISTANCE, real_scalar, require_problem, state_from

#: a step may be up to this fraction of the path's length so far (`LoadControl.max_step`)
TRAVEL_STEP = 0.1

#: `follow_mgdc`'s target_iterations for load control: its corrector converges in four
#: iterations on most steps (three corrections and the estimate of `newton.settled`), and
#: with the default target (4) the steps then never grow past the first one, which comes
#: from the linear response (a standing strip: 3889 steps, 21 s; with 5: 265 steps, 1.2 s)
TARGET_ITERATIONS = 5

#: statuses of a load-controlled path that are answers about the structure (every other
#: status, "not converged: ...", "timeout: ...", "stopped: ...", is a path cut short)
ANSWERS = ("ok", "snapped", "limit")


@dataclass
class LoadControl:
    """What `follow_load` follows: the dead loads (``pattern`` (m,) on the full DOFs
    ``dofs``, scaled to 1 N in all; ``total`` N at factor 1) times a load factor up to
    ``max_factor``. ``origin``: the stress-free coordinates of ``dofs``; ``start`` the full
    state at factor 0 (None: stress free) with ``d_start`` = d(start); ``travel`` (m): how
    far d may move from the start. The members the drivers use are `solver.problem.Control`'s
    (see there); there is no pushed node and no rig."""

    dofs: np.ndarray
    pattern: np.ndarray
    total: float
    max_factor: float
    travel: float
    origin: np.ndarray
    start: np.ndarray | None = None
    d_start: float = 0.0
    method = "mgdc"
    node = None
    axis = None
    rig_axis = None

    @property
    def distance(self) -> float:
        """The drivers' guards' reach (m): the start's d plus the travel allowed."""
        return self.d_start + self.travel

    def displacement(self, q) -> float:
        """d = f . (x - X) / F_tot (m) at the state ``q``: the work-conjugate displacement."""
        return float(self.pattern @ (q[self.dofs] - self.origin))

    def force(self, system) -> float:
        """The load (N) along the pattern that the last evaluated gradient balances."""
        g = system.grad_full[self.dofs]
        return float(self.pattern @ g) / float(self.pattern @ self.pattern)

    def unit_load(self, system) -> np.ndarray:
        """Reduced load vector W^T p of the unit pattern (tied and grouped nodes' shares
        on their group's DOFs; supported components dropped)."""
        P = np.zeros(system.n)
        red = system.dof_map[self.dofs]
        free = red >= 0
        np.add.at(P, red[free], self.pattern[free])
        return P

    def reduced_weights(self, system):
        """(weights, indices) with d's change along a reduced vector u = weights @ u[indices]."""
        P = self.unit_load(system)
        idx = np.flatnonzero(P)
        return P[idx], idx

    def end_factor(self, unit_N) -> float:
        """``max_factor`` in the driver's load units (``unit_N`` N per unit)."""
        return self.max_factor * self.total / unit_N

    def span(self, flexibility, unit_N) -> float:
        """The linear response's d at max_factor (m): the driver's first steps are a
        fraction of it (``flexibility``: dd per unit of the driver's load factor)."""
        return self.end_factor(unit_N) * flexibility

    def reached(self, d, lam, unit_N) -> bool:
        """Has the load factor reached max_factor?"""
        return lam >= self.end_factor(unit_N)

    def max_step(self, s_max, arc) -> float:
        """The cap of the driver's step norm: its own (from the linear response, `span`),
        or TRAVEL_STEP of the path's length so far (``arc``, in that norm), whichever is
        larger. The linear response can underestimate the path a millionfold (a column
        standing under its own weight shortens, then bends over): the steps grow with it."""
        return max(s_max, TRAVEL_STEP * arc)

    def landing(self, lam_prev, lam_new, unit_N):
        """max_factor (driver units) when a step from lam_prev to lam_new passes it."""
        end = self.end_factor(unit_N)
        return end if lam_prev < end <= lam_new else None

    def first_state(self, structure) -> np.ndarray:
        """The full state at load factor 0 (a fresh copy)."""
        return structure.initial_state() if self.start is None else self.start.copy()


def make_load_control(structure, max_factor, start=None, travel=None) -> LoadControl:
    """The `LoadControl` of ``structure``'s dead loads (ValueError when it has none)."""
    if not structure.has_dead_loads:
        raise ValueError("the structure has no dead loads to follow (add_load or add_gravity "
                         "first)")
    q0 = structure.initial_state()
    f = np.zeros(q0.shape[0])
    f[: structure.dim * structure.n_nodes] = structure.dead_loads().reshape(-1)
    dofs = np.flatnonzero(f)
    total = structure.total_dead_load()
    pattern = f[dofs] / total
    d_start = 0.0 if start is None else float(pattern @ (start[dofs] - q0[dofs]))
    if travel is None:
        travel = MAX_DISTANCE * structure.scales()[0]
    return LoadControl(dofs, pattern, total, float(max_factor), float(travel), q0[dofs],
                       start, d_start)


class _Watch:
    """The driver's ``stop``: ends the path when, past a maximum of the load factor, it has
    fallen to ``min_factor`` ("limit"), when d left the start by more than the travel
    allowed ("distance"), or when the caller's own ``stop`` says so ("caller")."""

    def __init__(self, control, min_factor, stop):
        self.control, self.min_factor, self.stop = control, min_factor, stop
        self.reason = None
        self.peaked = False

    def __call__(self, rows):
        F, d, c = rows["F"], rows["d"], self.control
        if self.stop is not None and self.stop(rows):
            self.reason = "caller"
        elif abs(d[-1] - c.d_start) > c.travel:
            self.reason = "distance"
        else:
            self.peaked = self.peaked or (len(F) > 1 and F[-1] < F[-2])
            if self.peaked and F[-1] <= self.min_factor * c.total:
                self.reason = "limit"
        return self.reason is not None


def follow_load(structure, max_factor=1.0, method="mgdc", *, start=None, min_factor=0.0,
                distance=None, stop=None, **options):
    """Follow the dead loads of ``structure`` (`add_load`, `add_gravity`) times one load
    factor from 0 to ``max_factor`` with MGDC (``options``: `solver.mgdc.follow_mgdc`'s;
    ``target_iterations`` defaults to TARGET_ITERATIONS here).

    ``start``: the state at factor 0, (n_nodes, dim) positions or a full state (e.g.
    ``structure.path_state(path, k)``), an equilibrium without the dead loads (polished by
    Newton); default the stress-free state. ``min_factor``: past a limit point the path
    goes on (MGDC follows the load factor down the unstable branch) until the factor falls
    to this value; ``distance`` (m): how far the displacement d may move from the start
    (default 10 x the structure's size).

    Returns a `solver.path.Path`: ``load_factor`` (K,), ``force`` = load factor x F_tot (N),
    ``displacement`` d (m, from the stress-free state; module doc), ``energy`` the total
    potential (elastic, minus F d), stability counts (``negative_eigenvalues``: under the
    dead loads; ``_displacement``: with d held), ``critical_points`` and
    ``limit_load_factor`` (the first maximum of the load factor, where the structure snaps;
    None when none was passed). ``status``:

    - "ok": max_factor reached with no limit point passed; the last row is at exactly
      max_factor (``info["landed"]``);
    - "snapped: ...": a limit point was passed below max_factor and the path reached
      max_factor again on a branch beyond it (the state the structure snaps to);
    - "limit: ...": past the limit point the factor fell to ``min_factor``: the structure
      does not carry max_factor on this path;
    - anything else ("not converged: ...", "timeout: ...", "stopped: ...") is a path cut
      short: no answer.
    """
    require_problem(structure)
    if method != "mgdc":
        raise ValueError(f"method must be 'mgdc' (displacement control cannot hold a "
                         f"distributed dead load); got {method!r}")
    max_factor = real_scalar(max_factor, "max_factor", "(a load factor)")
    if not (np.isfinite(max_factor) and max_factor > 0.0):
        raise ValueError(f"max_factor must be finite and > 0; got {max_factor!r}")
    min_factor = real_scalar(min_factor, "min_factor", "(a load factor)")
    if np.isnan(min_factor) or not min_factor < max_factor:
        raise ValueError(f"min_factor must be below max_factor ({max_factor:g}; -inf: never "
                         f"stop on it); got {min_factor!r}")
    if distance is not None:
        distance = real_scalar(distance, "distance", "m")
        if not (np.isfinite(distance) and distance > 0.0):
            raise ValueError(f"distance must be finite and > 0 m; got {distance!r}")
    free = structure.without_dead_loads()
    if start is not None:
        start = equilibrium(free, state_from(structure, start, "start"), None, None, 0.0)[1]["state"]
    control = make_load_control(structure, max_factor, start, distance)
    watch = _Watch(control, min_factor, stop)
    options.setdefault("target_iterations", TARGET_ITERATIONS)
    path = follow_mgdc(free, control, stop=watch, **options)
    return _finish(path, control, watch, min_factor)


def _finish(path, control, watch, min_factor):
    """The load factors, the total potential energy, the limit load factor and the status
    of a load-controlled path (see `follow_load`)."""
    total, mf = control.total, control.max_factor
    path.load_factor = path.force / total
    if path.status == "ok" and watch.reason is None and path.info.get("landed"):
        path.load_factor[-1] = mf  # solved at exactly that factor (F = it x F_tot in N)
    path.energy = path.energy - path.force * path.displacement
    path.info["dead_load_total"] = total
    limits = [c for c in path.critical_points if c.kind == "limit" and c.control == "force"]
    if limits:
        path.limit_load_factor = float(limits[0].F / total)
    elif watch.peaked or (len(path) > 1 and np.any(np.diff(path.force) < 0)):
        # no critical-point monitor (critical=False): the largest sampled factor before
        # the first fall, a lower bound of the limit
        first = int(np.argmax(np.diff(path.force) < 0))
        path.limit_load_factor = float(np.max(path.load_factor[: first + 1]))
        path.info["limit_sampled"] = True
    lim = path.limit_load_factor
    past = "" if lim is None else f", past the limit point at load factor {lim:.6g}"
    if watch.reason == "limit":
        path.status = (f"limit: the load factor peaks at {lim:.6g} < max_factor = {mf:g} "
                       f"and falls back to min_factor = {min_factor:g} past it: the "
                       f"structure does not carry max_factor on this path (it snaps at "
                       f"the limit point)")
    elif watch.reason == "distance":
        path.status = (f"stopped: the displacement d moved more than {control.travel:.6g} m "
                       f"from the start (load factor {path.load_factor[-1]:.6g}{past})")
    elif watch.reason == "caller":
        path.status = (f"stopped: the caller's stop ended the path at load factor "
                       f"{path.load_factor[-1]:.6g}{past}")
    elif path.status == "ok" and lim is not None and lim < mf:
        path.status = (f"snapped: the load factor peaks at {lim:.6g} (a limit point) below "
                       f"max_factor = {mf:g}; the path went on past it and reached max_factor "
                       f"on a branch beyond (the state the structure snaps to)")
    return path
