"""The map file of any kind: assemble a block over all grid points into an xarray Dataset and
write it as compressed netCDF4, atomically.

The assembler does no physics: it reshapes, labels (CF `units`, `long_name`, status
`flag_values` / `flag_meanings` from the kind's status codes) and adds the global attributes.
The file's bytes are decided here and by the kind's spec, never by the clock or the checkout:
see `pipeline.build` for what a build records. netCDF-C does not store HDF5 object times, so
the same Dataset written twice gives the same bytes; the file's hidden `_NCProperties`
attribute names the netCDF-C and HDF5 versions, so the bytes are those of one library build.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from snapmorph.maps.schema import SOLVE_TIME_ATTRS, status_attrs
# the version a map records is a build input, so it lives with the fingerprint
from snapmorph.pipeline.fingerprint import UNKNOWN_VERSION, canonical, package_version


def provenance() -> dict:
    """What a new build records of itself: the package version, and "created" and
    "git_commit" as `fingerprint.RECORDED_PROVENANCE` (not the clock or the checkout: a map's
    bytes depend only on its inputs)."""
    from snapmorph.pipeline.fingerprint import RECORDED_PROVENANCE

    return {**RECORDED_PROVENANCE, "package_version": package_version()}


def generic_attrs(spec, grid, options: dict, provenance: dict) -> dict:
    """The global attributes of a map of a kind without its own `global_attrs` hook."""
    return {"title": f"{spec.title or 'snapmorph map of kind ' + spec.name} (grid {grid.name})",
            "schema_version": np.int32(spec.schema_version), "grid": grid.name,
            "package_version": provenance["package_version"], "git_commit": provenance["git_commit"],
            "created": provenance["created"], "model_options": canonical(options), **spec.attrs}


def assemble(spec, grid, total: dict, options: dict, provenance: dict) -> xr.Dataset:
    """The Dataset of the block `total` over all points of `grid` (index = arange(grid.size))
    of kind `spec` built with the resolved model `options`; `provenance` holds "created",
    "package_version" and "git_commit". Coordinates and variables carry CF `units` and
    `long_name`; extra dimensions of the array variables get their `dim_labels` (else
    0, 1, ...)."""
    shape = grid.shape
    order = np.argsort(total["index"])
    if not np.array_equal(total["index"][order], np.arange(grid.size)):
        raise ValueError(f"result block does not cover the {grid.size} grid points exactly once")

    def coord(dim, values):
        units, long_name = spec.dim_attrs.get(dim, ("1", dim if dim in spec.dims else f"index along {dim}"))
        return (dim, values, {"units": units, "long_name": long_name})

    coords = {d: coord(d, np.asarray(v)) for d, v in grid.axes.items()}
    dims = spec.grid_dims(grid)
    data = {}
    for name, (units, long_name) in spec.float_vars.items():
        data[name] = (dims, total[name][order].reshape(shape), {"units": units, "long_name": long_name})
    for name, (units, long_name) in spec.flag_vars.items():
        data[name] = (dims, total[name][order].astype(np.int8).reshape(shape),
                      {"units": units, "long_name": long_name})
    for name, (units, long_name) in spec.text_vars.items():
        data[name] = (dims, np.array([str(v) for v in total[name][order]], dtype=object).reshape(shape),
                      {"units": units, "long_name": long_name})
    data["status"] = (dims, total["status"][order].astype(np.int8).reshape(shape),
                      status_attrs(spec.all_codes))
    for name, (extra, _, units, long_name) in spec.array_vars.items():
        sizes = spec.array_shape(name, options)
        for d, n in zip(extra, sizes):
            if d not in coords:
                labels = spec.dim_labels.get(d)
                coords[d] = coord(d, np.arange(n, dtype=np.int32) if labels is None else np.array(labels))
        data[name] = ((*dims, *extra), total[name][order].reshape(*shape, *sizes),
                      {"units": units, "long_name": long_name})
    data["solve_time"] = (dims, total["solve_time"][order].reshape(shape), dict(SOLVE_TIME_ATTRS))
    hook = spec.hook("global_attrs")
    attrs = hook(grid, options, provenance) if hook else generic_attrs(spec, grid, options, provenance)
    return xr.Dataset(data, coords=coords, attrs=attrs)


def encoding(ds: xr.Dataset) -> dict:
    """zlib-compressed variables; no _FillValue on integer or coordinate variables."""
    enc = {}
    for name, var in ds.variables.items():
        if name in ds.coords:
            enc[name] = {"_FillValue": None}
        elif var.dtype.kind in "OUS":  # variable-length strings: HDF5 does not compress them
            enc[name] = {"dtype": str}
        elif np.issubdtype(var.dtype, np.integer):
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


def check_file(spec, path) -> None:
    """Raise ValueError unless `path` holds a finished map of kind `spec`: the kind's own check
    first (`validate_file`, whose messages know its schema), then every variable, known status
    codes, none pending."""
    own = spec.hook("validate_file")
    if own:
        own(path)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        missing = [v for v in (*spec.float_vars, *spec.flag_vars, "status", *spec.array_vars) if v not in ds]
        if missing:
            raise ValueError(f"map {path} lacks variables {missing}")
        status = np.asarray(ds["status"].values)
    unknown = set(np.unique(status).tolist()) - set(spec.status_codes)
    if unknown:
        raise ValueError(f"map {path} holds unknown or pending status codes {sorted(unknown)}")


__all__ = ["assemble", "write_netcdf", "check_file", "provenance", "package_version"]
