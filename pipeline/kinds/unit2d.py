"""The 2-D units (`units.unit2d`: a frame on a regular polygon of side L, arches from every
side's midpoint to one apex) as kinds of map over (h/L, t/L), one kind per footprint:
`unit2d` the paper's square unit (two crossing arches), `unit2d_triangle`, `unit2d_hexagon`.

    snapmorph maps build --kind unit2d --grid small --out maps/data/unit2d-square-small.nc
    snapmorph maps build --kind unit2d_triangle --grid small \
        --out maps/data/unit2d-triangle-small.nc
    snapmorph maps build --kind unit2d_hexagon --grid small \
        --out maps/data/unit2d-hexagon-small.nc

`solve_map_point` simulates one unit and returns its dimensionless record (it never raises);
`unit2d_spec(sides)` is a kind's schema section (`SPEC`, `TRIANGLE`, `HEXAGON`): in state
(iii) the mean over the sides of S / L, theta and curvature x L, the spread of theta between
the sides and the per-side values, the same in the released state (iii) (actuator and
supports removed) where it is self-standing. The number of sides is the file's `sides`
attribute; the `side` coordinate numbers the sides in `units.polygon.side_names` order.
"""

from __future__ import annotations

import math

import numpy as np

from snapmorph.pipeline.solvers import MapGrid, SolverSpec, failure_statuses, status_codes
from snapmorph.units import status as unit_status
from snapmorph.units.frame3d import UnitGeometry
from snapmorph.units.polygon import check_geometry_polygon, side_names
from snapmorph.units.unit2d import DEFAULT_NODES_2D, check_geometry_2d, simulate_unit_2d

#: reference base length (m) of the SI geometry; the normalised outputs do not depend on it
L_REF = 0.1


#: the footprints with a kind of map: sides -> (kind name, footprint)
FOOTPRINTS = {4: ("unit2d", "square"), 3: ("unit2d_triangle", "triangle"),
              6: ("unit2d_hexagon", "hexagon")}


def _per_side(edges, L, sides=4):
    """(spread of theta between the sides (deg), theta of each side, curvature x L of each
    side) of the edge metrics of one state; NaN when the state has none."""
    names = side_names(sides)
    if not edges:
        return math.nan, np.full(sides, math.nan), np.full(sides, math.nan)
    th = np.array([edges[s]["theta_deg"] for s in names])
    return float(np.ptp(th)), th, np.array([edges[s]["curvature"] * L for s in names])


def solve_map_point(h_over_L, t_over_L, w_over_L=0.05, b_over_L=0.0, resolution=DEFAULT_NODES_2D,
                    time_limit=None, sides=4) -> dict:
    """One point of the map of the 2-D unit on a footprint of ``sides`` sides (3, 4, 6),
    dimensionless (L = 0.1 m, E = PETG; the results are scale free): F_cr L^2 / (E I) with
    I = w t^3 / 12, d / L, and in state (iii) the mean over the sides of S / L, theta (deg)
    and curvature x L, and the largest difference of theta between sides (deg; 0 for a
    symmetric second state); self_standing and the same means, spread and per-side values in
    the released state (iii) (actuator and supports removed), where it is self-standing.
    Never raises."""
    L = L_REF
    rec = {"status": unit_status.NOT_CONVERGED, "message": ""}
    try:
        g = UnitGeometry(L=L, h=h_over_L * L, t=t_over_L * L, w=w_over_L * L, b=b_over_L * L)
        if sides == 4:
            check_geometry_2d(g)
        else:
            check_geometry_polygon(g, sides)
    except ValueError as exc:
        return {"status": unit_status.INVALID_GEOMETRY, "message": str(exc)}
    try:
        r = simulate_unit_2d(g, nodes=int(resolution), sides=sides)
    except Exception as exc:  # noqa: BLE001 - a map point never raises
        return {"status": unit_status.NOT_CONVERGED, "message": f"{type(exc).__name__}: {exc}"}
    EI = g.E * g.w * g.t**3 / 12.0
    rec.update(F_cr=r.F_cr * L**2 / EI, d_cr=r.d_cr / L, d_unstable=r.d_unstable / L,
               d_second=r.d_second / L, S=r.S / L, theta=r.theta_deg,
               curvature=r.curvature * L, message=r.status if r.status != "ok" else "")
    rec["theta_spread"], rec["edge_theta"], rec["edge_curvature"] = _per_side(
        r.edges.get("iii"), L, sides)
    rel = r.released.get("edges") if r.self_standing else None
    rec.update(S_released=r.S_released / L, theta_released=r.theta_released_deg,
               curvature_released=r.curvature_released * L)
    (rec["theta_spread_released"], rec["edge_theta_released"],
     rec["edge_curvature_released"]) = _per_side(rel, L, sides)
    # the map's code of the result's status; a status text of no known name is a failure
    rec["status"] = unit_status.status_code(r.status)
    if rec["status"] not in (unit_status.OK, *unit_status.NOT_BISTABLE):
        rec["status"] = unit_status.NOT_CONVERGED
    rec["bistable"] = 1 if r.bistable else (0 if rec["status"] in unit_status.NOT_BISTABLE else -1)
    rec["self_standing"] = -1 if r.self_standing is None else int(bool(r.self_standing))
    return rec


def _preset_small() -> MapGrid:
    return MapGrid({"h_over_L": (0.25, 0.3, 0.35, 0.4, 0.45),
                    "t_over_L": (0.004, 0.005, 0.0075)}, name="small")


def _preset_ci() -> MapGrid:
    return MapGrid({"h_over_L": (0.3, 0.4), "t_over_L": (0.005, 0.0075)}, {"resolution": 21},
                   name="ci")


def _triangle_small() -> MapGrid:
    # the triangle is bistable only next to the declared domain's edge, h = its arch span
    # 2 (r - b - w/2) = 0.527 L at w = L / 20, and only in thin sheets (docs/sheets.md: the
    # scan of the whole domain)
    return MapGrid({"h_over_L": TRIANGLE_H, "t_over_L": (0.0025, 0.005)}, name="small")


def _triangle_ci() -> MapGrid:
    # points of the small map at its resolution: a rebuild must reproduce them bit for bit
    return MapGrid({"h_over_L": TRIANGLE_H[-2:], "t_over_L": (0.0025, 0.005)}, name="ci")


def _hexagon_small() -> MapGrid:
    return MapGrid({"h_over_L": (0.1, 0.2, 0.3, 0.5, 0.8), "t_over_L": (0.005, 0.0075)},
                   name="small")


def _hexagon_ci() -> MapGrid:
    return MapGrid({"h_over_L": (0.2, 0.4), "t_over_L": (0.005, 0.0075)}, {"resolution": 21},
                   name="ci")


#: h/L of the triangle's small map
TRIANGLE_H = (0.3, 0.4, 0.5, 0.51, 0.515, 0.52, 0.525)
_IN_III = "in state (iii)"
_RELEASED = "in the released state (iii)"


def solve_triangle_point(h_over_L, t_over_L, **options) -> dict:
    """`solve_map_point` of the unit on a triangle (3 sides)."""
    return solve_map_point(h_over_L, t_over_L, **options, sides=3)


def solve_hexagon_point(h_over_L, t_over_L, **options) -> dict:
    """`solve_map_point` of the unit on a hexagon (6 sides)."""
    return solve_map_point(h_over_L, t_over_L, **options, sides=6)


def unit2d_spec(sides: int) -> SolverSpec:
    """The kind of map of the 2-D unit on a footprint of ``sides`` sides (`FOOTPRINTS`)."""
    name, footprint = FOOTPRINTS[sides]
    solve, presets = {4: (solve_map_point, {"small": _preset_small, "ci": _preset_ci}),
                      3: (solve_triangle_point, {"small": _triangle_small, "ci": _triangle_ci}),
                      6: (solve_hexagon_point, {"small": _hexagon_small, "ci": _hexagon_ci}),
                      }[sides]
    each = f"the {sides}" if sides != 4 else "the four"
    names = ", ".join(side_names(sides))
    arches = ("two crossing arches" if sides == 4
              else f"arches from the {sides} side midpoints to one apex")
    return SolverSpec(
        name=name,
        solve=solve,
        dims=("h_over_L", "t_over_L"),
        float_vars={
            "F_cr": ("1", "critical force before snap through, F_cr L^2 / (E w t^3 / 12)"),
            "d_cr": ("1", "apex displacement at F_cr, d_cr / L"),
            "d_unstable": ("1", "apex displacement of the unstable state (ii), d / L"),
            "d_second": ("1", "apex displacement of the second stable state (iii), d / L"),
            "S": ("1", f"corner-to-corner chord of a side {_IN_III}, mean of {each}, S / L"),
            "theta": ("degree", f"angle between the end tangents of a side {_IN_III}, mean"),
            "curvature": ("1", f"mean curvature of a side {_IN_III} times L, mean of {each}"),
            "theta_spread": ("degree", "largest difference of theta between the sides in (iii)"),
            "S_released": ("1", f"chord of a side {_RELEASED} (actuator and supports removed), "
                                f"mean of {each}, S / L"),
            "theta_released": ("degree", f"angle between the end tangents of a side "
                                         f"{_RELEASED}, mean of {each}"),
            "curvature_released": ("1", f"mean curvature of a side {_RELEASED} times L, mean of "
                                        f"{each}"),
            "theta_spread_released": ("degree", "largest difference of theta between the sides "
                                                f"{_RELEASED}"),
        },
        flag_vars={"bistable": ("1", "1 when the second stable state (iii) exists and is "
                                     "stable, 0 when not (monostable or (iii) unstable)"),
                   "self_standing": ("1", "1 when state (iii) stays stable, arches inverted, "
                                          "with the actuator and supports removed; 0 when "
                                          "not; -1 unknown or not bistable")},
        array_vars={
            "edge_theta": (("side",), (sides,), "degree",
                           f"theta of each side ({names}) {_IN_III}"),
            "edge_curvature": (("side",), (sides,), "1",
                               f"mean curvature of each side {_IN_III} times L"),
            "edge_theta_released": (("side",), (sides,), "degree",
                                    f"theta of each side {_RELEASED}"),
            "edge_curvature_released": (("side",), (sides,), "1",
                                        f"mean curvature of each side {_RELEASED} times L"),
        },
        dim_attrs={"h_over_L": ("1", "arch apex height over the side length, h / L"),
                   "t_over_L": ("1", "sheet thickness over the side length, t / L"),
                   "side": ("1", f"side of the footprint, counter-clockwise ({names})")},
        status_codes=status_codes(),
        failure_statuses=failure_statuses(),
        required_when_ok=("F_cr", "d_cr", "d_unstable", "d_second", "S", "theta", "curvature",
                          "edge_theta", "edge_curvature"),
        options={"w_over_L": 0.05, "b_over_L": 0.0, "resolution": DEFAULT_NODES_2D},
        presets=presets,
        # the 2-D unit model and this module (with the modules they import: the solver, the
        # 3-D frame, the polygon meshes, the push-through, ...)
        sources=(__name__,),
        title=f"snapmorph map of the 2-D unit on a {footprint} ({arches})",
        attrs={"sides": sides, "footprint": footprint},
    )


#: the square unit (the paper's), the triangle and the hexagon
SPEC = unit2d_spec(4)
TRIANGLE = unit2d_spec(3)
HEXAGON = unit2d_spec(6)
