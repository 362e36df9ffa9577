"""Meshes of rod assemblies in 3-D, independent of the solver: what `Structure3D` is given.

A `Mesh3D` records rods (points, widths, thickness, face normal), rigid joints, ties, supports
and rigid groups with global node indices, numbered as `solver.Structure3D` numbers them
(rod after rod, in the order added). Meshes can be checked (topology, widths, bonds,
supports) without solving; `Mesh3D.to_structure()` builds the `Structure3D`. SI units.

Also the arc-length mesh of an arch with a rigid actuator joint that the 3-D unit uses (the
shared geometry helpers, sinusoid, arc length and end angles, are `units.shapes`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snapmorph.units.geometry import UnitGeometry  # noqa: F401 - re-exported
from snapmorph.units.shapes import arch_height, cumulative_length, segment_points

PETG_NU = 0.38  # Poisson's ratio of PETG (unit-model.md)
JOINT_LENGTH_DEFAULT = 0.003175  # m, 1/8 in acrylic stem (unit-model.md)
SUPPORT_OFFSET = 0.03  # rollers at 0.03 L from each end


@dataclass
class RodSpec:
    """One rod: points (N, 3) m, width per edge (N-1,) m, thickness m, face normal at the
    first edge (the thickness direction, carried along the rod by the solver)."""

    name: str
    xyz: np.ndarray
    width: np.ndarray
    thickness: float
    normal: tuple
    nodes: np.ndarray  # global node indices
    E_factor: float = 1.0  # Young's modulus of this rod / the mesh's E
    plate: bool = False  # part of a continuous plate: torsion constant w t^3 / 3 per edge


@dataclass
class Mesh3D:
    """Rods and their connections, with global node indices (rod after rod)."""

    E: float
    nu: float
    rods: list = field(default_factory=list)
    joints: list = field(default_factory=list)  # (a, b): rigid joints (position + orientation)
    ties: list = field(default_factory=list)  # (a, b): equal positions
    fixes: list = field(default_factory=list)  # (node, "xyz" subset)
    rigid: list = field(default_factory=list)  # lists of nodes translating together
    named: dict = field(default_factory=dict)  # name -> int node
    groups: dict = field(default_factory=dict)  # name -> node index array

    @property
    def n_nodes(self) -> int:
        return int(sum(len(r.xyz) for r in self.rods))

    @property
    def positions(self) -> np.ndarray:
        """(n_nodes, 3) stress-free positions, m."""
        return np.concatenate([r.xyz for r in self.rods], axis=0)

    def add_rod(self, name, xyz, width, thickness, normal=(0.0, 0.0, 1.0), *,
                E_factor=1.0, plate=False) -> np.ndarray:
        """Add a rod; ``E_factor`` multiplies the mesh's Young's modulus for it (a stiffened
        part), ``plate``: the strip is cut out of a continuous plate (its torsion constant is
        the plate's w t^3 / 3: its edges are not free, whatever its width). Returns its
        global node indices."""
        xyz = np.ascontiguousarray(xyz, dtype=float)
        width = np.broadcast_to(np.asarray(width, dtype=float), (len(xyz) - 1,)).copy()
        start = self.n_nodes
        nodes = np.arange(start, start + len(xyz), dtype=np.int64)
        self.rods.append(RodSpec(name, xyz, width, float(thickness), tuple(normal), nodes,
                                 float(E_factor), bool(plate)))
        return nodes

    def _rod_index(self, node):
        for r in self.rods:
            if r.nodes[0] <= node <= r.nodes[-1]:
                return r, int(node - r.nodes[0])
        raise IndexError(node)

    def _edge_dir(self, node, into):
        """Direction of the edge `Structure3D.joint` couples at ``node``: the edge pointing
        into the node (``into``) or out of it, reversed at a rod's end."""
        r, i = self._rod_index(node)
        e = np.diff(r.xyz, axis=0)
        e = e / np.linalg.norm(e, axis=1)[:, None]
        if into:
            return e[i - 1] if i > 0 else -e[0]
        return e[i] if i < len(e) else -e[i - 1]

    def bond(self, node_a, node_b):
        """Rigidly join two coincident nodes with `Structure3D.joint` in both orders that are
        valid, so that the coupling is the same seen from either side.

        A joint couples the edge of its first rod *into* the node with the edge of its second
        rod *out of* it (reversed at a rod's end): one order alone ties a rod to the edges on
        one side of the node only, and a structure that is mirror symmetric would respond
        asymmetrically. An order whose two edges are antiparallel (two parallel rods that
        both start, or both end, at the node) cannot be a joint; with no valid order the
        nodes are tied (positions shared) and their orientations are carried by neighbouring
        joints. Returns the number of joints added (0: tied)."""
        added = 0
        for a, b in ((node_a, node_b), (node_b, node_a)):
            if self._edge_dir(a, True) @ self._edge_dir(b, False) > -0.9:
                self.joints.append((int(a), int(b)))
                added += 1
        if not added:
            self.ties.append((int(node_a), int(node_b)))
        return added

    def rod(self, name) -> RodSpec:
        for r in self.rods:
            if r.name == name:
                return r
        raise KeyError(name)

    def to_structure(self):
        """The `solver.Structure3D` of this mesh (rods, joints, ties, supports, rigid groups)."""
        from snapmorph.solver import Structure3D  # the 3-D solver (issue 13)

        st = Structure3D()
        for r in self.rods:
            J = r.width * r.thickness**3 / 3.0 if r.plate else None
            rod = st.add_rod(r.xyz, width=r.width, thickness=r.thickness,
                             E=self.E * r.E_factor, nu=self.nu, normal=r.normal,
                             torsion_constant=J)
            if not np.array_equal(np.asarray(rod.nodes), r.nodes):
                raise RuntimeError("Structure3D numbered the nodes differently from the mesh")
        for a, b in self.joints:
            st.joint(int(a), int(b))
        for a, b in self.ties:
            st.tie(int(a), int(b))
        for group in self.rigid:
            st.rigid([int(n) for n in group])
        for node, comps in self.fixes:
            st.fix(int(node), comps)
        return st


def arch_nodes_x(x_start, x_end, x0, span, h, spacing, x_act, joint_length):
    """Abscissae of the arch nodes on its raised part, from ``x_start`` to ``x_end`` (both
    kept), near-uniform in arc length, with the actuator joint centred on ``x_act``.

    As in the planar unit (docs/model-notes.md, note 2), the rigid joint covers an arc length
    ``joint_length`` centred on the actuator point and one edge straddles each end of it
    (DER reads a rigid edge's direction as the tangent at its midpoint). ``joint_length`` = 0
    is a point clamp: one rigid edge centred on the actuator point.

    Returns (x, node index of the actuator point or of the clamped edge's first node, the
    (start, stop) slice of the nodes that move rigidly with it)."""
    xs = np.linspace(x_start, x_end, 8001)
    s = cumulative_length(xs, arch_height(xs, x0, span, h))
    total = s[-1]
    s_act = float(np.interp(x_act, xs, s))
    half = 0.5 * joint_length
    if half > 0:
        room = min(s_act - half, total - s_act - half)
        if room <= 0:
            raise ValueError(
                f"the actuator joint (length {joint_length:.6g} m) does not fit on the arch "
                f"around x = {x_act:.6g} m")
        straddle = min(spacing, half, room)
        breaks = [0.0, s_act - half - 0.5 * straddle, s_act - half + 0.5 * straddle, s_act,
                  s_act + half - 0.5 * straddle, s_act + half + 0.5 * straddle, total]
    else:
        straddle = min(spacing, 0.5 * s_act, 0.5 * (total - s_act))
        breaks = [0.0, s_act - 0.5 * straddle, s_act + 0.5 * straddle, total]
    breaks = np.unique(np.array(breaks))
    targets = segment_points(breaks, spacing)
    x = np.interp(targets, s, xs)
    x[0], x[-1] = x_start, x_end
    if half > 0:
        lo = int(np.argmin(np.abs(targets - (s_act - half - 0.5 * straddle))))
        hi = int(np.argmin(np.abs(targets - (s_act + half + 0.5 * straddle))))
        act = int(np.argmin(np.abs(targets - s_act)))
    else:
        lo = int(np.argmin(np.abs(targets - (s_act - 0.5 * straddle))))
        hi = lo + 1
        act = lo
    return x, act, (lo, hi + 1)


def __getattr__(name):
    if name == "end_tangent_angle":  # moved to units.shapes (0.2); the old name warns
        import warnings

        from snapmorph.units import shapes

        warnings.warn("snapmorph.units.frame3d.end_tangent_angle is deprecated: use "
                      "snapmorph.units.shapes.end_tangent_angle", DeprecationWarning, stacklevel=2)
        return shapes.end_tangent_angle
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
