"""The design-map pipeline: kinds of map (`pipeline.kinds`, registered in `pipeline.solvers`),
and the dask-driven, checkpointed build that writes their netCDF files.

    from snapmorph.pipeline import preset, build_map
    build_map(preset("ci"), "maps/data/ci.nc")

`Grid`, `PRESETS` and `preset` are the planar unit's grids (`pipeline.kinds.unit`);
`build_map`, `BuildReport`, `solve_point` and the registry (`SolverSpec`, `MapGrid`,
`get_spec`, `register`; see `pipeline.solvers`) are imported on first use, so that importing
the package stays cheap (no dask, xarray or solver at import time).
"""

if __name__ != "snapmorph.pipeline":  # imported under its pre-0.2 top-level name `pipeline`
    from _snapmorph_legacy import alias_old_name  # warns, then hands out snapmorph.pipeline

    alias_old_name(__name__)

from snapmorph.maps.schema import SCHEMA_VERSION
from snapmorph.pipeline.kinds.unit import PRESETS, Grid, preset

__all__ = ["Grid", "PRESETS", "preset", "SCHEMA_VERSION", "build_map", "BuildReport", "solve_point",
           "SolverSpec", "MapGrid", "get_spec", "register"]

_LAZY = {"build_map": "snapmorph.pipeline.build", "BuildReport": "snapmorph.pipeline.build",
         "solve_point": "snapmorph.pipeline.kinds.unit", "SolverSpec": "snapmorph.pipeline.solvers",
         "MapGrid": "snapmorph.pipeline.solvers", "get_spec": "snapmorph.pipeline.solvers",
         "register": "snapmorph.pipeline.solvers"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'pipeline' has no attribute {name!r}")
