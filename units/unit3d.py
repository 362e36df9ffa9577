"""The bistable unit in 3-D: a rectangular frame base, the arch through its hole, and the
imperfections the paper saw (issue 14), on the 3-D discrete elastic rods of `solver.Structure3D`.

    >>> from units.unit3d import simulate_unit_3d
    >>> from units.frame3d import UnitGeometry
    >>> r = simulate_unit_3d(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), tilt_deg=2)
    >>> r.F_cr, r.theta_deg, r.arch_tilt_deg, r.rail_twist_deg
    >>> r.self_standing, r.S_released, r.theta_released_deg   # actuator and rollers removed

Geometry (x along the base, y across it, z up; `../shared/unit-model.md`, docs/unit3d.md):
- the base is a frame of outer width 4w: two side rails of width w (centrelines y = ±1.5 w)
  along the whole length, and two solid end regions 0 <= x <= b + w (and mirrored) of width 4w.
  An end region is a grid: the rails, a centre strip of width 2w (y = 0), cross bars along y
  at every end-region node before x0 (each as wide, in x, as the length of plate it stands
  for; each two rods running out from the centre), rigidly jointed where they cross (at one
  node frame, `units.junctions3d`; ``joints="bond"``: `Mesh3D.bond`), and two crossed pairs
  of braces for the plate's in-plane shear stiffness. The edges across the arch feet are 8
  times shorter than the spacing (``foot_refinement``).
  The hollow middle is the two rails only. ``end_plate="stiff"``: bars of 1e4 x E (rigid across the width).
- the arch, a strip of width w on the centre line, flat on the end regions and bonded there
  (shared positions; orientations jointed where both neighbouring edges are bonded),
  sinusoidal through the hole.
- rollers: z held along the line x = 0.03 L across the whole width (and mirrored);
- actuator: the arch nodes within ``joint_length`` around the push point move as one
  (`Structure3D.rigid`) with a short stiff head across the arch that holds its roll, and the
  push point cannot move in x or y.
As in the planar unit (docs/model-notes.md, note 1), the arch leaves the base at x0 = b + w,
the midpoint of an edge of the rails, the centre strip and the arch, so that the composite
(bonded) region ends exactly at x0 in the DER sense.

Imperfections: ``tilt_deg`` rotates the raised arch about the base's axis (x) toward +y;
``apex_offset`` (m) shifts the arch sideways by apex_offset * z(x) / h (a lateral bow, apex
moved by apex_offset); ``actuator_offset`` (m) glues and pushes the actuator that far along x
from mid-span.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.units.frame3d import (
    JOINT_LENGTH_DEFAULT,
    PETG_NU,
    SUPPORT_OFFSET,
    Mesh3D,
    UnitGeometry,
    arch_nodes_x,
)
from snapmorph.units.junctions3d import junction_pairs, rigid_junction
from snapmorph.units.planar import check_flag, check_steps
from snapmorph.units.push3d import (level, push_through, record_release, relax_released,
                                    transfer_state)
from snapmorph.units.push_through import PushOutcome
from snapmorph.units.result import UnitResultBase
from snapmorph.units.shapes import arch_height, end_tangent_angle, segment_points

__all__ = ["Unit3DModel", "Unit3DResult", "build_unit_mesh_3d", "build_unit_3d",
           "simulate_unit_3d", "DEFAULT_NODES_3D", "DEFAULT_JOINTS_3D",
           "DEFAULT_FOOT_REFINEMENT_3D"]

#: default resolution of the 3-D unit (nodes along a rail): with the default joints and foot
#: refinement, theta (iii) within 0.4 deg of its converged value and F_cr within 0.3 % of 161
#: nodes at h = 40.68 mm (docs/unit3d.md, "The default mesh since issue 25")
DEFAULT_NODES_3D = 41

#: default joints of rods crossing at a node: one node frame per junction
#: (`units.junctions3d`), the rigid joint that counts every half edge once; "bond" (the
#: `Mesh3D.bond` pairs, the default before issue 25) double-counts a crossing bar's half edge
#: and stiffens the rod running through (docs/unit3d.md, "Two mesh options")
DEFAULT_JOINTS_3D = "node"

#: default foot refinement: the edges across the arch feet 8 times shorter than the spacing.
#: With node joints at 41 nodes theta (iii) is within 0.4 deg of its converged value for
#: elastic and stiff end plates (uniform 41 nodes: 1.4 deg; docs/unit3d.md, issue 25)
DEFAULT_FOOT_REFINEMENT_3D = 8

#: Young's modulus of the end plates' cross bars / E with end_plate="stiff": rigid next to
#: the sheet (1e3 is not yet rigid: theta moves 0.07 deg more at 161 nodes), and not so far
#: beyond that the solver's force tolerance, set by the stiffest rod, loosens for nothing
STIFF_PLATE_FACTOR = 1e4
NAN = float("nan")


@dataclass
class Unit3DModel:
    """A meshed 3-D unit: the mesh, the structure (None until built) and its named nodes."""

    mesh: Mesh3D
    structure: object
    push_node: int
    rail_left: np.ndarray  # y = -1.5 w
    rail_right: np.ndarray  # y = +1.5 w
    arch: np.ndarray
    supports: np.ndarray
    junctions: list = field(default_factory=list)  # node lists joined at one node frame
    #: the junctions' fitted pairs (`units.junctions3d.junction_pairs`), one dict per junction,
    #: filled by the first `to_structure`: the fit is Python work per pair, as costly as a
    #: tenth of a push, and the same for every structure of this mesh
    junction_pairs: list | None = None

    def to_structure(self):
        """The `solver.Structure3D` of the mesh with its junctions (`units.junctions3d`)."""
        st = self.mesh.to_structure()
        if self.junction_pairs is None:
            self.junction_pairs = [junction_pairs(st, nodes) for nodes in self.junctions]
        for nodes, pairs in zip(self.junctions, self.junction_pairs):
            rigid_junction(st, nodes, pairs)
        return st


def _real(name, value, unit, meaning):
    """``value`` as a finite float, or a ValueError naming the parameter."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} ({meaning}, {unit}) must be a number; got {value!r}") from None
    if isinstance(value, (bool, np.bool_)) or not math.isfinite(v):
        raise ValueError(f"{name} ({meaning}, {unit}) must be a finite number; got {value!r}")
    return v


def _check_imperfections(tilt_deg, apex_offset, actuator_offset, g):
    tilt = _real("tilt_deg", tilt_deg, "degrees", "arch tilt about the base axis")
    if not -45.0 <= tilt <= 45.0:
        raise ValueError(f"tilt_deg (arch tilt about the base axis, degrees) must be in "
                         f"[-45, 45]; got {tilt!r}")
    dy = _real("apex_offset", apex_offset, "m", "sideways offset of the apex")
    if abs(dy) > g.h:
        raise ValueError(f"apex_offset (sideways offset of the apex, m) must be within "
                         f"[-h, h] = [{-g.h:.6g}, {g.h:.6g}] m; got {dy!r}")
    dx = _real("actuator_offset", actuator_offset, "m", "actuator position from mid-span")
    lim = 0.25 * g.arch_span
    if abs(dx) > lim:
        raise ValueError(f"actuator_offset (actuator position from mid-span along x, m) must "
                         f"be within [-{lim:.6g}, {lim:.6g}] m (a quarter of the arch span); "
                         f"got {dx!r}")
    return tilt, dy, dx


def _check_nodes(nodes):
    if isinstance(nodes, bool) or not isinstance(nodes, (int, np.integer)) or nodes < 21:
        raise ValueError(f"nodes (resolution: nodes along a rail) must be an integer >= 21; "
                         f"got {nodes!r}")
    if nodes > 2001:
        raise ValueError(f"nodes (resolution: nodes along a rail) must be <= 2001; got {nodes!r}")
    return int(nodes)


def build_unit_mesh_3d(
    g: UnitGeometry,
    nodes: int = DEFAULT_NODES_3D,
    tilt_deg: float = 0.0,
    apex_offset: float = 0.0,
    actuator_offset: float = 0.0,
    nu: float = PETG_NU,
    actuator: bool = True,
    supports: bool = True,
    bar_divisions: int = 2,
    bond: str = "joint",
    brace_width: float | None = None,
    end_plate: str = "elastic",
    joints: str = DEFAULT_JOINTS_3D,
    foot_refinement: int = DEFAULT_FOOT_REFINEMENT_3D,
) -> Unit3DModel:
    """Mesh the 3-D unit (no solver needed): frame base, arch, bonds, rollers, actuator.

    ``nodes``: nodes along a rail (edge length about L / (nodes - 1)); imperfections as in the
    module docstring; ``bar_divisions``: edges of a cross bar per half width (>= 1);
    ``bond``: "joint" (orientations coupled at every bonded node) or "tie" (positions shared
    at every bonded node, orientations coupled next to the bond's two ends);
    ``brace_width``: width (m) of the in-plane braces of each end plate (default b + w, the
    plate's length: the end plate is then in-plane rigid next to the rest); ``end_plate``:
    "elastic" (the sheet's own stiffness) or "stiff" (cross bars of 1e4 x E: the end
    plates keep their shape across the width, as the planar model assumes);
    ``joints``: how rods crossing at a node are joined: "node" (default: one node frame per
    junction, `units.junctions3d`, listed in the model's ``junctions``; docs/unit3d.md) or
    "bond" (`Mesh3D.bond`: pairs of edges in both orders, the default before issue 25);
    ``foot_refinement``: the edges next to the arch feet x0 are this many times shorter than
    the spacing, doubling in length away from them (default 8; 1: the uniform mesh, the
    default before issue 25 with ``joints="bond"``).
    Returns a `Unit3DModel` whose ``structure`` is None.
    """
    if not isinstance(g, UnitGeometry):
        raise ValueError(f"g must be a UnitGeometry; got {type(g).__name__}")
    if g.h <= 0:
        raise ValueError("h (arch apex height, m) must be > 0 for a 3-D unit; got 0")
    nodes = _check_nodes(nodes)
    nu = _real("nu", nu, "-", "Poisson's ratio")
    if not -1.0 < nu <= 0.5:
        raise ValueError(f"nu (Poisson's ratio) must be in (-1, 0.5]; got {nu!r}")
    tilt, dy, dx = _check_imperfections(tilt_deg, apex_offset, actuator_offset, g)
    if isinstance(bar_divisions, bool) or not isinstance(bar_divisions, (int, np.integer)) \
            or not 1 <= bar_divisions <= 64:
        raise ValueError(f"bar_divisions (cross-bar edges per half width) must be an integer "
                         f"in [1, 64]; got {bar_divisions!r}")
    if bond not in ("joint", "tie"):
        raise ValueError(f"bond must be 'joint' or 'tie'; got {bond!r}")
    if joints not in ("bond", "node"):
        raise ValueError(f"joints (how rods crossing at a node are joined) must be 'bond' or "
                         f"'node'; got {joints!r}")
    if isinstance(foot_refinement, bool) or not isinstance(foot_refinement, (int, np.integer)) \
            or not 1 <= foot_refinement <= 64:
        raise ValueError(f"foot_refinement (edges at the arch feet this many times shorter than "
                         f"the spacing) must be an integer in [1, 64]; got {foot_refinement!r}")
    L, w, t, x0 = g.L, g.w, g.t, g.flat_length
    if end_plate not in ("elastic", "stiff"):
        raise ValueError(f"end_plate must be 'elastic' or 'stiff'; got {end_plate!r}")
    # The cross bars are strips of a continuous plate: their twisting stiffness is the
    # plate's (J = w t^3 / 3, no free-edge loss), which does not drift as the bars narrow
    # with the mesh. "stiff": bars of STIFF_PLATE_FACTOR x E (same thickness), rigid next to
    # the rest: the end plates keep their shape across the width, as the planar model
    # assumes (a diagnostic). Thicker bars do not do it: a bar one edge wide and 10 t thick
    # twists like a narrow strip, softer and softer as the mesh is refined (docs/unit3d.md).
    bar_E = STIFF_PLATE_FACTOR if end_plate == "stiff" else 1.0
    brace_width = x0 if brace_width is None else _real("brace_width", brace_width, "m",
                                                      "width of the end plates' braces")
    if not brace_width > 0:
        raise ValueError(f"brace_width (width of the end plates' braces, m) must be > 0; "
                         f"got {brace_width!r}")
    spacing = L / (nodes - 1)
    sup = SUPPORT_OFFSET * L
    he = 0.5 * min(spacing / foot_refinement, 0.5 * x0, 0.25 * g.arch_span)
    if abs(sup - x0) < he * (1 + 1e-9):  # as the planar unit: keep the roller at 0.03 L
        he = max(0.5 * abs(sup - x0), 0.05 * spacing)
        if abs(sup - x0) < he * (1 + 1e-9):
            sup = x0 - he
    breaks = np.array([0.0, sup, x0 - he, x0 + he, 0.5 * L, L - x0 - he, L - x0 + he,
                       L - sup, L])
    breaks = np.unique(np.round(breaks / L, 14)) * L
    if foot_refinement == 1:
        base_x = segment_points(breaks, spacing)
    else:  # edges of 2 he next to the feet, growing twice as long per edge away from them
        base_x = graded_points(breaks, spacing, [x0 - he, x0 + he, L - x0 - he, L - x0 + he],
                               2 * he)
    # exactly mirror-symmetric, so that mirrored nodes of different rods coincide bit for bit
    left = base_x[base_x <= 0.5 * L * (1 + 1e-12)]
    base_x = np.concatenate([left, L - left[::-1][1:]])
    n_end = int(np.count_nonzero(base_x <= x0 + he * (1 + 1e-9)))  # nodes of an end region
    end_x = base_x[:n_end]

    mesh = Mesh3D(E=g.E, nu=nu)
    yr = 1.5 * w
    zeros = np.zeros_like(base_x)
    rail_l = mesh.add_rod("rail_left", np.stack([base_x, zeros - yr, zeros], 1), w, t)
    rail_r = mesh.add_rod("rail_right", np.stack([base_x, zeros + yr, zeros], 1), w, t)

    # centre strips of the two end regions (width 2w), from the end to half an edge past x0
    zc = np.zeros(n_end)
    c_left = mesh.add_rod("centre_left", np.stack([end_x, zc, zc], 1), 2 * w, t)
    # (both strips run along +x, as the arch they are bonded to: see Mesh3D.bond)
    c_right = mesh.add_rod("centre_right", np.stack([L - end_x[::-1], zc, zc], 1), 2 * w, t)

    # cross bars across the width at every end-region node up to half an edge before x0;
    # each is as wide (in x) as the length of plate between the midpoints to its neighbours
    # (the last one up to x0). The centre strip's last edge, straddling x0, is the plate's
    # edge region; its end node half an edge past x0 carries the bonded arch node only (a bar
    # there would stiffen the rails' first hollow edge, an O(1/N) error).
    # bar nodes across the width: at the rails, the centre and between (bar_divisions parts
    # per half width; the end regions are short and stiff, see the convergence study)
    y_half = segment_points(np.array([0.0, yr]), yr / bar_divisions * (1 + 1e-12))
    mids = np.concatenate([[0.0], 0.5 * (end_x[1:] + end_x[:-1]), [end_x[-1]]])
    bar_w = np.minimum(mids[1:], x0) - np.minimum(mids[:-1], x0)
    support_nodes = []
    # joints="bond": every crossing joined by pairs of edges in both orders (Mesh3D.bond);
    # "node": the rods meeting at a node hang off one node frame (units.junctions3d), which
    # counts no half edge twice and adds no stiffness to a rod running through the node
    hubs = None if joints == "bond" else {}

    def join(through, *others):
        if hubs is None:
            for o in others:
                mesh.bond(through, o)
        else:
            hubs.setdefault(int(through), []).extend(int(o) for o in others)

    for side, (rail_a, rail_b, centre) in (("left", (rail_l, rail_r, c_left)),
                                           ("right", (rail_l[::-1], rail_r[::-1], c_right[::-1]))):
        for k in range(n_end - 1):  # no bar half an edge past x0: the plate ends at x0
            x = end_x[k] if side == "left" else L - end_x[k]
            # each bar is two rods running out from the centre strip to the rails, so that
            # the joints (which couple one edge of each rod, see Mesh3D.bond) are mirror
            # images of each other across y = 0: a single rod across would couple the centre
            # strip to one half only, and the unit would lean to that side under a push
            halves = []
            for sign, tag in ((-1.0, "m"), (1.0, "p")):
                pts = np.stack([np.full_like(y_half, x), sign * y_half, np.zeros_like(y_half)], 1)
                halves.append(mesh.add_rod(f"bar_{side}_{k}_{tag}", pts, bar_w[k], t,
                                           E_factor=bar_E, plate=True))
            minus, plus = halves
            join(centre[k], minus[0], plus[0])
            if hubs is None:
                mesh.bond(minus[0], plus[0])  # the bar continues straight across the centre
            join(rail_a[k], minus[-1])
            join(rail_b[k], plus[-1])
            if abs(end_x[k] - sup) < 1e-9 * L:
                support_nodes += [int(n) for n in minus] + [int(n) for n in plus]
                support_nodes += [int(rail_a[k]), int(rail_b[k]), int(centre[k])]
        # A grid of bars has no in-plane shear stiffness but the bars' own in-plane bending,
        # which vanishes as the bars get narrower with the mesh (the arch's thrust then slides
        # the centre strip along the rails: F_cr fell 7 % and 14 % below the planar model at
        # 41 and 81 nodes). The solid end plate is in-plane rigid next to everything else, so
        # two crossed pairs of braces over the whole end region (the plate's extent, fixed
        # whatever the mesh) carry the shear; each is jointed at its outer end and tied at
        # its inner end, so it adds in-plane stiffness and no bending worth the name.
        far = n_end - 2  # the last bar, half an edge before x0
        for outer, inner in ((rail_a[0], centre[far]), (rail_b[0], centre[far]),
                             (centre[0], rail_a[far]), (centre[0], rail_b[far])):
            pts = mesh.positions[[int(outer), int(inner)]]
            brace = mesh.add_rod(f"brace_{side}_{len(mesh.rods)}", pts, brace_width, t)
            join(outer, brace[0])
            mesh.ties.append((int(inner), int(brace[1])))

    # the arch: flat on the end regions up to half an edge past x0, raised in between
    x_act = 0.5 * L + dx
    jl = float(getattr(g, "joint_length", JOINT_LENGTH_DEFAULT))
    raised, act, (lo, hi) = arch_nodes_x(end_x[-1], L - end_x[-1], x0, g.arch_span, g.h,
                                         spacing, x_act, jl)
    arch_x = np.concatenate([end_x[:-1], raised, L - end_x[:-1][::-1]])
    z = arch_height(arch_x, x0, g.arch_span, g.h)
    z[:n_end] = 0.0  # the bonded edge across x0 lies on the base (as the planar unit)
    z[-n_end:] = 0.0
    a = math.radians(tilt)
    y = z * math.sin(a) + dy * z / g.h
    z = z * math.cos(a)
    arch = mesh.add_rod("arch", np.stack([arch_x, y, z], 1), w, t)
    # bond: the arch nodes on an end region share their positions with the coincident centre
    # strip nodes; bond="joint" also couples their orientations at every node (a rigid
    # joint adds a bending/twisting pair; at the rods' common end a tie, see Mesh3D.bond),
    # bond="tie" only next to the two ends of the bond
    glued = g.bond if hasattr(g, "bond") else x0
    n_bond = (n_end if glued >= x0 * (1 - 1e-12)
              else int(np.count_nonzero(end_x <= glued + 1e-12 * L)))
    # Orientations are coupled only at nodes whose both neighbouring edges are bonded (a
    # joint at the last bonded node would also tie the arch's first free edge to the base).
    for k in range(n_bond):
        inner = 1 <= k <= n_bond - 2
        for a_, b_ in ((arch[k], c_left[k]), (arch[-1 - k], c_right[-1 - k])):
            if inner and (bond == "joint" or k in (1, n_bond - 2)):
                if hubs is None:
                    mesh.bond(a_, b_)
                else:
                    join(b_, a_)
            else:
                mesh.ties.append((int(a_), int(b_)))

    junctions = [[through] + others for through, others in (hubs or {}).items()]
    offset = n_end - 1
    push = int(arch[offset + act])
    head = np.zeros(0, dtype=np.int64)
    if actuator:
        # the actuator (a T-rod glued on the arch) holds the arch's orientation: the glued
        # arch segment translates as one (which holds its tangent), and a short stiff head
        # across the arch, jointed to it at the push point and translating with it, holds the
        # roll about the arch's tangent that a rigid translation leaves free
        p0 = mesh.positions[push]
        across = np.array([0.0, math.cos(a), -math.sin(a)])
        normal = (0.0, math.sin(a), math.cos(a))
        ends = []
        for sign, tag in ((-1.0, "m"), (1.0, "p")):  # two halves: mirror-symmetric joints
            pts = p0 + np.outer([0.0, sign * 0.5 * w], across)
            half_head = mesh.add_rod(f"actuator_head_{tag}", pts, w, 3 * t, normal=normal)
            mesh.bond(push, half_head[0])
            ends.append(int(half_head[-1]))
            head = np.concatenate([head, half_head])
        mesh.rigid.append([int(n) for n in arch[offset + lo: offset + hi]] + ends)
        mesh.fixes.append((push, "xy"))
    if supports:
        for n in support_nodes:
            mesh.fixes.append((n, "z"))
    mid = int(np.argmin(np.abs(base_x - 0.5 * L)))
    mesh.named.update(push=push, h=g.h, base_mid_left=int(rail_l[mid]),
                      base_mid_right=int(rail_r[mid]))
    mesh.groups.update(rail_left=rail_l, rail_right=rail_r, arch=arch, centre_left=c_left,
                       centre_right=c_right, supports=np.array(support_nodes, dtype=np.int64),
                       actuator=arch[offset + lo: offset + hi].copy(), actuator_head=head)
    return Unit3DModel(mesh, None, push, rail_l, rail_r, arch,
                       np.array(support_nodes, dtype=np.int64), junctions)


def graded_points(breaks, spacing, feet, fine, ratio=2.0):
    """Points along sorted ``breaks`` (every break kept) as `units.shapes.segment_points`,
    edges no longer than ``spacing``, except in the intervals that end at one of ``feet``:
    there the edges start at ``fine`` next to the foot and grow by ``ratio`` up to
    ``spacing``."""
    pts = [float(breaks[0])]
    feet = np.asarray(feet, dtype=float)
    for a, b in zip(breaks[:-1], breaks[1:]):
        da, db = np.min(np.abs(feet - a)), np.min(np.abs(feet - b))
        if fine >= spacing or min(da, db) > 1e-9 * spacing or b - a <= fine * (1 + 1e-9):
            pts.extend(segment_points(np.array([a, b]), spacing)[1:])
            continue
        lengths = []
        while sum(lengths) < (b - a) * (1 - 1e-9):
            lengths.append(min(fine * ratio ** len(lengths), spacing))
        lengths = np.array(lengths) * ((b - a) / sum(lengths))
        if db < da:
            lengths = lengths[::-1]
        pts.extend(a + np.cumsum(lengths)[:-1])
        pts.append(float(b))
    return np.array(pts)


def build_unit_3d(g: UnitGeometry, nodes: int = DEFAULT_NODES_3D, **options) -> Unit3DModel:
    """Mesh the 3-D unit and build its `solver.Structure3D` (options: `build_unit_mesh_3d`)."""
    model = build_unit_mesh_3d(g, nodes=nodes, **options)
    model.structure = model.to_structure()
    return model


@dataclass(repr=False)
class Unit3DResult(UnitResultBase):
    """Metrics of the 3-D unit, SI (N, m, degrees), NaN where absent. The planar
    `UnitResult`'s metrics (`units.result.UnitResultBase`: F_cr, d_cr, d_unstable, d_second,
    bistable, shapes, ...; S, theta_deg) plus the out-of-plane ones:

    arch_tilt_deg: {"i", "ii", "iii"} -> equivalent tilt of the arch about x (`arch_lean_deg`:
    asin of its largest sideways offset from the plane of its feet over h; degrees, > 0
    toward +y; the imposed tilt in the stress-free state);
    rail_twist_deg: {"i", "ii", "iii"} -> largest rotation of the base's cross-section about x
    (from the heights of the two rails at the same x), degrees;
    arch_lateral: {"i", "ii", "iii"} -> largest sideways (y) displacement of an arch node, m.
    shapes[state] = {"rail_left", "rail_right", "arch", "base"} (n, 3) positions (base: the
    mean of the two rails, the planar model's base line), and "rods": every rod by name;
    ``reference``: the same for the stress-free state.

    S, theta_deg and base_shape are those of state (iii) and exist only when the unit is
    bistable: state (iii) found as an equilibrium and stable with the actuator unloaded
    (no negative eigenvalue of its tangent stiffness); otherwise ``reason`` says why
    (status "second state unstable: ..." when (iii) exists but is unstable).

    released: state (iii) with the actuator (rigid group, head and the push point's xy
    support) and the rollers removed, relaxed under no load with only the rigid-body motion
    held — the unit as an array holds it — and placed with the rails' nodes on the roller
    lines in a horizontal plane (`units.push3d.level`): {"S", "theta_deg" (as S and theta_deg),
    "base_shape", "rail_left", "rail_right", "arch" (n, 3), "rods", "rail_twist_deg",
    "arch_tilt_deg", "arch_lateral", "moved" (largest node displacement from (iii), m),
    "first_negative_eigenvalues" (of the equilibrium next to (iii) Newton finds first: 0
    when that is the released state; > 0 when it is unstable and the released state was
    found by leaving it along a mode of negative curvature, `units.push3d.relax_released`)};
    empty when the released unit is not stable or moves more than h / 4 from (iii) (the
    planar unit's test; then ``self_standing`` is False; None when not checked or not
    bistable).
    stability: {"ii", "iii"} -> `solver.stability.StateStability` with the actuator
    unloaded (None: singular), "released" -> negative eigenvalues of the released state.
    """

    geometry: UnitGeometry
    imperfection: dict = field(default_factory=dict)
    S: float = NAN
    theta_deg: float = NAN
    arch_tilt_deg: dict = field(default_factory=dict)
    rail_twist_deg: dict = field(default_factory=dict)
    arch_lateral: dict = field(default_factory=dict)
    base_shape: np.ndarray = field(default_factory=lambda: np.full((0, 3), np.nan))
    reference: dict = field(default_factory=dict)
    path_status: str = ""
    exact_states: bool = False

    def _summary_details(self) -> dict:
        out = {}
        for name in ("arch_tilt_deg", "rail_twist_deg", "arch_lateral"):
            for state, v in getattr(self, name).items():
                out[f"{name}_{state}"] = v
            out[f"{name}_released"] = float(self.released.get(name, NAN))
        out.update({f"imperfection_{k}": v for k, v in self.imperfection.items()})
        return out


def section_rotation_deg(rail_left_pos, rail_right_pos):
    """(n,) rotation of the base's cross-section about x at each rail node, degrees: the angle
    of the segment from the left to the right rail node against the horizontal."""
    d = np.asarray(rail_right_pos) - np.asarray(rail_left_pos)
    return np.degrees(np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1])))


def arch_lean_deg(arch_pos, h, foot_left, foot_right):
    """Equivalent tilt of the arch about x (degrees, > 0 toward +y): asin(e / h), with e the
    sideways offset of the arch node furthest from the vertical plane through its two bonded
    ends (signed), h the arch height. The stress-free arch tilted by alpha reads alpha;
    defined in every state (also where the arch is flat or inverted)."""
    p = np.asarray(arch_pos)
    a, b = p[foot_left], p[foot_right]
    axis = b - a
    axis[2] = 0.0
    n = np.linalg.norm(axis)
    axis = axis / n if n > 0 else np.array([1.0, 0.0, 0.0])
    side = np.cross(np.array([0.0, 0.0, 1.0]), axis)  # horizontal, across the arch
    off = (p - 0.5 * (a + b)) @ side
    k = int(np.argmax(np.abs(off)))
    return math.degrees(math.asin(float(np.clip(off[k] / h, -1.0, 1.0))))


def unit3d_metrics(model: Unit3DModel, positions) -> dict:
    """Base line, S, theta and the out-of-plane measures of one state (n_nodes, 3)."""
    P = np.asarray(positions)
    rl, rr, arch = P[model.rail_left], P[model.rail_right], P[model.arch]
    base = 0.5 * (rl + rr)
    foot = int(np.count_nonzero(model.mesh.groups["centre_left"] >= 0)) - 1
    X = model.mesh.positions
    return {
        "base": base, "rail_left": rl, "rail_right": rr, "arch": arch,
        "S": float(base[-1, 0] - base[0, 0]),
        "theta_deg": end_tangent_angle(base),
        "rail_twist_deg": float(np.max(np.abs(section_rotation_deg(rl, rr)))),
        "arch_tilt_deg": arch_lean_deg(arch, model.mesh.named["h"], foot, len(arch) - 1 - foot),
        "arch_lateral": float(np.max(np.abs(arch[:, 1] - X[model.arch, 1]))),
    }


def released_supports(model: Unit3DModel):
    """A statically determinate set of supports that holds only the rigid-body motion of the
    unit: (node, components). The rails' nodes on the roller lines: the left rail's at the
    first line all of x, y, z, the right rail's there x and z (no turning about z or x), the
    left rail's at the second line z (no turning about y). Under no load their reactions
    vanish, so they place the released unit without straining it (as the rollers would)."""
    sup = set(model.supports.tolist())
    X = model.mesh.positions

    def on_lines(rail):
        k = [int(n) for n in rail if int(n) in sup]
        if len(k) < 2:  # no roller line in the mesh: the rails' ends
            k = [int(rail[0]), int(rail[-1])]
        k.sort(key=lambda n: X[n, 0])
        return k[0], k[-1]

    l0, l1 = on_lines(model.rail_left)
    r0, _ = on_lines(model.rail_right)
    return [(l0, "xyz"), (r0, "xz"), (l1, "z")]


def released_state_3d(g, model: Unit3DModel, q_iii, build_options: dict):
    """State (iii) of ``model`` (full state ``q_iii``) released: the unit rebuilt without
    actuator and rollers, its rigid-body motion held by `released_supports`, relaxed under no
    load. Returns (self_standing, metrics dict or None, negative eigenvalues or None, why
    not self-standing ("" when it is))."""
    free = build_unit_mesh_3d(g, actuator=False, supports=False, **build_options)
    # the same rods and node numbers up to the arch (the actuator's head rods come after
    # every junction's rods, the rollers are fixes only): the junctions' fit carries over
    if free.junctions == model.junctions:
        free.junction_pairs = model.junction_pairs
    st = free.to_structure()
    for node, comps in released_supports(free):
        st.fix(node, comps)
    q0 = transfer_state(model.mesh, q_iii, free.mesh, st)
    q, neg, moved, why, first = relax_released(st, q0)
    if not why and not moved <= 0.25 * g.h:  # the planar unit's test
        why = (f"without the actuator the unit moves {moved:.3g} m (> h / 4) away from state "
               "(iii): it does not stay in its second state")
    if why:
        return False, None, neg, why
    # placed as the actuated unit stands: the rails' nodes on the roller lines in a
    # horizontal plane (rail twist and theta are measured against the vertical)
    sup = set(free.supports.tolist())
    rollers = [int(n) for n in np.concatenate([free.rail_left, free.rail_right]) if int(n) in sup]
    pos = level(st.positions_of(q), rollers or [n for n, _ in released_supports(free)],
                free.mesh.positions)
    m = unit3d_metrics(free, pos)
    rel = {"S": m["S"], "theta_deg": m["theta_deg"], "base_shape": m["base"].copy()}
    rel.update({k: m[k] for k in ("rail_left", "rail_right", "arch", "rail_twist_deg",
                                  "arch_tilt_deg", "arch_lateral")})
    rel["rods"] = {rod.name: np.array(pos[rod.nodes]) for rod in free.mesh.rods}
    rel["moved"] = moved
    rel["first_negative_eigenvalues"] = first
    return True, rel, neg, ""


def simulate_unit_3d(
    g: UnitGeometry,
    nodes: int | None = None,
    tilt_deg: float = 0.0,
    apex_offset: float = 0.0,
    actuator_offset: float = 0.0,
    nu: float = PETG_NU,
    steps: int = 60,
    critical: bool = False,
    bar_divisions: int = 2,
    bond: str = "joint",
    brace_width: float | None = None,
    end_plate: str = "elastic",
    check_self_standing: bool = True,
    joints: str = DEFAULT_JOINTS_3D,
    foot_refinement: int = DEFAULT_FOOT_REFINEMENT_3D,
) -> Unit3DResult:
    """Push the 3-D unit's actuator down until it snaps; the planar metrics plus arch tilt,
    rail twist and sideways motion of the arch (see `Unit3DResult`).

    ``nodes``: resolution (nodes along a rail; None = DEFAULT_NODES_3D); ``steps``: first
    step as a fraction of 3 h; ``critical``: detect bifurcations on the path (slower);
    ``check_self_standing``: also release the bistable unit's state (iii) (actuator and
    rollers removed) and report ``released`` and ``self_standing`` (as the planar unit);
    ``joints``, ``foot_refinement``: the mesh options of `build_unit_mesh_3d` (issue 25).
    Arguments are validated (ValueError naming the parameter); after that it never raises
    for a unit that can be built: failures come back in ``status`` and ``reason``.
    """
    nodes = DEFAULT_NODES_3D if nodes is None else nodes
    steps = int(check_steps(steps))
    critical = check_flag("critical", critical)
    check_self_standing = check_flag("check_self_standing", check_self_standing)
    t0 = time.perf_counter()
    options = dict(nodes=nodes, tilt_deg=tilt_deg, apex_offset=apex_offset,
                   actuator_offset=actuator_offset, nu=nu, bar_divisions=bar_divisions,
                   bond=bond, brace_width=brace_width, end_plate=end_plate,
                   joints=joints, foot_refinement=foot_refinement)
    model = build_unit_3d(g, **options)
    imperfection = {"tilt_deg": float(tilt_deg), "apex_offset": float(apex_offset),
                    "actuator_offset": float(actuator_offset)}
    out: PushOutcome = push_through(model.structure, model.push_node, 3.0 * g.h, steps=steps,
                                    critical=critical)
    r = Unit3DResult(g, out.status, imperfection=imperfection, curve=out.curve,
                     path_status=out.path_status, F_cr=out.F_cr, d_cr=out.d_cr,
                     d_unstable=out.d_unstable, d_second=out.d_second,
                     bistable=out.bistable, exact_states=out.exact_states,
                     reason=out.reason, stability=dict(out.stability))
    r.reference = unit3d_metrics(model, model.mesh.positions)
    r.reference["rods"] = {rod.name: rod.xyz.copy() for rod in model.mesh.rods}
    for state, pos in out.states.items():
        m = unit3d_metrics(model, pos)
        r.shapes[state] = {k: m[k] for k in ("rail_left", "rail_right", "arch", "base")}
        r.shapes[state]["rods"] = {rod.name: np.asarray(pos)[rod.nodes] for rod in model.mesh.rods}
        r.arch_tilt_deg[state] = m["arch_tilt_deg"]
        r.rail_twist_deg[state] = m["rail_twist_deg"]
        r.arch_lateral[state] = m["arch_lateral"]
        if state == "iii" and r.bistable:
            r.S, r.theta_deg, r.base_shape = m["S"], m["theta_deg"], m["base"].copy()
    if r.bistable and check_self_standing:
        record_release(r, lambda: released_state_3d(g, model, out.full_states["iii"], options))
    r.solve_time = time.perf_counter() - t0
    r.n_nodes = model.mesh.n_nodes
    return r
