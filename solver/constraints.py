"""`ConstrainedStructure`: the bookkeeping every rod structure shares, planar or 3-D.

Nodes and their stress-free positions, supports (components held at zero displacement),
exact ties and rigid groups (nodes that share displacements: supernodes), node checks,
the position DOFs of the state vector, the scales the drivers take tolerances from, dead
loads (point loads and self-weight, docs/loads.md), and the experiments on the shared
drivers: the push and the load-controlled path. `solver.structure.Structure` and
`solver.structure3d.Structure3D` add their rods, elements and DOF ordering; together they
provide the problem interface `solver.problem.PushProblem` (docs/problem-interface.md).
"""

from __future__ import annotations

import copy

import numpy as np
from numba import njit

from snapmorph.solver.displacement import follow_displacement
from snapmorph.solver.equilibrium import equilibrium
from snapmorph.solver.loading import follow_load
from snapmorph.solver.materials import Material
from snapmorph.solver.mgdc import follow_mgdc
from snapmorph.solver.problem import ConvergenceError, make_control, real_array, real_scalar


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


class _PairList:
    """The pairs of nodes that share displacements, collected for `group_minima`: the
    exact ties, and what a subclass's ``_share_extra`` joins with ``union(a, b)``."""

    def __init__(self, pairs):
        self.pairs = list(pairs)

    def union(self, a, b):
        self.pairs.append((a, b))

    def array(self) -> np.ndarray:
        """(n_pairs, 2) int64."""
        return np.array(self.pairs, dtype=np.int64).reshape(-1, 2)


@njit(cache=True)
def group_minima(n, pairs):
    """(n,) int64: for every node 0..n-1 the lowest node of its group, the groups joined by
    the ``pairs`` (n_pairs, 2) of nodes — what `UnionFind` gives after ``union`` of every
    pair, by a compiled loop (asked once per structure and copy: 30 us in Python)."""
    parent = np.arange(n)
    for k in range(pairs.shape[0]):
        ra, rb = _root(parent, pairs[k, 0]), _root(parent, pairs[k, 1])
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    # a parent is never above its node: the nodes in increasing order see their parent's root
    rep = np.empty(n, dtype=np.int64)
    for i in range(n):
        rep[i] = i if parent[i] == i else rep[parent[i]]
    return rep


@njit(cache=True)
def _root(parent, a):
    """The root of ``a``, halving the path to it (`UnionFind.find`)."""
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


def bandwidth(*element_dofs) -> int:
    """The half bandwidth of a matrix assembled from elements with these reduced DOF
    lists ((n_elements, k) int arrays, -1 for held DOFs): the largest spread of the free
    DOFs of one element."""
    return max((_spread(np.ascontiguousarray(d, dtype=np.int64)) for d in element_dofs
                if d.shape[0]), default=0)


@njit(cache=True)
def _spread(dofs):
    """The largest spread max - min of the free (>= 0) entries of a row of ``dofs`` (a
    compiled loop: every new DOF ordering asks, several per unit)."""
    out = 0
    for e in range(dofs.shape[0]):
        lo, hi = -1, -1
        for a in range(dofs.shape[1]):
            r = dofs[e, a]
            if r >= 0:
                if lo < 0 or r < lo:
                    lo = r
                if r > hi:
                    hi = r
        if hi >= 0 and hi - lo > out:
            out = hi - lo
    return out


class ConstrainedStructure:
    """Nodes, supports and shared displacements of a rod structure (see module doc).

    A subclass sets ``dim``, ``component_names`` and ``component_choices`` (how `fix`
    names the components it accepts), gives `add_gravity` its default direction, appends
    each rod to ``rods`` and its (N, dim) node positions to ``_positions``, and implements
    ``reduced_system`` (with the dead loads of `_system_loads` unless asked not to),
    ``_max_bending_stiffness`` and ``_edge_areas``; structures with extra internal nodes
    (planar clamps' ghosts) extend ``_n_total``, ``_share_extra``, ``_hold_extra`` and
    ``_complete_state``."""

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
        # dead loads: (node, force (dim,) N) and (rho g (N/m^3), unit direction, rod
        # indices or None for all rods)
        self._point_loads: list[tuple[int, np.ndarray]] = []
        self._gravity: list[tuple[float, np.ndarray, tuple | None]] = []

    # ------------------------------------------------------------------ nodes
    @property
    def n_nodes(self) -> int:
        # asked hundreds of times per push: counted again only when a rod was added
        memo = getattr(self, "_n_nodes_memo", None)
        if memo is None or memo[0] != len(self._positions):
            memo = self._n_nodes_memo = (len(self._positions),
                                         int(sum(len(p) for p in self._positions)))
        return memo[1]

    @property
    def reference_positions(self) -> np.ndarray:
        """(n_nodes, dim) stress-free node positions, m."""
        # read-only, joined again only when a rod was added (asked at every state check)
        memo = getattr(self, "_reference_memo", None)
        if memo is None or memo[0] != len(self._positions):
            X = np.concatenate(self._positions, axis=0) if self._positions \
                else np.zeros((0, self.dim))
            X.setflags(write=False)
            memo = self._reference_memo = (len(self._positions), X)
        return memo[1]

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
        self._constraints_changed()

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
            self._constraints_changed()
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
        self._constraints_changed()

    def _constraints_changed(self):
        """A support, exact tie or rigid group was added: drop what depends on them (here
        the model arrays; a structure whose elements do not depend on them keeps its
        elements, its DOF orderings being keyed on the constraints)."""
        self._cache = None

    def copy(self):
        """A copy with its own supports, ties, rigid groups, dead loads and rods list, that
        shares the rods' arrays and the built model arrays (read-only) with this one: the
        variants of one mesh (a unit with and without its actuator and rig) cost no second
        meshing. Adding rods, clamps or springs to either leaves the other as it was."""
        other = copy.copy(self)
        state = vars(other)
        for name, value in state.items():
            if isinstance(value, dict):
                state[name] = {k: (set(v) if isinstance(v, set) else v) for k, v in value.items()}
            elif isinstance(value, list):
                items = [list(v) if isinstance(v, list) else v for v in value]
                state[name] = items if type(value) is list else type(value)(items)
            elif isinstance(value, set):
                state[name] = type(value)(value)
        other._supernodes_memo = None
        return other

    # ------------------------------------------------------------------ dead loads
    def add_load(self, node, force):
        """A dead load: the constant force ``force`` (N, a vector of the structure's
        dimension, e.g. (0, -2.0)) on ``node``, acting through every push and path; loads
        on one node add up. `follow_load` follows all dead loads times one load factor;
        `push` starts from the equilibrium under them at full value."""
        node = self.check_node(node)
        f = real_array(force, "force (N)").reshape(-1)
        if f.shape != (self.dim,) or not np.all(np.isfinite(f)):
            raise ValueError(f"force must be a finite ({', '.join(self.component_names)}) "
                             f"vector in N; got {force!r}")
        self._point_loads.append((node, f))

    def add_gravity(self, density, g, direction, rods=None):
        """Self-weight: every rod edge's weight rho A |e_bar| g, half on each of its nodes
        (consistent nodal loads of a uniform weight per length; each edge its own section
        area A, so a rod of varying section weighs what it should). ``density``: kg/m^3, or
        a `solver.materials.Material` (its density); ``g`` (m/s^2, >= 0); ``direction``:
        the way gravity pulls (the subclasses' default -z: (0, -1) planar, (0, 0, -1) 3-D;
        normalised);
        ``rods``: the rods (or their indices) that weigh (default all; call again with
        another density for rods of another material). Nodes that are tied or in a rigid
        group keep their own share: it acts on their group's DOFs through W, as the
        gradient does; a supported component carries its share to the support."""
        rho = density.density if isinstance(density, Material) else real_scalar(
            density, "density", "kg/m^3")
        g = real_scalar(g, "g", "m/s^2")
        if not (np.isfinite(rho) and rho > 0.0):
            raise ValueError(f"density must be finite and > 0 kg/m^3; got {density!r}")
        if not (np.isfinite(g) and g >= 0.0):
            raise ValueError(f"g must be finite and >= 0 m/s^2; got {g!r}")
        n = real_array(direction, "direction").reshape(-1)
        if n.shape != (self.dim,) or not np.all(np.isfinite(n)) or not np.any(n != 0.0):
            raise ValueError(f"direction must be a finite non-zero "
                             f"({', '.join(self.component_names)}) vector; got {direction!r}")
        n = n / np.max(np.abs(n))
        which = None
        if rods is not None:
            which = tuple(self._rod_index(r) for r in rods)
        self._gravity.append((rho * g, n / np.linalg.norm(n), which))

    def clear_loads(self):
        """Remove every dead load (point loads and self-weight)."""
        self._point_loads.clear()
        self._gravity.clear()

    def _rod_index(self, rod) -> int:
        """The index of ``rod`` (a rod of this structure or its index), or a ValueError."""
        if isinstance(rod, (int, np.integer)) and not isinstance(rod, (bool, np.bool_)):
            if 0 <= int(rod) < len(self.rods):
                return int(rod)
        for k, r in enumerate(self.rods):
            if r is rod:
                return k
        raise ValueError(f"rods must list rods of this structure or their indices "
                         f"(0 .. {len(self.rods) - 1}); got {rod!r}")

    def dead_loads(self) -> np.ndarray:
        """(n_nodes, dim) N: the dead load on every node at load factor 1 (point loads and
        self-weight), before any constraint."""
        f = np.zeros((self.n_nodes, self.dim))
        for node, force in self._point_loads:
            f[node] += force
        for rho_g, n, which in self._gravity:
            for k in (range(len(self.rods)) if which is None else which):
                nodes = self.rods[k].nodes
                length = np.linalg.norm(np.diff(self._positions[k], axis=0), axis=1)
                half = 0.5 * rho_g * self._edge_areas(k) * length  # N per node per edge
                np.add.at(f, nodes[:-1], half[:, None] * n)
                np.add.at(f, nodes[1:], half[:, None] * n)
        return f

    def _edge_areas(self, k) -> np.ndarray:
        """(n_edges,) cross-section area (m^2) of each edge of rod ``k``."""
        raise NotImplementedError

    @property
    def has_dead_loads(self) -> bool:
        """Does any node carry a non-zero dead load?"""
        return bool(self._point_loads or self._gravity) and bool(np.any(self.dead_loads()))

    def total_dead_load(self) -> float:
        """Sum over the nodes of the magnitude of their dead loads, N (the total weight
        under self-weight alone): the force a load factor of 1 stands for."""
        return float(np.sum(np.linalg.norm(self.dead_loads(), axis=1)))

    def _system_loads(self, force_unit=1.0):
        """The dead loads a system assembles: (full DOFs, forces in the system's units
        (N / ``force_unit``), stress-free coordinates), or None when there are none."""
        if not (self._point_loads or self._gravity):
            return None
        f = np.zeros(self.initial_state().shape[0])
        f[: self.dim * self.n_nodes] = self.dead_loads().reshape(-1)
        full = np.flatnonzero(f)
        if full.size == 0:
            return None
        return full, f[full] / force_unit, self.initial_state()[full]

    def _copy_loads_to(self, other):
        """Give ``other`` (a copy of this structure's rods) the same dead loads."""
        other._point_loads = [(node, f.copy()) for node, f in self._point_loads]
        other._gravity = list(self._gravity)

    def without_dead_loads(self):
        """A shallow copy of the structure with no dead loads (its rods, supports and model
        arrays shared): what `follow_load` hands the drivers, its loads in the load vector."""
        other = copy.copy(self)
        other._point_loads, other._gravity = [], []
        return other

    def path_state(self, path, index=-1) -> np.ndarray:
        """The full state vector of row ``index`` of a path of this structure (positions,
        and what the structure's state holds besides: planar clamps' ghosts, 3-D twists
        in the canonical convention): a state any push, path or solve restarts from."""
        q = self.initial_state()
        q[: self.dim * self.n_nodes] = np.asarray(path.positions[index], dtype=float).reshape(-1)
        self._complete_state(q, path, index)
        return q

    def _complete_state(self, q, path, index):
        """Fill the state components past the node positions from a path row (none here)."""

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
        """Node -> representative of the group of nodes that share displacements (read-only;
        built again only when nodes, ties or clamps were added: the lists only grow)."""
        key = (self._n_total, len(self._merges), len(getattr(self, "_clamps", ())))
        memo = getattr(self, "_supernodes_memo", None)
        if memo is None or memo[0] != key:
            pairs = _PairList(self._merges)
            self._share_extra(pairs)
            rep = group_minima(self._n_total, pairs.array())
            rep.setflags(write=False)
            memo = self._supernodes_memo = (key, rep)
        return memo[1]

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

    def nodes_dofs(self, nodes) -> np.ndarray:
        """(len(nodes), dim) int64: `node_dofs` of each of ``nodes`` (an int array), at once
        (`solver.problem.make_control` asks it for the nodes sharing a pushed node's
        displacement; a subclass that numbers its state otherwise overrides both)."""
        nodes = np.asarray(nodes, dtype=np.int64)
        return self.dim * nodes[:, None] + np.arange(self.dim, dtype=np.int64)

    def positions_of(self, q) -> np.ndarray:
        """(n_nodes, dim) node positions (m) held in the state vector ``q`` (a view)."""
        return np.asarray(q)[: self.dim * self.n_nodes].reshape(-1, self.dim)

    def scales(self):
        """(length m, force N): the structure's size (largest extent of its reference shape)
        and EI_max / length^2; tolerances and step sizes are taken relative to these."""
        if not self.rods:
            raise ValueError("the structure has no rods")
        # asked by every driver, probe and control: computed again only when a rod was added
        memo = getattr(self, "_scales_memo", None)
        if memo is None or memo[0] != len(self.rods):
            X = self.reference_positions
            length = float(np.max(np.ptp(X, axis=0)))
            if not length > 0.0:
                length = float(max(np.max(np.abs(X)), 1e-300))
            memo = self._scales_memo = (len(self.rods),
                                        (length, self._max_bending_stiffness() / length**2))
        return memo[1]

    def _max_bending_stiffness(self) -> float:
        """The largest bending stiffness of the rods, N m^2 (the force scale's)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ experiments
    def _push(self, node, direction, distance, method, options):
        start = self._loaded_start(options.pop("start", None), options)
        control = make_control(self, node, direction, distance, method, start=start)
        if method == "mgdc":
            return follow_mgdc(self, control, **options)
        return follow_displacement(self, control, **options)

    def _loaded_start(self, start, options):
        """The state a push starts from: None (the stress-free state) for a structure
        without dead loads and no ``start``; else ``start`` (positions or a full state) or
        the end of `follow_load` to factor 1, polished by Newton under the dead loads at
        full value. ConvergenceError when the structure does not carry its dead loads."""
        if start is None and not self.has_dead_loads:
            return None
        if start is None:
            loaded = self.follow_load(1.0, time_limit=options.get("time_limit"))
            if loaded.status != "ok":
                raise ConvergenceError(
                    f"the structure does not carry its dead loads at full value: "
                    f"follow_load(1.0) ended with status {loaded.status!r} (push from a state "
                    f"of your own with start=...)")
            start = self.path_state(loaded)
        try:
            return equilibrium(self, start, None, None, 0.0)[1]["state"]
        except ConvergenceError as exc:
            raise ConvergenceError(f"the push's start is no equilibrium under the dead "
                                   f"loads: {exc}") from exc

    def follow_load(self, max_factor=1.0, method="mgdc", **options):
        """Follow every dead load (point loads and self-weight) times one load factor from
        0 (the stress-free state, or ``start=``) to ``max_factor``, with MGDC: passes
        limit points of the load factor (the load a structure snaps at) and records them.
        Returns a `solver.path.Path` with ``load_factor`` and ``limit_load_factor``; see
        `solver.loading.follow_load` for the options, the statuses and what the path's
        displacement and force are."""
        return follow_load(self, max_factor, method, **options)

    def _solve_equilibrium(self, positions, node, direction, force, options):
        return equilibrium(self, positions, node, direction, force, **options)
