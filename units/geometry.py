"""The bistable arch-on-base unit as a DER structure (`../shared/unit-model.md`).

`UnitGeometry` is the validated geometry record; `build_unit` meshes it and returns the
`Structure` with its named nodes. Simulation and metrics live in `units.planar` (re-exported
by `solver.unit`; this module by `solver.unit_model`).
"""

from __future__ import annotations

import functools

import math
from dataclasses import dataclass

import numpy as np

from snapmorph.solver.structure import Structure
from snapmorph.units.shapes import (arch_height, cumulative_length, polyline_length, segment_points,
                                    sinusoid)

PETG_E = 2.2e9  # Pa
SUPPORT_OFFSET = 0.03  # rollers at 0.03 L from each end
DEFAULT_NODES = 101  # base nodes at the default resolution (see the convergence study)
# The actuator (a T-rod of 1/8 in acrylic, paper Fig. 3) is glued over a finite length of the
# arch around the apex. The paper makes the apex node and its two neighbours rigid, which ties
# the joint's length to the mesh, so that every metric converges only as O(1/N). Here the
# joint has a physical arc length, `UnitGeometry.joint_length` (default 1/8 in). In DER the
# angle of a rigid edge stands for the tangent at the edge's midpoint (as for a clamp), so the
# arch is meshed with one edge straddling each end of the joint, centred on it, and the nodes
# of that edge and every node inside move with the apex. joint_length = 0 is a point clamp:
# one rigid edge centred on the apex, whose direction is the tangent at the apex.
JOINT_LENGTH_DEFAULT = 0.003175  # m, 1/8 in
#: the default joint as a fraction of the paper's L = 100 mm (what the design maps use)
JOINT_LENGTH = 0.03175
#: the valid domain's edges, as fractions of L (below them the mesh cannot resolve the unit)
MIN_SPAN_FRACTION = 0.02
MIN_SECTION_FRACTION = 1e-5  # t >= 1e-5 L (t = 1e-6 L does not converge)
try:  # rods longer than this many thicknesses are refused by the solver
    from snapmorph.solver.structure import MAX_SLENDERNESS
except ImportError:  # pragma: no cover - an older solver
    MAX_SLENDERNESS = 1e5
MIN_WIDTH_FRACTION = 1e-6  # w >= 1e-6 L
MIN_FLAT_FRACTION = 1e-4  # b + w >= 1e-4 L (the bonded flat part; 1e-5 L does not converge)
MAX_NODES = 20001

#: every UnitGeometry length: name -> what it is (for error messages)
_MEANING = {
    "L": "base length", "h": "arch apex height", "t": "sheet thickness", "w": "strip width",
    "b": "extra flat length of the arch ends", "E": "Young's modulus",
    "joint_length": "length of arch held by the actuator stem",
    "bond_length": "glued length at each end",
}


def check_real(name: str, value, unit: str = "m", meaning: str | None = None) -> float:
    """``value`` as a finite real float, or ValueError naming ``name``, its meaning and unit.

    Refuses strings, None, booleans, complex numbers, arrays with more than one value, NaN
    and infinities (numpy scalars and 0-d arrays are accepted)."""
    what = f"{name} ({meaning or _MEANING.get(name, name)}, {unit})"
    if isinstance(value, (bool, np.bool_)) or value is None or isinstance(value, (str, bytes)):
        raise ValueError(f"{what} must be a real number; got {value!r}")
    if isinstance(value, (complex, np.complexfloating)):
        raise ValueError(f"{what} must be a real number, not complex; got {value!r}")
    if isinstance(value, np.ndarray):
        if value.size != 1 or not np.issubdtype(value.dtype, np.number) or \
                np.iscomplexobj(value):
            raise ValueError(f"{what} must be one real number; got an array of shape "
                             f"{value.shape} and dtype {value.dtype}")
        value = value.reshape(-1)[0]
    try:
        out = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{what} must be a real number; got {value!r}") from None
    if not math.isfinite(out):
        raise ValueError(f"{what} must be finite; got {value!r}")
    return out


#: a unit is solved at the reference L = 0.1 m, E = 2.2 GPa and scaled back: its forces by
#: (E / 2.2 GPa)(L / 0.1 m)^2, energies by that x L / 0.1 m, stiffnesses by that / (L / 0.1 m);
#: each factor must lie within [1 / MAX_SCALE, MAX_SCALE] so that every result stays a normal
#: double (the metrics span ~1e-100 to 1e100 of the factor at the domain's other edges)
MAX_SCALE = 1e200


def _scale_problem(L, E, q) -> str:
    """Why L and E put the unit's results outside double precision, or "" (`MAX_SCALE`)."""
    lg = math.log10(L / 0.1)
    force = math.log10(E / PETG_E) + 2.0 * lg
    top = math.log10(MAX_SCALE)
    for what, x in (("forces (E L^2)", force), ("energies (E L^3)", force + lg),
                    ("stiffnesses (E L)", force - lg)):
        if abs(x) > top:
            return (f"L and E (base length and Young's modulus): the unit's {what} must stay "
                    f"within 1e{-top:.0f} to 1e{top:.0f} of those at L = 0.1 m, E = 2.2e9 Pa "
                    f"(valid domain: beyond it they overflow or underflow double precision); "
                    f"got 1e{x:.1f} with L = {q(L)}, E = {E:g} Pa")
    return ""


def geometry_problem(L, h, t, w, b, E, joint_length=JOINT_LENGTH_DEFAULT, bond_length=None,
                     unit: str = "m", scale: float = 1.0) -> str:
    """Why the (finite, real) dimensions cannot make a unit, or "" when they can.

    Lengths in m, E in Pa; messages quote lengths times ``scale`` in ``unit`` (the command
    line uses mm). This is the valid domain of the model (docs/unit-result.md)."""
    def q(x):
        return f"{x * scale:.6g} {unit}"

    for name, value in (("L", L), ("t", t), ("w", w)):
        if value <= 0:
            return f"{name} ({_MEANING[name]}, {unit}) must be > 0; got {q(value)}"
    if E <= 0:
        return f"E (Young's modulus, Pa) must be > 0; got {E!r}"
    overflow = _scale_problem(L, E, q)
    if overflow:
        return overflow
    for name, value in (("h", h), ("b", b), ("joint_length", joint_length)):
        if value < 0:
            return f"{name} ({_MEANING[name]}, {unit}) must be >= 0; got {q(value)}"
    if b + w >= 0.5 * L:
        return (f"b + w must be < L/2 (the sinusoid needs a span); got b + w = {q(b + w)} "
                f"with L/2 = {q(0.5 * L)}")
    span = L - 2.0 * (b + w)
    edge = 1.0 - 1e-12  # the edges themselves belong to the domain, whatever the rounding
    if span < MIN_SPAN_FRACTION * L * edge:
        return (f"b + w must be <= {0.5 * (1 - MIN_SPAN_FRACTION):g} L = "
                f"{q(0.5 * (1 - MIN_SPAN_FRACTION) * L)} (valid domain: the sinusoid's span "
                f"L - 2(b + w) >= {MIN_SPAN_FRACTION:g} L); got b + w = {q(b + w)}")
    if h > span:
        return (f"h must be <= the sinusoid's span L - 2(b + w) = {q(span)} (a steeper "
                f"sinusoid folds over itself in the model); got h = {q(h)}")
    if t > 0.05 * L:
        return f"t must be <= 0.05 L = {q(0.05 * L)} for a rod model; got {q(t)}"
    for name, value, low in (("t", t, MIN_SECTION_FRACTION), ("w", w, MIN_WIDTH_FRACTION)):
        if value < low * L * edge:
            return (f"{name} ({_MEANING[name]}, {unit}) must be >= {low:g} L = "
                    f"{q(low * L)} (valid domain of the model); got {q(value)}")
    if b + w < MIN_FLAT_FRACTION * L * edge:
        return (f"b + w (the flat, bonded end length) must be >= {MIN_FLAT_FRACTION:g} L = "
                f"{q(MIN_FLAT_FRACTION * L)} (valid domain of the model); got {q(b + w)}")
    if bond_length is not None and not (0.0 < bond_length <= b + w):
        return (f"bond_length ({_MEANING['bond_length']}, {unit}) must be > 0 and <= b + w = "
                f"{q(b + w)} (default: the whole flat part); got {q(bond_length)}")
    if h > 0:
        xs = np.linspace(b + w, L - b - w, 4001)
        arch = polyline_length(xs, sinusoid(xs, xs[0], span, h))
        rod = arch + 2.0 * (b + w)  # the arch rod, flat ends included
        if t < rod / MAX_SLENDERNESS * edge:
            return (f"t (sheet thickness, {unit}) must be >= the arch rod's length / "
                    f"{MAX_SLENDERNESS:.0e} = {q(rod / MAX_SLENDERNESS)} (valid domain: beyond "
                    f"that slenderness double precision no longer resolves bending); got {q(t)}")
        if joint_length > 0.5 * arch:
            hint = (" (the default 1/8 in is too long for this unit: give a shorter joint_length, "
                    "or 0 for a point clamp)" if joint_length == JOINT_LENGTH_DEFAULT else "")
            return (f"joint_length ({_MEANING['joint_length']}, {unit}) must be <= half the "
                    f"arch's arc length = {q(0.5 * arch)} (0 = a point clamp); got "
                    f"{q(joint_length)}{hint}")
    return ""


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
    joint_length: float = JOINT_LENGTH_DEFAULT
    bond_length: float | None = None

    def __post_init__(self):
        for name in ("L", "h", "t", "w", "b", "E", "joint_length"):
            unit = "Pa" if name == "E" else "m"
            object.__setattr__(self, name, check_real(name, getattr(self, name), unit))
        if self.bond_length is not None:
            object.__setattr__(self, "bond_length", check_real("bond_length", self.bond_length))
        problem = geometry_problem(self.L, self.h, self.t, self.w, self.b, self.E,
                                   self.joint_length, self.bond_length)
        if problem:
            raise ValueError(problem)

    @property
    def bond(self) -> float:
        """Glued length at each end (m): `bond_length`, or the whole flat part b + w."""
        return self.flat_length if self.bond_length is None else self.bond_length

    @property
    def arch_length(self) -> float:
        """Arc length of the sinusoidal part of the arch (m): twice the half arch's of the
        table the mesh is laid out on (`_arch_arc_table`, kept per geometry: no second
        integration)."""
        return 2.0 * float(_arch_arc_table(self)[1][-1])

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
        x0 = self.flat_length
        return arch_height(x, x0, self.arch_span, self.h, end=self.L - x0)

    def scaled(self, factor: float) -> "UnitGeometry":
        """The same unit with every length (joint and bond included) multiplied by ``factor``."""
        return UnitGeometry(
            self.L * factor, self.h * factor, self.t * factor, self.w * factor, self.b * factor,
            self.E, self.joint_length * factor,
            None if self.bond_length is None else self.bond_length * factor,
        )


def check_nodes(nodes) -> int:
    """The mesh resolution ``nodes`` as an int >= 11, or ValueError."""
    if isinstance(nodes, (bool, np.bool_)) or not isinstance(nodes, (int, np.integer)) \
            or nodes < 11 or nodes > MAX_NODES:
        raise ValueError(f"nodes (mesh resolution, about the number of base nodes) must be an "
                         f"integer in [11, {MAX_NODES}]; got {nodes!r}")
    return int(nodes)


@dataclass
class UnitModel:
    """A meshed unit: the structure and the nodes the experiment needs. ``joint``: the arch
    nodes the actuator holds rigid; ``bare``: the mesh with its bonds only (no rig, no
    actuator), which `variant` copies."""

    structure: Structure
    arch_nodes: np.ndarray
    base_nodes: np.ndarray
    apex: int
    supports: tuple[int, int]
    base_mid: int
    joint: tuple = ()
    bare: Structure | None = None

    def variant(self, actuator=True, supports=True) -> "UnitModel":
        """The same mesh with (or without) the actuator and the rig's rollers, as
        `build_unit` makes it: a copy of ``bare`` sharing its elements and DOF orderings
        (a unit's push, self-standing check and snap-back mesh it once)."""
        return _rigged(self.bare, self.arch_nodes, self.base_nodes, self.apex, self.supports,
                       self.base_mid, self.joint, actuator, supports)


@functools.lru_cache(maxsize=32)
def _arch_arc_table(g: UnitGeometry):
    """(x, s): 4001 abscissae from the arch's foot to the apex (m) and the arc length along
    the arch to each (m), read-only — kept per geometry: a unit is meshed three times (the
    push, the self-standing check, the snap-back) from the same table."""
    xs = np.linspace(g.flat_length, 0.5 * g.L, 4001)
    s = cumulative_length(xs, g.arch_z(xs))
    xs.setflags(write=False)
    s.setflags(write=False)
    return xs, s


def _half_sinusoid_x(g: UnitGeometry, spacing, start_x, joint_half):
    """x of the arch nodes from ``start_x`` (just past the flat region) towards the apex at
    L/2, near-uniform in arc length, with one edge centred on the end of the joint (arc length
    ``joint_half`` before the apex).

    ``joint_half`` = 0 (a point clamp): the nodes stop half an edge before the apex; mirrored,
    they give one edge centred on the apex, whose direction DER reads as the apex tangent.

    Returns (x, s_rigid): node abscissae, and the arc length from the apex within which
    nodes belong to the rigid joint."""
    xs, s = _arch_arc_table(g)
    total = s[-1]
    s_start = float(np.interp(start_x, xs, s))
    if joint_half <= 0.0:
        centre = min(spacing, 0.5 * (total - s_start))  # the clamped edge across the apex
        targets = segment_points(np.array([s_start, total - 0.5 * centre]), spacing)
        return np.interp(targets, s, xs), 0.5 * centre
    straddle = min(spacing, joint_half, 0.5 * (total - joint_half - s_start))
    outer = total - joint_half - 0.5 * straddle  # free side of the straddling edge
    inner = total - joint_half + 0.5 * straddle
    targets = segment_points(np.array([s_start, outer, inner, total]), spacing)
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

    Bonds: every arch node within ``g.bond`` of either end is tied to the coincident base
    node. With the default bond (the whole flat part b + w) the bonded edge straddles
    x0 = b + w (see below); a shorter bond leaves the arch flat on the base but loose between
    the bond's end and x0 (no contact is modelled there).
    """
    check_nodes(nodes)
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
    glued = g.bond  # the glued length at each end
    partial = glued < x0 * (1 - 1e-12)
    breaks = [0.0, sup, bond_end, x0 + half_edge, 0.5 * L, L - x0 - half_edge, L - bond_end,
              L - sup, L]
    if partial:
        breaks += [min(glued, bond_end), L - min(glued, bond_end)]
    breaks = np.sort(np.array(breaks))
    breaks = np.unique(np.round(breaks / L, 14)) * L
    base_x = segment_points(breaks, spacing)

    flat_left = base_x[base_x <= bond_end + 1e-12 * L]
    half, s_rigid = _half_sinusoid_x(g, spacing, x0 + half_edge, 0.5 * g.joint_length)
    mirror = L - half[::-1]
    if g.joint_length > 0:
        mirror = mirror[1:]  # the apex node is shared by both halves
    arch_x = np.concatenate([flat_left, half, mirror, (L - flat_left[::-1])])
    arch_xz = np.empty((arch_x.shape[0], 2))
    arch_xz[:, 0], arch_xz[:, 1] = arch_x, g.arch_z(arch_x)
    # The bonded arch node half an edge past x0 sits on the base, not on the sinusoid (which
    # is O(h^3) above it): exact ties share displacements, so a non-zero offset between tied
    # nodes would resist rigid rotation of the unit (it stressed neighbouring units in arrays
    # and made the snapped angle jump with the mesh). The bonded edge is then flat, as is
    # the sinusoid's tangent at x0.
    n_bond = len(flat_left) + 1
    arch_xz[:n_bond, 1] = 0.0
    arch_xz[-n_bond:, 1] = 0.0

    # per half edge: solid (4w) within the end regions, hollow (2w) between them
    halves = np.empty((base_x.shape[0] - 1, 2))
    halves[:, 0] = 0.75 * base_x[:-1] + 0.25 * base_x[1:]
    halves[:, 1] = 0.25 * base_x[:-1] + 0.75 * base_x[1:]
    base_width = np.where((halves < x0) | (halves > L - x0), 4.0 * g.w, 2.0 * g.w)

    st = Structure()
    base_xz = np.zeros((base_x.shape[0], 2))
    base_xz[:, 0] = base_x
    base = st.add_rod(base_xz, base_width, g.t, g.E)
    arch = st.add_rod(arch_xz, g.w, g.t, g.E)

    # bond every arch node of a flat end region to the coincident base node, and the nodes
    # half an edge past x0 that close the bonded edge across x0
    n_flat = len(flat_left) + 1  # base and arch share these abscissae
    if partial:
        n_flat = int(np.count_nonzero(base_x <= min(glued, bond_end) + 1e-12 * L))
    k = np.arange(n_flat)
    pairs = np.empty((2 * n_flat, 2), dtype=np.int64)  # (arch, base) pairs, from both ends in
    pairs[0::2, 0], pairs[0::2, 1] = arch.nodes[k], base.nodes[k]
    pairs[1::2, 0], pairs[1::2, 1] = arch.nodes[-1 - k], base.nodes[-1 - k]
    st.tie_all(pairs, method=tie, stiffness=tie_stiffness)

    apex_local = len(arch_x) // 2
    apex = int(arch.nodes[apex_local])
    # the joint: arch nodes up to the far end of the edges straddling its ends (and at
    # least the apex's two neighbours)
    xs, s_half = _arch_arc_table(g)
    arc_from_apex = s_half[-1] - np.interp(np.minimum(arch_x, L - arch_x), xs, s_half)
    in_joint = (arch_x > g.flat_length) & (arc_from_apex <= s_rigid * (1 + 1e-9) + 1e-15)
    if g.joint_length > 0:
        in_joint[apex_local - 1: apex_local + 2] = True
    else:  # the point clamp: the edge centred on the apex
        in_joint[:] = False
        in_joint[apex_local - 1: apex_local + 1] = True
    joint = [int(n) for n in arch.nodes[in_joint]]
    s0 = int(base.nodes[int(np.argmin(np.abs(base_x - sup)))])
    s1 = int(base.nodes[int(np.argmin(np.abs(base_x - (L - sup))))])
    base_mid = int(base.nodes[int(np.argmin(np.abs(base_x - 0.5 * L)))])
    st.elements()  # built once, shared by the variants (`UnitModel.variant`)
    st.scales()  # (likewise: every variant's drivers and probes ask for them)
    return _rigged(st, arch.nodes.copy(), base.nodes.copy(), apex, (s0, s1), base_mid,
                   tuple(joint), actuator, supports)


def _rigged(bare, arch_nodes, base_nodes, apex, rollers, base_mid, joint, actuator,
            supports) -> UnitModel:
    """The unit on a copy of the mesh ``bare``: the rig's rollers (z held at ``rollers``)
    when ``supports``, the actuator (the ``joint`` nodes rigid, the apex held in x) when
    ``actuator``."""
    st = bare.copy()
    if supports:
        st.fix(rollers[0], "z")
        st.fix(rollers[1], "z")
    if actuator:
        st.rigid(list(joint))
        st.fix(apex, "x")
    return UnitModel(st, arch_nodes, base_nodes, apex, tuple(rollers), base_mid, joint, bare)
