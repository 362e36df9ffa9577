"""The pipeline maps any registered point solver with its own schema section (a fake 2-D kind)."""

import math

import numpy as np
import pytest

import fake_unit2d
from pipeline_testing import load
from snapmorph.pipeline.batch import solve_points
from snapmorph.pipeline.build import build_map, open_checkpoint
from snapmorph.pipeline.checkpoint import checkpoint_dir
from snapmorph.pipeline.solvers import MapGrid, SolverSpec, get_spec, kinds, register
from snapmorph.cli import main

KIND = "fake_unit2d:SPEC"
GRID = fake_unit2d.SPEC.preset("small")


def check_map(ds):
    assert ds.F_cr.dims == ("h_over_L", "t_over_L")
    assert ds.edge_curvature.dims == ("h_over_L", "t_over_L", "edge") and ds.sizes["edge"] == 4
    assert ds.attrs["kind"] == "fake2d" and ds.h_over_L.attrs["long_name"] == "apex height / L"
    assert list(ds.status.attrs["flag_values"]) == [-1, 0, 1, 2, 4]
    assert ds.status.attrs["flag_meanings"] == "pending ok monostable not_converged timeout"
    for h in GRID.axes["h_over_L"]:
        for t in GRID.axes["t_over_L"]:
            p = ds.sel(h_over_L=h, t_over_L=t)
            if (h, t) == fake_unit2d.FAILED_POINT:
                assert int(p.status) == 2 and np.isnan(float(p.F_cr))
            elif h < 0.15:
                assert int(p.status) == 1 and float(p.F_cr) == fake_unit2d.fields(h, t)["F_cr"]
                assert np.all(np.isnan(p.edge_curvature.values))
            else:
                assert int(p.status) == 0 and int(p.bistable) == 1
                assert float(p.S_edge) == fake_unit2d.fields(h, t)["S_edge"]
                np.testing.assert_array_equal(p.edge_curvature.values, fake_unit2d.curvature(h, t))


def test_a_registered_kind_builds_its_own_map(tmp_path, monkeypatch):
    log = tmp_path / "calls.log"
    monkeypatch.setenv("FAKE2D_LOG", str(log))
    out = tmp_path / "unit2d.nc"
    report = build_map(GRID, out, kind=KIND, workers=1, progress=False, time_limit=7.5)
    assert report.points == 6 and report.failed == 1 and report.status_counts == {0: 3, 1: 2, 2: 1}
    check_map(load(out))
    calls = [line.split() for line in log.read_text().splitlines()]
    assert len(calls) == 6
    assert all(c[2] == "31" and c[3] == "7.5" for c in calls)  # grid options and time limit reach it
    assert "not converged (fake 2-D)" in report.summary() and "h/L=0.3, t/L=0.01" in report.summary()


def test_cli_builds_any_kind_and_is_idempotent(tmp_path, capsys):
    out = tmp_path / "m.nc"
    args = ["maps", "build", "--kind", KIND, "--grid", "small", "--out", str(out), "--workers", "1",
            "--no-progress"]
    assert main(args) == 1  # one failed point, none allowed
    assert "FAILED: 1 of 6 points failed" in capsys.readouterr().out
    assert main(args + ["--max-failed", "1"]) == 0
    assert "is up to date" in capsys.readouterr().out
    check_map(load(out))
    assert main(["maps", "info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "(kind fake2d)" in text and "points: 6 (ok 3, monostable 2, not_converged 1)" in text
    assert "t_over_L: 0.005 .. 0.01 (2 values)" in text
    assert main(["maps", "build", "--kind", KIND, "--grid", "default", "--out", str(out)]) == 2
    assert "--grid must be one of small for kind fake2d" in capsys.readouterr().err


def test_resume_with_another_kind(tmp_path, monkeypatch):
    out = tmp_path / "m.nc"
    ckpt = open_checkpoint(out, GRID, fake_unit2d.SPEC.solve, kind=KIND)
    opts = get_spec(KIND).grid_options(GRID)
    idx = np.arange(3)
    ckpt.write(solve_points(idx, GRID.points()[idx], get_spec(KIND), opts, fake_unit2d.SPEC.solve))
    ckpt.close()
    log = tmp_path / "calls.log"
    monkeypatch.setenv("FAKE2D_LOG", str(log))
    report = build_map(GRID, out, kind=KIND, workers=1, progress=False)
    assert (report.computed, report.resumed) == (3, 3) and len(log.read_text().splitlines()) == 3
    check_map(load(out))
    assert not checkpoint_dir(out).exists()


def test_registry():
    assert "unit" in kinds() and "unit2d" in kinds()
    assert get_spec().name == "unit" and get_spec("unit").dims == ("h_over_L", "t_over_L", "w_over_L", "b_over_L")
    spec = register(SolverSpec(name="fake2d-registered", solve="fake_unit2d:solve",
                               dims=("h_over_L", "t_over_L"), float_vars={"F_cr": ("1", "F")}))
    assert get_spec("fake2d-registered") is spec
    with pytest.raises(ValueError, match="kind must be one of"):
        get_spec("no-such-kind")
    with pytest.raises(ValueError, match="cannot import"):
        get_spec("no_such_module:SPEC")
    with pytest.raises(ValueError, match="must map 0 to 'ok'"):
        SolverSpec(name="x", solve="m:f", dims=("a",), float_vars={}, status_codes={1: "ok"})
    with pytest.raises(ValueError, match="grid dimensions"):
        build_map(MapGrid({"a": (1, 2)}), "x.nc", kind=KIND)


def test_generic_record_checks():
    spec, opts = fake_unit2d.SPEC, {"resolution": 21, "n_edges": 4}
    good = fake_unit2d.solve(0.3, 0.005, resolution=21, n_edges=4)
    assert spec.finalise_record(good, opts)["status"] == 0
    for bad, why in (({**good, "S_edge": math.nan}, "missing/invalid: S_edge"),
                     ({**good, "status": 7}, "unknown status 7"),
                     ({**good, "edge_curvature": np.zeros(3)}, "edge_curvature has shape"),
                     ({**good, "bistable": 2}, "flag bistable = 2"),
                     ("not a dict", "not dict")):
        rec = spec.finalise_record(bad, opts)
        assert rec["status"] == 2 and why in rec["message"], (why, rec["message"])
