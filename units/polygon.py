"""Meshes of 2-D units on regular polygon footprints: a frame base on a triangle, square or
hexagon of side L, with arches rising from every side's midpoint to one apex above the
centre (no solver needed; `units.unit2d` simulates them).

Geometry (x, y in the base plane, z up; SI units): side k runs from vertex k to vertex k + 1
counter-clockwise, side 0 along y = 0 from (0, 0) to (L, 0) (the square's "south"); a side's
nodes are those of the square unit's sides (`side_abscissae`: one edge over each overlap).
The arches have the square unit's profile: flat over their first b + w/2 from the foot,
then a sinusoid rising to h with zero slope over the centre, i.e. half of a sinusoidal arch
of span 2 (r - b - w/2), r the inradius (L/2 for the square, L / (2 sqrt 3) for the triangle,
L sqrt(3) / 2 for the hexagon). With an even number of sides the arches from opposite
midpoints are one continuous strip through the apex (the square is today's 2-D unit, whose
mesh `units.unit2d.build_unit_mesh_2d` builds itself, bit for bit as before); the
triangle's three half-arches end at the apex and are rigidly bonded there. Every strip
crossing the apex is bonded to the first one there, as the square unit's two arches.

Actuator, supports and the released unit's rigid-body holds follow the square unit:
the arch nodes within ``joint_length`` of the apex move as one, the apex cannot move in
x or y, z is held at every side midpoint; `released_holds` is a statically determinate set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from snapmorph.units.frame3d import JOINT_LENGTH_DEFAULT, PETG_NU, Mesh3D, UnitGeometry
from snapmorph.units.shapes import arch_height, cumulative_length, segment_points

__all__ = ["POLYGON_SIDES", "Unit2DModel", "check_sides", "polygon_vertices", "inradius",
           "side_names", "check_geometry_polygon", "build_polygon_mesh", "add_cell_arches",
           "side_abscissae",
           "arch_raised", "arch_flat"]

#: the footprints of the 2-D unit: triangle, square, hexagon (the polygons that tile a plane)
POLYGON_SIDES = (3, 4, 6)
#: thickness of the overlap edges / t with overlaps="rigid" (`units.unit2d` module docstring)
RIGID_OVERLAP_THICKNESS = 10.0
OVERLAPS = ("elastic", "rigid")


@dataclass
class Unit2DModel:
    """A meshed 2-D unit: the mesh, the structure (None until built) and named nodes.

    ``sides``: side name -> node indices, corner to corner; ``arches``: arch name -> node
    indices, foot first; ``supports``: the side midpoints (one per side, in side order);
    ``holds``: the rigid-body holds of the released unit ((node, components) pairs; None:
    the square unit's, `units.unit2d.released_supports_2d`); ``n_sides``: 3, 4 or 6."""

    mesh: Mesh3D
    structure: object
    push_node: int
    sides: dict
    arches: dict
    supports: np.ndarray
    overlaps: str = "elastic"
    holds: list | None = None
    n_sides: int = 4


def check_sides(sides) -> int:
    """``sides`` (number of sides of the unit's footprint) as an int, or a ValueError."""
    if isinstance(sides, (bool, np.bool_)) or not isinstance(sides, (int, np.integer)) \
            or int(sides) not in POLYGON_SIDES:
        raise ValueError(f"sides (number of sides of the unit's footprint) must be one of "
                         f"{POLYGON_SIDES} (triangle, square, hexagon); got {sides!r}")
    return int(sides)


def side_names(sides: int) -> tuple:
    """Names of the sides: the square unit's compass names, "s0", "s1", ... otherwise."""
    if sides == 4:
        return ("south", "east", "north", "west")
    return tuple(f"s{k}" for k in range(sides))


def inradius(L: float, sides: int) -> float:
    """Distance (m) from the centre of a regular polygon of side L to a side's midpoint."""
    return 0.5 * L / math.tan(math.pi / sides)


def polygon_vertices(L: float, sides: int) -> np.ndarray:
    """(sides, 2) vertices (m) of the regular polygon of side L, counter-clockwise from
    (0, 0), side 0 along +x."""
    angles = 2 * math.pi * np.arange(sides) / sides
    steps = L * np.stack([np.cos(angles), np.sin(angles)], 1)
    return np.concatenate([[[0.0, 0.0]], np.cumsum(steps, axis=0)[:-1]])


def arch_flat(g) -> float:
    """Length (m) of an arch's flat foot: across the frame strip (w/2) and the extra b."""
    return g.b + 0.5 * g.w


def check_geometry_polygon(g: UnitGeometry, sides: int):
    """Limits of a polygon unit (its arches' flat feet are b + w/2 long; a sinusoid of span
    2 (r - b - w/2) must have h below its span)."""
    if not isinstance(g, UnitGeometry):
        raise ValueError(f"g must be a UnitGeometry; got {type(g).__name__}")
    if g.h <= 0:
        raise ValueError("h (arch apex height, m) must be > 0 for a 2-D unit; got 0")
    span = 2 * (inradius(g.L, sides) - arch_flat(g))
    if not span > 0 or g.h > span:
        raise ValueError(f"h (arch apex height, m) must be <= the arch span 2 (r - b - w/2) = "
                         f"{span:.6g} m of a {sides}-sided unit of side L = {g.L:.6g} m; "
                         f"got {g.h:.6g} m")
    if not float(getattr(g, "joint_length", JOINT_LENGTH_DEFAULT)) > 0:
        raise ValueError("joint_length (length of arch held by the actuator, m) must be > 0 "
                         "for a 2-D unit (the arches cross at the apex, which must be a node "
                         "between the actuator's edges); got 0")


def side_abscissae(L, w, spacing):
    """Abscissae (m) of a side's nodes from corner to corner and the index of its midpoint:
    one edge over each overlap ([0, w/2] at the corners, [L/2 - w/2, L/2 + w/2] under the
    arch foot), edges no longer than ``spacing`` in between."""
    inner = segment_points(np.array([0.5 * w, 0.5 * (L - w)]), spacing)
    half = np.concatenate([[0.0], inner, [0.5 * L]])
    return np.concatenate([half, L - half[::-1][1:]]), len(half) - 1


def arch_raised(x0, span, h, spacing, joint_length, w, overlaps):
    """Abscissae of the arch nodes on its raised part [x0, x0 + span], near-uniform in arc
    length (edges no longer than ``spacing``) except at the apex, where the nodes do not
    depend on the mesh: "elastic", the actuator's rigid joint of arc length ``joint_length``
    centred on the apex with one edge straddling each end of it (as `arch_nodes_x` with the
    straddle at its coarse-mesh length joint_length / 2); "rigid", the crossing's w/2 each
    side of the apex (and the ends of a longer joint). Returns (x, index of the apex node,
    (start, stop) slice of the nodes the actuator moves as one, [first, stop) of the edges
    of the crossing made rigid (empty for "elastic"))."""
    xs = np.linspace(x0, x0 + span, 8001)
    s = cumulative_length(xs, arch_height(xs, x0, span, h))
    total = s[-1]
    s_act = float(np.interp(x0 + 0.5 * span, xs, s))
    half = 0.5 * joint_length
    if overlaps == "elastic":
        room = min(s_act - half, total - s_act - half)
        straddle = min(half, room)
        core = [-half - 0.5 * straddle, -half + 0.5 * straddle, 0.0, half - 0.5 * straddle,
                half + 0.5 * straddle]
        c = 0.0
    else:
        c = 0.5 * w
        reach = max(c, half)
        room = min(s_act, total - s_act) - reach
        core = sorted({-reach, -c, 0.0, c, reach})
    if not room > 0:
        raise ValueError(f"the actuator joint (joint_length {joint_length:.6g} m) or the "
                         f"crossing (w {w:.6g} m) does not fit on the arch")
    left = segment_points(np.array([0.0, s_act + core[0]]), spacing)
    right = segment_points(np.array([s_act + core[-1], total]), spacing)
    targets = np.concatenate([left, s_act + np.array(core[1:-1]), right])
    x = np.interp(targets, s, xs)
    x[0], x[-1] = x0, x0 + span
    lo = len(left) - 1
    apex = lo + core.index(0.0)
    stiff = (lo + core.index(-c), lo + core.index(c)) if c > 0 else (apex, apex)
    return x, apex, (lo, lo + len(core)), stiff


def _add_frame(mesh, g, sides, spacing, rigid):
    """The frame's rods (one per side, bonded at the corners); returns ({name: nodes},
    index of the midpoint node along a side)."""
    s, mid = side_abscissae(g.L, g.w, spacing)
    V = polygon_vertices(g.L, sides)
    names = side_names(sides)
    out = {}
    for k, name in enumerate(names):
        a, b = V[k], V[(k + 1) % sides]
        d = (b - a) / g.L
        xyz = np.stack([a[0] + s * d[0], a[1] + s * d[1], np.zeros_like(s)], 1)
        out[name] = mesh.add_rod(name, xyz, g.w, g.t)
    if rigid:
        side_t = np.full(len(s) - 1, g.t)
        side_t[[0, mid - 1, mid, len(s) - 2]] = RIGID_OVERLAP_THICKNESS * g.t
        for rod in mesh.rods:
            rod.thickness = side_t
    for a, b in zip(names, names[1:] + names[:1]):
        mesh.bond(out[a][-1], out[b][0])
    return out, mid


def build_polygon_mesh(g: UnitGeometry, sides: int, nodes: int, nu: float = PETG_NU,
                       actuator: bool = True, supports: bool = True,
                       overlaps: str = "elastic") -> Unit2DModel:
    """Mesh the 2-D unit on a regular polygon of ``sides`` sides of length L (module
    docstring); ``nodes``: resolution, the spacing is L / (nodes - 1) (arguments validated
    by the caller, `units.unit2d.build_unit_mesh_2d`)."""
    sides = check_sides(sides)
    check_geometry_polygon(g, sides)
    spacing = g.L / (int(nodes) - 1)
    mesh = Mesh3D(E=g.E, nu=nu)
    frame, mid = _add_frame(mesh, g, sides, spacing, overlaps == "rigid")
    names = side_names(sides)
    feet = [int(frame[n][mid]) for n in names]
    arches, apex, ring = add_cell_arches(mesh, g, polygon_vertices(g.L, sides), feet, names,
                                         spacing, overlaps)
    support = np.array(feet, dtype=np.int64)
    if actuator:
        mesh.rigid.append(ring)
        mesh.fixes.append((apex, "xy"))
    if supports:
        for n in support:
            mesh.fixes.append((int(n), "z"))
    mesh.named.update(push=apex)
    mesh.groups.update({f"side_{k}": v for k, v in frame.items()})
    mesh.groups.update(arches)
    mesh.groups.update(supports=support)
    return Unit2DModel(mesh, None, apex, frame, arches, support, overlaps,
                       released_holds(frame, names, mid, sides), sides)


def add_cell_arches(mesh, g, vertices, feet, names, spacing, overlaps="elastic", prefix="",
                    through=None):
    """Add one cell's arches to ``mesh``: from the midpoint nodes ``feet`` of its sides (in
    the order of the polygon's ``vertices`` (n, 2), counter-clockwise, side k from vertex k
    to k + 1; ``names`` of the sides) to an apex h above the centre (module docstring),
    bonded to the feet and to each other at the apex. Returns ({arch name: nodes}, the apex
    node (the first arch's), the nodes the actuator moves as one (apex first))."""
    V = np.asarray(vertices, dtype=float)
    sides = len(V)
    r = inradius(g.L, sides)
    centre = V.mean(axis=0)
    x0 = arch_flat(g)
    span = 2 * (r - x0)
    jl = float(getattr(g, "joint_length", JOINT_LENGTH_DEFAULT))
    flat = np.concatenate([[0.0], segment_points(np.array([0.5 * g.w, x0]), spacing)]) \
        if x0 > 0.5 * g.w * (1 + 1e-12) else np.array([0.0, x0])
    raised, act, (lo, hi), stiff = arch_raised(x0, span, g.h, spacing, jl, g.w, overlaps)
    # opposite feet: one strip through the apex (``through``: True / False forces it)
    full = sides % 2 == 0 if through is None else bool(through)
    if full:
        u = np.concatenate([flat[:-1], raised, 2 * r - flat[:-1][::-1]])
        pairs = [(k, k + sides // 2) for k in range(sides // 2)]
        ring = slice(len(flat) - 1 + lo, len(flat) - 1 + hi)
    else:
        u = np.concatenate([flat[:-1], raised[:act + 1]])
        pairs = [(k, None) for k in range(sides)]
        ring = slice(len(flat) - 1 + lo, len(u))
    k_apex = len(flat) - 1 + act
    zz = arch_height(u, x0, span, g.h)
    thick = None
    if overlaps == "rigid":  # the feet's first w/2 on the strip, and the crossing
        thick = np.full(len(u) - 1, RIGID_OVERLAP_THICKNESS * g.t)
        thick[1:len(flat) - 1 + stiff[0]] = g.t
        if full:
            thick[len(flat) - 1 + stiff[1]:len(u) - 2] = g.t
    arches = {}
    for k, far in pairs:
        m = 0.5 * (V[k] + V[(k + 1) % sides])
        d = (centre - m) / np.linalg.norm(centre - m)
        name = f"{prefix}arch_{names[k]}" + ("" if far is None else f"_{names[far]}")
        xyz = np.stack([m[0] + u * d[0], m[1] + u * d[1], zz], 1)
        arches[name] = mesh.add_rod(name, xyz, g.w, g.t)
        if thick is not None:
            mesh.rods[-1].thickness = thick
        mesh.bond(arches[name][0], feet[k])
        if far is not None:
            mesh.bond(arches[name][-1], feet[far])
    apexes = [int(a[k_apex]) for a in arches.values()]
    for other in apexes[1:]:
        mesh.bond(apexes[0], other)
    group = [apexes[0]] + [int(n) for a in arches.values() for n in a[ring]
                           if int(n) not in apexes]
    return arches, apexes[0], group


def released_holds(frame, names, mid, sides):
    """A statically determinate set of (node, components) that holds only the rigid-body
    motion of a polygon unit: side 0's midpoint xyz; the frame node straight across from it
    (the opposite midpoint for an even number of sides, the opposite corner for the
    triangle: on the same x) in x and z (no turning about z or x); side 1's midpoint in z
    (no turning about y)."""
    first = int(frame[names[0]][mid])
    across = int(frame[names[sides // 2]][mid]) if sides % 2 == 0 \
        else int(frame[names[1]][-1])
    return [(first, "xyz"), (across, "xz"), (int(frame[names[1]][mid]), "z")]
