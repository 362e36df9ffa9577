"""Helpers of the pipeline tests: the fake solver's expected output, subprocess environment."""

import hashlib
import os
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]

import fake_unit_solver as fake

FAKE = "fake_unit_solver:solve"
#: the unit kind whose "ci" grid is the fake solver's three-axis grid (see `fake_kind`)
FAKE_CI_KIND = "pipeline_testing:fake_kind"


def _fake_ci():
    """The grid the machinery tests build with the fake solver: the CI grid of the three-axis
    maps (4 x 3 x 2 points at b/L = 0), where the fake's failing points sit. (The CI preset has
    a b/L axis since schema 3: 48 points.)"""
    from snapmorph.pipeline.kinds.unit import Grid

    return Grid(h_over_L=(0.10, 0.20, 0.30, 0.40), t_over_L=(0.005, 0.0075, 0.01),
                w_over_L=(0.04, 0.06), name="ci")


CI = _fake_ci()


def fake_kind():
    """The unit kind with only the point solver's own module hashed into the fingerprint: the
    unit's sources (solver/, units/) may change while a test runs in a shared work tree."""
    import dataclasses

    from snapmorph.pipeline.solvers import get_spec

    spec = get_spec("unit")
    return dataclasses.replace(spec, sources=(), presets={**spec.presets, "ci": _fake_ci})


def load(path):
    """The map file `path`, read into memory."""
    import xarray as xr

    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


def sha(path):
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def finished_indices(out):
    """The grid indices held by the batch files of the checkpoint of `out`."""
    from snapmorph.pipeline.checkpoint import checkpoint_dir

    idx = set()
    for p in checkpoint_dir(out).glob("batch-*.npz"):
        with np.load(p) as z:
            idx |= set(z["index"].tolist())
    return idx


def solve_batch(indices, coords, b_over_L, resolution, samples, solve):
    """A checkpoint block of the planar unit's kind: `solve` at the points `coords` with flat
    indices `indices`."""
    from snapmorph.pipeline.batch import solve_points
    from snapmorph.pipeline.solvers import get_spec

    options = {"b_over_L": b_over_L, "resolution": resolution, "samples": samples}
    return solve_points(indices, coords, get_spec("unit"), options, solve)


def subprocess_env(**extra) -> dict:
    """Environment for subprocesses that must import the fake solver."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), str(REPO), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.pop("FAKE_SOLVER_LOG", None)
    env.pop("FAKE_SOLVER_DELAY", None)
    env.update({k: str(v) for k, v in extra.items()})
    return env


def expected_record(h, t, w, samples):
    """What the pipeline must store for one point of the fake solver."""
    if fake._near((h, t, w), fake.RAISING_POINT) or fake._near((h, t, w), fake.NOT_CONVERGED_POINT):
        return {"status": 2}
    f = fake.fields(h, t, w)
    if h < fake.boundary(t):
        return {"status": 1, "F_cr": f["F_cr"], "d_cr": f["d_cr"]}
    return {"status": 0, **f, "base_shape": fake.shape(h, t, w, samples)}


def assert_matches_fake(ds):
    """Every point of `ds` holds exactly what the fake solver computes there."""
    samples = ds.sizes["sample"]
    for i, h in enumerate(ds.h_over_L.values):
        for j, t in enumerate(ds.t_over_L.values):
            for k, w in enumerate(ds.w_over_L.values):
                exp = expected_record(float(h), float(t), float(w), samples)
                p = ds.isel(h_over_L=i, t_over_L=j, w_over_L=k)
                assert int(p.status) == exp["status"], (h, t, w)
                for name in ("F_cr", "d_cr", "d_unstable", "d_second", "S", "theta",
                             "energy_barrier", "energy_stored"):
                    got = float(p[name])
                    if name in exp:
                        assert got == pytest.approx(exp[name], rel=1e-12), (name, h, t, w)
                    else:
                        assert np.isnan(got), (name, h, t, w)
                if exp["status"] == 0:
                    np.testing.assert_allclose(p.base_shape.values, exp["base_shape"], rtol=0, atol=1e-12)
                    assert int(p.bistable) == 1
                else:
                    assert np.all(np.isnan(p.base_shape.values))
                    assert int(p.bistable) == 0
