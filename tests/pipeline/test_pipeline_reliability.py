"""Time limits, the watchdog, idempotent builds, exit codes and option checks of `maps build`."""

import subprocess
import sys
import time

import numpy as np
import pytest

import fake_unit_solver as fake
from pipeline_testing import FAKE, FAKE_CI_KIND, REPO, assert_matches_fake, fake_kind, load, sha, subprocess_env
from snapmorph.pipeline.build import allowed_failures, build_map, parse_max_failed
from snapmorph.pipeline.checkpoint import checkpoint_dir
from snapmorph.pipeline import preset
from snapmorph.pipeline.solvers import get_spec
from snapmorph.units.status import TIMEOUT
from snapmorph.cli import main

from pipeline_testing import CI  # noqa: E402  (the three-axis CI grid of the fake solver)
SLOW = (0.2, 0.005, 0.06)  # a bistable point of the CI grid


def without(ds, point):
    """`ds` with `point` restored to what the fake computes there (to compare the rest)."""
    sel = dict(zip(("h_over_L", "t_over_L", "w_over_L"), point))
    ds["status"].loc[sel] = 0
    for name, v in fake.fields(*point).items():
        ds[name].loc[sel] = v
    ds["bistable"].loc[sel] = 1
    ds["self_standing"].loc[sel] = 0
    ds["bifurcation"].loc[sel] = 0
    ds["base_shape"].loc[sel] = fake.shape(*point, CI.samples)
    return ds


# -- time limits -----------------------------------------------------------------------------

def test_time_limit_reaches_the_point_solver(tmp_path, monkeypatch):
    monkeypatch.setenv("FAKE_SOLVER_SLOW", " ".join(map(str, SLOW)))
    t0 = time.monotonic()
    report = build_map(CI, tmp_path / "m.nc", solve=FAKE, workers=2, progress=False, time_limit=0.3)
    assert time.monotonic() - t0 < 60
    ds = load(tmp_path / "m.nc")
    p = ds.sel(h_over_L=SLOW[0], t_over_L=SLOW[1], w_over_L=SLOW[2])
    assert int(p.status) == TIMEOUT and np.isnan(float(p.F_cr))
    assert report.failed == 3 and any("time limit 0.3 s reached" in f[-1] for f in report.failures)
    assert_matches_fake(without(ds, SLOW))


@pytest.mark.slow
def test_watchdog_stops_a_solver_that_ignores_its_time_limit(tmp_path, monkeypatch):
    """The point never returns; the build still ends, with that point "timeout" and every
    other point as an uninterrupted build computes it."""
    monkeypatch.setenv("FAKE_SOLVER_HANG", " ".join(map(str, SLOW)))
    t0 = time.monotonic()
    report = build_map(CI, tmp_path / "m.nc", solve=FAKE, workers=2, batch_size=3, progress=False,
                       time_limit=0.5, timeout=60)
    elapsed = time.monotonic() - t0
    assert elapsed < 90, elapsed
    ds = load(tmp_path / "m.nc")
    p = ds.sel(h_over_L=SLOW[0], t_over_L=SLOW[1], w_over_L=SLOW[2])
    assert int(p.status) == TIMEOUT
    assert any("its worker was restarted" in f[-1] for f in report.failures), report.summary()
    assert_matches_fake(without(ds, SLOW))


# -- idempotent, reproducible builds -------------------------------------------------------------

# The unit kind hashes solver/ and units/, which other work in this tree may be editing while the
# tests run; these tests hash only the fake solver's module (the unit's own sources are listed
# in test_unit_kind_hashes_the_model_source).
FAKE_KIND = fake_kind()


def _assert_imports_hashed(names, modules):
    """Every module of units/ that the files `modules` import is among the hashed `names` (a
    new import is hashed without an edit: the fingerprint follows imports)."""
    import ast
    for module in modules:
        tree = ast.parse((REPO / module).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("snapmorph.units."):
                assert node.module.removeprefix("snapmorph.").replace(".", "/") + ".py" in names, (module, node.module)


def test_unit_kind_hashes_the_model_source():
    from snapmorph.pipeline.fingerprint import solver_modules, source_files

    names = {rel for rel, _ in source_files(solver_modules(get_spec("unit"), fake.solve))}
    # (solver/unit.py and solver/unit_model.py are units/planar.py and units/geometry.py now,
    # pipeline/point.py is pipeline/kinds/unit.py, pipeline/schema.py is maps/schema.py, the
    # path drivers of solver/continuation.py are solver/mgdc.py and solver/displacement.py)
    assert {"solver/mgdc.py", "solver/displacement.py", "units/__init__.py", "units/geometry.py",
            "units/planar.py", "pipeline/kinds/unit.py", "maps/schema.py", "pipeline/dataset.py",
            "fake_unit_solver.py"} <= names
    # every module of units/ the planar unit imports is hashed
    _assert_imports_hashed(names, ("units/planar.py", "units/geometry.py", "pipeline/kinds/unit.py"))


def test_unit2d_kind_hashes_the_model_source():
    from snapmorph.pipeline.fingerprint import solver_modules, source_files

    spec = get_spec("unit2d")
    names = {rel for rel, _ in source_files(solver_modules(spec, spec.solve))}
    assert {"units/__init__.py", "units/unit2d.py", "units/frame3d.py", "units/push3d.py",
            "units/planar.py", "units/status.py", "pipeline/kinds/unit2d.py", "pipeline/solvers.py",
            "pipeline/dataset.py"} <= names
    assert "pipeline/kinds/unit.py" not in names  # the planar kind does not change this map
    _assert_imports_hashed(names, ("units/unit2d.py", "units/frame3d.py", "units/push3d.py",
                                   "pipeline/kinds/unit2d.py"))


def test_up_to_date_map_is_left_alone_and_force_rebuilds_the_same_bytes(tmp_path, monkeypatch):
    import snapmorph.pipeline.build as build

    out = tmp_path / "ci.nc"
    build_map(CI, out, kind=FAKE_KIND, solve=FAKE, workers=2, progress=False)
    first, mtime = sha(out), out.stat().st_mtime_ns
    log = tmp_path / "calls.log"
    monkeypatch.setenv("FAKE_SOLVER_LOG", str(log))
    report = build_map(CI, out, kind=FAKE_KIND, solve=FAKE, workers=2, progress=False)
    assert report.up_to_date and report.computed == 0 and not log.exists()
    assert out.stat().st_mtime_ns == mtime and "is up to date" in report.summary()
    assert report.failed == 2  # read from the file: the exit policy still applies
    report = build_map(CI, out, kind=FAKE_KIND, solve=FAKE, workers=1, batch_size=5, progress=False,
                       force=True)
    assert not report.up_to_date and report.computed == CI.size
    assert sha(out) == first  # bit-identical, whatever the workers and batches
    # other inputs rebuild, saying why: the solver resolution, the solver's source
    with pytest.warns(UserWarning, match="inputs differ .*model_options"):
        report = build_map(CI.with_resolution(40), out, kind=FAKE_KIND, solve=FAKE, workers=1,
                           progress=False)
    assert report.computed == CI.size and sha(out) != first
    build_map(CI, out, kind=FAKE_KIND, solve=FAKE, workers=1, progress=False, force=True)
    assert sha(out) == first
    monkeypatch.setattr(build, "source_hash", lambda modules: "0" * 64)
    with pytest.warns(UserWarning, match="inputs differ .*solver_source_sha256"):
        report = build_map(CI, out, kind=FAKE_KIND, solve=FAKE, workers=1, progress=False)
    assert report.computed == CI.size


def test_keep_solve_time(tmp_path):
    out = tmp_path / "m.nc"
    build_map(CI, out, solve=FAKE, workers=1, progress=False, keep_solve_time=True)
    assert np.all(np.isfinite(load(out).solve_time.values))


# -- exit codes --------------------------------------------------------------------------------

@pytest.mark.parametrize("value, allowed", [("0", 0), ("2", 2), ("0.05", 1), ("0.1", 2), ("10%", 2),
                                            ("100%", 24), (3, 3), (0.5, 12)])
def test_max_failed_values(value, allowed):
    assert allowed_failures(value, 24) == allowed


@pytest.mark.parametrize("value", ["-1", "1.5", "abc", "200%", "nan", "", -1, 1.0, True])
def test_bad_max_failed(value):
    with pytest.raises(ValueError, match="max-failed"):
        parse_max_failed(value)


def test_exit_status_follows_failed_points(tmp_path, capsys):
    out = tmp_path / "m.nc"
    base = ["maps", "build", "--grid", "ci", "--out", str(out), "--solver", FAKE, "--kind", FAKE_CI_KIND, "--workers", "2",
            "--no-progress"]
    assert main(base) == 1  # 2 of 24 fake points fail, none allowed
    text = capsys.readouterr().out
    assert "FAILED: 2 of 24 points failed, more than --max-failed 0 allows (0)" in text
    assert out.exists() and not checkpoint_dir(out).exists()
    assert main(base) == 1  # up to date, still failed
    assert "is up to date" in capsys.readouterr().out
    assert main(base + ["--max-failed", "0.05"]) == 1
    assert main(base + ["--max-failed", "10%"]) == 0
    assert main(base + ["--max-failed", "2"]) == 0


# -- bad options: one line, exit 2, before any work ------------------------------------------------

BAD = [
    (["--workers", "0"], "--workers"), (["--workers", "two"], "--workers"),
    (["--batch-size", "0"], "--batch-size"), (["--resolution", "3"], "--resolution"),
    (["--resolution", "1e3"], "--resolution"), (["--resolution", "7"], "--resolution 7: resolution"),
    (["--resolution", "1000000"], "--resolution"), (["--workers", "100000"], "--workers"),
    (["--workers", "200"], "--workers"), (["--time-limit", "1e300"], "--time-limit"),
    (["--connect-timeout", "1e9"], "--connect-timeout"),
    (["--time-limit", "0"], "--time-limit"), (["--time-limit", "-5"], "--time-limit"),
    (["--time-limit", "nan"], "--time-limit"), (["--time-limit", "inf"], "--time-limit"),
    (["--connect-timeout", "0"], "--connect-timeout"),
    (["--max-failed", "-1"], "--max-failed"), (["--max-failed", "1.5"], "--max-failed"),
    (["--max-failed", "lots"], "--max-failed"), (["--max-failed", "101%"], "--max-failed"),
    (["--scheduler", ""], "--scheduler"), (["--scheduler", "tcp://127.0.0.1"], "--scheduler"),
    (["--scheduler", "tcp://127.0.0.1:99999"], "--scheduler"),
    (["--scheduler", "/no/such/scheduler.json"], "scheduler file"),
    (["--solver", "nocolon"], "--solver"), (["--solver", "no_such_module:f"], "--solver"),
    (["--solver", "math:no_such_function"], "--solver"),
    (["--kind", "no-such-kind"], "--kind"), (["--kind", "no_such_module:SPEC"], "--kind"),
    (["--grid", "huge"], "--grid"), (["--grid", "default", "--kind", "fake_unit2d:SPEC"], "--grid"),
    (["--bogus"], "unrecognized arguments"),
]


@pytest.mark.parametrize("extra, names", BAD, ids=[" ".join(b[0]) for b in BAD])
def test_bad_build_option(extra, names, tmp_path, capsys):
    out = tmp_path / "m.nc"
    args = ["maps", "build", "--grid", "ci", "--out", str(out), "--no-progress", *extra]
    t0 = time.monotonic()
    assert main(args) == 2
    assert time.monotonic() - t0 < 15
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert names in err and "Traceback" not in err
    assert not out.exists() and not checkpoint_dir(out).exists()


@pytest.mark.parametrize("extra, names", [(["--rtol", "-1"], "--rtol"), (["--atol", "nan"], "--atol"),
                                          (["--against", "/no/such/map.nc"], "--against")])
def test_bad_check_option(extra, names, capsys):
    args = ["maps", "check", "--grid", "ci", "--against", "maps/data/ci.nc", "--no-progress", *extra]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and names in err, err


def test_bad_output_paths(tmp_path, capsys):
    plain = tmp_path / "plain.txt"
    plain.write_text("a file\n")
    for out, why in ((plain / "m.nc", "is a file, not a folder"), (tmp_path, "is a folder")):
        assert main(["maps", "build", "--grid", "ci", "--out", str(out), "--solver", FAKE, "--kind", FAKE_CI_KIND]) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and "--out" in err and why in err, err
    # missing folders are created (the rule of every command)
    deep = tmp_path / "new" / "folder" / "m.nc"
    assert main(["maps", "build", "--grid", "ci", "--out", str(deep), "--solver", FAKE, "--kind", FAKE_CI_KIND,
                 "--workers", "1", "--no-progress", "--max-failed", "2"]) == 0
    assert deep.exists()


def test_unreachable_scheduler_fails_fast_with_one_line(tmp_path):
    t0 = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "snapmorph", "maps", "build", "--grid", "ci", "--out",
                        str(tmp_path / "m.nc"), "--solver", FAKE, "--kind", FAKE_CI_KIND, "--scheduler", "tcp://127.0.0.1:1"],
                       cwd=REPO, env=subprocess_env(), capture_output=True, text=True, timeout=120)
    elapsed = time.monotonic() - t0
    assert r.returncode == 2, r.stdout + r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "cannot connect to the dask scheduler at tcp://127.0.0.1:1 within 5 s" \
        in lines[0], r.stderr
    assert elapsed < 20, elapsed


# -- the committed maps are up to date (a fresh clone's `make maps` changes nothing) -----------

@pytest.mark.parametrize("name", ["default", "ci"])
def test_committed_map_is_up_to_date(name):
    """`make maps` / `make maps-ci` leave the committed file alone only if its recorded inputs
    are this tree's: after a change to the solver, units, point.py, schema.py or dataset.py,
    rebuild them (`make maps maps-ci`) and commit the files."""
    from snapmorph.pipeline.build import build_identity, read_map_identity
    from snapmorph.pipeline.fingerprint import differences

    path = REPO / "maps" / "data" / f"{name}.nc"
    recorded = read_map_identity(path)
    if recorded is None:
        pytest.skip(f"{path} records no build inputs (built before fingerprints): run `make maps maps-ci`")
    _, _, inputs, fp = build_identity(preset(name))
    assert recorded["fingerprint"] == fp, (
        f"{path} is stale (differing inputs: {', '.join(differences(recorded['inputs'], inputs))}); "
        f"run `make maps maps-ci` and commit the maps")
