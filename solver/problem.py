"""The problem layer under the drivers: what a push is, and what a structure must offer.

`PushProblem` and `System` are the problem interface (docs/problem-interface.md) as
checkable protocols: the drivers (`solver.mgdc`, `solver.displacement`, `solver.equilibrium`),
the critical-point monitor (`solver.branching`), `solver.stability` and the probes of
`solver.states` use a structure and its systems through these members only. The rest of the
module turns a push request into a `Control`, states into full state vectors, and builds the
system a driver works on with its load vector and load unit. SI units throughout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

# A push may not ask for more than this times the structure's size (its largest extent): a
# node of a held structure cannot move that far without stretching its rods several-fold.
MAX_DISTANCE = 10.0

METHODS = ("mgdc", "displacement")


class ConvergenceError(RuntimeError):
    """Newton iterations did not converge to an equilibrium."""


@runtime_checkable
class System(Protocol):
    """A constrained, assembled problem: energy, gradient and banded tangent stiffness at a
    full state ``q``, their factorisation and solves, in reduced DOFs (`solver.system`)."""

    n: int
    dof_map: np.ndarray
    representative: np.ndarray
    bandwidth: int
    band: np.ndarray
    grad: np.ndarray
    grad_full: np.ndarray
    energy: float
    negative_eigenvalues: int
    factor_ok: bool
    force_unit: float

    def evaluate(self, q) -> float: ...
    def factor(self) -> bool: ...
    def solve(self, rhs) -> np.ndarray: ...
    def fused_newton(self, q, lam, P, tol_force) -> tuple: ...
    def fused_mgdc(self, q, lam, P, uP1, tol_force) -> tuple: ...
    def accept(self, q) -> None: ...
    def reset_frames(self) -> None: ...
    def state_fields(self, q) -> dict: ...
    def step_norm(self, q_new, q_old) -> float: ...
    def reduced(self, q) -> np.ndarray: ...
    def increment(self, q, du, scale=1.0) -> None: ...
    def settle(self, q, lam, P) -> float | None: ...
    def second_order_term(self, q, step, uP, bend_fraction) -> tuple | None: ...


@runtime_checkable
class PushProblem(Protocol):
    """A structure the drivers can push: node positions in a flat state vector, supports,
    shared displacements, scales, and a fresh `System` for any extra held components."""

    dim: int
    component_names: str

    @property
    def n_nodes(self) -> int: ...

    def initial_state(self) -> np.ndarray: ...
    def node_dofs(self, node) -> np.ndarray: ...
    def positions_of(self, q) -> np.ndarray: ...
    def state_fields(self, q) -> dict: ...
    def scales(self) -> tuple: ...
    def supernodes(self) -> np.ndarray: ...
    def fixed_components(self, rep=None) -> np.ndarray: ...
    def reduced_system(self, extra_fixed=None, normalized=False) -> System: ...
    def check_node(self, node, name="node") -> int: ...


def require_problem(structure) -> None:
    """TypeError naming the missing members when ``structure`` is no `PushProblem`."""
    if type(structure) in _PROBLEM_TYPES:  # (a protocol check costs some 30 us)
        return
    if not isinstance(structure, PushProblem):
        missing = [m for m in _members(PushProblem) if not hasattr(structure, m)]
        raise TypeError(f"{type(structure).__name__} cannot be pushed: it lacks "
                        f"{', '.join(missing)} (see docs/problem-interface.md)")
    _PROBLEM_TYPES.add(type(structure))


#: the types whose instances passed `require_problem`
_PROBLEM_TYPES: set = set()


def _members(protocol) -> list:
    """The public members a protocol declares (attributes and methods)."""
    names = set(getattr(protocol, "__annotations__", {}))
    names.update(k for k in vars(protocol) if not k.startswith("_"))
    return sorted(names)


@dataclass
class Control:
    """What is pushed: ``node`` (with every node sharing its displacement) along ``direction``.

    ``dofs`` (dim,): the node's position components in the state vector; ``member_dofs``
    (members, dim): those of every node sharing its displacement; ``origin`` (dim,) m: the
    node's stress-free position (the displacement is measured from it); ``start``: the full
    state the push starts from (None: the stress-free one), an equilibrium under the
    structure's dead loads, at displacement ``d_start`` (m).

    The drivers use a control only through its methods (a `LoadControl` follows dead loads
    instead of a pushed node); each takes the N per unit of the driver's load factor
    (``unit_N``) where the answer depends on it."""

    node: int
    members: np.ndarray
    direction: np.ndarray
    distance: float
    method: str
    axis: int | None
    dofs: np.ndarray = None
    member_dofs: np.ndarray = None
    origin: np.ndarray = None
    start: np.ndarray | None = None
    d_start: float = 0.0

    def displacement(self, q) -> float:
        """The pushed node's displacement (m) along the direction at the state ``q``."""
        return float(self.direction @ (q[self.dofs] - self.origin))

    def force(self, system) -> float:
        """The external force (N) along the direction that holds the pushed node (and the
        nodes sharing its displacement) at the state last evaluated by ``system``."""
        return float(self.direction @ system.grad_full[self.member_dofs].sum(axis=0))

    def unit_load(self, system) -> np.ndarray:
        """Reduced load vector of a unit force (N) on the pushed node along the direction."""
        P = np.zeros(system.n)
        for c, dof in enumerate(self.dofs):
            r = system.dof_map[dof]
            if r >= 0:
                P[r] = self.direction[c]
        return P

    def reduced_weights(self, system):
        """(weights, indices): the push's displacement component of a reduced vector u is
        ``weights @ u[indices]`` (the pushed node's free components along the direction)."""
        r_node = np.array([system.dof_map[dof] for dof in self.dofs])
        return (np.where(r_node >= 0, self.direction, 0.0),
                np.where(r_node >= 0, r_node, 0))

    @property
    def rig_axis(self) -> int | None:
        """The state component a displacement-controlled rig holds (an axis-aligned push),
        else None."""
        n = self.direction
        axes = [k for k in range(len(n)) if abs(abs(n[k]) - 1.0) < 1e-12]
        return axes[0] if axes else None

    @property
    def travel(self) -> float:
        """The push's travel (m) from its start to its distance: the scale of the drivers'
        guards (a path that wanders, a node that runs away)."""
        return self.distance - self.d_start

    def span(self, flexibility=None, unit_N=None) -> float:
        """The length (m) the driver's first steps are a fraction of: the push's travel."""
        return self.travel

    def reached(self, d, lam, unit_N) -> bool:
        """Is the path's target reached at displacement ``d`` (m)?"""
        return not d < self.distance

    def max_step(self, s_max, arc) -> float:
        """The cap of the driver's step norm after a path of length ``arc`` (its norm, m):
        a push keeps the driver's own (``s_max``, from its distance)."""
        return s_max

    def landing(self, lam_prev, lam_new, unit_N):
        """The load factor to land the last step on exactly, or None (a push lands
        nowhere: it ends at the first state past its distance)."""
        return None

    def first_state(self, structure) -> np.ndarray:
        """The full state the path starts from (a fresh copy)."""
        return structure.initial_state() if self.start is None else self.start.copy()


def make_control(structure, node, direction, distance, method, start=None) -> Control:
    """Validate a push request and describe it. ``start``: the full state the push starts
    from (an equilibrium; None: the stress-free state); ``distance`` counts from the
    stress-free state and must lie beyond the start's displacement."""
    require_problem(structure)
    node = structure.check_node(node)
    dim, names = int(structure.dim), structure.component_names
    if method not in METHODS:
        raise ValueError(f"method must be 'mgdc' or 'displacement'; got {method!r}")
    n = unit_direction(direction, dim, names)
    if distance is None:
        raise ValueError("distance (m) is required")
    distance = real_scalar(distance, "distance", "m")
    length = structure.scales()[0]
    dofs = np.asarray(structure.node_dofs(node), dtype=np.int64)
    origin = structure.initial_state()[dofs]
    d_start = 0.0 if start is None else float(n @ (start[dofs] - origin))
    if start is not None and np.isfinite(distance) and not distance > d_start:
        raise ValueError(f"distance ({distance!r} m from the stress-free state) must lie "
                         f"beyond the start's displacement {d_start:.6g} m along the push")
    low = 0.0 if start is None else -MAX_DISTANCE * length  # from a start: beyond it
    if not np.isfinite(distance) or distance <= low or distance > MAX_DISTANCE * length:
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
    many = getattr(structure, "nodes_dofs", None)  # the node_dofs of many nodes at once
    member_dofs = np.asarray(many(members), dtype=np.int64) if many is not None else \
        np.array([structure.node_dofs(m) for m in members], dtype=np.int64)
    if start is not None:
        d_start = float(n @ (start[dofs] - origin))  # n rounded for displacement control
    return Control(node, members, n, distance, method, axis, dofs, member_dofs, origin,
                   start, d_start)


#: `unit_direction`'s memory: the unit vector of every direction asked for (by the bytes of
#: the validated input: a unit pushes, probes and checks states along one or two directions)
_DIRECTIONS: dict = {}
_DIRECTIONS_KEPT = 64


def unit_direction(direction, dim, names) -> np.ndarray:
    """``direction`` as a unit (dim,) vector (a new array), or a ValueError naming it: finite,
    non-zero, any length (``names``: the structure's component names, for the message)."""
    n = real_array(direction, "direction").reshape(-1)
    key = n.tobytes() if n.shape == (dim,) else None  # (-0.0 and 0.0 differ in bytes)
    unit = _DIRECTIONS.get(key)
    if unit is not None:
        return unit.copy()
    if n.shape != (dim,) or not np.all(np.isfinite(n)) or not np.any(n != 0.0):
        raise ValueError(f"direction must be a finite non-zero ({', '.join(names)}) vector "
                         f"(any length; it is normalised); got {direction!r}")
    n = n / np.max(np.abs(n))  # no overflow for huge components
    n = n / np.linalg.norm(n)
    if len(_DIRECTIONS) < _DIRECTIONS_KEPT:
        _DIRECTIONS[key] = n.copy()
    return n


def real_array(value, name):
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


def real_scalar(value, name, unit):
    """``value`` as a float, or a ValueError naming the parameter and its unit."""
    if type(value) is float:  # (what the code passes itself: nothing to convert)
        return value
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be a real number in {unit}; got {value!r}")
    arr = real_array(value, f"{name} ({unit})")
    if arr.shape != ():
        raise ValueError(f"{name} must be a single real number in {unit}; got shape {arr.shape}")
    return float(arr)


def check_options(**options):
    """Validate numeric driver options given as name=(value, kind, low, high, unit); kind
    "int", "pos" (> 0) or "real", a trailing "?" allowing None. Returns them cleaned (ints
    as int)."""
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
            value = real_scalar(value, name, unit)
        if not (np.isfinite(value) and low <= value <= high) or (kind.startswith("pos") and value <= 0):
            rng = f"> 0 and <= {high:g}" if kind.startswith("pos") else f"in [{low:g}, {high:g}]"
            raise ValueError(f"{name} must be finite and {rng}{' ' + unit if unit else ''}; "
                             f"got {value!r}")
        out[name] = value
    return out


def state_from(structure, positions, name="positions"):
    """A full state vector from ``positions``: (n_nodes, dim) node positions (m; the
    structure's other state components, e.g. 3-D twist, start stress free) or a full state
    vector; None gives the stress-free state."""
    q0 = structure.initial_state()
    if positions is None:
        return q0
    arr = _real_values(positions, name)  # (copied below: no copy of its own)
    shape = (structure.n_nodes, int(structure.dim))
    if arr.shape == q0.shape:
        q = arr.copy()
    elif arr.shape == shape:
        q = q0
        view = structure.positions_of(q)
        if np.shares_memory(view, q):  # the positions are a view of the state: write them
            view[...] = arr
        else:
            dofs = np.array([structure.node_dofs(i) for i in range(structure.n_nodes)])
            q[dofs] = arr
    else:
        raise ValueError(f"{name} must have shape {shape} (m) or {q0.shape}; got {arr.shape}")
    if not np.isfinite(q).all():  # (the method: half the cost of np.all)
        raise ValueError(f"{name} contain NaN or infinite values")
    return q


def _real_values(value, name):
    """`real_array` without its copy where ``value`` already is a float array (a view: the
    caller copies)."""
    if type(value) is np.ndarray and value.dtype == np.float64:
        return value
    return real_array(value, name)


def driver_system(structure, extra_fixed=None):
    """The system a driver works on, and its force unit (N per system force unit).

    Asked for per-unit-modulus stiffnesses (``normalized=True``): a structure that has them
    (planar rods) then changes no bit of a path with E (only the final conversion to N and
    J); one that has not (3-D rods) answers in physical units, force unit 1."""
    system = structure.reduced_system(extra_fixed=extra_fixed, normalized=True)
    return system, float(system.force_unit)


def load_vector(system, control):
    """Reduced load vector of a unit load of ``control`` (a unit force, N, on the pushed
    node along the direction; a `LoadControl`'s dead loads scaled to 1 N in all)."""
    return control.unit_load(system)


def load_unit(fscale):
    """The power of two nearest the force scale (N): the drivers solve for the load factor
    lam = F / this, so that the tangent K^-1 P is of the structure's size whatever E is
    (no overflow or underflow for E = 1e200 or 1e-200), and scaling by a power of two is
    exact: the path does not depend on it."""
    if 0.0 < fscale < math.inf:  # (scalar math: the same power, a tenth of the time)
        return float(2.0 ** round(math.log2(fscale)))
    return float(2.0 ** np.round(np.log2(fscale)))
