"""The states of a simulated sheet (`units.sheet.SheetResult`) as a netCDF file: every
state (as made, then after each step) with its node positions, snapped cells, stability and
the step's force peak; units and long names in the attributes (SI)."""

from __future__ import annotations

import numpy as np

__all__ = ["states_dataset", "write_states"]


def states_dataset(result):
    """The `xarray.Dataset` of ``result``'s states: dims state (0 = as made, k = after
    step k), node, component (x, y, z), cell."""
    import xarray as xr

    sheet = result.sheet
    X0 = sheet.mesh.positions
    P = np.stack([X0] + [s.positions for s in result.steps])
    n = len(result.steps)
    snapped = np.zeros((n + 1, sheet.n_cells), dtype=np.int8)
    heights = np.zeros((n + 1, sheet.n_cells))
    from snapmorph.units.sheet import apex_heights

    heights[0] = apex_heights(sheet, X0)
    for k, s in enumerate(result.steps, start=1):
        snapped[k] = s.snapped
        heights[k] = s.apex_heights

    def per_step(values, fill):
        return np.array([fill] + list(values))

    ds = xr.Dataset(
        {
            "positions": (("state", "node", "component"), P,
                          {"units": "m", "long_name": "node positions"}),
            "snapped": (("state", "cell"), snapped,
                        {"units": "1", "long_name": "cell snapped (1) or as made (0)"}),
            "apex_height": (("state", "cell"), heights,
                            {"units": "m", "long_name": "apex above the centroid of the "
                             "cell's side midpoints, along the cell's normal"}),
            "pushed_cell": (("state",), per_step([s.cell for s in result.steps], -1),
                            {"units": "1", "long_name": "cell pushed in the step (-1: as made)"}),
            "F_cr": (("state",), per_step([s.F_cr for s in result.steps], np.nan),
                     {"units": "N", "long_name": "critical force of the step's push"}),
            "stable": (("state",), per_step([int(bool(s.stable)) for s in result.steps], 1)
                       .astype(np.int8),
                       {"units": "1", "long_name": "released sheet stable (no negative "
                        "eigenvalue of its tangent stiffness)"}),
            "global_mode": (("state",), per_step([int(s.global_mode) for s in result.steps], 0)
                            .astype(np.int8),
                            {"units": "1", "long_name": "released sheet fell along a global "
                             "mode into the reported state"}),
        },
        coords={"component": ["x", "y", "z"], "cell": np.arange(sheet.n_cells)},
        attrs={"title": "snapmorph sheet states", "tiling": sheet.tiling,
               "rows": sheet.shape[0], "cols": sheet.shape[1], "boundary": result.boundary,
               "protocol": result.protocol,
               "order": ",".join(map(str, result.order)), "L_m": sheet.geometry.L,
               "h_m": sheet.geometry.h, "t_m": sheet.geometry.t, "w_m": sheet.geometry.w,
               "nodes_per_side": sheet.nodes},
    )
    return ds


def write_states(result, path):
    """Write `states_dataset` of ``result`` to the netCDF file ``path``."""
    states_dataset(result).to_netcdf(path)
