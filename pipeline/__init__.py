"""The design-map pipeline: grids, the point solver, and the dask-driven, checkpointed build.

    from pipeline import preset, build_map
    build_map(preset("ci"), "maps/data/ci.nc")

`build_map`, `BuildReport`, `solve_point` and the point-solver registry (`SolverSpec`,
`MapGrid`, `get_spec`, `register`; see `pipeline.solvers`) are imported on first use, so that importing the
package stays cheap (no dask, xarray or solver at import time).
"""

from pipeline.grid import Grid, PRESETS, preset
from pipeline.schema import SCHEMA_VERSION

__all__ = ["Grid", "PRESETS", "preset", "SCHEMA_VERSION", "build_map", "BuildReport", "solve_point",
           "SolverSpec", "MapGrid", "get_spec", "register"]

_LAZY = {"build_map": "pipeline.build", "BuildReport": "pipeline.build", "solve_point": "pipeline.point",
         "SolverSpec": "pipeline.solvers", "MapGrid": "pipeline.solvers", "get_spec": "pipeline.solvers",
         "register": "pipeline.solvers"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'pipeline' has no attribute {name!r}")
