"""`Structure3D`: discrete elastic rods in 3-D (rectangular strips with twist), their rigid
joints, ties, supports and clamps, and the push experiment on the shared path followers.

Physics in `solver.energies3d` and `solver.frames3d`, assembly in `solver.assembly3d`, the
constrained system `solver.system.RodSystem3D`, the bookkeeping of supports and shared
displacements `solver.constraints`; the drivers are the planar solver's own (`solver.mgdc`,
`solver.displacement`, `solver.branching`) through docs/problem-interface.md. SI units.

>>> st = Structure3D()
>>> rod = st.add_rod(xyz, width=5e-3, thickness=0.5e-3, E=2.2e9, nu=0.38, normal=(0, 0, 1))
>>> st.clamp(rod.nodes[0], toward=rod.nodes[1])
>>> path = st.push(rod.nodes[-1], direction=(0.0, 0.0, -1.0), distance=0.02)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse

from snapmorph.solver.assembly3d import element_dofs3d
from snapmorph.solver.constraints import ConstrainedStructure, bandwidth
from snapmorph.solver.descent import descend
from snapmorph.solver.energies3d import material_curvature, tip_moment_terms, twist_angle
from snapmorph.solver.frames3d import space_parallel_frames
from snapmorph.solver.ordering import envelope_order
from snapmorph.solver.problem import ConvergenceError
from snapmorph.solver.system import RodSystem3D

_AXES = "xyz"


def torsion_constant(width, thickness):
    """J (m^4) of a w x t rectangle: w t^3 (1/3 - 0.21 (t/w)(1 - (t/w)^4 / 12)), t <= w
    (the two sides swapped for t > w)."""
    a = np.maximum(width, thickness)
    b = np.minimum(width, thickness)
    r = b / a
    return a * b**3 * (1.0 / 3.0 - 0.21 * r * (1.0 - r**4 / 12.0))


@dataclass(frozen=True, eq=False)
class Rod3D:
    """One rod of a `Structure3D`: global node and edge indices (in order), section data."""

    nodes: np.ndarray
    edges: np.ndarray
    width: np.ndarray  # (N-1,) m, in the strip's plane
    thickness: np.ndarray  # (N-1,) m, along the face normal m1
    E: float  # Pa
    nu: float
    J: np.ndarray | None = None  # (N-1,) m^4 torsion constant; None: a free strip's

    @cached_property
    def EA(self):
        """(N-1,) axial stiffness, N."""
        return self.E * self.width * self.thickness

    @cached_property
    def EI1(self):
        """(N-1,) bending stiffness through the thickness (the easy way), E w t^3 / 12, N m^2."""
        return self.E * self.width * self.thickness**3 / 12.0

    @cached_property
    def EI2(self):
        """(N-1,) bending stiffness in the strip's plane, E t w^3 / 12, N m^2."""
        return self.E * self.thickness * self.width**3 / 12.0

    @cached_property
    def GJ(self):
        """(N-1,) torsional stiffness, G = E / (2 (1 + nu)), N m^2."""
        J = torsion_constant(self.width, self.thickness) if self.J is None else self.J
        return self.E / (2.0 * (1.0 + self.nu)) * J


def _finite_array(value, name, unit):
    if isinstance(value, (str, bytes)) or value is None:
        raise ValueError(f"{name} must be numbers in {unit}; got {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be real numbers in {unit}; got {value!r}") from exc
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite ({unit}); got {value!r}")
    return arr


def _per_edge(value, n_edges, name, unit="m"):
    arr = _finite_array(value, name, unit)
    if arr.ndim == 0:
        arr = np.full(n_edges, float(arr))
    if arr.shape != (n_edges,):
        raise ValueError(f"{name} must be a scalar or one value per edge, shape ({n_edges},) "
                         f"({unit}); got shape {arr.shape}")
    if np.any(arr <= 0.0):
        raise ValueError(f"{name} must be > 0 {unit}; got min {arr.min()!r}")
    return arr


def _frame_pair(ta, da, tb, db, sa=1.0, sb=1.0):
    """The 18 frame components of `solver.energies3d` for two (tangent, m1) frames."""
    z = np.empty(18)
    for k, (t, d, sg) in enumerate(((ta, da, sa), (tb, db, sb))):
        o = 9 * k
        z[o: o + 3] = sg * t
        z[o + 3: o + 6] = d
        z[o + 6] = sg * (t[1] * d[2] - t[2] * d[1])
        z[o + 7] = sg * (t[2] * d[0] - t[0] * d[2])
        z[o + 8] = sg * (t[0] * d[1] - t[1] * d[0])
    return z


def _natural(z):
    """(kappa1, kappa2, psi) of a frame pair: the natural values of a stress-free pair."""
    g = np.empty(18)
    h = np.empty((18, 18))
    return (material_curvature(z, 1, g, h), material_curvature(z, 2, g, h),
            twist_angle(z, g, h))


class Structure3D(ConstrainedStructure):
    """Discrete elastic rods in 3-D: positions (x, y, z) per node, one twist angle per edge.

    The full state vector is ``3 n_nodes`` positions (m) then ``n_edges`` twists (rad).
    Provides the problem interface of the path followers (`solver.problem.PushProblem`,
    docs/problem-interface.md); the bookkeeping of nodes, supports and shared displacements
    is `solver.constraints.ConstrainedStructure`'s.
    """

    dim = 3
    component_names = "xyz"
    component_choices = "a non-empty subset of 'xyz' such as 'xz'"

    def __init__(self):
        super().__init__()
        self._tangents: list[np.ndarray] = []
        self._directors: list[np.ndarray] = []
        self._lengths: list[np.ndarray] = []
        self._edge_nodes: list[np.ndarray] = []
        # bending/twisting pairs: key -> (frame_a, sign_a, frame_b, sign_b, k1, k2, kt,
        # kappa1_bar, kappa2_bar, psi_bar); frames >= 0 are edges, < 0 clamp frames -1 - c
        self._pairs: dict = {}
        self._clamp_frames: list[tuple[np.ndarray, np.ndarray]] = []
        self._clamped: set[int] = set()

    # ------------------------------------------------------------------ sizes
    @property
    def n_edges(self) -> int:
        return int(self.rods[-1].edges[-1]) + 1 if self.rods else 0

    def _node_position(self, node):
        rod, i = self._rod_of(node)
        r = int(np.searchsorted(self._rod_starts(), rod.nodes[0], side="right")) - 1
        return self._positions[r][i]

    def _size(self):
        """Largest extent of the stress-free structure along x, y or z (m)."""
        cached = getattr(self, "_size_cache", None)
        if cached is None or cached[0] != len(self.rods):
            X = self.reference_positions
            cached = self._size_cache = (len(self.rods), float(np.max(np.ptp(X, axis=0))))
        return cached[1]

    def reference_frames(self):
        """(tangents, directors), each (n_edges, 3): the stress-free edges' unit tangents
        and face normals m1 (the material frames at theta = 0)."""
        return np.concatenate(self._tangents), np.concatenate(self._directors)

    # ------------------------------------------------------------------ building
    def add_rod(self, xyz, width, thickness, E, nu=0.38, normal=(0.0, 0.0, 1.0), *,
                natural_curvature=None, natural_twist=None, torsion_constant=None) -> Rod3D:
        """Add a strip through the points ``xyz`` (N, 3) m; its shape is stress free.

        ``width``, ``thickness`` (m): scalars or one per edge (N-1,); ``E`` Young's modulus
        (Pa), ``nu`` Poisson's ratio (G = E / (2 (1 + nu))). ``normal``: the strip's face
        normal (thickness direction) at the first edge, carried along the rod by parallel
        transport; or one normal per edge (N-1, 3) for a strip with a natural twist.
        ``natural_curvature`` (1/m): (kappa1, kappa2) or one pair per interior node (N-2, 2),
        and ``natural_twist`` (rad/m): scalar or (N-2,), replace the natural curvature and
        twist read off the stress-free shape (e.g. a straight rod that wants to be a helix).
        ``torsion_constant`` (m^4): scalar or one per edge, replaces the free strip's J of
        `torsion_constant` (e.g. w t^3 / 3 for a strip cut out of a continuous plate, whose
        edges are not free: a plate's twisting stiffness per width is G t^3 / 3).
        """
        xyz = _finite_array(xyz, "xyz", "m")
        if xyz.ndim != 2 or xyz.shape[1] != 3:
            raise ValueError(f"xyz must be an (N, 3) array of node positions in m; got shape "
                             f"{xyz.shape}")
        n = xyz.shape[0]
        if n < 2:
            raise ValueError(f"a rod needs at least 2 nodes; got {n}")
        e = np.diff(xyz, axis=0)
        lengths = np.linalg.norm(e, axis=1)
        scale = max(float(np.max(np.ptp(xyz, axis=0))), 1e-300)
        if np.any(lengths <= 1e-9 * scale):
            i = int(np.argmin(lengths))
            raise ValueError(f"xyz has coincident consecutive nodes (edge {i} has zero length)")
        tangents = e / lengths[:, None]
        if n > 2 and np.any(np.sum(tangents[:-1] * tangents[1:], axis=1) < -0.9):
            raise ValueError("xyz turns back on itself (an edge turns by more than ~150 degrees)")
        width = _per_edge(width, n - 1, "width")
        thickness = _per_edge(thickness, n - 1, "thickness")
        if isinstance(E, (bool, np.bool_)) or not np.isscalar(E):
            raise ValueError(f"E (Young's modulus) must be a number in Pa; got {E!r}")
        E = float(_finite_array(E, "E (Young's modulus)", "Pa"))
        if not E > 0.0:
            raise ValueError(f"E (Young's modulus) must be finite and > 0 Pa; got {E!r}")
        if isinstance(nu, (bool, np.bool_)) or not np.isscalar(nu):
            raise ValueError(f"nu (Poisson's ratio) must be a number; got {nu!r}")
        nu = float(_finite_array(nu, "nu (Poisson's ratio)", "-"))
        if not -1.0 < nu <= 0.5:
            raise ValueError(f"nu (Poisson's ratio) must be in (-1, 0.5]; got {nu!r}")
        normal = _finite_array(normal, "normal", "a direction")
        if normal.shape not in ((3,), (n - 1, 3)):
            raise ValueError(f"normal must be a 3-vector or one per edge, shape ({n - 1}, 3); "
                             f"got shape {normal.shape}")
        nn = np.atleast_2d(normal)
        tt = tangents[:1] if normal.ndim == 1 else tangents
        nlen = np.linalg.norm(nn, axis=1)
        if np.any(nlen == 0.0) or np.any(
                np.linalg.norm(np.cross(nn, tt), axis=1) <= 1e-6 * nlen):
            raise ValueError("normal must be non-zero and not parallel to its edge (it is the "
                             "strip's face normal, across the rod)")
        directors = space_parallel_frames(tangents, normal)

        start_node = self.n_nodes
        start_edge = self.n_edges
        nodes = np.arange(start_node, start_node + n, dtype=np.int64)
        edges = np.arange(start_edge, start_edge + n - 1, dtype=np.int64)
        J = None
        if torsion_constant is not None:
            J = _per_edge(torsion_constant, n - 1, "torsion_constant", "m^4")
        rod = Rod3D(nodes=nodes, edges=edges, width=width, thickness=thickness, E=E, nu=nu, J=J)

        kbar = tw = None
        if natural_curvature is not None or natural_twist is not None:
            lbar = 0.5 * (lengths[:-1] + lengths[1:])
            kbar = np.zeros((n - 2, 2))
            tw = np.zeros(n - 2)
            if natural_curvature is not None:
                kc = _finite_array(natural_curvature, "natural_curvature", "1/m")
                if kc.shape not in ((2,), (n - 2, 2)):
                    raise ValueError(f"natural_curvature must be (kappa1, kappa2) or shape "
                                     f"({n - 2}, 2) (1/m); got shape {kc.shape}")
                kbar[:] = kc * lbar[:, None]
            if natural_twist is not None:
                tc = _finite_array(natural_twist, "natural_twist", "rad/m")
                if tc.shape not in ((), (n - 2,)):
                    raise ValueError(f"natural_twist must be a scalar or shape ({n - 2},) "
                                     f"(rad/m); got shape {tc.shape}")
                tw[:] = tc * lbar
        self.rods.append(rod)
        self._positions.append(xyz.copy())
        self._tangents.append(tangents)
        self._directors.append(directors)
        self._lengths.append(lengths)
        self._edge_nodes.append(np.stack([nodes[:-1], nodes[1:]], axis=1))
        for i in range(1, n - 1):
            a, b = i - 1, i
            pair = self._make_pair(rod, a, 1.0, rod, b, 1.0)
            if kbar is not None:
                pair = pair[:7] + (kbar[i - 1, 0], kbar[i - 1, 1], tw[i - 1])
            self._pairs[("node", int(nodes[i]))] = pair
        self._cache = None
        return rod

    def _frame(self, rod, j):
        r = int(np.searchsorted(self._rod_starts(), rod.nodes[0], side="right")) - 1
        return self._tangents[r][j], self._directors[r][j], self._lengths[r][j]

    def _rod_starts(self):
        """(n_rods,) first node of every rod (increasing: rods are numbered in order)."""
        if len(getattr(self, "_starts", ())) != len(self.rods):
            self._starts = np.array([int(r.nodes[0]) for r in self.rods], dtype=np.int64)
        return self._starts

    def _make_pair(self, rod_a, ja, sa, rod_b, jb, sb, lengths=None):
        """A pair of two rod edges with series stiffnesses over their half lengths and the
        natural values of the stress-free frames."""
        ta, da, la = self._frame(rod_a, ja)
        tb, db, lb = self._frame(rod_b, jb)
        if lengths is not None:
            la, lb = lengths
        ks = [1.0 / (0.5 * la / A[ja] + 0.5 * lb / B[jb])
              for A, B in ((rod_a.EI1, rod_b.EI1), (rod_a.EI2, rod_b.EI2),
                           (rod_a.GJ, rod_b.GJ))]
        nat = _natural(_frame_pair(ta, da, tb, db, sa, sb))
        return (int(rod_a.edges[ja]), sa, int(rod_b.edges[jb]), sb, *ks, *nat)

    def _rod_of(self, node):
        r = int(np.searchsorted(self._rod_starts(), node, side="right")) - 1
        if r < 0 or not node <= self.rods[r].nodes[-1]:
            raise IndexError(node)
        rod = self.rods[r]
        return rod, int(node - rod.nodes[0])

    def add_gravity(self, density, g=9.81, direction=(0.0, 0.0, -1.0), rods=None):
        """Self-weight along ``direction`` (default -z); see
        `solver.constraints.ConstrainedStructure.add_gravity`."""
        super().add_gravity(density, g, direction, rods)

    def fix(self, node, components="xyz"):
        """Hold the displacement of ``node`` at zero in any subset of "x", "y", "z"."""
        self._fix(node, components)

    def clamp(self, node, toward):
        """Hold the position, tangent and twist of the rod at exactly ``node``; the tangent
        points to ``toward``, a neighbour of ``node`` on the same rod.

        The clamp is a fixed frame at the node coupled to each adjacent edge by bending and
        twisting over that edge's half length (the part of the node's Voronoi region on the
        edge's side), so that the clamped end of a cantilever is at the node itself."""
        node = self.check_node(node)
        toward = self.check_node(toward, "toward")
        rod, i = self._rod_of(node)
        rod_t, it = self._rod_of(toward)
        if rod_t is not rod or abs(it - i) != 1:
            raise ValueError(f"toward ({toward}) must be a neighbour of node {node} on its rod")
        if node in self._clamped:
            raise ValueError(f"node {node} is already clamped")
        r = next(k for k, other in enumerate(self.rods) if other is rod)
        j_tow = min(i, it)  # the edge between node and toward
        t = self._tangents[r][j_tow]
        d = self._directors[r][j_tow]
        c = len(self._clamp_frames)
        self._clamp_frames.append((t.copy(), d.copy()))
        frame = -1 - c
        self._pairs.pop(("node", node), None)
        n_local = len(rod.nodes)
        GJ, EI1, EI2 = rod.GJ, rod.EI1, rod.EI2
        for j, side in ((i - 1, "before"), (i, "after")):
            if not 0 <= j < n_local - 1:
                continue
            tj, dj, lj = self._frame(rod, j)
            half = 0.5 * lj
            ks = (EI1[j] / half, EI2[j] / half, GJ[j] / half)
            if side == "before":
                nat = _natural(_frame_pair(tj, dj, t, d))
                pair = (int(rod.edges[j]), 1.0, frame, 1.0, *ks, *nat)
            else:
                nat = _natural(_frame_pair(t, d, tj, dj))
                pair = (frame, 1.0, int(rod.edges[j]), 1.0, *ks, *nat)
            self._pairs[("clamp", node, side)] = pair
        self._clamped.add(node)
        self.fix(node, "xyz")
        self._cache = None

    def joint(self, node_a, node_b):
        """Rigid joint between two rods meeting at the coincident nodes ``node_a`` and
        ``node_b``: the nodes share their position, and an edge of each rod at the joint is
        coupled by bending about both axes and twisting (the pair a kink inside one rod would
        have, with the stress-free angle between them as natural curvature and twist), so
        orientations are carried through the joint.

        The coupled edges are node_a's rod's edge *into* node_a and node_b's rod's edge *out
        of* node_b (a rod's only edge where the node is its end). Where both nodes are
        interior the coupling therefore sits on one side of the joint; a structure that must
        stay mirror-symmetric joins in both orders, ``joint(a, b)`` and ``joint(b, a)`` (as
        `units.frame3d.Mesh3D.bond` does). Rods running side by side from a common end node
        (a fold of the two coupled edges) are coupled frame to frame."""
        a = self.check_node(node_a, "node_a")
        b = self.check_node(node_b, "node_b")
        if a == b:
            raise ValueError(f"cannot joint node {a} to itself")
        rod_a, ia = self._rod_of(a)
        rod_b, ib = self._rod_of(b)
        xa, xb = self._node_position(a), self._node_position(b)
        gap = float(np.linalg.norm(xa - xb))
        if gap > 1e-9 * self._size():
            raise ValueError(f"joint needs coincident nodes; nodes {a} and {b} are "
                             f"{gap:.3g} m apart")
        # edge of rod a pointing into the joint, edge of rod b pointing out of it
        ja, sa = (ia - 1, 1.0) if ia > 0 else (0, -1.0)
        jb, sb = (ib, 1.0) if ib < len(rod_b.nodes) - 1 else (ib - 1, -1.0)
        ta = sa * self._frame(rod_a, ja)[0]
        tb = sb * self._frame(rod_b, jb)[0]
        if ta @ tb < -0.9:
            # a fold of more than ~150 degrees (two rods that both start, or both end, at
            # the joint and run side by side), where the kink's curvature measure is
            # singular: couple b's edge reversed instead, i.e. the frames themselves, whose
            # relative rotation is then small (the pair measures the rotation between two
            # frames; reversing an edge turns its frame 180 degrees about the face normal)
            sb = -sb
        self._merges.append((a, b))
        self._pairs[("joint", a, b, len(self._pairs))] = self._make_pair(rod_a, ja, sa, rod_b, jb, sb)
        self._cache = None

    def tie(self, node_a, node_b, method="exact"):
        """Bond two nodes: equal displacements (orientations stay independent; see `joint`)."""
        super().tie(node_a, node_b, method)

    def _tie_other(self, a, b, method, stiffness):
        raise ValueError(f"tie method must be 'exact' for 3-D rods; got {method!r}")

    # ------------------------------------------------------------------ problem interface
    def initial_state(self) -> np.ndarray:
        """The stress-free state q0 (3 n_nodes + n_edges,): positions (m), zero twists."""
        return np.concatenate([self.reference_positions.reshape(-1), np.zeros(self.n_edges)])

    def twist_of(self, q) -> np.ndarray:
        """(n_edges,) twist angles (rad) held in the state ``q`` (a view)."""
        return np.asarray(q)[3 * self.n_nodes:]

    def state_fields(self, q) -> dict:
        """{"twist": (n_edges,) rad}: recorded on a path besides positions."""
        return {"twist": self.twist_of(q)}

    def _max_bending_stiffness(self) -> float:
        """EI1_max (N m^2): bending through the thickness, the easy way."""
        return max(float(np.max(r.EI1)) for r in self.rods)

    def _edge_areas(self, k) -> np.ndarray:
        """(n_edges,) section area w t of each edge of rod ``k``, m^2."""
        return self.rods[k].width * self.rods[k].thickness

    def _complete_state(self, q, path, index):
        """The twists of a path row (recorded in the canonical convention)."""
        q[3 * self.n_nodes:] = np.asarray(path.fields["twist"][index], dtype=float)

    def model(self):
        """The model arrays of `solver.assembly3d` (cached until the structure changes)."""
        if self._cache is None:
            if not self.rods:
                raise ValueError("the structure has no rods")
            n_edges = self.n_edges
            t, d = self.reference_frames()
            edge_nodes = np.concatenate(self._edge_nodes, axis=0)
            n_clamps = len(self._clamp_frames)
            if n_clamps:
                t = np.concatenate([t, [f[0] for f in self._clamp_frames]])
                d = np.concatenate([d, [f[1] for f in self._clamp_frames]])
                edge_nodes = np.concatenate([edge_nodes, -np.ones((n_clamps, 2), np.int64)])
            stretch = np.concatenate(
                [np.stack([r.EA, L], axis=1) for r, L in zip(self.rods, self._lengths)])
            pairs = list(self._pairs.values())

            def frame_index(f):
                return f if f >= 0 else n_edges + (-1 - f)

            pe = np.array([[frame_index(p[0]), frame_index(p[2])] for p in pairs],
                          dtype=np.int64).reshape(-1, 2)
            ps = np.array([[p[1], p[3]] for p in pairs], dtype=float).reshape(-1, 2)
            pp = np.array([p[4:10] for p in pairs], dtype=float).reshape(-1, 6)
            self._cache = {
                "n_nodes": self.n_nodes,
                "edge_nodes": np.ascontiguousarray(edge_nodes, dtype=np.int64),
                "src_t": np.ascontiguousarray(t),
                "src_d": np.ascontiguousarray(d),
                "stretch_params": np.ascontiguousarray(stretch),
                "pair_edges": np.ascontiguousarray(pe),
                "pair_signs": np.ascontiguousarray(ps),
                "pair_params": np.ascontiguousarray(pp),
            }
        return self._cache

    def reduced_system(self, extra_fixed=None, normalized=False,
                       dead_loads=True) -> RodSystem3D:
        """A fresh system (reference frames at the stress-free state) with the DOFs ordered
        by reverse Cuthill–McKee over node groups and edge twists, so that positions and
        twists interleave along each rod, started where the envelope the factorisation
        works on is smallest (`solver.ordering`).

        ``extra_fixed``: iterable of (node, component 0..2) held in addition to supports.
        ``normalized``: 3-D rods have no per-unit-modulus elements: the system is in
        physical units whatever it says (``force_unit`` 1). ``dead_loads``: assemble the
        structure's dead loads at full value (docs/loads.md)."""
        model = self.model()
        n, ne = self.n_nodes, self.n_edges
        rep, fixed = self._held(extra_fixed)
        uniq, group = np.unique(rep, return_inverse=True)
        n_groups = len(uniq) + ne  # node groups, then one group per edge twist
        group_of_full = np.concatenate([np.repeat(group, 3), len(uniq) + np.arange(ne)])
        dof_map0 = np.arange(3 * n + ne)
        sf, _, pf, _ = element_dofs3d(n, model["edge_nodes"], ne, model["pair_edges"], dof_map0)
        key = "group_order"
        order = model.get(key)
        if order is None:  # the graph changes only with the structure (the cache's lifetime)
            rows, cols = [], []
            for full in (sf, pf):
                if full.shape[0] == 0:
                    continue
                g = np.where(full >= 0, group_of_full[np.maximum(full, 0)], -1)
                for i in range(g.shape[1]):
                    for j in range(g.shape[1]):
                        if i != j:
                            ok = (g[:, i] >= 0) & (g[:, j] >= 0)
                            rows.append(g[ok, i])
                            cols.append(g[ok, j])
            r = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
            c = np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64)
            graph = scipy.sparse.csr_matrix((np.ones(len(r)), (r, c)),
                                            shape=(n_groups, n_groups))
            sizes = np.concatenate([np.full(len(uniq), 3), np.ones(ne)]).astype(np.int64)
            order = model[key] = envelope_order(graph, sizes)

        free_full = np.concatenate([~fixed.reshape(-1), np.ones(ne, dtype=bool)])
        # full DOFs of each group, in component order (-1: none); merged nodes share the
        # representative's DOFs
        members = -np.ones((n_groups, 3), dtype=np.int64)
        members[: len(uniq)] = 3 * uniq[:, None] + np.arange(3)
        members[len(uniq):, 0] = 3 * n + np.arange(ne)
        seq = members[order].reshape(-1)
        seq = seq[seq >= 0]
        seq = seq[free_full[seq]]
        dof_map = -np.ones(3 * n + ne, dtype=np.int64)
        k = len(seq)
        dof_map[seq] = np.arange(k)
        # merged nodes take their representative's reduced DOFs
        node_map = dof_map[: 3 * n].reshape(-1, 3)
        node_map[:] = node_map[rep]
        if k == 0:
            raise ValueError("every degree of freedom is fixed: nothing to solve")
        bw = bandwidth(*(np.where(full >= 0, dof_map[np.maximum(full, 0)], -1)
                         for full in (sf, pf)))
        twist_length = np.concatenate(
            [np.maximum(r.width, r.thickness) for r in self.rods])
        return RodSystem3D(model, dof_map, k, bw, twist_length=twist_length,
                           loads=self._system_loads() if dead_loads else None)

    # ------------------------------------------------------------------ energy access
    def state(self, positions=None, twist=None) -> np.ndarray:
        """A full state vector from positions (n_nodes, 3) m and twists (n_edges,) rad
        (defaults: the stress-free values)."""
        q = self.initial_state()
        if positions is not None:
            pos = _finite_array(positions, "positions", "m")
            if pos.shape != (self.n_nodes, 3):
                raise ValueError(f"positions must have shape ({self.n_nodes}, 3) (m); got "
                                 f"{pos.shape}")
            q[: 3 * self.n_nodes] = pos.reshape(-1)
        if twist is not None:
            tw = _finite_array(twist, "twist", "rad")
            if tw.shape != (self.n_edges,):
                raise ValueError(f"twist must have shape ({self.n_edges},) (rad); got {tw.shape}")
            q[3 * self.n_nodes:] = tw
        return q

    def unconstrained_system(self) -> RodSystem3D:
        """A system with every DOF free and in natural order (for energy checks)."""
        model = self.model()
        n_full = 3 * self.n_nodes + self.n_edges
        return RodSystem3D(model, np.arange(n_full), n_full, n_full - 1,
                           loads=self._system_loads())

    def energy(self, q=None) -> float:
        """Total potential energy (J) of the full state ``q`` (default: stress free): the
        elastic energy, plus the dead loads' potential -sum f (x - X) when there are any."""
        sysm = self.unconstrained_system()
        return float(sysm.evaluate(self.initial_state() if q is None else np.asarray(q, float)))

    # ------------------------------------------------------------------ experiments
    def push(self, node, direction=(0.0, 0.0, -1.0), distance=None, method="mgdc", **options):
        """Push ``node`` along ``direction`` (x, y, z) until its displacement reaches
        ``distance`` (m), with the planar solver's path followers (`Structure.push`).

        Returns a `solver.path.Path`: displacement (K,), force (K,), positions
        (K, n_nodes, 3), twist (K, n_edges), status, stability counts, critical points.
        Dead loads act at full value from the start, and ``start=`` pushes from a given
        equilibrium, as for `Structure.push`."""
        return self._push(node, direction, distance, method, options)

    def solve_equilibrium(self, positions=None, node=None, direction=(0.0, 0.0, -1.0),
                          force=0.0, **options):
        """Newton from ``positions`` ((n_nodes, 3) m or a full state; default stress free) to
        the equilibrium under ``force`` (N) on ``node`` along ``direction`` (no load when
        ``node`` is None), with the planar solver's `solver.equilibrium.equilibrium`.
        Returns (positions (n_nodes, 3), info dict with the full "state")."""
        return self._solve_equilibrium(positions, node, direction, force, options)

    def relax(self, q=None, moments=(), ramp=1, tol=1e-8, max_iter=100):
        """Minimise the energy from the state ``q`` (default: stress free) with the solver's
        energy descent (`solver.descent.descend`, the Levenberg–Marquardt rule: banded Newton
        on K + mu I, mu raised until it is positive definite and the step, at most a tenth
        of the structure's size, lowers the energy), optionally under dead couples
        ``moments`` = [(node_a, node_b, M (N m), axis (3,))], each on the edge from node_a to
        node_b, which must turn in the plane normal to the axis. ``ramp``: the couples and
        the natural curvatures and twists are raised to their values in this many equal
        stages (a homotopy through equilibria). The reference frames are carried along after
        every step. Converged when the residual is below ``tol`` x the force scale or the
        last full Newton step below 1e-11 x the size. Returns (q, info dict); RuntimeError
        when a stage does not converge in ``max_iter`` steps."""
        q = self.initial_state() if q is None else self.state(self.positions_of(q),
                                                              self.twist_of(q))
        if isinstance(ramp, (bool, np.bool_)) or not isinstance(ramp, (int, np.integer)) \
                or ramp < 1:
            raise ValueError(f"ramp must be an integer >= 1; got {ramp!r}")
        sysm = self.reduced_system()
        length, fscale = self.scales()
        natural = np.array(sysm.pair_params[:, 3:6], copy=True)
        sysm.pair_params = np.array(sysm.pair_params, copy=True)
        loads = []
        for a, b, M, axis in moments:
            a = self.check_node(a, "moment node_a")
            b = self.check_node(b, "moment node_b")
            ax = _finite_array(axis, "moment axis", "a direction")
            if ax.shape != (3,) or not np.linalg.norm(ax) > 0:
                raise ValueError(f"moment axis must be a non-zero 3-vector; got {axis!r}")
            M = float(_finite_array(M, "moment M", "N m"))
            loads.append((a, b, M, ax / np.linalg.norm(ax)))
        total_it = 0
        loaded = _Couples(sysm, loads)
        for stage in range(1, ramp + 1):
            loaded.fraction = f = stage / ramp
            sysm.pair_params[:, 3:6] = f * natural
            try:
                total_it += descend(loaded, q, tol * fscale, 1e-11 * length, max_iter,
                                    max_move=0.1 * length, carry_frames=True)
            except ConvergenceError as exc:
                if "energy decrease" in str(exc):
                    raise RuntimeError("relax: no energy decrease along the gradient") from exc
                raise RuntimeError(f"relax did not converge in {max_iter} iterations at stage "
                                   f"{stage} of {ramp}") from exc
        E = loaded.evaluate(q)
        return q, {"iterations": total_it, "energy": E,
                   "residual": float(np.max(np.abs(sysm.grad[: sysm.n])))}


class _Couples:
    """A `RodSystem3D` with dead couples on edges (`Structure3D.relax`): ``loads`` =
    [(node_a, node_b, M (N m), unit axis)], applied at ``fraction`` of their moments; every
    other member is the system's own."""

    def __init__(self, system, loads):
        self.system = system
        self.loads = loads
        self.fraction = 1.0

    def __getattr__(self, name):
        return getattr(self.system, name)

    def evaluate(self, q):
        """Energy (J) with the couples' potential; leaves the load-including gradient in
        the system's ``grad`` and K in its ``band``."""
        sysm = self.system
        E = sysm.evaluate(q)
        X = np.asarray(q)[: 3 * sysm.n_nodes].reshape(-1, 3)
        for a, b, M, ax in self.loads:
            ge = np.empty(3)
            he = np.empty((3, 3))
            E += tip_moment_terms(X[b] - X[a], self.fraction * M, ax, ge, he)
            dofs = [(-1.0, r) for r in sysm.dof_map[3 * a: 3 * a + 3]]
            dofs += [(1.0, r) for r in sysm.dof_map[3 * b: 3 * b + 3]]
            for i, (s_i, r_i) in enumerate(dofs):
                if r_i < 0:
                    continue
                sysm.grad[r_i] += s_i * ge[i % 3]
                for j, (s_j, r_j) in enumerate(dofs):
                    if 0 <= r_j <= r_i:
                        sysm.band[r_i - r_j, r_j] += s_i * s_j * he[i % 3, j % 3]
        return E
