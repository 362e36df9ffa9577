"""`Structure`: rods in the x–z plane, their bonds and supports, and the push experiment.

A structure owns arrays (node positions, element connectivity, stiffnesses, constraints);
the physics lives in `solver.energies`, assembly in `solver.assembly`, the bookkeeping of
supports and shared displacements in `solver.constraints`, and the path followers in
`solver.mgdc` and `solver.displacement`. All quantities are SI (m, N, Pa).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph
from numba import njit

from snapmorph.solver.assembly import _connectivity_dofs, _fill_slots, total_energy
from snapmorph.solver.banded import _profile, _row_starts
from snapmorph.solver.constraints import ConstrainedStructure, _spread
from snapmorph.solver.problem import state_from
from snapmorph.solver.system import ReducedSystem

# The thinnest rod `add_rod` accepts: arc length / smallest thickness. The ratio of
# stretching to bending stiffness grows as 12 (length / thickness)^2 (length / edge), and
# beyond this paths stop converging in double precision (measured on a clamped arch:
# 3e4 solves, 1e5 fails for some pushes, 3.3e5 for all).
MAX_SLENDERNESS = 3e4

# The reference modulus (Pa) of the normalised elements the path followers work on: every
# structure is solved as if made of this material and its forces scaled by E_max / E_REF
# afterwards, so E changes no bit of a path. It is the project's default material (PETG,
# 2.2 GPa), for which the normalised and physical systems coincide exactly.
E_REF = 2.2e9


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

    def __repr__(self):
        # short: the arrays hold one entry per (half) edge and would print kilobytes
        n = len(self.nodes)
        first, last = (int(self.nodes[0]), int(self.nodes[-1])) if n else (0, -1)
        return (f"Rod(nodes {first}..{last} ({n}), width {np.min(self.width) * 1e3:.4g}.."
                f"{np.max(self.width) * 1e3:.4g} mm, thickness {np.min(self.thickness) * 1e3:.4g}.."
                f"{np.max(self.thickness) * 1e3:.4g} mm, E={self.E:.4g} Pa)")


def _real(value, name, what):
    """``value`` as a float array, or a ValueError naming the parameter (strings, None,
    complex numbers, ragged sequences)."""
    if value is None or isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be {what}; got {value!r}")
    try:
        arr = np.asarray(value)
    except Exception as exc:
        raise ValueError(f"{name} must be {what}; got {value!r}") from exc
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name} must be {what} (real numbers); got {value!r}")
    return arr.astype(float)


def _columns(*columns) -> np.ndarray:
    """``np.stack(columns, axis=1)`` of 1-D arrays of one dtype, without its generality
    (3 us a call, a dozen calls per rod)."""
    out = np.empty((len(columns[0]), len(columns)), dtype=columns[0].dtype)
    for j, c in enumerate(columns):
        out[:, j] = c
    return out


def _per_edge(value, n_edges, name):
    """Section data per half edge, (n_edges, 2): a scalar, one value per edge, or one per
    half edge (the section may change at an edge's midpoint)."""
    if type(value) is float and 0.0 < value < np.inf:  # (a valid scalar: no checks to repeat)
        return np.full((n_edges, 2), value)
    arr = _real(value, name, "a positive number in m (or one per edge)")
    if arr.ndim == 0:
        arr = np.full(n_edges, float(arr))
    if arr.shape == (n_edges,):
        arr = _columns(arr, arr)
    if arr.shape != (n_edges, 2):
        raise ValueError(
            f"{name} must be a scalar, one value per edge, shape ({n_edges},), or one per "
            f"half edge, shape ({n_edges}, 2); got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise ValueError(f"{name} must be finite and > 0 (m); got min {np.nanmin(arr)!r}")
    return arr


class Structure(ConstrainedStructure):
    """A planar structure of discrete elastic rods.

    >>> st = Structure()
    >>> rod = st.add_rod(xz, width=5e-3, thickness=0.5e-3, E=2.2e9)
    >>> st.fix(rod.nodes[0], "xz"); path = st.push(rod.nodes[-1], (0, -1), 0.01)

    The path followers use only the members of `solver.problem.PushProblem`
    (docs/problem-interface.md); the bookkeeping of nodes, supports and shared displacements
    is `solver.constraints.ConstrainedStructure`'s.
    """

    dim = 2  # components per node position (x, z)
    component_names = "xz"
    component_choices = "'x', 'z' or 'xz'"

    def __init__(self):
        super().__init__()
        self._stretch_nodes: list[np.ndarray] = []
        self._stretch_params: list[np.ndarray] = []
        self._bend_nodes: list[np.ndarray] = []
        self._bend_params: list[np.ndarray] = []
        self._spring_nodes: list[tuple[int, int]] = []
        self._spring_params: list[tuple[float, float, float]] = []
        # clamps: one record per clamped side, each with a ghost node appended after the
        # real nodes in the state vector (see `clamp`)
        self._clamps: list[dict] = []
        self._replaced_bends: set[int] = set()
        # E-free copies of the stiffness parameters (see `elements(normalized=True)`)
        self._rod_E: list[float] = []
        self._stretch_free: list[np.ndarray] = []
        self._bend_free: list[np.ndarray] = []

    # ------------------------------------------------------------------ building
    def add_rod(self, xz, width, thickness, E) -> Rod:
        """Add a rod through the points ``xz`` (N, 2) m; its shape is stress free.

        ``width`` and ``thickness`` (m) are scalars, one value per edge (N-1,), or one
        per half edge (N-1, 2) for a section that changes at an edge's midpoint;
        ``E`` is Young's modulus (Pa).
        """
        xz = _real(xz, "xz", "an (N, 2) array of node positions in m")
        if xz.ndim != 2 or xz.shape[1] != 2:
            raise ValueError(f"xz must be an (N, 2) array of node positions in m; got shape {xz.shape}")
        n = xz.shape[0]
        if n < 3:
            raise ValueError(f"xz must hold at least 3 nodes (N >= 3: one bending node) in m; "
                             f"got {n}")
        if not np.all(np.isfinite(xz)):
            raise ValueError("xz contains NaN or infinite coordinates")
        edges = xz[1:] - xz[:-1]
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        extent = xz.max(axis=0) - xz.min(axis=0)
        scale = max(extent[0], extent[1], 1e-300)
        if np.any(lengths <= 1e-9 * scale):
            i = int(np.argmin(lengths))
            raise ValueError(f"xz has coincident consecutive nodes (edge {i} has zero length)")
        # a rod that turns back on itself (consecutive edges anti-parallel): its turning
        # curvature 2 tan(phi / 2) is infinite
        dots = edges[:-1] * edges[1:]
        cosines = (dots[:, 0] + dots[:, 1]) / (lengths[:-1] * lengths[1:])
        if np.any(cosines <= -1.0 + 1e-6):
            i = int(np.argmin(cosines))
            raise ValueError(f"xz turns back on itself at node {i + 1} (edges {i} and {i + 1} "
                             "are anti-parallel): a rod's turning angle must stay below 180 deg")
        width = _per_edge(width, n - 1, "width")
        thickness = _per_edge(thickness, n - 1, "thickness")
        slenderness = float(np.sum(lengths) / np.min(thickness))
        if slenderness > MAX_SLENDERNESS:
            raise ValueError(
                f"thickness too small for this rod: length / thickness = {slenderness:.3g} > "
                f"{MAX_SLENDERNESS:.0e} (stretching / bending stiffness grows as "
                "(length / thickness)^2 and double precision no longer resolves bending); "
                f"valid: thickness >= {np.sum(lengths) / MAX_SLENDERNESS:.3g} m for this rod")
        E = _real(E, "E", "Young's modulus in Pa, a single number")
        if E.shape != ():
            raise ValueError(f"E (Young's modulus) must be a single number in Pa; got shape {E.shape}")
        E = float(E)
        if not np.isfinite(E) or E <= 0.0:
            raise ValueError(f"E (Young's modulus) must be finite and > 0 Pa; got {E!r}")

        start = self.n_nodes
        nodes = np.arange(start, start + n, dtype=np.int64)
        rod = Rod(nodes=nodes, width=width, thickness=thickness, E=E)
        self.rods.append(rod)
        self._positions.append(xz.copy())

        free = Rod(nodes=nodes, width=width, thickness=thickness, E=E_REF)  # see E_REF
        self._rod_E.append(E)
        self._stretch_free.append(_columns(free.EA, lengths))
        EA = rod.EA
        self._stretch_nodes.append(_columns(nodes[:-1], nodes[1:]))
        self._stretch_params.append(_columns(EA, lengths))

        EI = rod.EI
        # Node stiffness EI / l_bar over the Voronoi region (half of each adjacent edge). Where
        # the section changes at a node the two halves act in series (the moment is common,
        # the rotations add), so the compliances add: l_bar / EI_eff = l0/(2 EI0) + l1/(2 EI1).
        # An arithmetic mean of EI there would make every result converge only as O(1/N).
        node_stiffness = 1.0 / (0.5 * lengths[:-1] / EI[:-1, 1] + 0.5 * lengths[1:] / EI[1:, 0])
        kappa_bar = _turning_curvatures(xz)
        self._bend_nodes.append(_columns(nodes[:-2], nodes[1:-1], nodes[2:]))
        self._bend_params.append(_columns(node_stiffness, kappa_bar))
        EI_free = free.EI
        self._bend_free.append(_columns(
            1.0 / (0.5 * lengths[:-1] / EI_free[:-1, 1] + 0.5 * lengths[1:] / EI_free[1:, 0]),
            kappa_bar))
        self._cache = None
        return rod

    # ------------------------------------------------------------------ problem interface
    @property
    def _n_total(self) -> int:
        """Real nodes plus the clamps' ghost nodes (held or moving with their node)."""
        return self.n_nodes + len(self._clamps)

    def _share_extra(self, uf):
        for k, c in enumerate(self._clamps):
            if not c["hold_position"]:  # a sliding clamp's ghost translates with its node
                uf.union(c["node"], self.n_nodes + k)

    def _hold_extra(self, fixed_rep, rep):
        for k, c in enumerate(self._clamps):
            if c["hold_position"]:
                fixed_rep[rep[self.n_nodes + k], :] = True

    def _ghost_positions(self, X=None):
        """(n_clamps, 2) reference positions of the ghost nodes, m."""
        if not self._clamps:
            return np.zeros((0, 2))
        X = self.reference_positions if X is None else X
        return np.array([X[c["node"]] + c["offset"] for c in self._clamps], dtype=float)

    def initial_state(self) -> np.ndarray:
        """The stress-free full state vector q0 (2 n_nodes + 2 n_ghosts,) m: node positions,
        then the clamps' ghost nodes (see `clamp`); a fresh copy every call."""
        X = self.reference_positions
        if not self._clamps:  # (the positions alone: one copy, no joining)
            return X.reshape(-1).copy()
        return np.concatenate([X, self._ghost_positions(X)]).reshape(-1)

    def state_fields(self, q) -> dict:
        """Per-state arrays recorded on a path besides positions: none for planar rods."""
        return {}

    def _max_bending_stiffness(self) -> float:
        return max(float(np.max(r.EI)) for r in self.rods)  # N m^2

    def _edge_areas(self, k) -> np.ndarray:
        """(n_edges,) section area of each edge of rod ``k``, m^2: the mean of its two
        halves' w t (the section may change at an edge's midpoint)."""
        rod = self.rods[k]
        return 0.5 * np.sum(rod.width * rod.thickness, axis=1)

    def _complete_state(self, q, path, index):
        """A sliding clamp's ghost translates with its node (a held one stays put)."""
        X = self.reference_positions
        G = self._ghost_positions(X)
        pos = np.asarray(path.positions[index], dtype=float)
        for k, c in enumerate(self._clamps):
            if not c["hold_position"]:
                q[2 * (self.n_nodes + k): 2 * (self.n_nodes + k) + 2] = (
                    G[k] + pos[c["node"]] - X[c["node"]])

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
        done = set()
        for c in self._clamps:
            if c["group"] not in done:
                done.add(c["group"])
                new.clamp(c["node"], toward=c["toward"], hold_position=c["hold_position"])
        self._copy_loads_to(new)
        return new

    def add_gravity(self, density, g=9.81, direction=(0.0, -1.0), rods=None):
        """Self-weight along ``direction`` (default -z); see
        `solver.constraints.ConstrainedStructure.add_gravity`."""
        super().add_gravity(density, g, direction, rods)

    def fix(self, node, components="xz"):
        """Hold the displacement of ``node`` at zero in "x", "z" or "xz".

        DER convention: a rod's tangent lives on its edges (a bending node measures the
        turning between its two edges). Fixing the first two nodes of a rod therefore holds
        the tangent of the first edge, i.e. at the edge's midpoint, half an edge into the
        rod: the clamp sits ds/2 away from node 0 and results converge only as O(1/N).
        `clamp` holds position and tangent at exactly the node (O(1/N^2))."""
        self._fix(node, components)

    def clamp(self, node, toward, hold_position=True, tangent=None):
        """Clamp ``node``: hold its tangent (and, with ``hold_position``, its position) at
        exactly the node.

        ``toward``: the node's neighbour along its rod (tells which rod, and for an end node
        which side is the rod). The tangent held is the reference shape's tangent at the
        node (second-order estimate through three nodes), or ``tangent`` (a 2-vector).
        Each clamped side gets a ghost node one edge beyond the node along the tangent,
        held in place (or translating with the node when ``hold_position`` is False: a
        sliding clamp, rotation held only); the bending node at ``node`` then measures the
        turning between the held tangent and the real edge over the real half edge only
        (stiffness 2 EI / l). An interior node is clamped on both sides (its own bending
        term replaced by the two one-sided ones). The ghosts are internal: positions,
        paths and `n_nodes` show real nodes only.
        """
        node = self.check_node(node)
        toward = self.check_node(toward, "toward")
        found = None
        for rod in self.rods:
            idx = np.flatnonzero(rod.nodes == node)
            jdx = np.flatnonzero(rod.nodes == toward)
            if idx.size and jdx.size and abs(int(idx[0]) - int(jdx[0])) == 1:
                found = (rod, int(idx[0]))
        if found is None:
            raise ValueError(f"toward ({toward}) must be a neighbour of node {node} along its rod")
        if any(c["node"] == node for c in self._clamps):
            raise ValueError(f"node {node} is clamped already")
        rod, i = found
        X = self._positions[self.rods.index(rod)]
        n = len(rod.nodes)
        forward = rod.nodes[i + 1] == toward if i + 1 < n else False
        if tangent is None:
            t = _tangent_estimate(X, i)
        else:
            t = np.asarray(tangent, dtype=float).reshape(-1)
            if t.shape != (2,) or not np.all(np.isfinite(t)) or not np.any(t):
                raise ValueError(f"tangent must be a finite non-zero (x, z) vector; got {tangent!r}")
        t = t / np.linalg.norm(t)
        if not forward:
            t = -t  # t points from the node along the rod towards `toward`
        if np.dot(t, X[i + 1] - X[i] if forward else X[i - 1] - X[i]) <= 0.0:
            raise ValueError("tangent points away from the rod at the clamped node")
        group = len(self._clamps)
        sides = []
        # the side towards `toward`, and for an interior node the other side too
        other = i - 1 if forward else i + 1
        for j, sgn in ((i + 1 if forward else i - 1, 1.0), (other, -1.0)):
            if not 0 <= j < n:
                continue
            length = float(np.linalg.norm(X[j] - X[i]))
            edge = min(i, j)
            EI = float(rod.EI[edge, 0 if j > i else 1])  # the half edge next to the node
            EI_free = float(E_REF * rod.width[edge, 0 if j > i else 1]
                            * rod.thickness[edge, 0 if j > i else 1] ** 3 / 12.0)
            # ghost one edge length behind the node, opposite to the real edge's side
            direction = t if sgn > 0 else -t
            offset = -length * direction
            sides.append(dict(node=node, neighbour=int(rod.nodes[j]), offset=offset,
                              stiffness=2.0 * EI / length, stiffness_free=2.0 * EI_free / length,
                              E=rod.E, group=group, toward=toward,
                              hold_position=bool(hold_position)))
        self._clamps.extend(sides)
        if len(sides) == 2:
            self._replaced_bends.add(node)
        if hold_position:
            self._fixed.setdefault(node, set()).update((0, 1))
        self._cache = None

    def tie(self, node_a, node_b, method="exact", stiffness=None):
        """Bond two nodes: ``method="exact"`` (equal displacements, u = W u_i) or
        ``"spring"`` (stiff zero-length spring; ``stiffness`` N/m, default 1e3 times the
        stiffest adjacent edge's EA / length).

        Both keep the nodes' reference offset fixed in global axes, so bond coincident nodes
        (as the unit does): an offset bond resists rigid rotation of the structure."""
        super().tie(node_a, node_b, method, stiffness)

    def tie_all(self, pairs, method="exact", stiffness=None):
        """`tie` every pair (node_a, node_b) of ``pairs`` (a sequence, or an (n, 2) int
        array: a mesh's bonds). Exact ties given as an int array of valid, distinct nodes
        are checked at once (`tie` checks each pair: 3 us a bond); anything else goes
        through `tie`, with its errors."""
        n = self.n_nodes
        if (method == "exact" and isinstance(pairs, np.ndarray) and pairs.ndim == 2
                and pairs.shape[1] == 2 and pairs.shape[0] and pairs.dtype.kind in "iu"
                and n and pairs.min() >= 0 and pairs.max() < n
                and not np.any(pairs[:, 0] == pairs[:, 1])):
            self._merges.extend(map(tuple, pairs.tolist()))
            self._constraints_changed()
            return
        for a, b in pairs:
            self.tie(a, b, method, stiffness)

    def _tie_other(self, a, b, method, stiffness):
        if method != "spring":
            raise ValueError(f"tie method must be 'exact' or 'spring'; got {method!r}")
        if stiffness is None:
            stiffness = 1e3 * self._max_axial_stiffness((a, b))
        stiffness = float(stiffness)
        if not np.isfinite(stiffness) or stiffness <= 0:
            raise ValueError(f"spring stiffness must be finite and > 0 N/m; got {stiffness!r}")
        X = self.reference_positions
        off = X[a] - X[b]
        self._spring_nodes.append((a, b))
        self._spring_params.append((stiffness, off[0], off[1]))

    def _max_axial_stiffness(self, nodes):
        best = 0.0
        for sn, sp in zip(self._stretch_nodes, self._stretch_params):
            mask = np.isin(sn, nodes).any(axis=1)
            if mask.any():
                best = max(best, float(np.max(sp[mask, 0] / sp[mask, 1])))
        return best

    def _constraints_changed(self):
        """Supports, exact ties and rigid groups do not change the elements (the DOF
        orderings built from them are keyed on the constraints, `_ordering`): a copy that
        only adds constraints keeps sharing its original's elements and orderings."""

    # ------------------------------------------------------------------ model arrays
    def elements(self, normalized=False):
        """The element tuple consumed by `solver.assembly` (see its docstring).

        ``normalized``: the same structure made of the reference material (E_max -> E_REF,
        other rods in proportion): the path followers work on these, so that E changes no
        bit of a path (forces and energies scale back by E_max / E_REF)."""
        if self._cache is None:
            self._cache = (self._build_elements(False), self._build_elements(True))
            # the orderings of these elements (`_ordering`), shared by later copies
            self._orderings = (self._cache, {})
        return self._cache[1 if normalized else 0]

    @property
    def E_max(self) -> float:
        """The largest Young's modulus of the rods, Pa (the normalised elements' unit)."""
        return max(rod.E for rod in self.rods) if self.rods else 1.0

    def _build_elements(self, normalized):
        def cat(parts, shape, dtype):
            return (
                np.ascontiguousarray(np.concatenate(parts, axis=0), dtype=dtype)
                if parts
                else np.zeros(shape, dtype=dtype)
            )

        E_max = self.E_max
        springs_n = np.array(self._spring_nodes, dtype=np.int64).reshape(-1, 2)
        springs_p = np.array(self._spring_params, dtype=float).reshape(-1, 3)
        if normalized:
            # section factors computed with E_REF, times E / E_max (exactly 1 for a single
            # material, so these arrays do not depend on E at all)
            stretch_p = cat([_columns(f[:, 0] * (E / E_max), f[:, 1])
                             for f, E in zip(self._stretch_free, self._rod_E)], (0, 2), float)
            bend_p = cat([_columns(f[:, 0] * (E / E_max), f[:, 1])
                          for f, E in zip(self._bend_free, self._rod_E)], (0, 2), float)
            springs_p = springs_p.copy()
            springs_p[:, 0] *= E_REF / E_max
        else:
            stretch_p = cat(self._stretch_params, (0, 2), float)
            bend_p = cat(self._bend_params, (0, 2), float)
        bend_n = cat(self._bend_nodes, (0, 3), np.int64)
        if self._clamps:
            keep = ~np.isin(bend_n[:, 1], list(self._replaced_bends))
            bend_n, bend_p = bend_n[keep], bend_p[keep]
            X = self.reference_positions
            G = self._ghost_positions(X)
            extra_n, extra_p = [], []
            for k, c in enumerate(self._clamps):
                g = self.n_nodes + k
                # ordered ghost -> node -> neighbour or neighbour -> node -> ghost,
                # along the rod's node order (the curvature's sign convention)
                if c["neighbour"] > c["node"]:
                    tri, pts = (g, c["node"], c["neighbour"]), (G[k], X[c["node"]], X[c["neighbour"]])
                else:
                    tri, pts = (c["neighbour"], c["node"], g), (X[c["neighbour"]], X[c["node"]], G[k])
                extra_n.append(tri)
                k_c = c["stiffness_free"] * (c["E"] / E_max) if normalized else c["stiffness"]
                extra_p.append((k_c, float(_turning_curvatures(np.array(pts))[0])))
            bend_n = np.ascontiguousarray(np.concatenate([bend_n, np.array(extra_n, dtype=np.int64)]))
            bend_p = np.ascontiguousarray(np.concatenate([bend_p, np.array(extra_p, dtype=float)]))
        return (
            cat(self._stretch_nodes, (0, 2), np.int64),
            np.ascontiguousarray(stretch_p),
            bend_n,
            np.ascontiguousarray(bend_p),
            np.ascontiguousarray(springs_n),
            np.ascontiguousarray(springs_p),
        )

    def reduced_system(self, extra_fixed=None, normalized=False,
                       dead_loads=True) -> ReducedSystem:
        """Assemble the DOF map (ordered by reverse Cuthill–McKee) and band storage.

        ``extra_fixed``: iterable of (node, component) pairs held or prescribed in addition
        to the supports (the displacement-controlled DOF). ``normalized``: the structure
        made of the reference material (`E_REF`); the system's ``force_unit`` = E_max / E_REF
        turns its forces, energies and stiffnesses into N, J and N/m. The path followers use
        it: paths then do not depend on E at all, bit for bit (dead loads aside: they are
        divided by the force unit, so a heavy structure's path depends on E as it should).
        ``dead_loads``: assemble the structure's dead loads at full value (docs/loads.md).
        """
        if self.n_nodes == 0:
            raise ValueError("the structure has no rods")
        elements = self.elements()
        ordering, layout = self._ordering(extra_fixed, elements)
        force_unit = self.E_max / E_REF if normalized else 1.0
        loads = self._system_loads(force_unit) if dead_loads else None
        system = ReducedSystem(self.elements(normalized), *ordering, loads=loads,
                               layout=layout)
        system.force_unit = force_unit
        return system

    def _ordering(self, extra_fixed, elements):
        """((dof_map, n_reduced, bandwidth), layout) of `reduced_system`, built once per set
        of held components and shared displacements: a unit's pushes, probes and state
        checks, and the copies of a structure (`copy`) that share its elements, reuse it
        (the key holds the supports, the extra held components, the exact ties and rigid
        groups, and the element tables it was built from). ``layout``: (element DOFs,
        envelope heights, band slots, representatives) of the systems built from it
        (`ReducedSystem`), read-only."""
        key = (tuple(sorted((int(n), tuple(sorted(c))) for n, c in self._fixed.items())),
               tuple((int(n), int(c)) for n, c in (extra_fixed or ())),
               tuple(self._merges))
        memo = getattr(self, "_orderings", None)
        if memo is None or memo[0] is not self._cache:  # built from other elements
            memo = self._orderings = (self._cache, {})
        if key not in memo[1]:
            memo[1][key] = self._build_ordering(extra_fixed, elements)
        return memo[1][key]

    def _build_ordering(self, extra_fixed, elements):
        """((dof_map, n_reduced, bandwidth), layout) of `_ordering`: remembered for the last
        few inputs across structures (`_LAYOUT_MEMO`: every unit of one resolution, and its
        released and snap-back variants, has the same graph and held components)."""
        rep, fixed = self._held(extra_fixed)
        fixed = np.ascontiguousarray(fixed, dtype=np.bool_)
        conns, graph = self._connectivity(elements)
        key = (rep.tobytes(), fixed.tobytes(), graph)
        for k, built in _LAYOUT_MEMO:
            if k == key:
                return built
        built = self._new_ordering(rep, fixed, conns)
        _LAYOUT_MEMO.append((key, built))
        del _LAYOUT_MEMO[:-_LAYOUT_MEMO_SIZE]
        return built

    def _connectivity(self, elements):
        """(the node index arrays of the three element kinds, their bytes): taken once per
        set of elements (kept with their orderings, `_ordering`: a structure's copies share
        them)."""
        memo = self._orderings[1]
        got = memo.get("connectivity")
        if got is None:
            conns = tuple(np.ascontiguousarray(elements[i], dtype=np.int64) for i in (0, 2, 4))
            got = memo["connectivity"] = (conns, b"".join(
                c.tobytes() + bytes(str(c.shape), "ascii") for c in conns))
        return got

    @staticmethod
    def _new_ordering(rep, fixed, conns):
        """`_build_ordering` computed: the node groups of the supernodes ``rep``, their RCM
        order and the layout (`_ordering_layout`) with the held components ``fixed``."""
        group, n_groups = node_groups(rep)
        order = _rcm_order(group, n_groups, conns)
        out = _ordering_layout(group, fixed, np.ascontiguousarray(order, dtype=np.int64),
                               *conns)
        dof_map, k, bw, dofs, heights, slots, representative = \
            out[0], out[1], out[2], out[3:6], out[6], out[7:10], out[10]
        if k == 0:
            raise ValueError("every degree of freedom is fixed: nothing to solve")
        for a in (dof_map, *dofs, heights, *slots, representative):
            a.setflags(write=False)  # shared by every system built from this ordering
        return (dof_map, k, bw), (dofs, heights, slots, representative)

    # ------------------------------------------------------------------ energy access
    def energy(self, positions=None) -> float:
        """Total potential energy (J) at ``positions`` (n_nodes, 2) m or a full state
        (default: reference): the elastic energy, plus the dead loads' potential
        -sum f (x - X) when the structure has any."""
        q = self._flat(positions)
        energy = float(total_energy(q, self.elements()))
        loads = self._system_loads()
        if loads is not None:
            full, f, ref = loads
            energy += float(-f @ (q[full] - ref))
        return energy

    def gradient(self, positions=None) -> np.ndarray:
        """dE/dx (n_nodes, 2), N, of the potential energy of `energy`: the internal force,
        minus the dead loads."""
        sysm = self._unconstrained()
        sysm.evaluate(self._flat(positions))
        return sysm.grad_full[: 2 * self.n_nodes].reshape(-1, 2).copy()

    def hessian(self, positions=None) -> np.ndarray:
        """Dense tangent stiffness d2E/dx2 (2 n_nodes, 2 n_nodes), N/m, without constraints
        (dead loads add none)."""
        sysm = self._unconstrained()
        dense = sysm.dense_stiffness(self._flat(positions))
        # reduced DOFs are numbered by reverse Cuthill-McKee: map back to natural order
        perm = sysm.dof_map[: 2 * self.n_nodes]
        return dense[np.ix_(perm, perm)]

    def _unconstrained(self) -> ReducedSystem:
        # every real node its own DOFs, nothing fixed: used for energy checks only (the
        # clamps' ghosts stay held, or moving with their node: they are the clamps)
        saved = (self._merges, self._fixed)
        held = {self.n_nodes + k: {0, 1} for k, c in enumerate(self._clamps) if c["hold_position"]}
        self._merges, self._fixed = [], held
        try:
            return self.reduced_system()
        finally:
            self._merges, self._fixed = saved

    def _flat(self, positions):
        if positions is None:
            return self.initial_state()
        return state_from(self, positions)

    # ------------------------------------------------------------------ experiments
    def push(self, node, direction=(0.0, -1.0), distance=None, method="mgdc", **options):
        """Push ``node`` along ``direction`` until its displacement reaches ``distance`` (m).

        ``method="mgdc"``: load control with the modified generalised displacement control
        path follower (passes limit points, negative stiffness and snap-back).
        ``method="displacement"``: the node's displacement along an axis-aligned direction
        is prescribed step by step. Every other constraint on the node is kept.
        Returns a `solver.path.Path`. Options: see the drivers `solver.mgdc.follow_mgdc`
        and `solver.displacement.follow_displacement`.

        Dead loads (`add_load`, `add_gravity`) act at full value from the start: the push
        starts from their equilibrium (`follow_load` to factor 1, ConvergenceError when the
        structure does not carry them) and ``path.force`` is the push's extra force. The
        displacement (and ``distance``) count from the stress-free shape: the path starts
        at the sag of the node. ``start=`` (positions or a full state, e.g.
        ``path_state(path, k)``): push from that equilibrium instead (polished by Newton).
        """
        return self._push(node, direction, distance, method, options)

    def solve_equilibrium(self, positions, node=None, direction=(0.0, -1.0), force=0.0, **options):
        """Equilibrium near ``positions`` with ``force`` (N) applied to ``node`` along
        ``direction`` (no load when ``node`` is None). Returns (positions, info dict)."""
        return self._solve_equilibrium(positions, node, direction, force, options)


def _tangent_estimate(X, i):
    """Unit tangent of the polyline X at node i, second order in the edge lengths: the
    derivative of the parabola through three consecutive nodes (one-sided at an end)."""
    n = len(X)
    if n < 3:
        t = X[min(i + 1, n - 1)] - X[max(i - 1, 0)]
        return t / np.linalg.norm(t)
    if i == 0:
        a, b, c, where = X[0], X[1], X[2], 0
    elif i == n - 1:
        a, b, c, where = X[n - 3], X[n - 2], X[n - 1], 2
    else:
        a, b, c, where = X[i - 1], X[i], X[i + 1], 1
    h1 = float(np.linalg.norm(b - a))
    h2 = float(np.linalg.norm(c - b))
    s = (0.0, h1, h1 + h2)[where]
    # derivative of the Lagrange parabola through (0, a), (h1, b), (h1 + h2, c) at s
    da = (2 * s - h1 - (h1 + h2)) / ((0 - h1) * (0 - h1 - h2))
    db = (2 * s - 0 - (h1 + h2)) / ((h1 - 0) * (h1 - h1 - h2))
    dc = (2 * s - 0 - h1) / ((h1 + h2) * h2)
    t = da * a + db * b + dc * c
    return t / np.linalg.norm(t)


def _turning_curvatures(xz):
    e0 = xz[1:-1] - xz[:-2]
    e1 = xz[2:] - xz[1:-1]
    cross = e0[:, 0] * e1[:, 1] - e0[:, 1] * e1[:, 0]
    dots = e0 * e1  # (the sum of two columns as np.sum(axis=1) adds them)
    g = np.hypot(e0[:, 0], e0[:, 1]) * np.hypot(e1[:, 0], e1[:, 1]) + (dots[:, 0] + dots[:, 1])
    return 2.0 * cross / g


def node_groups(rep):
    """(group (n,) int64, n_groups): ``np.unique(rep, return_inverse=True)``'s inverse and
    count for node representatives ``rep`` (>= 0): the groups numbered by increasing
    representative."""
    return _node_groups(np.ascontiguousarray(rep, dtype=np.int64))


@njit(cache=True)
def _node_groups(rep):
    """`node_groups` by a compiled loop (np.unique sorts: 15 us per ordering)."""
    n_values = 0
    for i in range(rep.shape[0]):
        n_values = max(n_values, rep[i] + 1)
    rank = np.full(n_values, -1, dtype=np.int64)
    for i in range(rep.shape[0]):
        rank[rep[i]] = 0
    n_groups = 0
    for v in range(n_values):
        if rank[v] == 0:
            rank[v] = n_groups
            n_groups += 1
    group = np.empty(rep.shape[0], dtype=np.int64)
    for i in range(rep.shape[0]):
        group[i] = rank[rep[i]]
    return group, n_groups


def number_dofs(group, fixed, order):
    """(dof_map (2 n,) int64, n_reduced): the free components of the node groups numbered
    in the groups' ``order`` (a permutation of 0..n_groups-1), x before z within a group,
    -1 for held ones; ``group`` (n,): each node's group, ``fixed`` (n, 2) bool: its held
    components (the same for every node of a group)."""
    return _number_dofs(np.ascontiguousarray(group, dtype=np.int64),
                        np.ascontiguousarray(fixed, dtype=np.bool_),
                        np.ascontiguousarray(order, dtype=np.int64))


@njit(cache=True)
def _number_dofs(group, fixed, order):
    """`number_dofs` by a compiled loop (eight numpy passes cost 25 us per ordering)."""
    n_groups = order.shape[0]
    group_fixed = np.zeros((n_groups, 2), dtype=np.bool_)
    for i in range(group.shape[0]):  # the last node of a group decides, as numpy's
        for c in range(2):           # fancy assignment does (all agree)
            group_fixed[group[i], c] = fixed[i, c]
    group_dof = np.empty((n_groups, 2), dtype=np.int64)
    k = 0
    for j in range(n_groups):
        for c in range(2):
            if group_fixed[order[j], c]:
                group_dof[order[j], c] = -1
            else:
                group_dof[order[j], c] = k
                k += 1
    dof_map = np.empty(2 * group.shape[0], dtype=np.int64)
    for i in range(group.shape[0]):
        dof_map[2 * i] = group_dof[group[i], 0]
        dof_map[2 * i + 1] = group_dof[group[i], 1]
    return dof_map, k


@njit(cache=True)
def _ordering_layout(group, fixed, order, stretch, bend, spring):
    """Everything a new DOF ordering fixes, in one compiled call (a dozen calls of the
    kernels below cost 25 us per ordering): (dof_map, n_reduced, bandwidth, the element
    DOFs of the three element kinds (`solver.assembly.element_dofs`), the envelope heights
    of the band (`solver.banded.envelope_heights`), the band slots of the three kinds
    (`solver.assembly.band_slots`), one full DOF per reduced DOF)."""
    dof_map, k = _number_dofs(group, fixed, order)
    ds = _connectivity_dofs(stretch, dof_map)
    db = _connectivity_dofs(bend, dof_map)
    dp = _connectivity_dofs(spring, dof_map)
    bw = max(_spread(ds), _spread(db), _spread(dp))
    first = np.arange(max(k, 1))
    _row_starts(ds, first)
    _row_starts(db, first)
    _row_starts(dp, first)
    heights = _profile(first)
    ss = np.empty((ds.shape[0], 10), dtype=np.int64)
    sb = np.empty((db.shape[0], 21), dtype=np.int64)
    sp = np.empty((dp.shape[0], 10), dtype=np.int64)
    _fill_slots(ds, bw + 1, ss)
    _fill_slots(db, bw + 1, sb)
    _fill_slots(dp, bw + 1, sp)
    representative = np.empty(k, dtype=np.int64)
    for j in range(dof_map.shape[0]):
        if dof_map[j] >= 0:
            representative[dof_map[j]] = j  # the last full DOF of a reduced one
    return dof_map, k, bw, ds, db, dp, heights, ss, sb, sp, representative


#: `Structure._build_ordering`'s memory: (key, ordering and layout) of the last ones built
#: (the key holds the bytes of the supernodes, the held components and the connectivity)
_LAYOUT_MEMO: list = []
_LAYOUT_MEMO_SIZE = 8

#: `_rcm_order`'s memory: (key, order) of the last orderings computed (a unit's pushes,
#: probes, released and snap-back structures share their graphs)
_RCM_MEMO: list = []
_RCM_MEMO_SIZE = 8


def _rcm_order(group, n_groups, connectivity):
    """Reverse Cuthill-McKee order of the groups of nodes (``group``: each node's group)
    joined by the elements' ``connectivity`` (node index arrays (n_elements, k)). Depends
    on the graph alone, not on which components are held: remembered for the last few
    graphs (the key holds the arrays' bytes, so equal graphs get the same order)."""
    key = (n_groups, group.tobytes(), *(c.tobytes() + bytes(str(c.shape), "ascii")
                                        for c in connectivity))
    for k, order in _RCM_MEMO:
        if k == key:
            return order
    rows, cols = [], []
    for conn in connectivity:
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
        # the canonical CSR graph scipy builds from these (row, col) pairs (duplicates
        # summed, columns sorted in each row), without its general conversion
        pairs = np.unique(r.astype(np.int64) * n_groups + c)
        indptr = np.zeros(n_groups + 1, dtype=np.int32)
        np.cumsum(np.bincount(pairs // n_groups, minlength=n_groups), out=indptr[1:])
        graph = scipy.sparse.csr_matrix(
            (np.ones(len(pairs)), (pairs % n_groups).astype(np.int32), indptr),
            shape=(n_groups, n_groups))
        order = scipy.sparse.csgraph.reverse_cuthill_mckee(graph, symmetric_mode=True)
    else:
        order = np.arange(n_groups)
    order.setflags(write=False)
    _RCM_MEMO.append((key, order))
    del _RCM_MEMO[:-_RCM_MEMO_SIZE]
    return order
