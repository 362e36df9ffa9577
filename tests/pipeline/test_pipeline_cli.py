"""`snapmorph maps build / check / info` with the fake solver."""

import subprocess
import sys

import pytest
import xarray as xr

from pipeline_testing import FAKE, FAKE_CI_KIND, REPO
from snapmorph.pipeline.dataset import write_netcdf
from snapmorph.maps.schema import SCHEMA_VERSION
from snapmorph.cli import main


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "ci.nc"
    rc = main(["maps", "build", "--grid", "ci", "--out", str(out), "--solver", FAKE, "--kind", FAKE_CI_KIND,
               "--workers", "2", "--no-progress", "--max-failed", "2"])
    assert rc == 0
    return out


def test_help_is_fast_and_lists_the_subcommands():
    r = subprocess.run([sys.executable, "-X", "importtime", "-m", "snapmorph", "maps", "--help"],
                       cwd=REPO, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0
    for sub in ("build", "check", "info"):
        assert sub in r.stdout
    imported = {line.rsplit("|", 1)[-1].strip() for line in r.stderr.splitlines() if "|" in line}
    assert "argparse" in imported
    assert imported.isdisjoint({"numpy", "xarray", "dask", "distributed", "numba", "scipy"})


def test_build_prints_a_summary(built, capsys):
    out = built.with_name("again.nc")
    assert main(["maps", "build", "--grid", "ci", "--out", str(out), "--solver", FAKE, "--kind", FAKE_CI_KIND,
                 "--workers", "1", "--no-progress", "--max-failed", "2"]) == 0
    text = capsys.readouterr().out
    assert f"wrote {out}: 24 points (ok 16, monostable 6, not_converged 2)" in text
    assert "pipeline overhead: wall / (solve sum / workers)" in text


def test_check_passes_on_an_identical_map(built, capsys):
    assert main(["maps", "check", "--grid", "ci", "--against", str(built), "--solver", FAKE, "--kind", FAKE_CI_KIND,
                 "--workers", "2", "--no-progress"]) == 0
    assert "OK: the recomputed ci grid matches" in capsys.readouterr().out


def test_check_reports_differing_variables_and_points(built, tmp_path, capsys):
    with xr.open_dataset(built, engine="netcdf4") as ds:
        ds = ds.load()
    ds["theta"].loc[dict(h_over_L=0.4, t_over_L=0.005, w_over_L=0.06)] += 1e-3
    ds["status"].loc[dict(h_over_L=0.1, t_over_L=0.0075, w_over_L=0.04)] = 2
    ds["base_shape"].loc[dict(h_over_L=0.3, t_over_L=0.01, w_over_L=0.04, sample=30, xz="z")] *= 1.01
    bad = tmp_path / "tampered.nc"
    write_netcdf(ds, bad)
    rc = main(["maps", "check", "--grid", "ci", "--against", str(bad), "--solver", FAKE, "--kind", FAKE_CI_KIND,
               "--workers", "2", "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 1
    assert "FAIL" in out
    assert "theta: 1 of 24 points differ" in out and "h/L=0.4 t/L=0.005 w/L=0.06" in out
    assert "status: 1 of 24 points differ" in out and "expected 2 (not_converged), got 1 (monostable)" in out
    assert "base_shape: 1 of 24 points differ" in out and "h/L=0.3 t/L=0.01 w/L=0.04" in out
    assert "F_cr:" not in out


def test_check_with_loose_tolerance_passes(built, tmp_path, capsys):
    with xr.open_dataset(built, engine="netcdf4") as ds:
        ds = ds.load()
    ds["F_cr"] = ds["F_cr"] * (1 + 1e-5)
    path = tmp_path / "close.nc"
    write_netcdf(ds, path)
    args = ["maps", "check", "--grid", "ci", "--against", str(path), "--solver", FAKE, "--kind", FAKE_CI_KIND, "--workers", "1",
            "--no-progress"]
    assert main(args) == 1
    assert main(args + ["--rtol", "1e-4"]) == 0


def test_info(built, capsys):
    assert main(["maps", "info", str(built)]) == 0
    out = capsys.readouterr().out
    assert f"schema_version: {SCHEMA_VERSION}" in out and "h_over_L: 0.1 .. 0.4 (4 values)" in out
    assert "points: 24 (ok 16, monostable 6, not_converged 2)" in out


def test_user_errors_exit_2(tmp_path, capsys):
    assert main(["maps", "info", str(tmp_path / "missing.nc")]) == 2
    junk = tmp_path / "junk.nc"
    junk.write_bytes(b"not netcdf")
    assert main(["maps", "info", str(junk)]) == 2
    err = capsys.readouterr().err
    assert "missing.nc does not exist" in err and "junk.nc: not a readable netCDF file" in err
    assert main(["maps", "build", "--grid", "huge", "--out", "x.nc"]) == 2
    assert main(["maps", "build", "--out", "x.nc", "--workers", "0"]) == 2
