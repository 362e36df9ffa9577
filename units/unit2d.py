"""The paper's 2-D unit (its Fig. 9a-b, "left for future work"): a square frame base of side L
made of strips of width w, and two arches joining opposite midpoints of the square's sides,
crossing (and bonded) at the apex, pushed down at the apex. On `solver.Structure3D`.

    >>> from units.unit2d import simulate_unit_2d
    >>> r = simulate_unit_2d(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3))
    >>> r.bistable, r.F_cr, r.edges["iii"]   # per edge: S, theta, mean curvature

Model (x, y in the base plane, z up; SI units; docs/unit3d.md):
- frame: four rods along the sides of the square [0, L]^2 (centrelines), width w, thickness
  t, rigidly jointed at the corners; a node at each side's midpoint;
- arches: "x" along y = L/2 from x = 0 to L, "y" along x = L/2; each flat over its first and
  last b + w/2 (across the frame strip and the extra flat length b), sinusoidal in between,
  apex h at the centre; each end rigidly jointed to the side's midpoint node (the glued
  overlap of the two strips is w x w); the two apex nodes are rigidly jointed (bonded where
  the arches cross);
- overlaps: where two strips meet at right angles (the frame's corners, the arch feet on the
  sides, the arches' crossing) `Structure3D.joint` couples the edge of each rod next to the
  node, and its stiffness is the series of those edges' half lengths, with bending and twist
  of the two rods paired as if they were collinear. With edges of the mesh spacing there
  (as before) that coupling is an extra compliance proportional to the spacing: the model
  converged at first order only (an L-shaped cantilever of two jointed strips: -8.3, -4.4,
  -2.3, -1.1, -0.58 % tip deflection at 5-80 edges per leg, a straight one at second
  order), F_cr 1.271 / 1.250 / 1.240 / 1.234 N at 21 / 41 / 81 / 161 nodes per side, and
  the released warped state, whose curl concentrates at the corners, not at all in practice
  (curled pair 41.6 / 61.7 / 72.2 / 77.5 deg). Now each rod has one edge of fixed length
  over each overlap, whatever the mesh: the first and last w/2 of a side (to the inner edge
  of the crossing strip), the w/2 each side of its midpoint (under the arch foot), the arch
  feet's first w/2 (on the strip), and at the apex the actuator's edges (``joint_length``:
  the straddling edges are ``joint_length / 2`` long, the apex's own two edges half that).
  ``overlaps="elastic"`` (default): those edges have the sheet's stiffness (the overlap is
  lumped on one edge; at 41 nodes and w = L / 20, spacing = w/2, the mesh is the old one);
  ``overlaps="rigid"``: a diagnostic in which the w x w overlaps are rigid (those edges, and
  the crossing's w/2 each side of the apex, `RIGID_OVERLAP_THICKNESS` x thicker; the
  actuator holds the crossing). Both converge at second order.
- actuator: the nodes of both arches within ``joint_length`` of the apex move as one, the
  apex cannot move in x or y, and it is pushed down (-z);
- supports: z held at the four side midpoints, under the arch feet (the analogue of the
  planar unit's rollers next to the bonds).
Metrics of each side ("south" y = 0, "east" x = L, "north" y = L, "west" x = 0) in a state:
the chord S between its corners, theta (signed angle between its end tangents in its
vertical plane, > 0 when the corners rise above the middle, as the planar unit's theta) and
the mean curvature theta / arc length (1/m).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from snapmorph.units.frame3d import JOINT_LENGTH_DEFAULT, PETG_NU, Mesh3D, UnitGeometry
from snapmorph.units.planar import check_flag, check_steps
from snapmorph.units.polygon import (OVERLAPS, RIGID_OVERLAP_THICKNESS, Unit2DModel,
                                     build_polygon_mesh, check_sides)
from snapmorph.units.polygon import arch_raised as _arch_raised
from snapmorph.units.polygon import side_abscissae as _side_abscissae
from snapmorph.units.push3d import level, push_through, record_release, relax_released, transfer_state
from snapmorph.units.result import UnitResultBase
from snapmorph.units.shapes import arch_height, end_tangent_angle, segment_points

__all__ = ["Unit2DModel", "Unit2DResult", "build_unit_mesh_2d", "build_unit_2d",
           "simulate_unit_2d", "edge_metrics", "DEFAULT_NODES_2D", "SIDES"]

#: default resolution: nodes along one side of the square
DEFAULT_NODES_2D = 41
#: how the w x w overlaps of strips meeting at right angles are modelled (module docstring):
#: OVERLAPS; RIGID_OVERLAP_THICKNESS, the thickness of the overlap edges / t with
#: overlaps="rigid", is 1000x the bending stiffness (5x instead moved the released theta by
#: 0.16 deg and F_cr by 0.1 % at 81 nodes), not so stiff that the solver's force scale (set
#: by the stiffest edge) loosens its tolerances more (both in `units.polygon`)
SIDES = ("south", "east", "north", "west")
NAN = float("nan")


def _flat_2d(g):
    return g.b + 0.5 * g.w


def check_geometry_2d(g: UnitGeometry):
    """Extra limits of the 2-D unit (its flat arch ends are b + w/2 long)."""
    if not isinstance(g, UnitGeometry):
        raise ValueError(f"g must be a UnitGeometry; got {type(g).__name__}")
    if g.h <= 0:
        raise ValueError("h (arch apex height, m) must be > 0 for a 2-D unit; got 0")
    span = g.L - 2 * _flat_2d(g)
    if g.h > span:
        raise ValueError(f"h (arch apex height, m) must be <= the arch span L - 2 b - w = "
                         f"{span:.6g} m; got {g.h:.6g} m")
    if not float(getattr(g, "joint_length", JOINT_LENGTH_DEFAULT)) > 0:
        raise ValueError("joint_length (length of arch held by the actuator, m) must be > 0 "
                         "for a 2-D unit (the arches cross at the apex, which must be a node "
                         "between the actuator's edges); got 0")


def build_unit_mesh_2d(g: UnitGeometry, nodes: int = DEFAULT_NODES_2D, nu: float = PETG_NU,
                       actuator: bool = True, supports: bool = True,
                       overlaps: str = "elastic", sides: int = 4) -> Unit2DModel:
    """Mesh the 2-D unit (no solver needed). ``nodes``: resolution, the spacing is
    L / (nodes - 1) (a side has that many nodes when w/2 is a multiple of the spacing, as at
    41 with w = L / 20; each side always has a node at its midpoint). ``overlaps``: "elastic"
    or "rigid" (module docstring). ``sides``: the footprint, 3 (triangle), 4 (the square
    unit, built here as it always was) or 6 (hexagon) sides of length L
    (`units.polygon.build_polygon_mesh`)."""
    sides = check_sides(sides)
    if sides == 4:
        check_geometry_2d(g)
    if overlaps not in OVERLAPS:
        raise ValueError(f"overlaps (model of the w x w overlaps) must be one of {OVERLAPS}; "
                         f"got {overlaps!r}")
    if (isinstance(nodes, bool) or not isinstance(nodes, (int, np.integer))
            or not 11 <= nodes <= 1001):
        raise ValueError(f"nodes (resolution: nodes along a side) must be an integer in "
                         f"[11, 1001]; got {nodes!r}")
    try:
        if isinstance(nu, (bool, np.bool_)):
            raise TypeError
        nu = float(nu)
    except (TypeError, ValueError):
        raise ValueError(f"nu (Poisson's ratio) must be a number; got {nu!r}") from None
    if not -1.0 < nu <= 0.5:
        raise ValueError(f"nu (Poisson's ratio) must be in (-1, 0.5]; got {nu!r}")
    if sides != 4:
        return build_polygon_mesh(g, sides, int(nodes), nu, actuator, supports, overlaps)
    L, w, t = g.L, g.w, g.t
    spacing = L / (int(nodes) - 1)
    s, mid = _side_abscissae(L, w, spacing)  # symmetric, midpoint a node
    z = np.zeros_like(s)
    mesh = Mesh3D(E=g.E, nu=nu)
    sides = {
        "south": mesh.add_rod("south", np.stack([s, z, z], 1), w, t),
        "east": mesh.add_rod("east", np.stack([z + L, s, z], 1), w, t),
        "north": mesh.add_rod("north", np.stack([L - s, z + L, z], 1), w, t),
        "west": mesh.add_rod("west", np.stack([z, L - s, z], 1), w, t),
    }
    rigid = overlaps == "rigid"
    if rigid:  # the overlap edges (per-edge thickness, which Structure3D.add_rod takes)
        side_t = np.full(len(s) - 1, t)
        side_t[[0, mid - 1, mid, len(s) - 2]] = RIGID_OVERLAP_THICKNESS * t
        for rod in mesh.rods:
            rod.thickness = side_t
    order = list(SIDES)
    for a, b in zip(order, order[1:] + order[:1]):  # corners
        mesh.bond(sides[a][-1], sides[b][0])

    x0 = _flat_2d(g)
    span = L - 2 * x0
    jl = float(getattr(g, "joint_length", JOINT_LENGTH_DEFAULT))
    # the arch's first edge is the w/2 it lies on the frame strip, whatever the mesh: the
    # joint at the foot holds that edge's orientation, so the glued overlap stays rigid
    # (meshing it finer left its inner nodes unbonded: F_cr fell 1.7 % per doubling)
    flat = np.concatenate([[0.0], segment_points(np.array([0.5 * w, x0]), spacing)]) \
        if x0 > 0.5 * w * (1 + 1e-12) else np.array([0.0, x0])
    raised, act, (lo, hi), stiff = _arch_raised(x0, span, g.h, spacing, jl, w, overlaps)
    u = np.concatenate([flat[:-1], raised, L - flat[:-1][::-1]])
    zz = arch_height(u, x0, span, g.h)
    c = np.full_like(u, 0.5 * L)
    arches = {
        "x": mesh.add_rod("arch_x", np.stack([u, c, zz], 1), w, t),
        "y": mesh.add_rod("arch_y", np.stack([c, u, zz], 1), w, t),
    }
    if rigid:  # the feet's first w/2 on the strip, and the crossing
        arch_t = np.full(len(u) - 1, t)
        arch_t[[0, len(u) - 2]] = RIGID_OVERLAP_THICKNESS * t
        arch_t[len(flat) - 1 + stiff[0]: len(flat) - 1 + stiff[1]] = RIGID_OVERLAP_THICKNESS * t
        for rod in mesh.rods[-2:]:
            rod.thickness = arch_t
    k_apex = len(flat) - 1 + act
    apex_x, apex_y = int(arches["x"][k_apex]), int(arches["y"][k_apex])
    mesh.bond(apex_x, apex_y)
    # arch feet on the side midpoints: x arch on west (start) and east (end), y arch on south
    # (start) and north (end)
    feet = [(arches["x"][0], sides["west"][mid]), (arches["x"][-1], sides["east"][mid]),
            (arches["y"][0], sides["south"][mid]), (arches["y"][-1], sides["north"][mid])]
    for a, b in feet:
        mesh.bond(a, b)
    support = np.array([int(sides[n][mid]) for n in SIDES], dtype=np.int64)
    ring = slice(len(flat) - 1 + lo, len(flat) - 1 + hi)
    if actuator:
        group = [int(n) for n in arches["x"][ring]]
        group += [int(n) for n in arches["y"][ring] if int(n) != apex_y]
        mesh.rigid.append(group)
        mesh.fixes.append((apex_x, "xy"))
    if supports:
        for n in support:
            mesh.fixes.append((int(n), "z"))
    mesh.named.update(push=apex_x, apex_y=apex_y)
    mesh.groups.update({f"side_{k}": v for k, v in sides.items()})
    mesh.groups.update(arch_x=arches["x"], arch_y=arches["y"], supports=support)
    return Unit2DModel(mesh, None, apex_x, sides, arches, support, overlaps)


def build_unit_2d(g: UnitGeometry, nodes: int = DEFAULT_NODES_2D, **options) -> Unit2DModel:
    """Mesh the 2-D unit (``options`` of `build_unit_mesh_2d`, ``sides`` among them) and
    build its `solver.Structure3D`."""
    model = build_unit_mesh_2d(g, nodes=nodes, **options)
    model.structure = model.mesh.to_structure()
    return model


def edge_metrics(points) -> dict:
    """S (chord between the corners, m), theta (degrees, > 0 when the corners rise above the
    middle), arc length (m), mean curvature theta / arc length (1/m) and the sag of the
    midpoint below the chord (m, > 0 when the middle is lower) of one side (n, 3)."""
    p = np.asarray(points, dtype=float)
    chord = p[-1] - p[0]
    S = float(np.linalg.norm(chord))
    arc = float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
    theta = end_tangent_angle(p)
    m = p[len(p) // 2]
    sag = float(0.5 * (p[0, 2] + p[-1, 2]) - m[2])
    return {"S": S, "theta_deg": theta, "arc_length": arc,
            "curvature": math.radians(theta) / arc, "sag": sag}


@dataclass(repr=False)
class Unit2DResult(UnitResultBase):
    """Metrics of the 2-D unit (SI; NaN where absent): F_cr, d_cr, d_unstable, d_second,
    bistable as the planar unit (`units.result.UnitResultBase`); ``edges[state][side]`` = `edge_metrics` of each side;
    ``shapes[state]`` = {side or "arch_x"/"arch_y": (n, 3) positions}.

    bistable: state (iii) exists and is stable with the actuator unloaded (no negative
    eigenvalue of its tangent stiffness); otherwise ``reason`` says why (status "second
    state unstable: ..." when (iii) exists but is unstable). ``stability``: {"ii", "iii"}
    -> `solver.stability.StateStability` (None: singular), "released" -> negative
    eigenvalues of the released state.
    released: state (iii) with the actuator and the four supports removed, relaxed under no
    load with only the rigid-body motion held (the unit as an array holds it), placed with
    the best-fit plane of the four side midpoints horizontal (`units.push3d.level`):
    {"edges": {side: `edge_metrics`}, "S", "theta_deg", "curvature" (means over the sides,
    as `S`, `theta_deg`, `curvature`), "shapes" (as ``shapes[state]``), "apex_height" (m,
    `apex_height`), "moved" (largest node displacement from (iii), m),
    "first_negative_eigenvalues" (of the equilibrium next to (iii) that Newton finds
    first: > 0 when that symmetric state is unstable and the released state was found by
    leaving it along a mode of negative curvature, as at h/L = 0.4: the frame warps, one
    pair of opposite sides curling much more than the other)}; empty when the released
    unit is not stable or its arches do not stay inverted (then ``self_standing`` is
    False; None when not checked or not bistable).
    """

    geometry: UnitGeometry
    edges: dict = field(default_factory=dict)
    path_status: str = ""
    exact_states: bool = False

    STATE_KEYS = ("curvature",)
    MORE_KEYS = ("curvature_released",)

    @property
    def curvature_released(self) -> float:
        """Mean over the four sides of the mean curvature in the released state (iii), 1/m."""
        return float(self.released.get("curvature", NAN))

    @property
    def theta_deg(self) -> float:
        """Mean over the four sides of theta in state (iii), degrees (NaN if absent)."""
        return _side_mean(self.edges.get("iii"), "theta_deg")

    @property
    def curvature(self) -> float:
        """Mean over the four sides of the mean curvature in state (iii), 1/m."""
        return _side_mean(self.edges.get("iii"), "curvature")

    @property
    def S(self) -> float:
        """Mean over the four sides of the corner-to-corner chord in state (iii), m."""
        return _side_mean(self.edges.get("iii"), "S")

    def _summary_details(self) -> dict:
        out = {}
        for side, m in self.edges.get("iii", {}).items():
            for k, v in m.items():
                out[f"{side}_{k}"] = v
        for side, m in self.released.get("edges", {}).items():
            for k, v in m.items():
                out[f"{side}_{k}_released"] = v
        return out


def _side_mean(edges, key) -> float:
    """Mean over the sides of ``edges[side][key]`` (NaN without edges)."""
    return float(np.mean([m[key] for m in edges.values()])) if edges else NAN


def _state_shapes(model: Unit2DModel, pos) -> dict:
    pos = np.asarray(pos)
    out = {side: pos[n] for side, n in model.sides.items()}
    # the square unit's arches are "x" and "y" (shapes "arch_x", "arch_y"); a polygon
    # unit's are named "arch_<side>[_<side>]" already
    out.update({k if k.startswith("arch_") else f"arch_{k}": pos[v]
                for k, v in model.arches.items()})
    out["rods"] = {rod.name: pos[rod.nodes] for rod in model.mesh.rods}
    return out


def _mean_metrics(edges: dict) -> dict:
    return {k: _side_mean(edges, k) for k in ("S", "theta_deg", "curvature")}


def released_supports_2d(model: Unit2DModel):
    """A statically determinate set of supports that holds only the rigid-body motion of the
    2-D unit: (node, components) at the side midpoints (where the supports were): south x,
    y, z; north x, z (no turning about z or x); east z (no turning about y). Under no load
    their reactions vanish, so they place the released unit without straining it. A polygon
    unit's own set when it has one (``model.holds``, `units.polygon.released_holds`)."""
    if model.holds is not None:
        return list(model.holds)
    south, east, north, _ = (int(n) for n in model.supports)
    return [(south, "xyz"), (north, "xz"), (east, "z")]


def apex_height(model: Unit2DModel, positions) -> float:
    """Height (m) of the apex above the mean height of the four side midpoints: h in the
    stress-free state, < 0 in the second state (the arches inverted)."""
    P = np.asarray(positions)
    return float(P[model.push_node, 2] - np.mean(P[model.supports, 2]))


def released_state_2d(g, model: Unit2DModel, q_iii, nodes, nu):
    """State (iii) of ``model`` (full state ``q_iii``) released: the unit rebuilt without
    actuator and supports, its rigid-body motion held by `released_supports_2d`, relaxed
    under no load (`units.push3d.relax_released`). It is self-standing when that state is
    stable and the apex stays nearer its height in (iii) than its stress-free height h
    (`apex_height`; not the planar unit's "moves less than h / 4": the released frame may
    warp by more than that while the arches stay inverted). Returns (self_standing,
    released dict or None, negative eigenvalues or None, why not self-standing ("" when it
    is))."""
    free = build_unit_mesh_2d(g, nodes=nodes, nu=nu, actuator=False, supports=False,
                              overlaps=model.overlaps, sides=model.n_sides)
    st = free.mesh.to_structure()  # same rods, same node numbers (the actuator adds no rod)
    for node, comps in released_supports_2d(free):
        st.fix(node, comps)
    q0 = transfer_state(model.mesh, q_iii, free.mesh, st)
    q, neg, moved, why, first = relax_released(st, q0)
    if why:
        return False, None, neg, why
    # placed as the actuated unit stands: the side midpoints' best-fit plane at z = 0 (the
    # metrics below measure angles against the vertical)
    pos = level(st.positions_of(q), free.supports, free.mesh.positions)
    z_iii = apex_height(free, st.positions_of(q0))
    z_rel = apex_height(free, pos)
    if not z_rel < 0.5 * (g.h + z_iii):
        return False, None, neg, (f"without the actuator the apex rises to {z_rel:.3g} m above "
                                  "the side midpoints: the unit does not stay in its second "
                                  "state")
    edges = {side: edge_metrics(pos[n]) for side, n in free.sides.items()}
    rel = {"edges": edges, **_mean_metrics(edges), "shapes": _state_shapes(free, pos),
           "apex_height": z_rel, "moved": moved, "first_negative_eigenvalues": first}
    return True, rel, neg, ""


def simulate_unit_2d(g: UnitGeometry, nodes: int | None = None, nu: float = PETG_NU,
                     steps: int = 60, critical: bool = False,
                     check_self_standing: bool = True,
                     overlaps: str = "elastic", sides: int = 4) -> Unit2DResult:
    """Push the 2-D unit's apex down until it snaps; F_cr, the d's and each side's S, theta
    and curvature in the second stable state, and (``check_self_standing``) in the released
    state (iii) (actuator and supports removed; see `Unit2DResult`). ``overlaps``: "elastic"
    (default) or "rigid" w x w overlaps (module docstring); ``sides``: the footprint, 3, 4
    (default: the square unit) or 6 (`units.polygon`; per-side metrics under its side
    names). Arguments are validated (ValueError naming the parameter); failures of the
    solve come back in ``status``."""
    nodes = DEFAULT_NODES_2D if nodes is None else nodes
    check_steps(steps)
    critical = check_flag("critical", critical)
    check_self_standing = check_flag("check_self_standing", check_self_standing)
    t0 = time.perf_counter()
    model = build_unit_2d(g, nodes=nodes, nu=nu, overlaps=overlaps, sides=sides)
    out = push_through(model.structure, model.push_node, 3.0 * g.h, steps=int(steps),
                       critical=critical)
    r = Unit2DResult(g, out.status, bistable=out.bistable, F_cr=out.F_cr, d_cr=out.d_cr,
                     d_unstable=out.d_unstable, d_second=out.d_second, curve=out.curve,
                     path_status=out.path_status, exact_states=out.exact_states,
                     reason=out.reason, stability=dict(out.stability))
    states = dict(out.states)
    states["0"] = model.mesh.positions
    for state, pos in states.items():
        pos = np.asarray(pos)
        r.shapes[state] = _state_shapes(model, pos)
        if state == "iii" and not r.bistable:
            continue  # as the planar unit: the shape, but no S or theta of an unstable (iii)
        r.edges[state] = {side: edge_metrics(pos[n]) for side, n in model.sides.items()}
    if r.bistable and check_self_standing:
        record_release(r, lambda: released_state_2d(g, model, out.full_states["iii"], nodes, nu))
    r.solve_time = time.perf_counter() - t0
    r.n_nodes = model.mesh.n_nodes
    return r
