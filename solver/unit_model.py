"""The bistable arch-on-base unit as a DER structure (`../shared/unit-model.md`).

`UnitGeometry` is the validated geometry record; `build_unit` meshes it and returns the
`Structure` with its named nodes. Simulation and metrics live in `solver.unit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.structure import Structure

PETG_E = 2.2e9  # Pa
SUPPORT_OFFSET = 0.03  # rollers at 0.03 L from each end
DEFAULT_NODES = 101  # base nodes at the default resolution (see the convergence study)
# The actuator (a T-rod of 1/8 in acrylic, paper Fig. 3) is glued over a finite length of the
# arch around the apex. The paper makes the apex node and its two neighbours rigid, which ties
# the joint's length to the mesh, so that every metric converges only as O(1/N). Here the
# joint has a physical arc length, JOINT_LENGTH * L (3.175 mm at L = 100 mm). In DER the angle
# of a rigid edge stands for the tangent at the edge's midpoint (as for a clamp), so the arch
# is meshed with one edge straddling each end of the joint, centred on it, and the nodes of
# that edge and every node inside move with the apex.
JOINT_LENGTH = 0.03175


@dataclass(frozen=True)
class UnitGeometry:
    """Geometry of one unit, SI units (m, Pa).

    L: base length; h: arch apex height above the base centreline (0 = arch-less unit);
    t: sheet thickness; w: strip width; b: extra flat length of the arch ends (b = w for
    the paper's specimens, 0 in its parametric study); E: Young's modulus (PETG default).
    """

    L: float
    h: float
    t: float
    w: float
    b: float = 0.0
    E: float = PETG_E

    def __post_init__(self):
        for name in ("L", "h", "t", "w", "b", "E"):
            value = getattr(self, name)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{name} must be a number; got {value!r}") from None
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite; got {value!r}")
            object.__setattr__(self, name, value)
        for name in ("L", "t", "w", "E"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be > 0; got {getattr(self, name)!r}")
        for name in ("h", "b"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0; got {getattr(self, name)!r}")
        if self.b + self.w >= 0.5 * self.L:
            raise ValueError(
                f"b + w must be < L/2 (the sinusoid needs a span); got b + w = "
                f"{self.b + self.w:.6g} m with L/2 = {0.5 * self.L:.6g} m"
            )
        if self.h > self.arch_span:
            raise ValueError(
                f"h must be <= the sinusoid's span L - 2(b + w) = {self.arch_span:.6g} m "
                f"(a steeper sinusoid folds over itself in the model); got h = {self.h:.6g} m"
            )
        if self.t > 0.05 * self.L:
            raise ValueError(
                f"t must be <= 0.05 L = {0.05 * self.L:.6g} m for a rod model; got {self.t:.6g} m"
            )

    @property
    def flat_length(self) -> float:
        """Length of each flat (solid) end region, b + w (m)."""
        return self.b + self.w

    @property
    def arch_span(self) -> float:
        """Horizontal span of the sinusoid, L - 2(b + w) (m)."""
        return self.L - 2.0 * self.flat_length

    @property
    def I_arch(self) -> float:
        """Second moment of area of the arch strip, w t^3 / 12 (m^4)."""
        return self.w * self.t**3 / 12.0

    def arch_z(self, x):
        """Arch centreline height z(x) (m): flat ends, sinusoid in between."""
        x = np.asarray(x, dtype=float)
        x0, la = self.flat_length, self.arch_span
        inside = (x > x0) & (x < self.L - x0)
        return np.where(inside, 0.5 * self.h * (1.0 - np.cos(2 * np.pi * (x - x0) / la)), 0.0)

    def scaled(self, factor: float) -> "UnitGeometry":
        """The same unit with every length multiplied by ``factor``."""
        return UnitGeometry(
            self.L * factor, self.h * factor, self.t * factor, self.w * factor, self.b * factor, self.E
        )


@dataclass
class UnitModel:
    """A meshed unit: the structure and the nodes the experiment needs."""

    structure: Structure
    arch_nodes: np.ndarray
    base_nodes: np.ndarray
    apex: int
    supports: tuple[int, int]
    base_mid: int


def _segment_points(breaks, spacing):
    """Points along sorted ``breaks`` with every interval split into equal parts no longer
    than ``spacing`` (keeps every break point exactly)."""
    pts = [breaks[0]]
    for a, b in zip(breaks[:-1], breaks[1:]):
        n = max(1, int(math.ceil((b - a) / spacing - 1e-9)))
        pts.extend(a + (b - a) * np.arange(1, n + 1) / n)
    return np.array(pts)


def _half_sinusoid_x(g: UnitGeometry, spacing, start_x, joint_half):
    """x of the arch nodes from ``start_x`` (just past the flat region) to the apex at L/2,
    near-uniform in arc length, with one edge centred on the end of the joint (arc length
    ``joint_half`` before the apex).

    Returns (x, s_rigid): node abscissae, and the arc length from the apex within which
    nodes belong to the rigid joint."""
    x0, xm = g.flat_length, 0.5 * g.L
    xs = np.linspace(x0, xm, 4001)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(xs), np.diff(g.arch_z(xs))))])
    total = s[-1]
    s_start = float(np.interp(start_x, xs, s))
    straddle = min(spacing, joint_half, 0.5 * (total - joint_half - s_start))
    outer = total - joint_half - 0.5 * straddle  # free side of the straddling edge
    inner = total - joint_half + 0.5 * straddle
    targets = _segment_points(np.array([s_start, outer, inner, total]), spacing)
    return np.interp(targets, s, xs), joint_half + 0.5 * straddle


def build_unit(
    g: UnitGeometry,
    nodes: int = DEFAULT_NODES,
    tie: str = "exact",
    tie_stiffness: float | None = None,
    actuator: bool = True,
    supports: bool = True,
) -> UnitModel:
    """Mesh the unit: base rod, arch rod, bonds, supports and the actuator joint.

    ``nodes``: resolution, about the number of base nodes (edge length about L / nodes);
    ``tie``: "exact" (shared displacements) or "spring" (stiff springs, as the paper).
    ``actuator``/``supports`` off give the free unit used for the self-standing check.
    """
    if not isinstance(nodes, (int, np.integer)) or nodes < 11:
        raise ValueError(f"nodes (resolution) must be an integer >= 11; got {nodes!r}")
    if g.h <= 0:
        raise ValueError("an arch-less unit (h = 0) has no arch to mesh")
    L, x0 = g.L, g.flat_length
    spacing = L / (nodes - 1)
    sup = SUPPORT_OFFSET * L
    # The arch leaves the base at x0 = b + w, where the base also changes from solid (4w) to
    # hollow (2w); the arch's end moment enters the base there, so the curvature of both rods
    # jumps at x0. In DER a curvature jump inside a node's Voronoi region costs O(h) in the
    # energy and every metric then converges only as O(1/N); on the boundary between two
    # regions it costs nothing. DER also reads a constrained edge's angle as the tangent at
    # its midpoint (as at a clamp). So x0 is the midpoint of one edge of each rod, and that
    # edge is bonded at both ends: the bonded (composite) part ends, in the DER sense, exactly
    # at x0, and the base edge across x0 is solid over its first half, hollow over its second.
    half_edge = 0.5 * min(spacing, 0.5 * x0, 0.25 * g.arch_span)
    if abs(sup - x0) < half_edge * (1 + 1e-9):
        # The roller would sit inside the edge that straddles x0: shorten that edge so that
        # the roller stays at 0.03 L, down to a tenth of the spacing; closer than that the
        # roller moves to the bonded node (a shift below spacing / 20).
        half_edge = max(0.5 * abs(sup - x0), 0.05 * spacing)
        if abs(sup - x0) < half_edge * (1 + 1e-9):
            sup = x0 - half_edge
    bond_end = x0 - half_edge
    breaks = np.array([0.0, sup, bond_end, x0 + half_edge, 0.5 * L, L - x0 - half_edge,
                       L - bond_end, L - sup, L])
    breaks = np.unique(np.round(breaks / L, 14)) * L
    base_x = _segment_points(breaks, spacing)

    flat_left = base_x[base_x <= bond_end + 1e-12 * L]
    half, s_rigid = _half_sinusoid_x(g, spacing, x0 + half_edge, 0.5 * JOINT_LENGTH * L)
    arch_x = np.concatenate([flat_left, half, (L - half[::-1])[1:], (L - flat_left[::-1])])
    arch_xz = np.stack([arch_x, g.arch_z(arch_x)], axis=1)
    # The bonded arch node half an edge past x0 sits on the base, not on the sinusoid (which
    # is O(h^3) above it): exact ties share displacements, so a non-zero offset between tied
    # nodes would resist rigid rotation of the unit (it stressed neighbouring units in arrays
    # and made the snapped angle jump with the mesh). The bonded edge is then flat, as is
    # the sinusoid's tangent at x0.
    n_bond = len(flat_left) + 1
    arch_xz[:n_bond, 1] = 0.0
    arch_xz[-n_bond:, 1] = 0.0

    # per half edge: solid (4w) within the end regions, hollow (2w) between them
    halves = np.stack([0.75 * base_x[:-1] + 0.25 * base_x[1:],
                       0.25 * base_x[:-1] + 0.75 * base_x[1:]], axis=1)
    base_width = np.where((halves < x0) | (halves > L - x0), 4.0 * g.w, 2.0 * g.w)

    st = Structure()
    base = st.add_rod(np.stack([base_x, np.zeros_like(base_x)], 1), base_width, g.t, g.E)
    arch = st.add_rod(arch_xz, g.w, g.t, g.E)

    # bond every arch node of a flat end region to the coincident base node, and the nodes
    # half an edge past x0 that close the bonded edge across x0
    n_flat = len(flat_left) + 1  # base and arch share these abscissae
    for k in range(n_flat):
        pairs = ((arch.nodes[k], base.nodes[k]), (arch.nodes[-1 - k], base.nodes[-1 - k]))
        for a, b in pairs:
            st.tie(a, b, method=tie, stiffness=tie_stiffness)

    apex_local = len(arch_x) // 2
    apex = int(arch.nodes[apex_local])
    # the joint: arch nodes up to the far end of the edges straddling its ends (and at
    # least the apex's two neighbours)
    xs = np.linspace(g.flat_length, 0.5 * L, 4001)
    s_half = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(xs), np.diff(g.arch_z(xs))))])
    arc_from_apex = s_half[-1] - np.interp(np.minimum(arch_x, L - arch_x), xs, s_half)
    in_joint = (arch_x > g.flat_length) & (arc_from_apex <= s_rigid * (1 + 1e-9) + 1e-15)
    in_joint[apex_local - 1: apex_local + 2] = True
    joint = [int(n) for n in arch.nodes[in_joint]]
    s0 = int(base.nodes[int(np.argmin(np.abs(base_x - sup)))])
    s1 = int(base.nodes[int(np.argmin(np.abs(base_x - (L - sup))))])
    base_mid = int(base.nodes[int(np.argmin(np.abs(base_x - 0.5 * L)))])
    if supports:
        st.fix(s0, "z")
        st.fix(s1, "z")
    if actuator:
        st.rigid(joint)
        st.fix(apex, "x")
    return UnitModel(st, arch.nodes.copy(), base.nodes.copy(), apex, (s0, s1), base_mid)
