"""The 2-D units on polygon footprints as kinds of map (`pipeline.kinds.unit2d`: `unit2d`,
`unit2d_triangle`, `unit2d_hexagon`): plugged in as any kind, their committed small maps
(maps/data/unit2d-<footprint>-small.nc) up to date, self-describing and sensible, and a
fresh build through the pipeline reproducing committed points bit for bit."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from snapmorph.pipeline.build import build_identity, build_map, read_map_identity
from snapmorph.pipeline.fingerprint import differences
from snapmorph.pipeline.solvers import get_spec
from snapmorph.units import status as unit_status
from snapmorph.units.polygon import side_names

REPO = Path(__file__).resolve().parents[2]
KINDS = {"triangle": ("unit2d_triangle", 3), "square": ("unit2d", 4),
         "hexagon": ("unit2d_hexagon", 6)}


def _committed(footprint) -> Path:
    return REPO / "maps" / "data" / f"unit2d-{footprint}-small.nc"


def _load(path):
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


@pytest.mark.parametrize("footprint", KINDS)
def test_each_footprint_is_a_kind_with_its_sides(footprint):
    kind, sides = KINDS[footprint]
    spec = get_spec(kind)
    assert spec.name == kind and spec.attrs["sides"] == sides
    assert spec.dims == ("h_over_L", "t_over_L")
    assert spec.array_shape("edge_theta", spec.options) == (sides,)
    assert ", ".join(side_names(sides)) in spec.dim_attrs["side"][1]
    assert {"small", "ci"} <= set(spec.presets)


@pytest.mark.parametrize("footprint", KINDS)
def test_committed_small_map_is_up_to_date(footprint):
    """After a change to the 2-D unit, its solver or this kind, rebuild the maps
    (`make maps-polygons MAPS_FLAGS=--force`, docs/sheets.md) and commit them."""
    kind, _ = KINDS[footprint]
    path = _committed(footprint)
    recorded = read_map_identity(path)
    assert recorded is not None, f"{path} is missing or records no build inputs"
    _, _, inputs, fp = build_identity(get_spec(kind).preset("small"), spec=kind)
    assert recorded["fingerprint"] == fp, (
        f"{path} is stale (differing inputs: {', '.join(differences(recorded['inputs'], inputs))})")


@pytest.mark.parametrize("footprint", KINDS)
def test_committed_small_map_describes_itself_and_its_statuses_are_sensible(footprint):
    kind, sides = KINDS[footprint]
    ds = _load(_committed(footprint))
    assert ds.attrs["kind"] == kind and int(ds.attrs["sides"]) == sides
    assert ds.attrs["footprint"] == footprint and ds.sizes["side"] == sides
    for name in [*ds.data_vars, *ds.coords]:
        assert ds[name].attrs.get("units") and ds[name].attrs.get("long_name"), name
    status, bistable = ds.status.values, ds.bistable.values
    standing = ds.self_standing.values
    # ok exactly where bistable; a point that is not bistable has no self-standing verdict
    assert np.array_equal(status == unit_status.OK, bistable == 1)
    assert np.all(np.isin(standing[bistable == 1], (0, 1)))
    assert np.all(standing[bistable != 1] == -1)
    assert np.all(np.isfinite(ds.F_cr.values[status != unit_status.NOT_CONVERGED]))
    ok = status == unit_status.OK
    assert np.all(np.isfinite(ds.edge_theta.values[ok]))
    assert np.all(np.isnan(ds.edge_theta.values[~ok]))
    # bistable over part of its h/L range only (monostable below), at every thickness
    for j in range(ds.sizes["t_over_L"]):
        column = bistable[:, j]
        assert column[0] == 0 and column.max() == 1, (footprint, j, column)
    # a self-standing unit stays curled: its released sides' corners rise above their middles
    # on average (one side may turn the other way when the released frame warps)
    standing_ok = standing == 1
    assert np.any(standing_ok)
    assert np.all(ds.theta_released.values[standing_ok] > 0)
    assert np.all(np.isnan(ds.theta_released.values[~standing_ok]))


@pytest.mark.slow
def test_a_fresh_build_reproduces_the_committed_triangle_points(tmp_path):
    """The triangle's `ci` grid (points of its small map, same options) built through the
    pipeline equals the committed small map there, bit for bit, statuses included."""
    spec = get_spec("unit2d_triangle")
    grid = spec.preset("ci")
    out = tmp_path / "tri.nc"
    report = build_map(grid, out, kind="unit2d_triangle", workers=1, progress=False)
    assert report.computed == grid.size
    fresh = _load(out)
    committed = _load(_committed("triangle")).sel(h_over_L=list(grid.axes["h_over_L"]),
                                                  t_over_L=list(grid.axes["t_over_L"]))
    for name in fresh.data_vars:
        if name != "solve_time":
            np.testing.assert_array_equal(fresh[name].values, committed[name].values, name)
    assert int(fresh.attrs["sides"]) == 3
