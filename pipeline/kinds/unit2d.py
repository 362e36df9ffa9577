"""The paper's 2-D unit (`units.unit2d`: a square frame, two crossing arches) as a kind of map
over (h/L, t/L).

    snapmorph maps build --kind unit2d --grid small --out maps/data/unit2d.nc

`solve_map_point` simulates one unit and returns its dimensionless record (it never raises);
`SPEC` is its schema section: in state (iii) the mean over the four sides of S / L, theta and
curvature x L, the spread of theta between the sides and the per-side values, the same in the
released state (iii) (actuator and supports removed) where it is self-standing.
"""

from __future__ import annotations

import math

import numpy as np

from snapmorph.pipeline.solvers import MapGrid, SolverSpec, failure_statuses, status_codes
from snapmorph.units import status as unit_status
from snapmorph.units.frame3d import UnitGeometry
from snapmorph.units.unit2d import DEFAULT_NODES_2D, SIDES, check_geometry_2d, simulate_unit_2d

#: reference base length (m) of the SI geometry; the normalised outputs do not depend on it
L_REF = 0.1


def _per_side(edges, L):
    """(spread of theta between the sides (deg), theta of each side, curvature x L of each
    side) of the edge metrics of one state; NaN when the state has none."""
    if not edges:
        return math.nan, np.full(len(SIDES), math.nan), np.full(len(SIDES), math.nan)
    th = np.array([edges[s]["theta_deg"] for s in SIDES])
    return float(np.ptp(th)), th, np.array([edges[s]["curvature"] * L for s in SIDES])


def solve_map_point(h_over_L, t_over_L, w_over_L=0.05, b_over_L=0.0, resolution=DEFAULT_NODES_2D,
                    time_limit=None) -> dict:
    """One point of the 2-D unit's map, dimensionless (L = 0.1 m, E = PETG; the results are
    scale free): F_cr L^2 / (E I) with I = w t^3 / 12, d / L, and in state (iii) the mean over
    the sides of S / L, theta (deg) and curvature x L, and the largest difference of theta
    between sides (deg; 0 for a symmetric second state); self_standing and the same means,
    spread and per-side values in the released state (iii) (actuator and supports removed),
    where it is self-standing. Never raises."""
    L = L_REF
    rec = {"status": unit_status.NOT_CONVERGED, "message": ""}
    try:
        g = UnitGeometry(L=L, h=h_over_L * L, t=t_over_L * L, w=w_over_L * L, b=b_over_L * L)
        check_geometry_2d(g)
    except ValueError as exc:
        return {"status": unit_status.INVALID_GEOMETRY, "message": str(exc)}
    try:
        r = simulate_unit_2d(g, nodes=int(resolution))
    except Exception as exc:  # noqa: BLE001 - a map point never raises
        return {"status": unit_status.NOT_CONVERGED, "message": f"{type(exc).__name__}: {exc}"}
    EI = g.E * g.w * g.t**3 / 12.0
    rec.update(F_cr=r.F_cr * L**2 / EI, d_cr=r.d_cr / L, d_unstable=r.d_unstable / L,
               d_second=r.d_second / L, S=r.S / L, theta=r.theta_deg,
               curvature=r.curvature * L, message=r.status if r.status != "ok" else "")
    rec["theta_spread"], rec["edge_theta"], rec["edge_curvature"] = _per_side(r.edges.get("iii"), L)
    rel = r.released.get("edges") if r.self_standing else None
    rec.update(S_released=r.S_released / L, theta_released=r.theta_released_deg,
               curvature_released=r.curvature_released * L)
    (rec["theta_spread_released"], rec["edge_theta_released"],
     rec["edge_curvature_released"]) = _per_side(rel, L)
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


_IN_III = "in state (iii)"
_RELEASED = "in the released state (iii)"

SPEC = SolverSpec(
    name="unit2d",
    solve=solve_map_point,
    dims=("h_over_L", "t_over_L"),
    float_vars={
        "F_cr": ("1", "critical force before snap through, F_cr L^2 / (E w t^3 / 12)"),
        "d_cr": ("1", "apex displacement at F_cr, d_cr / L"),
        "d_unstable": ("1", "apex displacement of the unstable state (ii), d / L"),
        "d_second": ("1", "apex displacement of the second stable state (iii), d / L"),
        "S": ("1", f"corner-to-corner chord of a side {_IN_III}, mean of the four, S / L"),
        "theta": ("degree", f"angle between the end tangents of a side {_IN_III}, mean"),
        "curvature": ("1", f"mean curvature of a side {_IN_III} times L, mean of the four"),
        "theta_spread": ("degree", "largest difference of theta between the sides in (iii)"),
        "S_released": ("1", f"chord of a side {_RELEASED} (actuator and supports removed), "
                            "mean of the four, S / L"),
        "theta_released": ("degree", f"angle between the end tangents of a side {_RELEASED}, "
                                     "mean of the four"),
        "curvature_released": ("1", f"mean curvature of a side {_RELEASED} times L, mean of "
                                    "the four"),
        "theta_spread_released": ("degree", "largest difference of theta between the sides "
                                            f"{_RELEASED}"),
    },
    flag_vars={"bistable": ("1", "1 when the second stable state (iii) exists and is "
                                 "stable, 0 when not (monostable or (iii) unstable)"),
               "self_standing": ("1", "1 when state (iii) stays stable, arches inverted, "
                                      "with the actuator and supports removed; 0 when "
                                      "not; -1 unknown or not bistable")},
    array_vars={
        "edge_theta": (("side",), (len(SIDES),), "degree",
                       f"theta of each side ({', '.join(SIDES)}) {_IN_III}"),
        "edge_curvature": (("side",), (len(SIDES),), "1",
                           f"mean curvature of each side {_IN_III} times L"),
        "edge_theta_released": (("side",), (len(SIDES),), "degree",
                                f"theta of each side {_RELEASED}"),
        "edge_curvature_released": (("side",), (len(SIDES),), "1",
                                    f"mean curvature of each side {_RELEASED} times L"),
    },
    status_codes=status_codes(),
    failure_statuses=failure_statuses(),
    required_when_ok=("F_cr", "d_cr", "d_unstable", "d_second", "S", "theta", "curvature",
                      "edge_theta", "edge_curvature"),
    options={"w_over_L": 0.05, "b_over_L": 0.0, "resolution": DEFAULT_NODES_2D},
    presets={"small": _preset_small, "ci": _preset_ci},
    # the 2-D unit model and this module (with the modules they import: the solver, the 3-D
    # frame, the push-through, ...)
    sources=(__name__,),
    title="snapmorph map of the 2-D unit (square frame, two crossing arches)",
)
