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

from snapmorph.solver.branching import BranchMonitor, PathState
from snapmorph.solver.stability import held_count


# Newton has converged when the residual is below tol x the force scale, or when the last
# correction moved no DOF by more than this fraction of the structure's size (the residual of
# very stiff stretching terms cannot drop below round-off, positions can).
TOL_DISP = 1e-11

# The MGDC corrector has also converged when the next correction, estimated from the last
# two (du_k^2 / du_(k-1): quadratic convergence), falls below the displacement tolerance
# while the last one is within this factor of it: an iteration that would only confirm
# digits already there is skipped (`_settled`). Step control still counts it (`_counted`),
# so a path keeps the steps it had: its sampling, and the branches its steps can reach, do
# not change. Not for Newton at a held displacement (`_newton`): there the force is read
# off the reaction, which the stiff stretching terms make sensitive to the last digits of
# the positions (a skipped iteration leaves it off by ~1e-10 relative).
SETTLE_FACTOR = 1e3

# A step across which the stability count changes while the path keeps its direction is
# retried smaller down to this fraction of the first step: a bifurcation persists however
# small the step, a fold of the path that a long step jumped over does not.
CROSSING_REFINE = 1.0 / 256.0

# A path on which the pushed node travels (sum of |dd|) more than this times the push
# distance goes back and forth between branches instead of on to the target: it is stopped
# with a "stopped: the path wanders" status (a snap-back adds its own return only).
WANDER = 6.0

# Along a displacement-controlled equilibrium path dE/dd = F, so over a step the energy
# change must match the trapezoidal work 0.5 (F_k + F_k+1) dd to within this fraction of
# |dE| + fscale dd (smooth steps of the arch: <= 0.05, up to 0.09 just after a rig jump;
# a step over the fold where the stable branch ends: 0.15; a jump to a far state: 0.65-1).
# A step that misses it is retried smaller; one that still misses it at the smallest step
# is a real jump (see `_work_mismatch`).
WORK_TOL = 0.1

# A push may not ask for more than this times the structure's size (its largest extent): a
# node of a held structure cannot move that far without stretching its rods several-fold.
MAX_DISTANCE = 10.0


class ConvergenceError(RuntimeError):
    """Newton iterations did not converge to an equilibrium."""


@dataclass
class Control:
    """What is pushed: ``node`` (with every node sharing its displacement) along ``direction``.

    ``dofs`` (dim,): the node's position components in the state vector; ``member_dofs``
    (members, dim): those of every node sharing its displacement; ``origin`` (dim,) m: the
    node's stress-free position."""

    node: int
    members: np.ndarray
    direction: np.ndarray
    distance: float
    method: str
    axis: int | None
    dofs: np.ndarray = None
    member_dofs: np.ndarray = None
    origin: np.ndarray = None

    def displacement(self, q) -> float:
        """The pushed node's displacement (m) along the direction at the state ``q``."""
        return float(self.direction @ (q[self.dofs] - self.origin))

    def force(self, system) -> float:
        """The external force (N) along the direction that holds the pushed node (and the
        nodes sharing its displacement) at the state last evaluated by ``system``."""
        return float(self.direction @ system.grad_full[self.member_dofs].sum(axis=0))

@dataclass(repr=False)
class Path:
    """An equilibrium path of a push. Arrays have one entry per converged step.

    displacement: (K,) m, of the node along the direction, from 0;
    force: (K,) N, applied to the node along the direction;
    positions: (K, n_nodes, dim) m; status: "ok" or why the path stopped early
    ("not converged: ...", "stopped: ...", "timeout: ...");
    negative_eigenvalues: (K,) of the tangent stiffness under the path's own control
    (force control for "mgdc", the node's displacement held for "displacement");
    negative_eigenvalues_displacement: (K,) the same with the pushed displacement held;
    critical_points: `solver.stability.CriticalPoint` records (limit points and
    bifurcations met, in path order; empty when the push ran with ``critical=False``);
    fields: the structure's other per-state arrays, name -> (K, ...) (3-D rods: "twist").
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
    fields: dict = field(default_factory=dict)

    @property
    def twist(self) -> np.ndarray:
        """(K, n_edges) rad: the edges' twist angles (3-D rods only)."""
        if "twist" not in self.fields:
            raise AttributeError("this path has no twist (a planar structure)")
        return self.fields["twist"]

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

    def __repr__(self):
        n = len(self)
        if n == 0:
            return f"Path(method={self.method!r}, 0 states, status={self.status!r})"
        kinds = {}
        for c in self.critical_points:
            kinds[c.kind] = kinds.get(c.kind, 0) + 1
        crit = ", ".join(f"{v} {k}" for k, v in kinds.items()) or "none"
        return (
            f"Path(method={self.method!r}, {n} states, status={self.status!r},\n"
            f"     d = {self.displacement[0]:.6g} .. {self.displacement[-1]:.6g} m, "
            f"F = {np.min(self.force):.6g} .. {np.max(self.force):.6g} N,\n"
            f"     critical points: {crit}, nodes x dim: "
            f"{self.positions.shape[1]} x {self.positions.shape[2]})"
        )


# ---------------------------------------------------------------------- set-up
def make_control(structure, node, direction, distance, method) -> Control:
    """Validate a push request and describe it."""
    node = structure._check_node(node)
    dim, names = int(structure.dim), structure.component_names
    if method not in ("mgdc", "displacement"):
        raise ValueError(f"method must be 'mgdc' or 'displacement'; got {method!r}")
    n = _real_array(direction, "direction").reshape(-1)
    if n.shape != (dim,) or not np.all(np.isfinite(n)) or not np.any(n != 0.0):
        raise ValueError(f"direction must be a finite non-zero ({', '.join(names)}) vector "
                         f"(any length; it is normalised); got {direction!r}")
    n = n / np.max(np.abs(n))  # no overflow for huge components
    n = n / np.linalg.norm(n)
    if distance is None:
        raise ValueError("distance (m) is required")
    distance = _real_scalar(distance, "distance", "m")
    length = structure.scales()[0]
    if not np.isfinite(distance) or distance <= 0.0 or distance > MAX_DISTANCE * length:
        raise ValueError(
            f"distance must be finite, > 0 m and at most {MAX_DISTANCE:g} x the structure's "
            f"size ({MAX_DISTANCE * length:.6g} m); got {distance!r}")
    rep = structure.supernodes()
    members = np.flatnonzero(rep == rep[node])
    fixed = structure.fixed_components(rep)[node]
    for c, name in enumerate(names):
        if fixed[c] and abs(n[c]) > 1e-12:
            raise ValueError(
                f"node {node} is fixed in {name}: it cannot be pushed along "
                f"({', '.join(f'{v:g}' for v in n)}); "
                "push along a free direction or remove the support"
            )
    if fixed.all():
        raise ValueError(f"node {node} is fixed in {names}: nothing to push")
    axis = None
    if method == "displacement":
        axis_aligned = [c for c in range(dim) if abs(abs(n[c]) - 1.0) < 1e-12]
        if not axis_aligned:
            example = tuple(-1.0 if c == dim - 1 else 0.0 for c in range(dim))
            raise ValueError(
                f"method='displacement' needs an axis-aligned direction such as {example}; "
                "use method='mgdc' for an oblique push"
            )
        axis = axis_aligned[0]
        n = np.round(n)
    dofs = np.asarray(structure.node_dofs(node), dtype=np.int64)
    member_dofs = np.array([structure.node_dofs(m) for m in members], dtype=np.int64)
    origin = structure.initial_state()[dofs]
    return Control(node, members, n, distance, method, axis, dofs, member_dofs, origin)


def _real_array(value, name):
    """``value`` as a float array, or a ValueError naming the parameter."""
    if isinstance(value, (str, bytes)) or value is None:
        raise ValueError(f"{name} must be numbers; got {value!r}")
    try:
        arr = np.asarray(value)
    except Exception as exc:  # ragged sequences and the like
        raise ValueError(f"{name} must be an array of real numbers; got {value!r}") from exc
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name} must be real numbers; got {value!r}")
    return arr.astype(float)


def _real_scalar(value, name, unit):
    """``value`` as a float, or a ValueError naming the parameter and its unit."""
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be a real number in {unit}; got {value!r}")
    arr = _real_array(value, f"{name} ({unit})")
    if arr.shape != ():
        raise ValueError(f"{name} must be a single real number in {unit}; got shape {arr.shape}")
    return float(arr)


def _scales(structure):
    """(length m, force N) of the structure: see ``Structure.scales``."""
    return structure.scales()


def _load_vector(system, control):
    """Reduced load vector of a unit force (N) on the pushed node along the direction."""
    P = np.zeros(system.n)
    for c, dof in enumerate(control.dofs):
        r = system.dof_map[dof]
        if r >= 0:
            P[r] = control.direction[c]
    return P


def _driver_system(structure, extra_fixed=None):
    """The system a path follower works on, and its force unit (N per system force unit).

    A structure that offers them gives stiffnesses per unit modulus (``normalized=True``):
    then E changes no bit of the path (only the final conversion to N and J)."""
    try:
        system = structure.reduced_system(extra_fixed=extra_fixed, normalized=True)
    except TypeError:  # a structure without normalised elements
        system = structure.reduced_system(extra_fixed=extra_fixed)
    return system, float(getattr(system, "force_unit", 1.0))


def _load_unit(fscale):
    """The power of two nearest the force scale (N): the drivers solve for the load factor
    lam = F / this, so that the tangent K^-1 P is of the structure's size whatever E is
    (no overflow or underflow for E = 1e200 or 1e-200), and scaling by a power of two is
    exact: the path does not depend on it."""
    return float(2.0 ** np.round(np.log2(fscale)))


def _node_force(system, control):
    return control.force(system)


def _node_displacement(q, control):
    return control.displacement(q)


def _check_options(**options):
    """Validate the numeric options of a driver; returns them cleaned (ints as int)."""
    out = {}
    for name, (value, kind, low, high, unit) in options.items():
        if value is None and kind.endswith("?"):
            out[name] = None
            continue
        if kind.startswith("int"):
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"{name} must be an integer in [{low}, {high}]; got {value!r}")
            value = int(value)
        else:
            value = _real_scalar(value, name, unit)
        if not (np.isfinite(value) and low <= value <= high) or (kind.startswith("pos") and value <= 0):
            rng = f"> 0 and <= {high:g}" if kind.startswith("pos") else f"in [{low:g}, {high:g}]"
            raise ValueError(f"{name} must be finite and {rng}{' ' + unit if unit else ''}; "
                             f"got {value!r}")
        out[name] = value
    return out


def _driver_options(steps, tol, max_iter, max_steps, min_step_ratio, max_step, switch_size,
                    max_switches, time_limit):
    return _check_options(
        steps=(steps, "int", 1, 10**7, ""),
        tol=(tol, "pos", 0.0, 1e-1, "(relative)"),
        max_iter=(max_iter, "int", 1, 10**4, ""),
        max_steps=(max_steps, "int", 1, 10**8, ""),
        min_step_ratio=(min_step_ratio, "pos", 0.0, 1.0, "(relative)"),
        max_step=(max_step, "pos?", 0.0, 1e300, "m"),
        switch_size=(switch_size, "pos", 0.0, 1e3, "(fraction of the first step)"),
        max_switches=(max_switches, "int", 0, 10**4, ""),
        time_limit=(time_limit, "pos?", 0.0, 1e9, "s"),
    )


class _Recorder:
    """Collects the converged states of a path (through the structure's interface only).
    Forces and energies come in the driver system's units and are kept in N and J
    (``force_unit``: see `_driver_system`)."""

    def __init__(self, structure, force_unit=1.0, system=None):
        self.structure = structure
        self.force_unit = float(force_unit)
        # a system that carries reference frames (3-D rods) records the twists in the
        # canonical convention, so that any other system can restart from a path's states
        self._system_fields = getattr(system, "state_fields", None)
        self.rows = {k: [] for k in ("d", "F", "q", "E", "it", "neg", "negd")}
        self.fields = {}

    def add(self, d, F, q, E, it, neg, negd):
        st = self.structure
        F, E = F * self.force_unit, E * self.force_unit
        pos = np.array(st.positions_of(q), dtype=float, copy=True)
        for k, v in zip(self.rows, (d, F, pos, E, it, neg, negd)):
            self.rows[k].append(v)
        fields = dict(st.state_fields(q))
        if self._system_fields is not None:
            fields.update(self._system_fields(q))
        for k, v in fields.items():
            self.fields.setdefault(k, []).append(np.array(v, dtype=float, copy=True))

    def path(self, status, method, info, critical_points=()):
        r = self.rows
        st = self.structure
        return Path(
            displacement=np.array(r["d"], dtype=float),
            force=np.array(r["F"], dtype=float),
            positions=np.array(r["q"], dtype=float).reshape(-1, st.n_nodes, int(st.dim)),
            status=status,
            method=method,
            energy=np.array(r["E"], dtype=float),
            iterations=np.array(r["it"], dtype=np.int64),
            negative_eigenvalues=np.array(r["neg"], dtype=np.int64),
            negative_eigenvalues_displacement=np.array(r["negd"], dtype=np.int64),
            info=info,
            critical_points=list(critical_points),
            fields={k: np.array(v) for k, v in self.fields.items()},
        )


# ---------------------------------------------------------------------- Newton
def _settled(du_max, du_prev, tol_disp):
    """Has Newton converged on the displacements? The last correction (``du_max``) is below
    ``tol_disp``, or it is within SETTLE_FACTOR of it and the next one, estimated as
    du_max^2 / du_prev, is below it (quadratic convergence: that correction would change
    no digit that matters)."""
    return du_max <= tol_disp or (du_max <= SETTLE_FACTOR * tol_disp
                                  and du_max * du_max <= tol_disp * du_prev)


def _counted(it, settled, du_max, tol_disp, r_max, tol_force):
    """The iterations a converged Newton reports to step control: ``it``, plus the one
    skipped when it stopped on the estimate of `_settled` alone (neither the last correction
    ``du_max`` nor the residual ``r_max`` was below its tolerance yet)."""
    early = settled and not du_max <= tol_disp and not r_max <= tol_force
    return it + 1 if early else it


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


def state_from(structure, positions, name="positions"):
    """A full state vector from ``positions``: (n_nodes, dim) node positions (m; the
    structure's other state components, e.g. 3-D twist, start stress free) or a full state
    vector; None gives the stress-free state."""
    q0 = structure.initial_state()
    if positions is None:
        return q0
    arr = _real_array(positions, name)
    shape = (structure.n_nodes, int(structure.dim))
    if arr.shape == q0.shape:
        q = np.ascontiguousarray(arr.copy())
    elif arr.shape == shape:
        q = q0
        dofs = np.array([structure.node_dofs(i) for i in range(structure.n_nodes)])
        q[dofs] = arr
    else:
        raise ValueError(f"{name} must have shape {shape} (m) or {q0.shape}; got {arr.shape}")
    if not np.all(np.isfinite(q)):
        raise ValueError(f"{name} contain NaN or infinite values")
    return q


def equilibrium(structure, positions, node, direction, force, tol=1e-9, max_iter=40):
    """Newton from ``positions`` (n_nodes, dim) m to the equilibrium under ``force`` (N) on
    ``node`` along ``direction``. Raises ConvergenceError when it fails."""
    q = state_from(structure, positions)
    force = _real_scalar(force, "force", "N")
    if not np.isfinite(force):
        raise ValueError(f"force must be finite (N); got {force!r}")
    opts = _check_options(tol=(tol, "pos", 0.0, 1e-1, "(relative)"),
                          max_iter=(max_iter, "int", 1, 10**4, ""))
    system = structure.reduced_system()
    length, fscale = structure.scales()
    P = None
    if node is not None:
        control = make_control(structure, node, direction, 1e-3 * length, "mgdc")
        P = _load_vector(system, control)
    tol_force = opts["tol"] * max(fscale, abs(force))
    it = _newton(system, q, force, P, tol_force, TOL_DISP * length, opts["max_iter"],
                 0.25 * length)
    if it < 0:
        raise ConvergenceError(
            f"equilibrium not found within {max_iter} Newton iterations from the given state"
        )
    system.accept(q)
    info = {
        "iterations": it,
        "energy": system.energy,
        "negative_eigenvalues": system.negative_eigenvalues,
        "state": q,
    }
    return structure.positions_of(q), info


def _timed_out(t0, time_limit):
    return time_limit is not None and time.perf_counter() - t0 > time_limit


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
    time_limit=None,
):
    """Prescribe the node's displacement along an axis from 0 to ``control.distance``.

    ``steps``: initial number of equal steps; steps are halved on failure and grow back
    (up to ``max_step`` m) when Newton converges quickly. ``stop(path_arrays)`` may end
    the path early (it receives the recorder's dict of lists).
    ``critical``: detect, classify and locate critical points (`solver.branching`);
    ``branch``: at a bifurcation, "follow" the branch a push rig follows (leave along
    the critical mode) or stay on the "primary" one; ``switch_size``: the perturbation
    as a fraction of the first step (distance / steps); at most ``max_switches`` switches.
    ``time_limit`` (s): wall time after which the path ends with status "timeout: ...";
    at most ``max_steps`` steps ("stopped: ...").
    """
    t0 = time.perf_counter()
    _check_branch(branch)
    o = _driver_options(steps, tol, max_iter, max_steps, min_step_ratio, max_step,
                        switch_size, max_switches, time_limit)
    steps, tol, max_iter, max_steps = o["steps"], o["tol"], o["max_iter"], o["max_steps"]
    time_limit = o["time_limit"]
    axis = control.axis
    system, fu = _driver_system(structure, [(control.node, axis)])
    length, fscale = structure.scales()
    fscale /= fu  # forces below are in the system's units (N / fu)
    unit = _load_unit(fscale)
    q0 = structure.initial_state()
    held = control.member_dofs[:, axis]
    q = q0.copy()
    rec = _Recorder(structure, fu, system)
    system.evaluate(q)
    system.factor()
    rec.add(0.0, 0.0, q, system.energy, 0, system.negative_eigenvalues, system.negative_eigenvalues)
    monitor = None
    if critical:
        monitor = BranchMonitor(structure, control, branch, tol, fscale, length,
                                nominal_step=control.distance / steps,
                                switch_size=o["switch_size"], max_switches=o["max_switches"],
                                load_unit=unit, rig_step=o["switch_size"] * control.distance / steps,
                                prefer_rig=True, driver_max_iter=max_iter, force_unit=fu,
                                driver_system=system)
        monitor.start(PathState(q.copy(), 0.0, 0.0, -1, system.negative_eigenvalues, 0.0, 1.0,
                                system.energy))
    dd0 = control.distance / steps
    dd_max = dd0 if o["max_step"] is None else o["max_step"]
    dd = dd0
    d = 0.0
    q_prev, d_prev = None, 0.0
    status = "ok"
    sign = control.direction[axis]
    turn_candidate = None
    snap_candidate = None  # first state of a refinement that released energy (a snap)
    energy_jumps = []  # d (m) of steps accepted as snaps by the work check
    while d < control.distance * (1 - 1e-12):
        if len(rec.rows["d"]) > max_steps:
            status = f"stopped: more than {max_steps} steps"
            break
        if _timed_out(t0, time_limit):
            status = f"timeout: time_limit {time_limit:g} s reached at d = {d:.6g} m"
            break
        step = min(dd, control.distance - d)
        q_try = q.copy()
        if q_prev is not None and d - d_prev > 0:
            q_try += (q - q_prev) * (step / (d - d_prev))
        target = d + step
        q_try[held] = q0[held] + sign * target
        fmax = max(fscale, abs(rec.rows["F"][-1]) / fu)
        predicted = system.step_norm(q_try, q)  # m: how far the predictor moved
        it = _newton(system, q_try, 0.0, None, tol * fmax, TOL_DISP * length, max_iter, 0.25 * length)
        if it >= 0:
            E_k, F_k = rec.rows["E"][-1] / fu, rec.rows["F"][-1] / fu
            gap, allowed = _work_mismatch(E_k, system.energy, F_k, control.force(system),
                                          step, fscale)
            if gap > WORK_TOL:  # Newton went to a far state, not along the path
                if step / 2 >= o["min_step_ratio"] * dd0:
                    if allowed and snap_candidate is None:
                        snap_candidate = (q_try.copy(), target, it)
                    dd = step / 2
                    continue
                if not allowed:  # no snap: it would need energy the push did not supply
                    status = (
                        f"stopped: energy jump: displacement control reached a state at "
                        f"d = {target:.6g} m whose energy exceeds the last one by more than "
                        f"the work of the push however small the step (a jump to a far "
                        f"branch, not a snap; use method='mgdc')"
                    )
                    break
                energy_jumps.append(target)  # a real snap: it releases energy
        if (it >= 0 and monitor is not None and step > CROSSING_REFINE * dd0
                and monitor.suspicious(system.negative_eigenvalues, 1.0)):
            dd = step / 2  # refine a step across which the count changes
            continue
        if it >= 0 and step > CROSSING_REFINE * dd0 and _force_turns(
                rec, control.force(system) * fu, target, 10 * tol * fmax * fu):
            # refine onto a force extremum or a kink (where branches exchange stability);
            # should a shorter step fail (the point may be singular), the longer one is taken
            # (not a state Newton reached only slowly or far from its predictor: that may be
            # a jump to a far branch, which the turn of F then merely reflects; 401-node
            # arch, centre free: F = -6e4 EI h / l^3 with status "ok")
            if (turn_candidate is None and it <= max_iter // 2
                    and system.step_norm(q_try, q) <= 10.0 * predicted):
                turn_candidate = (q_try.copy(), target, it)
            dd = step / 2
            continue
        if it < 0 and turn_candidate is not None:
            q_try, target, it = turn_candidate
            system.evaluate(q_try)
            system.factor()
        if it < 0:
            dd = step / 2
            if dd < o["min_step_ratio"] * dd0:
                reroute = _rig_rescue(monitor, rec, unit, held=True)
                if reroute is not None:  # the rig moved on (a snap): continue from there
                    q, d = reroute.state.q.copy(), reroute.state.d
                    q_prev, d_prev, dd = None, d, dd0
                    snap_candidate = None
                    system.evaluate(q)
                    system.factor()
                    system.accept(q)
                    neg = system.negative_eigenvalues
                    rec.add(d, control.force(system), q, system.energy, 0, neg, neg)
                    continue
                if snap_candidate is None:
                    snap_candidate = _snap_forward(system, q, d, held, q0, sign, dd0,
                                                   rec, fu, fscale, tol, length, max_iter,
                                                   control)
                if snap_candidate is not None:
                    # no rig to move on (branch="primary"): the path ends in d here (a fold
                    # of this branch; arch, centre free, primary branch at d = 1.91 h), so
                    # the push snaps forward to a state that releases energy, as a rig does
                    q_try, target, it = snap_candidate
                    energy_jumps.append(target)
                    system.evaluate(q_try)
                    system.factor()
                else:
                    status = (
                        f"not converged: displacement control failed near d = {d:.6g} m "
                        "(step size underflow; a snap-back? use method='mgdc')"
                    )
                    break
            else:
                continue
        turn_candidate = None
        snap_candidate = None
        q_prev, d_prev = q, d
        q, d = q_try, target
        system.accept(q)
        F = control.force(system)
        neg = system.negative_eigenvalues
        iterations = it
        if monitor is not None:
            new = PathState(q.copy(), F / unit, d, -1, neg, 0.0, 1.0, system.energy)
            reroute = monitor.observe(new, len(rec.rows["d"]) - 1)
            if reroute is not None:
                c = reroute.critical
                rec.add(c.d, c.lam * unit, c.q, c.energy, 0, c.neg_disp, c.neg_disp)
                # continue from the first state on the new branch; the next predictor
                # extrapolates along the branch's tangent dq/dd there
                q, d, iterations = reroute.state.q.copy(), reroute.state.d, 0
                dd = max(dd, dd0)  # steps were refined onto the point: start afresh
                q_prev, d_prev = None, d
                if reroute.rate is not None:
                    q_prev, d_prev = q - reroute.rate * dd, d - dd
                system.evaluate(q)
                system.factor()
                system.accept(q)
                F = control.force(system)
                neg = system.negative_eigenvalues
        rec.add(d, F, q, system.energy, iterations, neg, neg)
        if it <= 3:
            dd = min(1.5 * dd, dd_max)
        if stop is not None and stop(rec.rows):
            break
    info = {"wall_time": time.perf_counter() - t0, "bandwidth": system.bandwidth, "n_dofs": system.n,
            "energy_jumps": energy_jumps}
    return rec.path(status, "displacement", _monitor_info(info, monitor),
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
    time_limit=None,
):
    """Load-controlled path with MGDC until the node's displacement reaches
    ``control.distance``.

    ``steps``: the first step moves the node by about distance / (4 steps); later steps
    adapt to the iteration count, with a displacement norm per step up to ``max_step`` (m,
    default 8 x the first's); a step that needs more than ``max_accept_iter`` iterations
    is retried at half the size.
    ``stop(path_arrays)`` may end the path early.
    ``critical``, ``branch``, ``switch_size``, ``max_switches``, ``time_limit``,
    ``max_steps``: as for `follow_displacement` (critical points and branch switching).
    """
    t0 = time.perf_counter()
    _check_branch(branch)
    o = _driver_options(steps, tol, max_iter, max_steps, min_step_ratio, max_step,
                        switch_size, max_switches, time_limit)
    o.update(_check_options(max_accept_iter=(max_accept_iter, "int", 1, 10**4, ""),
                            target_iterations=(target_iterations, "int", 1, 10**4, "")))
    steps, tol, max_iter, max_steps = o["steps"], o["tol"], o["max_iter"], o["max_steps"]
    time_limit = o["time_limit"]
    system, fu = _driver_system(structure)
    length, fscale = structure.scales()
    fscale /= fu  # forces below are in the system's units (N / fu)
    tol_disp = TOL_DISP * length
    # the load factor lam is the force in units of `unit` N (see `_load_unit`)
    unit = _load_unit(fscale)
    P = _load_vector(system, control) * unit
    r_node = np.array([system.dof_map[dof] for dof in control.dofs])
    n_free = np.where(r_node >= 0, control.direction, 0.0)
    r_idx = np.where(r_node >= 0, r_node, 0)

    def node_component(u):
        return float(n_free @ u[r_idx])

    q = structure.initial_state()
    lam = 0.0
    rec = _Recorder(structure, fu, system)
    system.evaluate(q)
    if not system.factor():
        raise ValueError(
            "the structure is not held against rigid-body motion under load control "
            "(singular stiffness); add supports"
        )
    uP = system.solve(P)
    rec.add(0.0, 0.0, q, system.energy, 0, system.negative_eigenvalues, system.negative_eigenvalues)
    dd0 = control.distance / steps
    flex = node_component(uP)
    if not flex > 0:
        raise ValueError("the pushed node does not move along the direction under load")
    # the first step moves the node by a quarter of distance / steps (the path may bend
    # sharply at once); steps then grow up to four times that, i.e. about distance / steps
    s0 = 0.25 * dd0 * np.linalg.norm(uP) / flex
    monitor = None
    if critical:
        monitor = BranchMonitor(structure, control, branch, tol, fscale, length, s0,
                                system=system, switch_size=o["switch_size"],
                                max_switches=o["max_switches"], load_unit=unit,
                                rig_step=o["switch_size"] * 0.25 * dd0,
                                driver_max_iter=max_iter, force_unit=fu)
        neg0 = system.negative_eigenvalues
        monitor.start(PathState(q.copy(), 0.0, 0.0, neg0, neg0, 1.0, 1.0, system.energy))
    s = s0
    s_max = 8.0 * s0 if o["max_step"] is None else o["max_step"]
    sign = 1.0
    step_prev = None
    status = "ok"
    d = 0.0
    rejected = 0
    total_iterations = 0
    rescued = False
    travelled = 0.0  # sum of |dd| along the path, m (wandering guard)
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
            if _timed_out(t0, time_limit):
                status = (f"timeout: time_limit {time_limit:g} s reached at d = {d:.6g} m, "
                          f"F = {lam * unit * fu:.6g} N")
                break
            q_try = q.copy()
            dlam = sign * s / np.linalg.norm(uP1)
            lam_try = lam + dlam
            system.increment(q_try, uP1, dlam)
            fmax = max(fscale, abs(lam_try) * unit)
            du_max = du_prev = np.inf
            for it in range(1, max_iter + 1):
                settled = _settled(du_max, du_prev, tol_disp)
                fstat, r_max, du_step, dl = system.fused_mgdc(
                    q_try, lam_try, P, uP1, np.inf if settled else tol * fmax)
                if fstat == 0:
                    converged = True
                    it = _counted(it, settled, du_max, tol_disp, r_max, tol * fmax)
                    break
                if fstat == 2:
                    du_max, du_prev = du_step, du_max
                    lam_try += dl
                    total_iterations += 1
                    continue
                # LDL^T without pivoting failed: the general path with the dense fallback
                system.evaluate(q_try)
                R = system.grad - lam_try * P
                if not np.all(np.isfinite(R)) or not system.factor():
                    break
                r_max = float(np.max(np.abs(R)))
                if r_max <= tol * fmax or settled:
                    converged = True
                    it = _counted(it, settled, du_max, tol_disp, r_max, tol * fmax)
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
                du_max, du_prev = float(np.max(np.abs(du))), du_max
                system.increment(q_try, du)
                lam_try += dl
                total_iterations += 1
            # A corrector that wandered far from its predictor may have jumped to another
            # branch: reject the step and retry with half the size.
            # Too many iterations also means the predictor overshot a strongly curved path.
            if converged and (system.step_norm(q_try, q) > 4.0 * s or it > max_accept_iter):
                converged = False
            uP_try = None
            if converged and monitor is not None and s > CROSSING_REFINE * s0:
                uP_try = system.solve(P)
                converged = not _mgdc_crosses(system, uP_try, node_component, monitor, q, q_try)
            if not converged:
                rejected += 1
                s *= 0.5
                if s < o["min_step_ratio"] * s0:
                    status = (
                        f"not converged: MGDC step size underflow near d = {d:.6g} m, "
                        f"F = {lam * unit * fu:.6g} N"
                    )
                    reroute = _rig_rescue(monitor, rec, unit)
                    if reroute is not None:  # the rig moved on: continue from there
                        s_new = reroute.state
                        q, lam, step_prev = s_new.q.copy(), s_new.lam, reroute.step
                        system.accept(q)
                        uP = system.solve(P)
                        d = s_new.d
                        rec.add(d, lam * unit, q, s_new.energy, 0, s_new.neg_force,
                                s_new.neg_disp)
                        s, status, rescued = s0, "ok", True
                    break
                # restore the factorisation at the last converged state for the next try
                system.evaluate(q)
                system.factor()
        if rescued:
            rescued = False
            continue
        if not converged:
            break
        # accepted: the system holds K at q_try
        step_prev = system.reduced(q_try) - system.reduced(q)
        q, lam = q_try, lam_try
        system.accept(q)
        uP = system.solve(P) if uP_try is None else uP_try
        d = control.displacement(q)
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
            verdict = monitor.excursion_verdict(new)
            if verdict == "abandon":
                # the backward branch taken at a bifurcation climbs to ever less stable
                # branches instead of restabilising: back to the point, the rig jumps on
                row = monitor.excursion["row"]
                reroute = monitor.abandon_excursion()
                if reroute is None:
                    status = (f"stopped: the branch left at the bifurcation at d = "
                              f"{rec.rows['d'][row]:.6g} m turns back and does not "
                              f"restabilise, and no stable state lies ahead of the point")
                    break
                _rewind(rec, row + 1)
                travelled = float(np.sum(np.abs(np.diff(rec.rows["d"]))))
            else:
                reroute = monitor.observe(new, len(rec.rows["d"]) - 1)
                if reroute is not None:
                    if monitor.excursion is not None and "row" not in monitor.excursion:
                        monitor.excursion["row"] = len(rec.rows["d"])
                    c = reroute.critical
                    rec.add(c.d, c.lam * unit, c.q, c.energy, 0, c.neg_force, c.neg_disp)
            if reroute is not None:
                s_new = reroute.state
                # the monitor left the system factorised at the first state of the new branch
                q, lam, step_prev = s_new.q.copy(), s_new.lam, reroute.step
                system.accept(q)
                uP = system.solve(P)
                # Restart at a step half the distance from the point: near a bifurcation
                # the other branches are that close, and a longer step could land on one
                # of them (a wrong reversal); steps then grow by 1.5 per step.
                s = min(max(s, 0.5 * reroute.distance), s_max)
                d, neg, negd = s_new.d, s_new.neg_force, s_new.neg_disp
                energy, iterations = s_new.energy, 0
        rec.add(d, lam * unit, q, energy, iterations, neg, negd)
        travelled += abs(d - rec.rows["d"][-2])
        if travelled > WANDER * control.distance:
            status = _wandering(rec, travelled, control.distance)
            break
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
    return rec.path(status, "mgdc", _monitor_info(info, monitor),
                    monitor.points if monitor is not None else ())


def _mgdc_crosses(system, uP, node_component, monitor, q, q_try):
    """Would the converged MGDC trial state q_try (tangent ``uP = K^-1 P`` there) put a
    bifurcation or a jumped fold between itself and q (see CROSSING_REFINE)?"""
    flex = node_component(uP)
    step = system.reduced(q_try) - system.reduced(q)
    orient = 1.0 if float(uP @ step) >= 0.0 else -1.0
    return monitor.suspicious(held_count(system.negative_eigenvalues, flex),
                              orient * (1.0 if flex >= 0.0 else -1.0))


def _force_turns(rec, F_new, d_new, noise):
    """Does F(d) turn or bend sharply between the last path rows and a new state (F_new N
    at d_new m)? True when dF changes sign, or when the chord slope of the new step differs
    from the last step's by more than half the larger of the two (a kink, e.g. where a
    secondary branch rejoins and exchanges stability, hides inside one step); changes
    below ``noise`` N are round-off."""
    F, d = rec.rows["F"], rec.rows["d"]
    if len(F) < 2 or not (d[-1] > d[-2] and d_new > d[-1]):
        return False
    before, after = F[-1] - F[-2], F_new - F[-1]
    if abs(before) <= noise or abs(after) <= noise:
        return False
    if before * after < 0.0:
        return True
    s1, s2 = before / (d[-1] - d[-2]), after / (d_new - d[-1])
    return abs(s2 - s1) > 0.5 * max(abs(s1), abs(s2))


def _snap_forward(system, q, d, held, q0, sign, dd0, rec, fu, fscale, tol, length, max_iter,
                  control):
    """A displacement-controlled snap past the end of a branch: the nearest state ahead,
    on steps growing from CROSSING_REFINE x the first step up to the first step, that
    Newton reaches from ``q`` and that releases energy (dE <= work). None if there is none;
    the system is left assembled at ``q`` then."""
    E_k, F_k = rec.rows["E"][-1] / fu, rec.rows["F"][-1] / fu
    fmax = max(fscale, abs(F_k))
    step = CROSSING_REFINE * dd0
    while step <= dd0 * (1 + 1e-12):
        q_try = q.copy()
        q_try[held] = q0[held] + sign * (d + step)
        it = _newton(system, q_try, 0.0, None, tol * fmax, TOL_DISP * length, max_iter,
                     0.25 * length)
        if it >= 0:
            _, allowed = _work_mismatch(E_k, system.energy, F_k, control.force(system), step,
                                        fscale)
            if allowed:
                return q_try, d + step, it
        step *= 2.0
    system.evaluate(q)
    system.factor()
    return None


def _work_mismatch(E0, E1, F0, F1, dd, fscale):
    """Energy balance of a displacement-controlled step of dd m from energy E0 to E1 (J)
    with forces F0, F1 (N) along the push: along an equilibrium path dE/dd = F, so
    E1 - E0 = 0.5 (F0 + F1) dd up to the trapezoid's error. Returns (gap, allowed): gap is
    |E1 - E0 - work| / (|E1 - E0| + fscale dd) (fscale N: the structure's force scale);
    allowed says whether the energy rose no more than the work supplied (within WORK_TOL
    of that scale): a physical snap releases energy, a jump that gains it is no snap."""
    work = 0.5 * (F0 + F1) * dd
    dE = E1 - E0
    scale = abs(dE) + fscale * dd
    gap = abs(dE - work) / scale if scale > 0.0 else 0.0
    return gap, dE <= work + WORK_TOL * fscale * dd


def _rewind(rec, rows):
    """Drop the path rows from ``rows`` on (a branch abandoned)."""
    for v in rec.rows.values():
        del v[rows:]
    for v in rec.fields.values():
        del v[rows:]


def _wandering(rec, travelled, distance):
    """The status of a path stopped because d went back and forth (see WANDER)."""
    d = np.asarray(rec.rows["d"])
    dd = np.diff(d)
    dd = dd[dd != 0.0]
    turns = int(np.sum(dd[1:] * dd[:-1] < 0.0))
    return (f"stopped: the path wanders: the pushed node travelled {travelled / distance:.3g} "
            f"x the distance, turning back {turns} times between d = {d.min():.6g} and "
            f"{d.max():.6g} m (branches switched to do not lead to the target); "
            f"try method='displacement'")


def _rig_rescue(monitor, rec, unit=1.0, held=False):
    """When a driver's steps underflow: let the monitor move the push on as a
    displacement-controlled rig would (`BranchMonitor.rig_onwards`), if it may. A
    bifurcation found just ahead is added as a path row here (``unit``: N per unit of the
    states' load factor, in the system's force units; ``held``: the path's own count is
    the one with the displacement held, as under displacement control)."""
    if monitor is None or monitor.branch != "follow" or monitor.switches >= monitor.max_switches:
        return None
    reroute = monitor.rig_onwards(len(rec.rows["d"]) - 1)
    if reroute is not None and reroute.new_point:
        c = reroute.critical  # counted by the monitor's own switch
        if monitor.excursion is not None and "row" not in monitor.excursion:
            monitor.excursion["row"] = len(rec.rows["d"])
        rec.add(c.d, c.lam * unit, c.q, c.energy, 0, c.neg_disp if held else c.neg_force,
                c.neg_disp)
    elif reroute is not None:
        monitor.switches += 1
    return reroute


def _check_branch(branch):
    if branch not in ("follow", "primary"):
        raise ValueError(f"branch must be 'follow' or 'primary'; got {branch!r}")


def _monitor_info(info, monitor):
    """Add the critical-point bookkeeping to a path's info dict."""
    if monitor is not None:
        info["branch"] = monitor.branch
        info["branch_switches"] = monitor.switches
        info["critical_seconds"] = monitor.seconds
        info["rig_jumps"] = list(monitor.rig_jumps)
        # d (m) of bifurcations whose backward branch MGDC tried and left (it did not
        # restabilise where d turned); the path jumped on from there as a rig does
        info["abandoned_branches"] = list(monitor.abandoned)
    return info
