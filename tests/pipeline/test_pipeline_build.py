"""Builds with the fake solver on a LocalCluster: content, schema, determinism, resume."""

import datetime as dt
import json

import netCDF4
import numpy as np
import pytest

import snapmorph
from pipeline_testing import FAKE, assert_matches_fake, finished_indices, load, solve_batch
import fake_unit_solver as fake
from snapmorph.pipeline.build import build_map, open_checkpoint
from snapmorph.pipeline.checkpoint import CheckpointError, checkpoint_dir
from snapmorph.pipeline.compare import compare_maps
from snapmorph.maps.schema import FLAG_VARS, FLOAT_VARS, REQUIRED_ATTRS, SCHEMA_VERSION
from snapmorph.pipeline import preset
from snapmorph.units.status import NAME as STATUS_CODES

from pipeline_testing import CI  # noqa: E402  (the three-axis CI grid of the fake solver)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted build of the CI grid with the fake solver (2 workers)."""
    out = tmp_path_factory.mktemp("ref") / "ci.nc"
    report = build_map(CI, out, solve=fake.solve, workers=2, progress=False)
    return out, report


def test_build_stores_what_the_solver_computed(reference):
    out, report = reference
    ds = load(out)
    assert_matches_fake(ds)
    assert report.points == CI.size and report.computed == CI.size and report.resumed == 0
    assert report.status_counts == {0: 16, 1: 6, 2: 2}
    messages = " | ".join(m for *_, m in report.failures)
    assert "fake solver exploded" in messages and "not converged (fake)" in messages
    assert not checkpoint_dir(out).exists()


def test_dataset_follows_the_schema(reference):
    out, _ = reference
    ds = load(out)
    for name in (*FLOAT_VARS, *FLAG_VARS, "status", "base_shape", "solve_time", *ds.coords):
        assert ds[name].attrs.get("units") and ds[name].attrs.get("long_name"), name
    assert ds.theta.attrs["units"] == "degree" and ds.solve_time.attrs["units"] == "s"
    assert list(ds.status.attrs["flag_values"]) == sorted(STATUS_CODES)
    assert ds.status.attrs["flag_meanings"].startswith("pending ok monostable not_converged invalid_geometry")
    assert ds.base_shape.dims == ("h_over_L", "t_over_L", "w_over_L", "sample", "xz")
    assert list(ds.xz.values) == ["x", "z"] and ds.sizes["sample"] == 65
    for name in REQUIRED_ATTRS:
        assert name in ds.attrs, name
    assert int(ds.attrs["schema_version"]) == SCHEMA_VERSION
    assert ds.attrs["package_version"] == snapmorph.__version__
    # "created" is the date of the model source's commit, not the build's wall clock
    if ds.attrs["created"] != "unknown":
        assert dt.datetime.fromisoformat(ds.attrs["created"]).utcoffset() == dt.timedelta(0)
    assert len(ds.attrs["inputs_sha256"]) == 64 and json.loads(ds.attrs["build_inputs"])["kind"] == "unit"
    assert np.all(np.isnan(ds.solve_time.values))  # not stored: rebuilds write the same bytes
    with netCDF4.Dataset(out) as nc:
        for name in (*FLAG_VARS, "status"):
            v = nc[name]
            assert v.dtype == np.int8 and "_FillValue" not in v.ncattrs(), name
        for name in ("F_cr", "base_shape", "status"):
            assert nc[name].filters()["zlib"], name
    assert ds.status.dtype == np.int8  # no fill value: read back as integers


def test_result_does_not_depend_on_workers_or_batches(reference, tmp_path):
    out, _ = reference
    other = tmp_path / "one-worker.nc"
    report = build_map(CI, other, solve=FAKE, workers=1, batch_size=5, progress=False)
    assert (report.workers, report.batch_size) == (1, 5)
    assert compare_maps(load(out), load(other), rtol=0, atol=0) == []


def test_resume_recomputes_only_missing_points(reference, tmp_path, monkeypatch):
    ref, _ = reference
    out = tmp_path / "ci.nc"
    coords = CI.points()
    # a checkpoint holding two finished batches, a write cut short and a damaged batch file
    ckpt = open_checkpoint(out, CI, FAKE)
    started = {k: ckpt.meta[k] for k in ("created", "git_commit")}
    for idx in (np.arange(0, 7), np.arange(12, 20)):
        ckpt.write(solve_batch(idx, coords[idx], CI.b_over_L, CI.resolution, CI.samples, fake.solve))
    ckpt.close()
    finished = finished_indices(out)
    assert len(finished) == 15
    (ckpt.dir / ".batch-0000099-deadbeef.npz.0a1b2c3d.tmp").write_bytes(b"half a file")
    (ckpt.dir / "batch-0000020-damaged0.npz").write_bytes(b"PK\x03\x04 truncated")

    log = tmp_path / "calls.log"
    monkeypatch.setenv("FAKE_SOLVER_LOG", str(log))  # inherited by the spawned workers
    with pytest.warns(UserWarning, match="refusing checkpoint file .*damaged0"):
        report = build_map(CI, out, solve=FAKE, workers=2, progress=False)
    calls = [tuple(map(float, line.split())) for line in log.read_text().splitlines()]
    solved = {i for i, p in enumerate(map(tuple, coords)) if p in calls}
    assert len(calls) == len(solved) == CI.size - 15
    assert solved.isdisjoint(finished) and solved | finished == set(range(CI.size))
    assert (report.computed, report.resumed) == (CI.size - 15, 15)
    resumed, expected = load(out), load(ref)
    assert compare_maps(expected, resumed, rtol=0, atol=0) == []
    # the map records the build's start (time, commit); the rest equals an uninterrupted build
    assert {k: resumed.attrs[k] for k in started} == started
    assert {k: v for k, v in resumed.attrs.items() if k not in started} == \
        {k: v for k, v in expected.attrs.items() if k not in started}
    assert not checkpoint_dir(out).exists()


def test_checkpoint_of_another_grid_is_refused(tmp_path):
    out = tmp_path / "m.nc"
    open_checkpoint(out, CI, FAKE).close()
    other = CI.with_resolution(40)
    with pytest.raises(CheckpointError, match="another grid.*restart"):
        build_map(other, out, solve=FAKE, workers=1, progress=False)
    with pytest.raises(CheckpointError, match="another solver"):
        build_map(CI, out, solve="fake_unit_solver:fields", workers=1, progress=False)
    meta = json.loads((checkpoint_dir(out) / "build.json").read_text())
    assert meta["grid"] == CI.to_dict()


def test_restart_discards_the_checkpoint(tmp_path, monkeypatch):
    out = tmp_path / "m.nc"
    ckpt = open_checkpoint(out, CI.with_resolution(40), FAKE)
    idx = np.arange(3)
    ckpt.write(solve_batch(idx, CI.points()[idx], 0.0, 40, CI.samples, fake.solve))
    ckpt.close()
    log = tmp_path / "calls.log"
    monkeypatch.setenv("FAKE_SOLVER_LOG", str(log))
    report = build_map(CI, out, solve=FAKE, workers=1, restart=True, progress=False)
    assert report.computed == CI.size and len(log.read_text().splitlines()) == CI.size


def test_a_running_build_locks_its_checkpoint(tmp_path):
    out = tmp_path / "m.nc"
    first = open_checkpoint(out, CI, FAKE)
    try:
        with pytest.raises(CheckpointError, match="another build is writing"):
            open_checkpoint(out, CI, FAKE)
    finally:
        first.close()


@pytest.mark.parametrize("kwargs, match", [
    (dict(workers=0), r"workers must be an integer >= 1"),
    (dict(batch_size=0), r"batch_size must be an integer >= 1"),
    (dict(solve="no_colon"), r"solver must be a callable or 'module:function'"),
])
def test_bad_arguments(tmp_path, kwargs, match):
    with pytest.raises(ValueError, match=match):
        build_map(CI, tmp_path / "m.nc", **{"solve": FAKE, **kwargs})


@pytest.mark.slow
def test_a_point_that_kills_its_worker_is_recorded(tmp_path, monkeypatch):
    import dask
    import distributed  # noqa: F401 - its config defaults first: leaving the dask.config.set
    # below would otherwise drop the whole "distributed" section it created

    monkeypatch.setenv("FAKE_SOLVER_CRASH", "0.2 0.0075 0.04")  # os._exit on that point
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        report = build_map(CI, tmp_path / "m.nc", solve=FAKE, workers=2, batch_size=6,
                           progress=False, timeout=60)
    ds = load(tmp_path / "m.nc")
    p = ds.sel(h_over_L=0.2, t_over_L=0.0075, w_over_L=0.04)
    assert int(p.status) == 2 and np.isnan(float(p.F_cr))
    assert any("killed its worker" in m for *_, m in report.failures)
    # every other point is as an uninterrupted build computes it
    ds["status"].loc[dict(h_over_L=0.2, t_over_L=0.0075, w_over_L=0.04)] = 0
    fields = fake.fields(0.2, 0.0075, 0.04)
    for name, v in fields.items():
        ds[name].loc[dict(h_over_L=0.2, t_over_L=0.0075, w_over_L=0.04)] = v
    ds["bistable"].loc[dict(h_over_L=0.2, t_over_L=0.0075, w_over_L=0.04)] = 1
    ds["base_shape"].loc[dict(h_over_L=0.2, t_over_L=0.0075, w_over_L=0.04)] = fake.shape(0.2, 0.0075, 0.04, 65)
    assert_matches_fake(ds)
