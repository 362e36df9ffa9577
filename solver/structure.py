"""`Structure`: rods in the x–z plane, their bonds and supports, and the push experiment.

A structure owns arrays (node positions, element connectivity, stiffnesses, constraints);
the physics lives in `solver.energies`, assembly in `solver.assembly`, and the path followers
in `solver.continuation`. All quantities are SI (m, N, Pa).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph

from solver.system import ReducedSystem

_COMPONENTS = {"x": (0,), "z": (1,), "xz": (0, 1), "zx": (0, 1)}


@dataclass(frozen=True)
class Rod:
    """One rod of a structure: its global node indices (in order) and section data."""

    nodes: np.ndarray
    width: np.ndarray  # (N-1, 2) m: each edge's first and second half
    thickness: np.ndarray  # (N-1, 2) m
    E: float  # Pa

    @property
    def EA(self):
        """(N-1,) axial stiffness of each edge, N (its two halves in series)."""
        half = self.E * self.width * self.thickness
        return 2.0 / (1.0 / half[:, 0] + 1.0 / half[:, 1])

    @property
    def EI(self):
        """(N-1, 2) bending stiffness of each half edge, N m^2."""
        return self.E * self.width * self.thickness**3 / 12.0


def _per_edge(value, n_edges, name):
    """Section data per half edge, (n_edges, 2): a scalar, one value per edge, or one per
    half edge (the section may change at an edge's midpoint)."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        arr = np.full(n_edges, float(arr))
    if arr.shape == (n_edges,):
        arr = np.stack([arr, arr], axis=1)
    if arr.shape != (n_edges, 2):
        raise ValueError(
            f"{name} must be a scalar, one value per edge, shape ({n_edges},), or one per "
            f"half edge, shape ({n_edges}, 2); got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise ValueError(f"{name} must be finite and > 0 (m); got min {np.nanmin(arr)!r}")
    return arr


class _UnionFind:
    def __init__(self, n):
        self.parent = list(range(n))

    def find(self, a):
        while self.parent[a] != a:
            self.parent[a] = self.parent[self.parent[a]]
            a = self.parent[a]
        return a

    def union(self, a, b):
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


class Structure:
    """A planar structure of discrete elastic rods.

    >>> st = Structure()
    >>> rod = st.add_rod(xz, width=5e-3, thickness=0.5e-3, E=2.2e9)
    >>> st.fix(rod.nodes[0], "xz"); path = st.push(rod.nodes[-1], (0, -1), 0.01)

    The path followers use only the members listed in ``docs/problem-interface.md``
    (``dim``, ``component_names``, ``initial_state``, ``node_dofs``, ``positions_of``,
    ``state_fields``, ``scales``, ``supernodes``, ``fixed_components``, ``reduced_system``).
    """

    dim = 2  # components per node position (x, z)
    component_names = "xz"

    def __init__(self):
        self.rods: list[Rod] = []
        self._positions: list[np.ndarray] = []
        self._stretch_nodes: list[np.ndarray] = []
        self._stretch_params: list[np.ndarray] = []
        self._bend_nodes: list[np.ndarray] = []
        self._bend_params: list[np.ndarray] = []
        self._spring_nodes: list[tuple[int, int]] = []
        self._spring_params: list[tuple[float, float, float]] = []
        self._fixed: dict[int, set[int]] = {}
        self._merges: list[tuple[int, int]] = []
        self._rigid_groups: list[list[int]] = []
        self._cache = None

    # ------------------------------------------------------------------ building
    @property
    def n_nodes(self) -> int:
        return int(sum(len(p) for p in self._positions))

    @property
    def reference_positions(self) -> np.ndarray:
        """(n_nodes, 2) stress-free node positions, m."""
        if not self._positions:
            return np.zeros((0, 2))
        return np.concatenate(self._positions, axis=0)

    def add_rod(self, xz, width, thickness, E) -> Rod:
        """Add a rod through the points ``xz`` (N, 2) m; its shape is stress free.

        ``width`` and ``thickness`` (m) are scalars, one value per edge (N-1,), or one
        per half edge (N-1, 2) for a section that changes at an edge's midpoint;
        ``E`` is Young's modulus (Pa).
        """
        xz = np.asarray(xz, dtype=float)
        if xz.ndim != 2 or xz.shape[1] != 2:
            raise ValueError(f"xz must be an (N, 2) array of node positions in m; got shape {xz.shape}")
        n = xz.shape[0]
        if n < 3:
            raise ValueError(f"a rod needs at least 3 nodes (one bending node); got {n}")
        if not np.all(np.isfinite(xz)):
            raise ValueError("xz contains NaN or infinite coordinates")
        edges = np.diff(xz, axis=0)
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        scale = max(np.ptp(xz[:, 0]), np.ptp(xz[:, 1]), 1e-300)
        if np.any(lengths <= 1e-9 * scale):
            i = int(np.argmin(lengths))
            raise ValueError(f"xz has coincident consecutive nodes (edge {i} has zero length)")
        width = _per_edge(width, n - 1, "width")
        thickness = _per_edge(thickness, n - 1, "thickness")
        E = float(E)
        if not np.isfinite(E) or E <= 0.0:
            raise ValueError(f"E (Young's modulus) must be finite and > 0 Pa; got {E!r}")

        start = self.n_nodes
        nodes = np.arange(start, start + n, dtype=np.int64)
        rod = Rod(nodes=nodes, width=width, thickness=thickness, E=E)
        self.rods.append(rod)
        self._positions.append(xz.copy())

        EA = rod.EA
        self._stretch_nodes.append(np.stack([nodes[:-1], nodes[1:]], axis=1))
        self._stretch_params.append(np.stack([EA, lengths], axis=1))

        EI = rod.EI
        # Node stiffness EI / l_bar over the Voronoi region (half of each adjacent edge). Where
        # the section changes at a node the two halves act in series (the moment is common,
        # the rotations add), so the compliances add: l_bar / EI_eff = l0/(2 EI0) + l1/(2 EI1).
        # An arithmetic mean of EI there would make every result converge only as O(1/N).
        node_stiffness = 1.0 / (0.5 * lengths[:-1] / EI[:-1, 1] + 0.5 * lengths[1:] / EI[1:, 0])
        kappa_bar = _turning_curvatures(xz)
        self._bend_nodes.append(np.stack([nodes[:-2], nodes[1:-1], nodes[2:]], axis=1))
        self._bend_params.append(np.stack([node_stiffness, kappa_bar], axis=1))
        self._cache = None
        return rod

    # ------------------------------------------------------------------ problem interface
    def initial_state(self) -> np.ndarray:
        """The stress-free full state vector q0 (2 n_nodes,) m: a fresh copy every call."""
        return self.reference_positions.reshape(-1).copy()

    def node_dofs(self, node) -> np.ndarray:
        """(2,) int64 indices into the state vector of ``node``'s x and z."""
        node = int(node)
        return np.array([2 * node, 2 * node + 1], dtype=np.int64)

    def positions_of(self, q) -> np.ndarray:
        """(n_nodes, 2) node positions (m) held in the state vector ``q`` (a view)."""
        return np.asarray(q).reshape(-1, 2)

    def state_fields(self, q) -> dict:
        """Per-state arrays recorded on a path besides positions: none for planar rods."""
        return {}

    def scales(self):
        """(length m, force N): the structure's size (largest extent of its reference shape)
        and EI_max / length^2; tolerances and step sizes are taken relative to these."""
        if not self.rods:
            raise ValueError("the structure has no rods")
        X = self.reference_positions
        length = float(max(np.ptp(X[:, 0]), np.ptp(X[:, 1])))
        if not length > 0.0:
            length = float(max(np.max(np.abs(X)), 1e-300))
        EI = max(float(np.max(r.EI)) for r in self.rods)  # N m^2
        return length, EI / length**2

    def with_reference_positions(self, positions) -> "Structure":
        """A copy with the same rods, sections and constraints on new stress-free node
        positions (n_nodes, 2) m (used by `solver.stability.seed_imperfection`)."""
        X = np.asarray(positions, dtype=float)
        if X.shape != (self.n_nodes, 2) or not np.all(np.isfinite(X)):
            raise ValueError(f"positions must be a finite ({self.n_nodes}, 2) array in m; "
                             f"got shape {X.shape}")
        new = Structure()
        start = 0
        for rod in self.rods:
            n = len(rod.nodes)
            new.add_rod(X[start:start + n], rod.width, rod.thickness, rod.E)
            start += n
        for node, comps in self._fixed.items():
            for c in sorted(comps):
                new.fix(node, "xz"[c])
        rigid_pairs = set()
        for group in self._rigid_groups:
            new.rigid(group)
            rigid_pairs.update(zip(group[:-1], group[1:]))
        for a, b in self._merges:
            if (a, b) not in rigid_pairs:
                new.tie(a, b)
        for (a, b), (k, _, _) in zip(self._spring_nodes, self._spring_params):
            new.tie(a, b, method="spring", stiffness=k)
        return new

    def min_thickness(self) -> float:
        """The smallest section thickness of any rod, m."""
        return min(float(np.min(rod.thickness)) for rod in self.rods)

    def _check_node(self, node, name="node"):
        if isinstance(node, (bool, np.bool_)) or not isinstance(node, (int, np.integer)):
            raise ValueError(f"{name} must be an integer node index; got {node!r}")
        node = int(node)
        if not 0 <= node < self.n_nodes:
            raise ValueError(f"{name} {node} does not exist (valid: 0 .. {self.n_nodes - 1})")
        return node

    def fix(self, node, components="xz"):
        """Hold the displacement of ``node`` at zero in "x", "z" or "xz"."""
        node = self._check_node(node)
        if components not in _COMPONENTS:
            raise ValueError(f"components must be 'x', 'z' or 'xz'; got {components!r}")
        self._fixed.setdefault(node, set()).update(_COMPONENTS[components])
        self._cache = None

    def rigid(self, nodes):
        """Make ``nodes`` translate together (the paper's rigid joint through W)."""
        nodes = [self._check_node(n, "rigid node") for n in nodes]
        if len(nodes) < 2 or len(set(nodes)) != len(nodes):
            raise ValueError("rigid needs at least two distinct nodes")
        self._rigid_groups.append(nodes)
        for a, b in zip(nodes[:-1], nodes[1:]):
            self._merges.append((a, b))
        self._cache = None

    def tie(self, node_a, node_b, method="exact", stiffness=None):
        """Bond two nodes: ``method="exact"`` (equal displacements, u = W u_i) or
        ``"spring"`` (stiff zero-length spring; ``stiffness`` N/m, default 1e3 times the
        stiffest adjacent edge's EA / length).

        Both keep the nodes' reference offset fixed in global axes, so bond coincident nodes
        (as the unit does): an offset bond resists rigid rotation of the structure."""
        a = self._check_node(node_a, "node_a")
        b = self._check_node(node_b, "node_b")
        if a == b:
            raise ValueError(f"cannot tie node {a} to itself")
        if method == "exact":
            self._merges.append((a, b))
        elif method == "spring":
            if stiffness is None:
                stiffness = 1e3 * self._max_axial_stiffness((a, b))
            stiffness = float(stiffness)
            if not np.isfinite(stiffness) or stiffness <= 0:
                raise ValueError(f"spring stiffness must be finite and > 0 N/m; got {stiffness!r}")
            X = self.reference_positions
            off = X[a] - X[b]
            self._spring_nodes.append((a, b))
            self._spring_params.append((stiffness, off[0], off[1]))
        else:
            raise ValueError(f"tie method must be 'exact' or 'spring'; got {method!r}")
        self._cache = None

    def _max_axial_stiffness(self, nodes):
        best = 0.0
        for sn, sp in zip(self._stretch_nodes, self._stretch_params):
            mask = np.isin(sn, nodes).any(axis=1)
            if mask.any():
                best = max(best, float(np.max(sp[mask, 0] / sp[mask, 1])))
        return best

    # ------------------------------------------------------------------ model arrays
    def elements(self):
        """The element tuple consumed by `solver.assembly` (see its docstring)."""
        if self._cache is None:
            def cat(parts, shape, dtype):
                return (
                    np.ascontiguousarray(np.concatenate(parts, axis=0), dtype=dtype)
                    if parts
                    else np.zeros(shape, dtype=dtype)
                )

            springs_n = (
                np.array(self._spring_nodes, dtype=np.int64).reshape(-1, 2)
            )
            springs_p = np.array(self._spring_params, dtype=float).reshape(-1, 3)
            self._cache = (
                cat(self._stretch_nodes, (0, 2), np.int64),
                cat(self._stretch_params, (0, 2), float),
                cat(self._bend_nodes, (0, 3), np.int64),
                cat(self._bend_params, (0, 2), float),
                np.ascontiguousarray(springs_n),
                np.ascontiguousarray(springs_p),
            )
        return self._cache

    def supernodes(self):
        """Node -> representative of the group of nodes that share displacements."""
        uf = _UnionFind(self.n_nodes)
        for a, b in self._merges:
            uf.union(a, b)
        return np.array([uf.find(i) for i in range(self.n_nodes)], dtype=np.int64)

    def fixed_components(self, rep=None):
        """(n_nodes, 2) bool: component held by a support (shared across merged nodes)."""
        if rep is None:
            rep = self.supernodes()
        fixed_rep = np.zeros((self.n_nodes, 2), dtype=bool)
        for node, comps in self._fixed.items():
            for c in comps:
                fixed_rep[rep[node], c] = True
        return fixed_rep[rep]

    def reduced_system(self, extra_fixed=None) -> ReducedSystem:
        """Assemble the DOF map (ordered by reverse Cuthill–McKee) and band storage.

        ``extra_fixed``: iterable of (node, component) pairs held or prescribed in addition
        to the supports (the displacement-controlled DOF).
        """
        n = self.n_nodes
        if n == 0:
            raise ValueError("the structure has no rods")
        rep = self.supernodes()
        fixed = self.fixed_components(rep)
        if extra_fixed:
            for node, c in extra_fixed:
                fixed[rep == rep[node], c] = True
        uniq, group = np.unique(rep, return_inverse=True)
        n_groups = len(uniq)

        elements = self.elements()
        rows, cols = [], []
        for conn in (elements[0], elements[2], elements[4]):
            if conn.shape[0] == 0:
                continue
            g = group[conn]
            for i in range(g.shape[1]):
                for j in range(g.shape[1]):
                    if i != j:
                        rows.append(g[:, i])
                        cols.append(g[:, j])
        if rows:
            r = np.concatenate(rows)
            c = np.concatenate(cols)
            graph = scipy.sparse.csr_matrix(
                (np.ones(len(r)), (r, c)), shape=(n_groups, n_groups)
            )
            order = scipy.sparse.csgraph.reverse_cuthill_mckee(graph, symmetric_mode=True)
        else:
            order = np.arange(n_groups)

        group_fixed = np.zeros((n_groups, 2), dtype=bool)
        group_fixed[group] = fixed
        group_dof = -np.ones((n_groups, 2), dtype=np.int64)
        k = 0
        for gidx in order:
            for comp in range(2):
                if not group_fixed[gidx, comp]:
                    group_dof[gidx, comp] = k
                    k += 1
        dof_map = group_dof[group].reshape(-1)

        bandwidth = 0
        for conn in (elements[0], elements[2], elements[4]):
            if conn.shape[0] == 0:
                continue
            d = dof_map.reshape(-1, 2)[conn].reshape(conn.shape[0], -1)
            big = np.iinfo(np.int64).max
            hi = np.max(d, axis=1)
            lo = np.min(np.where(d < 0, big, d), axis=1)
            free = hi >= 0
            if free.any():
                bandwidth = max(bandwidth, int(np.max(hi[free] - lo[free])))
        if k == 0:
            raise ValueError("every degree of freedom is fixed: nothing to solve")
        return ReducedSystem(elements, dof_map, k, bandwidth)

    # ------------------------------------------------------------------ energy access
    def energy(self, positions=None) -> float:
        """Total elastic energy (J) at ``positions`` (n_nodes, 2) m (default: reference)."""
        from solver.assembly import total_energy

        q = self._flat(positions)
        return float(total_energy(q, self.elements()))

    def gradient(self, positions=None) -> np.ndarray:
        """Internal force dE/dx (n_nodes, 2), N."""
        sysm = self._unconstrained()
        sysm.evaluate(self._flat(positions))
        return sysm.grad_full.reshape(-1, 2).copy()

    def hessian(self, positions=None) -> np.ndarray:
        """Dense tangent stiffness d2E/dx2 (2 n_nodes, 2 n_nodes), N/m, without constraints."""
        sysm = self._unconstrained()
        dense = sysm.dense_stiffness(self._flat(positions))
        # reduced DOFs are numbered by reverse Cuthill-McKee: map back to natural order
        perm = sysm.dof_map
        return dense[np.ix_(perm, perm)]

    def _unconstrained(self) -> ReducedSystem:
        # every node its own DOFs, nothing fixed: used for energy checks only
        saved = (self._merges, self._fixed)
        self._merges, self._fixed = [], {}
        try:
            return self.reduced_system()
        finally:
            self._merges, self._fixed = saved

    def _flat(self, positions):
        if positions is None:
            return self.reference_positions.reshape(-1).copy()
        pos = np.asarray(positions, dtype=float)
        if pos.shape != (self.n_nodes, 2):
            raise ValueError(f"positions must have shape ({self.n_nodes}, 2); got {pos.shape}")
        return np.ascontiguousarray(pos.reshape(-1))

    # ------------------------------------------------------------------ experiments
    def push(self, node, direction=(0.0, -1.0), distance=None, method="mgdc", **options):
        """Push ``node`` along ``direction`` until its displacement reaches ``distance`` (m).

        ``method="mgdc"``: load control with the modified generalised displacement control
        path follower (passes limit points, negative stiffness and snap-back).
        ``method="displacement"``: the node's displacement along an axis-aligned direction
        is prescribed step by step. Every other constraint on the node is kept.
        Returns a `solver.continuation.Path`. Options: see the drivers in
        `solver.continuation`.
        """
        from solver.continuation import follow_displacement, follow_mgdc, make_control

        control = make_control(self, node, direction, distance, method)
        if method == "mgdc":
            return follow_mgdc(self, control, **options)
        return follow_displacement(self, control, **options)

    def solve_equilibrium(self, positions, node=None, direction=(0.0, -1.0), force=0.0, **options):
        """Equilibrium near ``positions`` with ``force`` (N) applied to ``node`` along
        ``direction`` (no load when ``node`` is None). Returns (positions, info dict)."""
        from solver.continuation import equilibrium

        return equilibrium(self, positions, node, direction, force, **options)


def _turning_curvatures(xz):
    e0 = xz[1:-1] - xz[:-2]
    e1 = xz[2:] - xz[1:-1]
    cross = e0[:, 0] * e1[:, 1] - e0[:, 1] * e1[:, 0]
    g = np.hypot(e0[:, 0], e0[:, 1]) * np.hypot(e1[:, 0], e1[:, 1]) + np.sum(e0 * e1, axis=1)
    return 2.0 * cross / g
