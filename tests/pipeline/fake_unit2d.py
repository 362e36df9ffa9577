"""A fake point solver of another kind (a 2-D unit over h/L and t/L), registered through
`pipeline.solvers.SolverSpec`: the pipeline must build its map with its own schema section.

- h/L < 0.15: monostable (F_cr only); the point (0.30, 0.01): not converged;
- else ok with analytic F_cr, S_edge and a 4-value edge_curvature array (one per edge).
FAKE2D_LOG=path appends "h t resolution time_limit" per call.
"""

import math
import os

import numpy as np

from snapmorph.pipeline.solvers import MapGrid, SolverSpec

FAILED_POINT = (0.30, 0.01)


def fields(h, t):
    return {"F_cr": 10.0 * h / t, "S_edge": 1.0 - h * h}


def curvature(h, t):
    return np.array([1.0, -1.0, 2.0, -2.0]) * h / (1.0 + 100.0 * t)


def solve(h_over_L, t_over_L, *, resolution, n_edges, time_limit=None):
    log = os.environ.get("FAKE2D_LOG")
    if log:
        with open(log, "a") as f:
            f.write(f"{h_over_L!r} {t_over_L!r} {resolution!r} {time_limit!r}\n")
    nan = math.nan
    rec = {"F_cr": nan, "S_edge": nan, "bistable": 0, "edge_curvature": np.full(n_edges, nan),
           "message": ""}
    if abs(h_over_L - FAILED_POINT[0]) < 1e-12 and abs(t_over_L - FAILED_POINT[1]) < 1e-12:
        return {**rec, "status": 2, "message": "not converged (fake 2-D)"}
    f = fields(h_over_L, t_over_L)
    if h_over_L < 0.15:
        return {**rec, "status": 1, "F_cr": f["F_cr"]}
    return {**rec, **f, "status": 0, "bistable": 1, "edge_curvature": curvature(h_over_L, t_over_L)}


def small():
    return MapGrid({"h_over_L": (0.1, 0.2, 0.3), "t_over_L": (0.005, 0.01)}, {"resolution": 31},
                   name="small")


SPEC = SolverSpec(
    name="fake2d",
    solve="fake_unit2d:solve",
    dims=("h_over_L", "t_over_L"),
    float_vars={"F_cr": ("1", "critical force, normalised"), "S_edge": ("1", "edge chord / L")},
    flag_vars={"bistable": ("1", "1 when bistable")},
    array_vars={"edge_curvature": (("edge",), ("n_edges",), "1", "curvature of each edge times L")},
    status_codes={0: "ok", 1: "monostable", 2: "not_converged", 4: "timeout"},
    required_when_ok=("F_cr", "S_edge", "edge_curvature"),
    options={"resolution": 21, "n_edges": 4},
    presets={"small": "fake_unit2d:small"},
    sources=("fake_unit2d",),
    schema_version=1,
    title="fake 2-D unit map",
    dim_attrs={"h_over_L": ("1", "apex height / L"), "t_over_L": ("1", "thickness / L")},
)
