"""The pipeline with the real unit solver on the CI grid: normalisation and base-shape frame."""

import math

import numpy as np
import pytest
import xarray as xr

unit = pytest.importorskip("snapmorph.units.planar")

from snapmorph.pipeline.build import build_map  # noqa: E402
from snapmorph.pipeline import preset, solve_point  # noqa: E402

CI = preset("ci")


@pytest.fixture(scope="module")
def ci_map(tmp_path_factory):
    out = tmp_path_factory.mktemp("real") / "ci.nc"
    report = build_map(CI, out, workers=2, progress=False)
    with xr.open_dataset(out, engine="netcdf4") as ds:
        return ds.load(), report


@pytest.mark.slow
def test_ci_grid_builds_with_the_real_solver(ci_map):
    ds, report = ci_map
    assert report.computed == CI.size
    assert int((ds.status == 0).sum()) >= CI.size // 2, report.summary()
    assert int(ds.attrs["resolution"]) > 0  # the solver's default, resolved and recorded


@pytest.mark.slow
def test_stored_values_are_the_normalised_simulation(ci_map):
    """F_norm = F L^2 / (E w t^3 / 12) etc.; a unit twice as large and of another material has
    the same normalised values (the model is scale-invariant), which is what makes one map
    serve every size and material."""
    ds, _ = ci_map
    h, t, w = 0.3, 0.0075, 0.04
    stored = ds.sel(h_over_L=h, t_over_L=t, w_over_L=w, b_over_L=0.0)
    assert int(stored.status) == 0
    res = int(ds.attrs["resolution"])
    for L, E in ((0.1, 2.2e9), (0.25, 3.0e9)):
        # the model options the map records (its actuator joint) scale with L too
        g = unit.UnitGeometry(L=L, h=h * L, t=t * L, w=w * L, b=0.0, E=E,
                              joint_length=float(ds.attrs["joint_length_over_L"]) * L)
        r = unit.simulate_unit(g, nodes=res)
        EI = E * (w * L) * (t * L) ** 3 / 12
        assert r.F_cr * L**2 / EI == pytest.approx(float(stored.F_cr), rel=1e-5)
        assert r.energy_stored * L / EI == pytest.approx(float(stored.energy_stored), rel=1e-5)
        assert r.S / L == pytest.approx(float(stored.S), rel=1e-6)
        assert r.d_second / L == pytest.approx(float(stored.d_second), rel=1e-6)
        assert r.theta_deg == pytest.approx(float(stored.theta), abs=1e-6)


@pytest.mark.slow
def test_base_shape_frame_agrees_with_theta(ci_map):
    ds, _ = ci_map
    for h in CI.h_over_L:
        p = ds.sel(h_over_L=h, t_over_L=0.005, w_over_L=0.06, b_over_L=0.0)
        if int(p.status) != 0:
            continue
        xy = p.base_shape.values
        np.testing.assert_array_equal(xy[0], [0.0, 0.0])
        seg = np.diff(xy, axis=0)
        ds_ = np.hypot(*seg.T)
        assert ds_.std() < 1e-3 * ds_.mean()  # uniform in arc length
        assert abs(seg[0, 1]) < 1e-12 and seg[0, 0] > 0  # start tangent +x (first base edge)
        end = math.degrees(math.atan2(seg[-1, 1], seg[-1, 0]))
        assert end == pytest.approx(float(p.theta), abs=1.0)  # end tangent turned by theta
        assert ds_.sum() == pytest.approx(1.0, abs=0.01)  # base length L


def test_solve_point_reports_invalid_geometry():
    rec = solve_point(0.2, 0.005, 0.3, 0.25, None)  # b + w > L/2
    assert rec["status"] == 3 and "b + w" in rec["message"]
