"""Path followers: Newton equilibrium, displacement control, and MGDC load control.

MGDC is the modified generalised displacement control method (Yang & Shieh 1990; modified
by Liu & Paulino 2017, the paper's choice). Each step starts from the tangent
``u_P = K^-1 P`` with a load increment ``dlam = ± s / |u_P|`` — a fixed displacement norm
``s`` per step, which is what GDC's stiffness parameter achieves. GDC flips the sign when
consecutive tangents point apart; here the predictor is oriented along the previous
converged step instead (``sign(u_P . du_prev)``), which turns at limit points the same way
but is not fooled when the tangent rotates fast in a very compliant structure. Corrector iterations keep the increment orthogonal to the step's
first tangent: ``dlam_j = -(u_P1 . u_R^j) / (u_P1 . u_P^j)``. The step size adapts to the
number of iterations, as in Liu & Paulino's modification.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from solver.branching import BranchMonitor, PathState
from solver.stability import held_count


# Newton has converged when the residual is below tol x the force scale, or when the last
# correction moved no DOF by more than this fraction of the structure's size (the residual of
# very stiff stretching terms cannot drop below round-off, positions can).
TOL_DISP = 1e-11

# A step across which the stability count changes while the path keeps its direction is
# retried smaller down to this fraction of the first step: a bifurcation persists however
# small the step, a fold of the path that a long step jumped over does not.
CROSSING_REFINE = 1.0 / 256.0


class ConvergenceError(RuntimeError):
    """Newton iterations did not converge to an equilibrium."""


@dataclass
class Control:
    """What is pushed: ``node`` (with every node sharing its displacement) along ``direction``."""

    node: int
    members: np.ndarray
    direction: np.ndarray
    distance: float
    method: str
    axis: int | None


@dataclass
class Path:
    """An equilibrium path of a push. Arrays have one entry per converged step.

    displacement: (K,) m, of the node along the direction, from 0;
    force: (K,) N, applied to the node along the direction;
    positions: (K, n_nodes, 2) m; status: "ok" or why the path stopped early;
    negative_eigenvalues: (K,) of the tangent stiffness under the path's own control
    (force control for "mgdc", the node's displacement held for "displacement");
    negative_eigenvalues_displacement: (K,) the same with the pushed displacement held;
    critical_points: `solver.stability.CriticalPoint` records (limit points and
    bifurcations met, in path order; empty when the push ran with ``critical=False``).
    """

    displacement: np.ndarray
    force: np.ndarray
    positions: np.ndarray
    status: str
    method: str
    energy: np.ndarray
    iterations: np.ndarray
    negative_eigenvalues: np.ndarray
    negative_eigenvalues_displacement: np.ndarray
    info: dict = field(default_factory=dict)
    critical_points: list = field(default_factory=list)

    @property
    def stable(self) -> np.ndarray:
        """(K,) bool: stable under the path's own control (no negative eigenvalue)."""
        return self.negative_eigenvalues == 0

    @property
    def stable_displacement(self) -> np.ndarray:
        """(K,) bool: stable with the pushed displacement held."""
        return self.negative_eigenvalues_displacement == 0

    @property
    def bifurcations(self) -> list:
        """The critical points where another branch crosses the path."""
        return [c for c in self.critical_points if c.kind == "bifurcation"]

    @property
    def limit_points(self) -> list:
        """The critical points where F (control "force") or d ("displacement") turns."""
        return [c for c in self.critical_points if c.kind == "limit"]

    def __len__(self):
        return len(self.displacement)


# ---------------------------------------------------------------------- set-up
def make_control(structure, node, direction, distance, method) -> Control:
    """Validate a push request and describe it."""
    node = structure._check_node(node)
    if method not in ("mgdc", "displacement"):
        raise ValueError(f"method must be 'mgdc' or 'displacement'; got {method!r}")
    n = np.asarray(direction, dtype=float).reshape(-1)
    if n.shape != (2,) or not np.all(np.isfinite(n)) or np.hypot(*n) == 0.0:
        raise ValueError(f"direction must be a finite non-zero (x, z) pair; got {direction!r}")
    n = n / np.hypot(*n)
    if distance is None:
        raise ValueError("distance (m) is required")
    distance = float(distance)
    if not np.isfinite(distance) or distance <= 0.0:
        raise ValueError(f"distance must be finite and > 0 m; got {distance!r}")
    rep = structure.supernodes()
    members = np.flatnonzero(rep == rep[node])
    fixed = structure.fixed_components(rep)[node]
    for c, name in enumerate("xz"):
        if fixed[c] and abs(n[c]) > 1e-12:
            raise ValueError(
                f"node {node} is fixed in {name}: it cannot be pushed along "
                f"({n[0]:g}, {n[1]:g}); "
                "push along a free direction or remove the support"
            )
    if fixed.all():
        raise ValueError(f"node {node} is fixed in x and z: nothing to push")
    axis = None
    if method == "displacement":
        axis_aligned = [c for c in range(2) if abs(abs(n[c]) - 1.0) < 1e-12]
        if not axis_aligned:
            raise ValueError(
                "method='displacement' needs an axis-aligned direction such as (0, -1); "
                "use method='mgdc' for an oblique push"
            )
        axis = axis_aligned[0]
        n = np.round(n)
    return Control(node, members, n, distance, method, axis)


def _scales(structure):
    X = structure.reference_positions
    length = float(max(np.ptp(X[:, 0]), np.ptp(X[:, 1]), 1e-12))
    EI = max(float(np.max(r.EI)) for r in structure.rods)  # N m^2
    force = EI / length**2
    return length, force


def _load_vector(system, control):
    P = np.zeros(system.n)
    for c in range(2):
        r = system.dof_map[2 * control.node + c]
        if r >= 0:
            P[r] = control.direction[c]
    return P


def _node_force(system, control):
    g = system.grad_full.reshape(-1, 2)[control.members].sum(axis=0)
    return float(control.direction @ g)


def _node_displacement(q, X, control):
    return float(control.direction @ (q.reshape(-1, 2)[control.node] - X[control.node]))


class _Recorder:
    def __init__(self):
        self.rows = {k: [] for k in ("d", "F", "q", "E", "it", "neg", "negd")}

    def add(self, d, F, q, E, it, neg, negd):
        for k, v in zip(self.rows, (d, F, q.copy(), E, it, neg, negd)):
            self.rows[k].append(v)

    def path(self, n_nodes, status, method, info, critical_points=()):
        r = self.rows
        return Path(
            displacement=np.array(r["d"], dtype=float),
            force=np.array(r["F"], dtype=float),
            positions=np.array(r["q"], dtype=float).reshape(-1, n_nodes, 2),
            status=status,
            method=method,
            energy=np.array(r["E"], dtype=float),
            iterations=np.array(r["it"], dtype=np.int64),
            negative_eigenvalues=np.array(r["neg"], dtype=np.int64),
            negative_eigenvalues_displacement=np.array(r["negd"], dtype=np.int64),
            info=info,
            critical_points=list(critical_points),
        )


# ---------------------------------------------------------------------- Newton
def _newton(system, q, lam, P, tol_force, tol_disp, max_iter, max_move):
    """Newton at fixed load ``lam P``; q is updated in place.

    Returns iterations used, or -1 when it failed. On success the system holds the
    assembled and factorised state at the converged q.
    """
    du_max = np.inf
    if P is None:
        P = np.zeros(system.n)
    for it in range(max_iter + 1):
        # the fused kernel does the whole iteration in one compiled call; the general path
        # below (dense pivoting fallback, damped steps) takes over when it cannot
        if it < max_iter:
            fstat, r_max, du_step = system.fused_newton(
                q, lam, P, tol_force if du_max > tol_disp else np.inf)
            if fstat == 0:
                return it
            if fstat == 2 and du_step <= max_move:
                du_max = du_step
                continue
            if fstat == 2:  # undo the too-long step and damp it below
                system.increment(q, system.last_correction, -1.0)
        system.evaluate(q)
        R = system.grad - lam * P
        if not np.all(np.isfinite(R)):
            return -1
        ok = system.factor()
        r_max = float(np.max(np.abs(R))) if R.size else 0.0
        if r_max <= tol_force or du_max <= tol_disp:
            return it if ok else -1
        if not ok or it == max_iter:
            return -1
        du = system.solve(-R)
        if not np.all(np.isfinite(du)):
            return -1
        du_max = float(np.max(np.abs(du)))
        scale = min(1.0, max_move / du_max) if du_max > 0 else 1.0
        system.increment(q, du, scale)
    return -1


def equilibrium(structure, positions, node, direction, force, tol=1e-9, max_iter=40):
    """Newton from ``positions`` (n_nodes, 2) to the equilibrium under ``force`` (N) on
    ``node`` along ``direction``. Raises ConvergenceError when it fails."""
    q = structure._flat(positions).copy()
    if not np.all(np.isfinite(q)):
        raise ValueError("positions contain NaN or infinite values")
    force = float(force)
    if not np.isfinite(force):
        raise ValueError(f"force must be finite (N); got {force!r}")
    system = structure.reduced_system()
    length, fscale = _scales(structure)
    P = None
    if node is not None:
        control = make_control(structure, node, direction, 1.0, "mgdc")
        P = _load_vector(system, control)
    tol_force = tol * max(fscale, abs(force))
    it = _newton(system, q, force, P, tol_force, TOL_DISP * length, max_iter, 0.25 * length)
    if it < 0:
        raise ConvergenceError(
            f"equilibrium not found within {max_iter} Newton iterations from the given state"
        )
    info = {
        "iterations": it,
        "energy": system.energy,
        "negative_eigenvalues": system.negative_eigenvalues,
    }
    return q.reshape(-1, 2), info


# ---------------------------------------------------------------------- displacement control
def follow_displacement(
    structure,
    control,
    steps=100,
    max_step=None,
    min_step_ratio=1e-6,
    tol=1e-9,
    max_iter=25,
    max_steps=20000,
    stop=None,
    branch="follow",
    critical=True,
    switch_size=0.5,
    max_switches=8,
):
    """Prescribe the node's displacement along an axis from 0 to ``control.distance``.

    ``steps``: initial number of equal steps; steps are halved on failure and grow back
    (up to ``max_step`` m) when Newton converges quickly. ``stop(path_arrays)`` may end
    the path early (it receives the recorder's dict of lists).
    ``critical``: detect, classify and locate critical points (`solver.branching`);
    ``branch``: at a bifurcation, "follow" the branch a push rig follows (leave along
    the critical mode) or stay on the "primary" one; ``switch_size``: the perturbation
    as a fraction of the first step (distance / steps); at most ``max_switches`` switches.
    """
    _check_branch(branch)
    X = structure.reference_positions
    axis = control.axis
    system = structure.reduced_system(extra_fixed=[(control.node, axis)])
    length, fscale = _scales(structure)
    q = X.reshape(-1).copy()
    rec = _Recorder()
    system.evaluate(q)
    system.factor()
    rec.add(0.0, 0.0, q, system.energy, 0, system.negative_eigenvalues, system.negative_eigenvalues)
    monitor = None
    if critical:
        monitor = BranchMonitor(structure, control, branch, tol, fscale, length,
                                nominal_step=control.distance / max(int(steps), 1),
                                switch_size=switch_size, max_switches=max_switches)
        monitor.start(PathState(q.copy(), 0.0, 0.0, -1, system.negative_eigenvalues, 0.0, 1.0,
                                system.energy))
    dd0 = control.distance / max(int(steps), 1)
    dd_max = dd0 if max_step is None else float(max_step)
    dd = dd0
    d = 0.0
    q_prev, d_prev = None, 0.0
    status = "ok"
    sign = control.direction[axis]
    t0 = time.perf_counter()
    while d < control.distance * (1 - 1e-12):
        if len(rec.rows["d"]) > max_steps:
            status = f"stopped: more than {max_steps} steps"
            break
        step = min(dd, control.distance - d)
        q_try = q.copy()
        if q_prev is not None and d - d_prev > 0:
            q_try += (q - q_prev) * (step / (d - d_prev))
        target = d + step
        for m in control.members:
            q_try[2 * m + axis] = X[m, axis] + sign * target
        fmax = max(fscale, abs(rec.rows["F"][-1]))
        it = _newton(system, q_try, 0.0, None, tol * fmax, TOL_DISP * length, max_iter, 0.25 * length)
        if (it >= 0 and monitor is not None and step > CROSSING_REFINE * dd0
                and monitor.suspicious(system.negative_eigenvalues, 1.0)):
            dd = step / 2  # refine a step across which the count changes
            continue
        if it < 0:
            dd = step / 2
            if dd < min_step_ratio * dd0:
                status = (
                    f"not converged: displacement control failed near d = {d:.6g} m "
                    "(step size underflow; a snap-back? use method='mgdc')"
                )
                break
            continue
        q_prev, d_prev = q, d
        q, d = q_try, target
        F = _node_force(system, control)
        neg = system.negative_eigenvalues
        iterations = it
        if monitor is not None:
            new = PathState(q.copy(), F, d, -1, neg, 0.0, 1.0, system.energy)
            reroute = monitor.observe(new, len(rec.rows["d"]) - 1)
            if reroute is not None:
                c = reroute.critical
                rec.add(c.d, c.lam, c.q, c.energy, 0, c.neg_disp, c.neg_disp)
                # continue from the first state on the new branch; the next predictor
                # extrapolates along the branch's tangent dq/dd there
                q, d, iterations = reroute.state.q.copy(), reroute.state.d, 0
                dd = max(dd, dd0)  # steps were refined onto the point: start afresh
                q_prev, d_prev = None, d
                if reroute.rate is not None:
                    q_prev, d_prev = q - reroute.rate * dd, d - dd
                system.evaluate(q)
                system.factor()
                F = _node_force(system, control)
                neg = system.negative_eigenvalues
        rec.add(d, F, q, system.energy, iterations, neg, neg)
        if it <= 3:
            dd = min(1.5 * dd, dd_max)
        if stop is not None and stop(rec.rows):
            break
    info = {"wall_time": time.perf_counter() - t0, "bandwidth": system.bandwidth, "n_dofs": system.n}
    return rec.path(structure.n_nodes, status, "displacement", _monitor_info(info, monitor),
                    monitor.points if monitor is not None else ())


# ---------------------------------------------------------------------- MGDC
def follow_mgdc(
    structure,
    control,
    steps=100,
    max_step=None,
    tol=1e-9,
    max_iter=12,
    max_accept_iter=8,
    target_iterations=4,
    max_steps=20000,
    stop=None,
    min_step_ratio=1e-7,
    branch="follow",
    critical=True,
    switch_size=0.5,
    max_switches=8,
):
    """Load-controlled path with MGDC until the node's displacement reaches
    ``control.distance``.

    ``steps``: the first step moves the node by about distance / (4 steps); later steps
    adapt to the iteration count, with a displacement norm per step up to ``max_step`` (m,
    default 8 x the first's); a step that needs more than ``max_accept_iter`` iterations
    is retried at half the size.
    ``stop(path_arrays)`` may end the path early.
    ``critical``, ``branch``, ``switch_size``, ``max_switches``: as for
    `follow_displacement` (critical points and branch switching).
    """
    _check_branch(branch)
    X = structure.reference_positions
    system = structure.reduced_system()
    length, fscale = _scales(structure)
    tol_disp = TOL_DISP * length
    P = _load_vector(system, control)
    r_node = np.array([system.dof_map[2 * control.node + c] for c in range(2)])
    n_free = np.where(r_node >= 0, control.direction, 0.0)
    r_idx = np.where(r_node >= 0, r_node, 0)

    def node_component(u):
        return float(n_free @ u[r_idx])

    q = X.reshape(-1).copy()
    lam = 0.0
    rec = _Recorder()
    system.evaluate(q)
    if not system.factor():
        raise ValueError(
            "the structure is not held against rigid-body motion under load control "
            "(singular stiffness); add supports"
        )
    uP = system.solve(P)
    rec.add(0.0, 0.0, q, system.energy, 0, system.negative_eigenvalues, system.negative_eigenvalues)
    dd0 = control.distance / max(int(steps), 1)
    flex = node_component(uP)
    if not flex > 0:
        raise ValueError("the pushed node does not move along the direction under load")
    # the first step moves the node by a quarter of distance / steps (the path may bend
    # sharply at once); steps then grow up to four times that, i.e. about distance / steps
    s0 = 0.25 * dd0 * np.linalg.norm(uP) / flex
    monitor = None
    if critical:
        monitor = BranchMonitor(structure, control, branch, tol, fscale, length, s0,
                                system=system, switch_size=switch_size,
                                max_switches=max_switches)
        neg0 = system.negative_eigenvalues
        monitor.start(PathState(q.copy(), 0.0, 0.0, neg0, neg0, 1.0, 1.0, system.energy))
    s = s0
    s_max = 8.0 * s0 if max_step is None else float(max_step)
    sign = 1.0
    step_prev = None
    status = "ok"
    d = 0.0
    rejected = 0
    total_iterations = 0
    t0 = time.perf_counter()
    while d < control.distance:
        if len(rec.rows["d"]) > max_steps:
            status = f"stopped: more than {max_steps} steps"
            break
        if step_prev is not None:
            # orient the predictor along the previous step (passes limit points, where the
            # tangent K^-1 P reverses, without being fooled by fast-rotating tangents)
            sign = 1.0 if float(uP @ step_prev) >= 0.0 else -1.0
        uP1 = uP
        converged = False
        while not converged:
            q_try = q.copy()
            dlam = sign * s / np.linalg.norm(uP1)
            lam_try = lam + dlam
            system.increment(q_try, uP1, dlam)
            fmax = max(fscale, abs(lam_try))
            du_max = np.inf
            for it in range(1, max_iter + 1):
                fstat, r_max, du_step, dl = system.fused_mgdc(
                    q_try, lam_try, P, uP1, tol * fmax if du_max > tol_disp else np.inf)
                if fstat == 0:
                    converged = True
                    break
                if fstat == 2:
                    du_max = du_step
                    lam_try += dl
                    total_iterations += 1
                    continue
                # LDL^T without pivoting failed: the general path with the dense fallback
                system.evaluate(q_try)
                R = system.grad - lam_try * P
                if not np.all(np.isfinite(R)) or not system.factor():
                    break
                r_max = float(np.max(np.abs(R)))
                if r_max <= tol * fmax or du_max <= tol_disp:
                    converged = True
                    break
                both = system.solve(np.stack([P, -R], axis=1))
                uPj, uRj = both[:, 0], both[:, 1]
                denom = float(uP1 @ uPj)
                if denom == 0.0 or not np.isfinite(denom):
                    break
                dl = -float(uP1 @ uRj) / denom
                du = dl * uPj + uRj
                if not np.all(np.isfinite(du)):
                    break
                du_max = float(np.max(np.abs(du)))
                system.increment(q_try, du)
                lam_try += dl
                total_iterations += 1
            # A corrector that wandered far from its predictor may have jumped to another
            # branch: reject the step and retry with half the size.
            # Too many iterations also means the predictor overshot a strongly curved path.
            if converged and (np.linalg.norm(q_try - q) > 4.0 * s or it > max_accept_iter):
                converged = False
            uP_try = None
            if converged and monitor is not None and s > CROSSING_REFINE * s0:
                uP_try = system.solve(P)
                converged = not _mgdc_crosses(system, uP_try, node_component, monitor, q, q_try)
            if not converged:
                rejected += 1
                s *= 0.5
                if s < min_step_ratio * s0:
                    status = (
                        f"not converged: MGDC step size underflow near d = {d:.6g} m, "
                        f"F = {lam:.6g} N"
                    )
                    break
                # restore the factorisation at the last converged state for the next try
                system.evaluate(q)
                system.factor()
        if not converged:
            break
        # accepted: the system holds K at q_try
        step_prev = system.reduced(q_try) - system.reduced(q)
        q, lam = q_try, lam_try
        uP = system.solve(P) if uP_try is None else uP_try
        d = _node_displacement(q, X, control)
        neg = system.negative_eigenvalues
        # Schur complement: dF/dd of the pushed node is 1 / (n . u_P); a negative one
        # accounts for one negative eigenvalue that holding the displacement removes.
        flex = node_component(uP)
        negd = held_count(neg, flex)
        energy, iterations = system.energy, it
        if monitor is not None:
            # direction of travel at the new state: along +-u_P, oriented like the last step
            orient = 1.0 if float(uP @ step_prev) >= 0.0 else -1.0
            new = PathState(q.copy(), lam, d, neg, negd, orient,
                            orient * (1.0 if flex >= 0.0 else -1.0), energy)
            reroute = monitor.observe(new, len(rec.rows["d"]) - 1)
            if reroute is not None:
                c, s_new = reroute.critical, reroute.state
                rec.add(c.d, c.lam, c.q, c.energy, 0, c.neg_force, c.neg_disp)
                # the monitor left the system factorised at the first state of the new branch
                q, lam, step_prev = s_new.q.copy(), s_new.lam, reroute.step
                uP = system.solve(P)
                s = max(s, s0)  # steps were refined onto the point: start afresh
                d, neg, negd = s_new.d, s_new.neg_force, s_new.neg_disp
                energy, iterations = s_new.energy, 0
        rec.add(d, lam, q, energy, iterations, neg, negd)
        if it <= target_iterations - 1:
            s = min(1.5 * s, s_max)
        elif it >= target_iterations + 3:
            s *= 0.6
        if stop is not None and stop(rec.rows):
            break
        if abs(d) > 10 * control.distance:
            status = "stopped: the pushed node moved away from the target distance"
            break
    info = {
        "wall_time": time.perf_counter() - t0,
        "bandwidth": system.bandwidth,
        "n_dofs": system.n,
        "final_step_norm": s,
        "rejected_steps": rejected,
        "total_iterations": total_iterations,
    }
    return rec.path(structure.n_nodes, status, "mgdc", _monitor_info(info, monitor),
                    monitor.points if monitor is not None else ())


def _mgdc_crosses(system, uP, node_component, monitor, q, q_try):
    """Would the converged MGDC trial state q_try (tangent ``uP = K^-1 P`` there) put a
    bifurcation or a jumped fold between itself and q (see CROSSING_REFINE)?"""
    flex = node_component(uP)
    step = system.reduced(q_try) - system.reduced(q)
    orient = 1.0 if float(uP @ step) >= 0.0 else -1.0
    return monitor.suspicious(held_count(system.negative_eigenvalues, flex),
                              orient * (1.0 if flex >= 0.0 else -1.0))


def _check_branch(branch):
    if branch not in ("follow", "primary"):
        raise ValueError(f"branch must be 'follow' or 'primary'; got {branch!r}")


def _monitor_info(info, monitor):
    """Add the critical-point bookkeeping to a path's info dict."""
    if monitor is not None:
        info["branch"] = monitor.branch
        info["branch_switches"] = monitor.switches
        info["critical_seconds"] = monitor.seconds
    return info
