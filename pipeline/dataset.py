"""Assemble a block over all grid points into the schema-2 xarray Dataset and write it.

The assembler does no physics: it reshapes, labels (CF `units`, `long_name`, status flags) and
writes compressed netCDF4 atomically.
"""

from __future__ import annotations

import datetime as _dt
import os
import subprocess
from pathlib import Path

import numpy as np
import xarray as xr

from snapmorph.pipeline.batch import INT_VARS
from snapmorph.pipeline.grid import Grid
from snapmorph.pipeline.point import E_REF, L_REF, model_options
from snapmorph.pipeline.schema import (
    COORD_ATTRS, FLAG_VARS, FLOAT_VARS, GRID_DIMS, NORMALISATION, SCHEMA_VERSION, SHAPE_ATTRS,
    SHAPE_VARS, SOLVE_TIME_ATTRS, STATUS_ATTRS,
)


def utc_now() -> str:
    """Current time, ISO 8601 UTC to the second."""
    return _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()


def git_commit() -> str:
    """`git rev-parse HEAD` of the source tree, or "unknown"."""
    here = Path(__file__).resolve().parent
    try:
        r = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True,
                           text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return r.stdout.strip() if r.returncode == 0 and r.stdout.strip() else "unknown"


def package_version() -> str:
    from snapmorph import __version__

    return __version__


def provenance() -> dict:
    """What a new build records: start time, package version, git commit."""
    return {"created": utc_now(), "package_version": package_version(), "git_commit": git_commit()}


def global_attrs(grid: Grid, prov: dict) -> dict:
    """The schema's global attributes for a map of `grid` built with provenance `prov`."""
    return {
        "title": f"snapmorph design map of the bistable arch-on-base unit (grid {grid.name})",
        "schema_version": np.int32(SCHEMA_VERSION),
        "grid": grid.name,
        "b_over_L": float(grid.b_over_L),
        # the resolution used (prov["resolution"], the solver default resolved at the start);
        # netCDF has no None: -1 means "the solver's default, which it did not state"
        "resolution": np.int32(_resolution(grid, prov)),
        "package_version": prov["package_version"],
        "git_commit": prov["git_commit"],
        "created": prov["created"],
        "normalisation": NORMALISATION,
        "E_reference": float(E_REF),
        "L_reference": float(L_REF),
        **model_options(),
    }


def _resolution(grid: Grid, prov: dict) -> int:
    r = prov.get("resolution", grid.resolution)
    return -1 if r is None else int(r)


def assemble(grid: Grid, total: dict, attrs: dict) -> xr.Dataset:
    """The Dataset of a block `total` over all points (index = arange(grid.size))."""
    shape = grid.shape
    coords = {
        "h_over_L": ("h_over_L", np.asarray(grid.h_over_L), COORD_ATTRS["h_over_L"]),
        "t_over_L": ("t_over_L", np.asarray(grid.t_over_L), COORD_ATTRS["t_over_L"]),
        "w_over_L": ("w_over_L", np.asarray(grid.w_over_L), COORD_ATTRS["w_over_L"]),
        "sample": ("sample", np.arange(grid.samples, dtype=np.int32), COORD_ATTRS["sample"]),
        "xz": ("xz", np.array(["x", "z"]), COORD_ATTRS["xz"]),
    }
    order = np.argsort(total["index"])
    if not np.array_equal(total["index"][order], np.arange(grid.size)):
        raise ValueError(f"result block does not cover the {grid.size} grid points exactly once")
    data = {}
    for name, (units, long_name) in FLOAT_VARS.items():
        data[name] = (GRID_DIMS, total[name][order].reshape(shape), {"units": units, "long_name": long_name})
    for name, (units, long_name) in FLAG_VARS.items():
        data[name] = (GRID_DIMS, total[name][order].astype(np.int8).reshape(shape),
                      {"units": units, "long_name": long_name})
    data["status"] = (GRID_DIMS, total["status"][order].astype(np.int8).reshape(shape), dict(STATUS_ATTRS))
    for name in SHAPE_VARS:
        data[name] = ((*GRID_DIMS, "sample", "xz"),
                      total[name][order].reshape(*shape, grid.samples, 2), dict(SHAPE_ATTRS[name]))
    data["solve_time"] = (GRID_DIMS, total["solve_time"][order].reshape(shape), dict(SOLVE_TIME_ATTRS))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def encoding(ds: xr.Dataset) -> dict:
    """zlib-compressed variables; no _FillValue on integer or coordinate variables."""
    enc = {}
    for name, var in ds.variables.items():
        if name in ds.coords:
            enc[name] = {"_FillValue": None}
        elif name in INT_VARS:
            enc[name] = {"zlib": True, "complevel": 4, "shuffle": True, "_FillValue": None}
        else:
            enc[name] = {"zlib": True, "complevel": 4, "shuffle": True, "_FillValue": np.nan}
    return enc


def write_netcdf(ds: xr.Dataset, path) -> None:
    """Write `ds` as compressed netCDF4 to `path` atomically (temp file + os.replace)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.partial")  # git-ignored if left behind
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding(ds))
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


__all__ = ["assemble", "write_netcdf", "global_attrs", "provenance"]
