"""Whole-array simulation: one DER model of n units, snapped one at a time (issue 6).

    from snapmorph.design import Unit
    from snapmorph.design.arrays import simulate_array
    u = Unit(L=0.1, h=0.02, t=0.5e-3, w=5e-3, side=+1, b=5e-3)
    r = simulate_array([u, u, u], snapped="101", order=[2, 0])
    r.status, r.base            # "ok", (K, 2) m from (0, 0) heading +x

The model
---------
One base rod runs through every unit (solid 4w over each unit's end regions and over spacers,
hollow 2w between); each arched unit adds its arch rod on its side, bonded to the base exactly as
in the single unit: each unit is meshed by `units.geometry.build_unit` (same nodes, sections,
ties, joint and support nodes as `units.planar.simulate_unit`) and the meshes are joined end to
end, sharing the base node at each junction. One change: every bond joins coincident nodes
(see `build_array`, ``coincident_ties``), so that no bond depends on a unit's orientation. The
first base edge is clamped; nothing else is held and there is no gravity.

Snapping unit i (the single-unit test, in the unit's own frame)
----------------------------------------------------------------
The `solver.Structure` API fixes components along the global x and z axes only, and its `push`
starts from the stress-free reference. The energy of a DER model does not change under a rigid
motion, so the current state is moved rigidly into unit i's frame (origin at its left support
node, x along the line of its two support nodes); there the single-unit test applies as it is:
rollers (z held) at the two support nodes, the actuator joint made rigid, the apex held in x and
its displacement towards the base prescribed step by step (displacement control by Newton on
the structure's `reduced_system`, from the current deformed state). The clamp is removed during the
push: the two rollers and the apex are then a statically determinate support of the whole array,
the actuator's force is carried by unit i's two rollers only, and the rest of the array, loaded
by nothing, follows as a rigid body. The actuator is self-equilibrated: the reactions are
internal to unit i. The push is the push-through experiment of every unit (`units.push_through`,
the one `simulate_unit` goes through): after the force has crossed zero twice, state (iii) with
the actuator still on is solved at zero force; then the array is moved rigidly back so the
clamped edge is where it was, the actuator and rollers are removed and the free equilibrium with
the clamp only is solved. Its stability (no negative eigenvalue) and that the unit stayed snapped
are checked (else status "second state unstable: unit i: ...").

Why the conjecture holds here: in a released state no external load acts (the clamp carries
nothing), so a cut through the base between two units transmits no force and no moment; each unit
then obeys the equations of the same unit alone and free, and the array is the concatenation of
released units, in any snapping order. `design.array_study` measures it (1e-12 of the length).

Everything is SI (m, N, Pa).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.design.interference import interference
from snapmorph.design.kinematics import parse_snapped as parse_state
from snapmorph.design.strains import path_strain
from snapmorph.design.units import Unit
from snapmorph.units import status as statuses
from snapmorph.units.push_through import Rules, largest_force, push_through
from snapmorph.units.shapes import end_tangent_angle

__all__ = ["ArrayModel", "ArrayResult", "SnapRecord", "build_array", "simulate_array",
           "snap_unit", "release", "rigid_residual"]

PETG_E = 2.2e9  # Pa (units.geometry.PETG_E; repeated so that importing this module is light)
#: a unit counts as snapped when its base turns by more than this towards its arch (deg); an
#: unsnapped unit of a released array is exactly straight (stress free)
SNAPPED_TURN_DEG = 0.1


# ---------------------------------------------------------------------------------- the mesh
@dataclass(frozen=True)
class UnitMesh:
    """Where unit i lives in the array model (global node indices).

    base: (k,) base nodes of the unit, first and last shared with the neighbours; arch: arch
    nodes (empty for a spacer); apex; joint: the actuator joint's nodes; supports: the two
    roller nodes (on the base); offset: x of the unit's start in the reference (m)."""

    base: np.ndarray
    arch: np.ndarray
    apex: int
    joint: tuple
    supports: tuple
    offset: float


@dataclass
class ArrayModel:
    """The meshed array: reference positions, rods, bonds and each unit's nodes.

    `structure(...)` builds a `solver.Structure` with the boundary conditions of one phase;
    every phase has the same node numbering, so positions carry over from one to the next."""

    units: list
    E: float
    nodes: int
    reference: np.ndarray  # (n_nodes, 2) m, stress free
    base_nodes: np.ndarray  # (K,) the base polyline, in order
    rods: list  # [(node indices, width (N-1, 2), thickness (N-1, 2))]
    ties: list  # [(arch node, base node)]
    meshes: list  # [UnitMesh]
    clamp: tuple = (0, 1)  # the first base edge
    coincident_ties: bool = True

    @property
    def n_nodes(self) -> int:
        return int(self.reference.shape[0])

    @property
    def length(self) -> float:
        """Sum of the units' base lengths (m)."""
        return float(sum(u.L for u in self.units))

    def structure(self, clamp: bool = True, actuator: int | None = None,
                  apex_z: bool = True):
        """A `Structure` of the array: clamped (first base edge fixed), or with unit
        ``actuator``'s single-unit test constraints instead (rollers in z at its support nodes,
        rigid joint, apex held in x, and in z too when ``apex_z`` — the displacement-controlled
        push)."""
        from snapmorph.solver import Structure

        st = Structure()
        for idx, width, thickness in self.rods:
            st.add_rod(self.reference[idx], width, thickness, self.E)
        for a, b in self.ties:
            st.tie(a, b)
        if clamp:
            for n in self.clamp:
                st.fix(n, "xz")
        if actuator is not None:
            m = self.meshes[actuator]
            st.fix(m.supports[0], "z")
            st.fix(m.supports[1], "z")
            st.rigid(list(m.joint))
            st.fix(m.apex, "xz" if apex_z else "x")
        return st


def _unit_geometry(u: Unit, E: float, i: int):
    from snapmorph.units.geometry import UnitGeometry

    try:
        return UnitGeometry(L=u.L, h=u.h, t=u.t, w=u.w, b=u.b, E=E)
    except ValueError as exc:
        raise ValueError(f"unit {i + 1}: {exc}") from None


def build_array(units, nodes: int | None = None, E: float = PETG_E,
                coincident_ties: bool = True) -> ArrayModel:
    """Mesh ``units`` (list of `design.Unit`) as one array, unit 1 starting at x = 0.

    ``nodes``: resolution per unit, about the number of base nodes of each unit (default: the
    single unit's converged default, `units.geometry.DEFAULT_NODES` = 101); ``E``: Young's
    modulus (Pa).

    ``coincident_ties``: `build_unit` bonds the arch node half an edge past x0 = b + w to the
    base node below it although it sits on the sinusoid, z = h/2 (1 - cos(2 pi e/la)) above it
    (e half an edge: 3 um at L = 100 mm, h = 20 mm). An exact tie shares displacements, so that
    offset keeps its direction in the global frame when the unit rotates: a rotated unit is
    stressed (an unsnapped unit turned by 80 deg bends by about 1 deg). In an array, where units
    turn by up to 360 deg, that couples every unit to the orientation the others give it. With
    True (default) that arch node is put on the base (the bonded arch edge straddling x0 is then
    flat, its direction the sinusoid's zero slope at x0), which makes every bond rotation
    invariant; False keeps `build_unit`'s mesh exactly."""
    from snapmorph.units.geometry import DEFAULT_NODES, build_unit

    units = list(units)
    if not units:
        raise ValueError("units must list at least one design.Unit")
    for i, u in enumerate(units):
        if not isinstance(u, Unit):
            raise ValueError(f"units[{i}] must be a design.Unit; got {type(u).__name__}")
    nodes = DEFAULT_NODES if nodes is None else nodes
    if isinstance(nodes, bool) or not isinstance(nodes, (int, np.integer)) or nodes < 11:
        raise ValueError(f"nodes (resolution per unit) must be an integer >= 11; got {nodes!r}")
    E = float(E)
    if not math.isfinite(E) or E <= 0:
        raise ValueError(f"E (Young's modulus) must be finite and > 0 Pa; got {E!r}")

    base_x, base_w, base_t = [np.zeros(1)], [], []
    arches = []  # (xz (m, 2) in the array frame, width, thickness, local index map)
    unit_info = []
    offset = 0.0
    for i, u in enumerate(units):
        if u.is_spacer:
            # a straight solid strip, 4w wide (the drawings' spacer), edges about L / (nodes-1)
            xs = np.linspace(0.0, u.L, nodes)
            base_x.append(offset + xs[1:])
            base_w.append(np.full((nodes - 1, 2), 4.0 * u.w))
            base_t.append(np.full((nodes - 1, 2), u.t))
            unit_info.append(dict(nb=nodes, arch=None))
        else:
            g = _unit_geometry(u, E, i)
            model = build_unit(g, nodes=int(nodes), tie="exact")
            st = model.structure
            base_rod, arch_rod = st.rods
            X = st.reference_positions
            bx = X[base_rod.nodes, 0]
            axz = X[arch_rod.nodes].copy()
            base_x.append(offset + bx[1:])
            base_w.append(base_rod.width)
            base_t.append(base_rod.thickness)
            # bonds and joint from the groups of nodes that share displacements
            rep = st.supernodes()
            groups: dict = {}
            for n, r in enumerate(rep):
                groups.setdefault(int(r), []).append(n)
            nb = len(base_rod.nodes)
            ties, joint = [], None
            for grp in groups.values():
                if len(grp) < 2:
                    continue
                if model.apex in grp:
                    joint = [n - nb for n in grp]
                    continue
                bnodes = [n for n in grp if n < nb]
                anodes = [n - nb for n in grp if n >= nb]
                if len(bnodes) != 1 or len(anodes) != 1:
                    raise RuntimeError(f"unit {i + 1}: unexpected bond group {grp}")
                ties.append((anodes[0], bnodes[0]))
            if coincident_ties:
                for a, b in ties:
                    axz[a] = X[base_rod.nodes[b]]
            axz[:, 1] *= u.side
            axz[:, 0] += offset
            arches.append((axz, arch_rod.width, arch_rod.thickness))
            unit_info.append(dict(nb=nb, arch=len(arches) - 1, ties=ties, joint=joint,
                                  apex=model.apex - nb, supports=model.supports))
        offset += u.L

    bx = np.concatenate(base_x)
    K = len(bx)
    reference = [np.stack([bx, np.zeros(K)], axis=1)]
    rods = [(np.arange(K), np.concatenate(base_w), np.concatenate(base_t))]
    arch_start = []
    n = K
    for axz, width, thickness in arches:
        arch_start.append(n)
        reference.append(axz)
        rods.append((np.arange(n, n + len(axz)), width, thickness))
        n += len(axz)
    reference = np.concatenate(reference, axis=0)

    meshes, all_ties = [], []
    first = 0
    offset = 0.0
    for i, (u, info) in enumerate(zip(units, unit_info)):
        base = np.arange(first, first + info["nb"])
        if info["arch"] is None:
            mid = int(base[len(base) // 2])
            meshes.append(UnitMesh(base, np.zeros(0, dtype=np.int64), mid, (), (), offset))
        else:
            a0 = arch_start[info["arch"]]
            arch = np.arange(a0, a0 + len(arches[info["arch"]][0]))
            all_ties += [(int(a0 + a), int(first + b)) for a, b in info["ties"]]
            meshes.append(UnitMesh(
                base, arch, int(a0 + info["apex"]), tuple(int(a0 + j) for j in info["joint"]),
                tuple(int(first + s) for s in info["supports"]), offset))
        first += info["nb"] - 1
        offset += u.L
    return ArrayModel(units, E, int(nodes), reference, np.arange(K), rods, all_ties, meshes,
                      coincident_ties=bool(coincident_ties))


# ---------------------------------------------------------------------------------- results
@dataclass
class SnapRecord:
    """One snap. unit: 0-based index; d, F: (k,) apex displacement towards the base (m) and
    actuator force (N) along the push; F_cr (N), d_cr (m): the force peak; d_zero (m): apex
    displacement of state (iii) with the actuator on; held: (n_nodes, 2) that state, in the
    clamp frame; neighbour_change: (n_units,) largest change of each other unit's shape (base
    and arch nodes, after the best rigid fit) from before the snap to after the release (m;
    NaN for the snapped unit); turn_deg: the unit's base turning after the release; steps;
    time (s); status: "ok" or "<status name>: unit i: why" (`units.status`)."""

    unit: int
    d: np.ndarray
    F: np.ndarray
    F_cr: float = float("nan")
    d_cr: float = float("nan")
    d_zero: float = float("nan")
    held: np.ndarray | None = None
    neighbour_change: np.ndarray | None = None
    neighbour_change_peak: np.ndarray | None = None
    turn_deg: float = float("nan")
    steps: int = 0
    time: float = 0.0
    status: str = "ok"
    #: the largest surface strain of the unit along its push, in state (iii) held and
    #: released (`design.strains`; dimensionless) and where it sits ("arch, middle", ...)
    strain_max: float = float("nan")
    strain_where: str = ""

    @property
    def status_code(self) -> int:
        """The map code of ``status`` (`units.status.status_code`)."""
        return statuses.status_code(self.status)

    def __repr__(self):
        return (f"SnapRecord(unit {self.unit}, {self.status!r}, F_cr={self.F_cr:.4g} N, "
                f"turn {self.turn_deg:.3f} deg, {self.steps} steps, {self.time:.2f} s)")


@dataclass
class ArrayResult:
    """A simulated array state.

    base: (K, 2) base polyline (m), from (0, 0) with its first edge along +x (the clamp);
    status: "ok" or why not (the failed snap's, `SnapRecord`; ``status_code`` its code); state: '0'/'1' string; order: the units snapped, in order
    (0-based); positions: (n_nodes, 2) every node (m); snaps: [SnapRecord]; unit_bases: [(k_i, 2)]
    each unit's base (sharing the junction points); joints: (n+1, 2) unit end points; angles:
    (n+1,) base direction at each joint (rad, from the edges next to it); model: the mesh;
    time: wall time (s); interference: [`design.interference.Overlap`] of every state the
    array went through (each snap's released state, and the loaded one); loaded: the array
    under its dead loads (`design.array_loads.LoadedArray`; None without gravity or loads)."""

    units: list
    state: str
    order: tuple
    status: str
    base: np.ndarray
    positions: np.ndarray
    snaps: list = field(default_factory=list)
    model: ArrayModel | None = None
    time: float = 0.0
    interference: list = field(default_factory=list)
    loaded: object = None

    def __repr__(self):
        # the arrays run to tens of kB: a summary a person can read instead
        n = len(self.units)
        length = float(np.sum(np.hypot(*np.diff(self.base, axis=0).T))) if len(self.base) > 1 else 0.0
        return (f"ArrayResult({n} units, state {self.state!r}, status {self.status!r}, "
                f"base {len(self.base)} points over {length * 1e3:.1f} mm, "
                f"{len(self.snaps)} snaps, {self.time:.2f} s)")

    @property
    def status_code(self) -> int:
        """The map code of ``status`` (`units.status.status_code`): 0 ok, 1 a unit is
        monostable, 5 a unit does not stay snapped released, 2 a computation failed."""
        return statuses.status_code(self.status)

    @property
    def unit_bases(self) -> list:
        return [self.positions[m.base] for m in self.model.meshes]

    @property
    def arches(self) -> list:
        """Each arched unit's arch polyline (m); None for a spacer."""
        return [self.positions[m.arch] if len(m.arch) else None for m in self.model.meshes]

    @property
    def joints(self) -> np.ndarray:
        return np.array([self.positions[self.model.meshes[0].base[0]]]
                        + [self.positions[m.base[-1]] for m in self.model.meshes])

    @property
    def angles(self) -> np.ndarray:
        """Direction (rad) of the base at each joint: the first edge of the array, then each
        unit's last edge (continuous, unwrapped)."""
        P = self.positions
        edges = [P[self.model.meshes[0].base[1]] - P[self.model.meshes[0].base[0]]]
        edges += [P[m.base[-1]] - P[m.base[-2]] for m in self.model.meshes]
        return np.unwrap([math.atan2(e[1], e[0]) for e in edges])

    def turns_deg(self) -> np.ndarray:
        """(n,) each unit's base turning, last edge from first edge (deg; > 0 left)."""
        return np.array([end_tangent_angle(self.positions[m.base]) for m in self.model.meshes])


# ---------------------------------------------------------------------------------- helpers
def _frame(P, origin, xaxis):
    """Positions P in the frame with ``origin`` and unit x axis ``xaxis`` (right-handed)."""
    ex = np.asarray(xaxis, dtype=float)
    ex = ex / np.hypot(*ex)
    R = np.array([[ex[0], -ex[1]], [ex[1], ex[0]]])  # columns: ex, ez
    return (P - origin) @ R


def _to_clamp_frame(model: ArrayModel, P):
    """Move P rigidly so that the clamped edge starts at the origin along +x."""
    a, b = model.clamp
    return _frame(P, P[a].copy(), P[b] - P[a])


def rigid_residual(A, B) -> float:
    """Largest distance (m) between point sets A and B (k, 2) after the best rigid motion of B
    onto A (least squares, no reflection): the change of shape, free of rigid motion."""
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    ca, cb = A.mean(axis=0), B.mean(axis=0)
    a, b = A - ca, B - cb
    # planar Kabsch: the angle maximising sum a . R b
    ang = math.atan2(float(np.sum(b[:, 0] * a[:, 1] - b[:, 1] * a[:, 0])),
                     float(np.sum(b[:, 0] * a[:, 0] + b[:, 1] * a[:, 1])))
    c, s = math.cos(ang), math.sin(ang)
    fit = b @ np.array([[c, s], [-s, c]])
    return float(np.max(np.hypot(*(fit - a).T)))


def _unit_points(model: ArrayModel, P, i):
    m = model.meshes[i]
    return P[np.concatenate([m.base, m.arch])]


def _shape_changes(model, before, after, skip):
    out = np.full(len(model.units), np.nan)
    for j in range(len(model.units)):
        if j != skip:
            out[j] = rigid_residual(_unit_points(model, before, j), _unit_points(model, after, j))
    return out


class _Newton:
    """Newton on one constrained structure, assembled once (`Structure.reduced_system`): the
    prescribed displacements are whatever the starting positions hold in the fixed DOFs.
    Converged as the solver's one Newton (`solver.newton.newton`): residual below ``tol`` x
    EI/l^2 (l the model's size) or a last correction below 1e-11 l."""

    def __init__(self, st, tol=1e-9, max_iter=30):
        self.structure = st
        X = st.reference_positions
        self.length = float(max(np.ptp(X[:, 0]), np.ptp(X[:, 1])))
        EI = max(float(np.max(r.EI)) for r in st.rods)
        self.tol_force = tol * EI / self.length**2
        self.tol_disp = 1e-11 * self.length
        self.max_iter = max_iter
        self.system = st.reduced_system()

    def solve(self, positions, max_move):
        """(positions (n, 2), iterations, negative eigenvalues); ConvergenceError on failure."""
        from snapmorph.solver import ConvergenceError
        from snapmorph.solver.newton import newton

        sysm = self.system
        q = np.array(positions, dtype=float).reshape(-1)
        it = newton(sysm, q, 0.0, None, self.tol_force, self.tol_disp, self.max_iter, max_move,
                    fused=False)
        if it >= 0:
            return q.reshape(-1, 2), it, sysm.negative_eigenvalues
        raise ConvergenceError(f"Newton did not converge in {self.max_iter} iterations")

    def force(self, members, direction):
        """Sum of the internal forces (N) of ``members`` along ``direction``, at the last
        evaluated state: the external force that holds them there."""
        g = self.system.grad_full.reshape(-1, 2)[list(members)].sum(axis=0)
        return float(direction @ g)


# ---------------------------------------------------------------------------------- one snap
#: the push-through of a unit of an array (`units.push_through`): F_cr is the parabola's
#: vertex at the largest force sampled; state (iii) with the actuator on is the answer (no
#: state (ii), no stability check: the released array's stability is checked instead)
ARRAY_RULES = Rules(peak=largest_force, refine_peak=False, unstable_state=False, exact=("iii",),
                    stability=False)


@dataclass
class _ArrayPath:
    """The samples of a unit's push in an array: apex displacement (m), force (N), states
    (K, n_nodes, 2) in the unit's frame, and "ok" or why the push ended early."""

    displacement: np.ndarray
    force: np.ndarray
    positions: np.ndarray
    status: str


class _UnitInArray:
    """Unit ``i`` of the array at positions ``P`` (in the unit's frame) as the model of
    `units.push_through`: its apex pushed towards the base by displacement control from the
    current deformed state (the `solver.Structure` drivers start from the stress-free one),
    the actuator's force summed over the joint; states are node positions (n, 2)."""

    def __init__(self, model: ArrayModel, i, P, steps, max_distance, min_step, towards=1.0):
        from snapmorph.solver import ConvergenceError

        self.failures = (ConvergenceError,)
        u, m = model.units[i], model.meshes[i]
        self.model, self.i, self.P, self.apex = model, i, P, m.apex
        self.h, self.steps, self.max_distance, self.min_step = u.h, steps, max_distance, min_step
        # towards the base (towards = -1: away from it, the pull back of a snapped unit)
        self.push_dir = np.array([0.0, -float(u.side) * towards])
        self.joint = np.array(m.joint)
        self.newton = _Newton(model.structure(clamp=False, actuator=i, apex_z=True))
        self.z0 = P[self.joint, 1].copy()
        self.probe = _ArrayProbe(self)
        self.hold = None

    def push(self, stop):
        """First step h/steps, halved when Newton fails (down to ``min_step`` h), grown by 1.5
        after an easy step (up to 4 h/steps), until ``stop`` or the apex moved
        ``max_distance`` h."""
        from snapmorph.solver import ConvergenceError

        h, newton, joint = self.h, self.newton, self.joint
        d, F, states = [0.0], [0.0], [self.P.copy()]
        dd = h / self.steps
        dd_max, dd_min = 4.0 * h / self.steps, self.min_step * h
        prev = None
        status = "ok"
        while d[-1] < self.max_distance * h:
            step = dd
            guess = states[-1].copy()
            if prev is not None:  # secant predictor
                guess += (states[-1] - prev[1]) * (step / (d[-1] - prev[0]))
            guess[joint, 1] = self.z0 + self.push_dir[1] * (d[-1] + step)
            try:
                P_new, iterations, _ = newton.solve(guess, max_move=0.25 * h)
            except ConvergenceError:
                dd = 0.5 * dd
                if dd < dd_min:
                    status = (f"not converged: displacement control failed at "
                              f"d = {d[-1] * 1e3:.4g} mm (step size underflow)")
                    break
                continue
            prev = (d[-1], states[-1])
            d.append(d[-1] + step)
            F.append(newton.force(joint, self.push_dir))
            states.append(P_new)
            if iterations <= 5:
                dd = min(1.5 * dd, dd_max)
            if stop({"d": d, "F": F}):
                break
        return _ArrayPath(np.array(d), np.array(F), np.array(states), status)

    def states(self, path):
        return path.positions

    def positions(self, state):
        return np.asarray(state).reshape(-1, 2)

    def displacement(self, positions) -> float:
        return float(self.push_dir @ (positions[self.apex] - self.P[self.apex]))

    def solve_unloaded(self, guess):
        """State (iii) with the actuator on at zero force: the apex free in z."""
        if self.hold is None:
            self.hold = self.model.structure(clamp=False, actuator=self.i, apex_z=False)
        held, _ = self.hold.solve_equilibrium(guess, node=None)
        return held, held

    def checkpoint(self, stage):
        pass


class _ArrayProbe:
    """Displacement-controlled solves of a unit in an array (its apex's displacement d
    prescribed), as `solver.states.zero_force_displacement` asks for them."""

    def __init__(self, unit: _UnitInArray):
        self.unit = unit
        self.structure = unit.newton.structure
        self.last_state = None

    def solve(self, guess, d):
        u = self.unit
        P = np.array(guess, dtype=float).reshape(-1, 2)
        P[u.joint, 1] = u.z0 + u.push_dir[1] * d
        P, _, neg = u.newton.solve(P, max_move=0.25 * u.h)
        self.last_state = P.reshape(-1).copy()
        return P, u.newton.force(u.joint, u.push_dir), neg


def _unit_status(out, i) -> str:
    """The push-through outcome's status for unit ``i`` (0-based) of an array:
    "<status name>: unit i + 1: <why>"."""
    name, _, why = out.status.partition(": ")
    return f"{name}: unit {i + 1}: {why or out.reason}"


def snap_unit(model: ArrayModel, positions, i: int, steps: int = 20,
              max_distance: float = 3.0, min_step: float = 1e-4):
    """Snap unit ``i`` (0-based) of the released array at ``positions`` (clamp frame, m).

    Displacement control of the apex towards the base in unit i's frame (`_UnitInArray`:
    first step h/steps, halved when Newton fails down to ``min_step`` h, grown up to
    4 h/steps), the push-through experiment of every unit (`units.push_through`, rules
    `ARRAY_RULES`) until the actuator force has crossed zero twice or the apex moved
    ``max_distance`` h. Returns (positions after the release, clamp frame; SnapRecord)."""
    from snapmorph.solver import ConvergenceError

    t0 = time.perf_counter()
    u, m = model.units[i], model.meshes[i]
    if u.is_spacer:
        raise ValueError(f"unit {i + 1} is a spacer (h = 0): it has no arch to snap")
    Q = np.asarray(positions, dtype=float)
    s0, s1 = m.supports
    # unit i's frame: origin at its left support, x along its supports, arch on side * z
    P = _frame(Q, Q[s0].copy(), Q[s1] - Q[s0])
    out = push_through(_UnitInArray(model, i, P, steps, max_distance, min_step), ARRAY_RULES)
    d, F = out.curve
    rec = SnapRecord(i, d, F, steps=len(d) - 1)
    rec.F_cr, rec.d_cr = out.F_cr, out.d_cr
    if not out.bistable:  # monostable, the push failed, or state (iii) was not found
        rec.status, rec.time = _unit_status(out, i), time.perf_counter() - t0
        return Q, rec
    held = out.states["iii"]
    rec.d_zero = out.d_second
    rec.held = _to_clamp_frame(model, held)
    # release: actuator and rollers off, the clamp back on the first base edge
    try:
        Q_new, info = release(model, rec.held)
    except ConvergenceError as exc:
        rec.status = f"not converged: unit {i + 1}: free equilibrium after release ({exc})"
        rec.time = time.perf_counter() - t0
        return Q, rec
    rec.turn_deg = end_tangent_angle(Q_new[m.base])
    if info["negative_eigenvalues"] > 0:
        rec.status = (f"second state unstable: unit {i + 1}: the released state has "
                      f"{info['negative_eigenvalues']} negative eigenvalue(s)")
    elif u.side * rec.turn_deg <= SNAPPED_TURN_DEG:
        rec.status = (f"second state unstable: unit {i + 1} did not stay snapped when "
                      "released")
    rec.neighbour_change = _shape_changes(model, Q, Q_new, i)
    rec.neighbour_change_peak = _shape_changes(model, P, out.states["i"], i)
    rec.strain_max, rec.strain_where = path_strain(
        model, list(out.path.positions) + [held, Q_new], i)
    rec.time = time.perf_counter() - t0
    return Q_new, rec


def release(model: ArrayModel, positions):
    """Free equilibrium of the clamped array near ``positions`` (clamp frame, m): no actuator,
    no rollers. Returns (positions, info) of `Structure.solve_equilibrium`; raises
    `solver.ConvergenceError`."""
    st = model.structure(clamp=True)
    return st.solve_equilibrium(np.asarray(positions, dtype=float), node=None)


# ---------------------------------------------------------------------------------- the API
def _order(order, snapped, n):
    """The snapping sequence: ``order`` lists every unit to snap once (0-based); it may also
    list units that stay unsnapped (skipped), e.g. a permutation of all units."""
    wanted = [i for i, s in enumerate(snapped) if s]
    if order is None:
        return wanted
    if isinstance(order, str):
        order = [k for k in order.replace(" ", "").split(",") if k]
    try:
        seq = [int(k) for k in order]
    except (TypeError, ValueError):
        raise ValueError(
            f"order must be a sequence of 0-based unit indices; got {order!r}") from None
    if any(k < 0 or k >= n for k in seq):
        raise ValueError(f"order entries must be unit indices 0 .. {n - 1} (0-based); got {seq}")
    if len(set(seq)) != len(seq):
        raise ValueError(f"order must not repeat a unit; got {seq}")
    missing = sorted(set(wanted) - set(seq))
    if missing:
        raise ValueError(f"order must list every unit to snap (0-based {wanted}); "
                         f"missing {missing} in {seq}")
    return [k for k in seq if k in wanted]


def simulate_array(units, snapped=None, order=None, nodes: int | None = None,
                   E: float | None = None, model: ArrayModel | None = None,
                   start=None, steps: int = 20, *, gravity=None, orientation="upright",
                   material=None, loads=None, max_factor: float | None = None) -> ArrayResult:
    """Simulate the clamped array of ``units`` with the units in ``snapped`` snapped one at a
    time, in ``order``.

    ``units``: list of `design.Unit` (SI; may be None with ``model``); ``snapped``: one
    boolean per unit or a '0'/'1' string (None: every arched unit); ``order``: 0-based indices
    of the units in the order they are snapped, a sequence or "2,0" (default ascending; units
    listed but not snapped are skipped); ``nodes``: resolution per unit (default 101, as
    `simulate_unit`); ``E`` (Pa); ``model``: a mesh from `build_array` to reuse;
    ``start``: an `ArrayResult` of the same units to continue from (its snapped units stay
    snapped; ``snapped`` must include them and ``order`` lists only the new ones); ``steps``:
    the push's first step is h/steps (`snap_unit`).

    Dead loads (issue 23; `design.array_loads`): ``gravity`` (None/False: none, the default;
    True: g = 9.81 m/s^2; or g), ``orientation`` ("upright": gravity (0, -1) in the array's
    frame and plane; "sideways": normal to the plane, no in-plane load; or an angle in degrees
    that turns gravity to (sin a, -cos a)), ``material`` (a `solver.materials.Material` or a
    preset name, "petg", "pla", "paper": its density; its E when ``E`` is not given; default
    the paper's PETG), ``loads`` ([`design.array_loads.ArrayLoad`]: forces in N on a unit's
    apex or end), ``max_factor`` (how far past the loads the first snap-back is looked for,
    default 10): the final state, clamped at its start, is loaded and reported in
    ``loaded`` (`LoadedArray`: sag, held, limit_factor, strains; None when the snapping
    itself failed: ``status`` says why). E defaults to the
    material's, else the paper's 2.2 GPa. Without gravity and loads nothing changes.
    ``interference`` lists overlapping parts in every state reached (`design.interference`).
    Returns an `ArrayResult`; failures come back in ``status`` (the state reached so far).
    """
    t0 = time.perf_counter()
    from snapmorph.design.array_loads import (DEFAULT_MAX_FACTOR, check_gravity, check_loads,
                                              gravity_direction, load_array, resolve_material)

    g = check_gravity(gravity)
    mat = resolve_material(material)
    if g > 0 and mat is None:
        mat = resolve_material("paper")
    if E is None:
        E = mat.E if mat is not None else PETG_E
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 2:
        raise ValueError(f"steps must be an integer >= 2 (first push step h/steps); got {steps!r}")
    if model is None and start is not None:
        model = start.model
    if model is None:
        model = build_array(units, nodes=nodes, E=E)
    elif units is not None and list(units) != list(model.units):
        raise ValueError("units must be the units the model (or start) was built from")
    units = model.units
    n = len(units)
    if snapped is None:
        flags = [not u.is_spacer for u in units]
    else:
        flags = parse_state(snapped, n)
    for i, (u, f) in enumerate(zip(units, flags)):
        if f and u.is_spacer:
            raise ValueError(
                f"snapped[{i}]: unit {i + 1} is a spacer (h = 0) and cannot be snapped")
    done = [False] * n
    Q = model.reference.copy()
    snaps, history = [], []
    if start is not None:
        if start.model is not model:
            raise ValueError("start must come from the same array model")
        done = [c == "1" for c in start.state]
        if any(a and not b for a, b in zip(done, flags)):
            raise ValueError(f"snapped ({flags}) must include the units already snapped in start "
                             f"({start.state}); unsnapping is not simulated")
        Q = start.positions.copy()
        snaps = list(start.snaps)
        history = list(start.order)
    gravity_direction(orientation)  # bad dead-load input fails before any simulation
    loads = check_loads(loads, model.units)
    todo = [f and not d for f, d in zip(flags, done)]
    seq = _order(order, todo, n)
    status = "ok" if start is None else start.status

    def key():
        return "".join("1" if s else "0" for s in done)

    overlaps = list(start.interference) if start is not None else interference(model, Q, key())
    if status == "ok":
        for i in seq:
            Q_new, rec = snap_unit(model, Q, i, steps=steps)
            snaps.append(rec)
            if rec.status != "ok":
                status = rec.status
                if rec.status.startswith("second state unstable"):  # released, not held
                    Q = Q_new
                break
            Q = Q_new
            done[i] = True
            history.append(i)
            overlaps += interference(model, Q, key())
    Q = _to_clamp_frame(model, Q)
    state = key()
    out = ArrayResult(units, state, tuple(history), status, Q[model.base_nodes].copy(), Q,
                      snaps, model, interference=overlaps)
    if g > 0 or loads:
        if status == "ok":
            out.loaded = load_array(model, Q, g=g, orientation=orientation, material=mat,
                                    loads=loads, max_factor=(DEFAULT_MAX_FACTOR if max_factor
                                                             is None else max_factor))
            out.interference += interference(model, out.loaded.positions, state + " loaded")
    out.time = time.perf_counter() - t0
    return out
