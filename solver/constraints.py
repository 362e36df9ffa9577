"""`ConstrainedStructure`: the bookkeeping every rod structure shares, planar or 3-D.

Nodes and their stress-free positions, supports (components held at zero displacement),
exact ties and rigid groups (nodes that share displacements: supernodes), node checks,
the position DOFs of the state vector, the scales the drivers take tolerances from, and the
push experiment on the shared drivers. `solver.structure.Structure` and
`solver.structure3d.Structure3D` add their rods, elements and DOF ordering; together they
provide the problem interface `solver.problem.PushProblem` (docs/problem-interface.md).
"""

from __future__ import annotations

import numpy as np

from snapmorph.solver.displacement import follow_displacement
from snapmorph.solver.equilibrium import equilibrium
from snapmorph.solver.mgdc import follow_mgdc
from snapmorph.solver.problem import make_control


class UnionFind:
    """Groups of nodes that share displacements (ties, rigid sets, joints); the
    representative of a group is its lowest node."""

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


def bandwidth(*element_dofs) -> int:
    """The half bandwidth of a matrix assembled from elements with these reduced DOF
    lists ((n_elements, k) int arrays, -1 for held DOFs): the largest spread of the free
    DOFs of one element."""
    out = 0
    big = np.iinfo(np.int64).max
    for d in element_dofs:
        if d.shape[0] == 0:
            continue
        hi = np.max(d, axis=1)
        lo = np.min(np.where(d < 0, big, d), axis=1)
        free = hi >= 0
        if free.any():
            out = max(out, int(np.max(hi[free] - lo[free])))
    return out


class ConstrainedStructure:
    """Nodes, supports and shared displacements of a rod structure (see module doc).

    A subclass sets ``dim``, ``component_names`` and ``component_choices`` (how `fix`
    names the components it accepts), appends each rod to ``rods`` and its (N, dim) node
    positions to ``_positions``, and implements ``reduced_system`` and
    ``_max_bending_stiffness``; structures with extra internal nodes (planar clamps'
    ghosts) extend ``_n_total``, ``_share_extra`` and ``_hold_extra``."""

    dim = 0
    component_names = ""
    component_choices = ""

    def __init__(self):
        self.rods: list = []
        self._positions: list[np.ndarray] = []
        self._fixed: dict[int, set[int]] = {}
        self._merges: list[tuple[int, int]] = []
        self._rigid_groups: list[list[int]] = []
        self._cache = None

    # ------------------------------------------------------------------ nodes
    @property
    def n_nodes(self) -> int:
        return int(sum(len(p) for p in self._positions))

    @property
    def reference_positions(self) -> np.ndarray:
        """(n_nodes, dim) stress-free node positions, m."""
        if not self._positions:
            return np.zeros((0, self.dim))
        return np.concatenate(self._positions, axis=0)

    def check_node(self, node, name="node") -> int:
        """``node`` as a valid int node index, or a ValueError naming the parameter."""
        if isinstance(node, (bool, np.bool_)) or not isinstance(node, (int, np.integer)):
            raise ValueError(f"{name} must be an integer node index; got {node!r}")
        node = int(node)
        if self.n_nodes == 0:
            raise ValueError(f"{name} {node}: the structure has no rods (add_rod first)")
        if not 0 <= node < self.n_nodes:
            raise ValueError(f"{name} {node} does not exist (valid: 0 .. {self.n_nodes - 1})")
        return node

    def min_thickness(self) -> float:
        """The smallest section thickness of any rod, m."""
        return min(float(np.min(rod.thickness)) for rod in self.rods)

    # ------------------------------------------------------------------ supports, bonds
    def _fix(self, node, components):
        node = self.check_node(node)
        names = self.component_names
        if (not isinstance(components, str) or not components
                or any(c not in names for c in components)
                or len(set(components)) != len(components)):
            raise ValueError(f"components must be {self.component_choices}; got {components!r}")
        self._fixed.setdefault(node, set()).update(names.index(c) for c in components)
        self._cache = None

    def tie(self, node_a, node_b, method="exact", stiffness=None):
        """Bond two nodes: ``method="exact"``: equal displacements (see the subclass for
        other methods). An offset bond keeps the nodes' reference offset fixed in global
        axes (it resists rigid rotation of the structure): bond coincident nodes."""
        a = self.check_node(node_a, "node_a")
        b = self.check_node(node_b, "node_b")
        if a == b:
            raise ValueError(f"cannot tie node {a} to itself")
        if method == "exact":
            self._merges.append((a, b))
        else:
            self._tie_other(a, b, method, stiffness)
        self._cache = None

    def _tie_other(self, a, b, method, stiffness):
        raise ValueError(f"tie method must be 'exact'; got {method!r}")

    def rigid(self, nodes):
        """Make ``nodes`` translate together (the paper's rigid joint through W)."""
        if isinstance(nodes, (str, bytes)) or not hasattr(nodes, "__iter__"):
            raise ValueError(f"rigid needs a list of node indices; got {nodes!r}")
        nodes = [self.check_node(n, "rigid node") for n in nodes]
        if len(nodes) < 2 or len(set(nodes)) != len(nodes):
            raise ValueError("rigid needs at least two distinct nodes")
        self._rigid_groups.append(nodes)
        for a, b in zip(nodes[:-1], nodes[1:]):
            self._merges.append((a, b))
        self._cache = None

    # ------------------------------------------------------------------ problem interface
    @property
    def _n_total(self) -> int:
        """Nodes of the DOF bookkeeping: the real ones (subclasses may add internal ones)."""
        return self.n_nodes

    def _share_extra(self, uf):
        """Further shared displacements of internal nodes (none here)."""

    def _hold_extra(self, fixed_rep, rep):
        """Further held components of internal nodes (none here)."""

    def supernodes(self):
        """Node -> representative of the group of nodes that share displacements."""
        uf = UnionFind(self._n_total)
        for a, b in self._merges:
            uf.union(a, b)
        self._share_extra(uf)
        return np.array([uf.find(i) for i in range(self._n_total)], dtype=np.int64)

    def fixed_components(self, rep=None):
        """(n_nodes, dim) bool: component held by a support (shared across merged nodes);
        rows past n_nodes belong to internal nodes (planar clamps' ghosts)."""
        if rep is None:
            rep = self.supernodes()
        fixed_rep = np.zeros((self._n_total, self.dim), dtype=bool)
        for node, comps in self._fixed.items():
            for c in comps:
                fixed_rep[rep[node], c] = True
        self._hold_extra(fixed_rep, rep)
        return fixed_rep[rep]

    def _held(self, extra_fixed):
        """(supernodes, held components) with the (node, component) pairs ``extra_fixed``
        held as well (for every node of their group)."""
        rep = self.supernodes()
        fixed = self.fixed_components(rep)
        if extra_fixed:
            for node, c in extra_fixed:
                fixed[rep == rep[node], c] = True
        return rep, fixed

    def node_dofs(self, node) -> np.ndarray:
        """(dim,) int64 indices into the state vector of ``node``'s position components."""
        node = int(node)
        return self.dim * node + np.arange(self.dim, dtype=np.int64)

    def positions_of(self, q) -> np.ndarray:
        """(n_nodes, dim) node positions (m) held in the state vector ``q`` (a view)."""
        return np.asarray(q)[: self.dim * self.n_nodes].reshape(-1, self.dim)

    def scales(self):
        """(length m, force N): the structure's size (largest extent of its reference shape)
        and EI_max / length^2; tolerances and step sizes are taken relative to these."""
        if not self.rods:
            raise ValueError("the structure has no rods")
        X = self.reference_positions
        length = float(np.max(np.ptp(X, axis=0)))
        if not length > 0.0:
            length = float(max(np.max(np.abs(X)), 1e-300))
        return length, self._max_bending_stiffness() / length**2

    def _max_bending_stiffness(self) -> float:
        """The largest bending stiffness of the rods, N m^2 (the force scale's)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ experiments
    def _push(self, node, direction, distance, method, options):
        control = make_control(self, node, direction, distance, method)
        if method == "mgdc":
            return follow_mgdc(self, control, **options)
        return follow_displacement(self, control, **options)

    def _solve_equilibrium(self, positions, node, direction, force, options):
        return equilibrium(self, positions, node, direction, force, **options)
