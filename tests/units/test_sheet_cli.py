"""`snapmorph sheet`: bad input gives one line naming the option and exit status 2; a 1 x 1
sheet runs, writes its states as netCDF (units and long names) and its 3-D views."""

import pytest

from snapmorph.cli import main

BASE = ["sheet", "--L", "100", "--h", "40", "--t", "0.5", "--w", "5"]


@pytest.mark.parametrize("extra, match", [
    (["--cells", "3y3", "--order", "0"], "--cells"),
    (["--cells", "3x3", "--order", "a,b"], "--order"),
    (["--cells", "3x3", "--order", "9"], r"order must be .* \[0, 8\]"),
    (["--cells", "0x3", "--order", "0"], "cells must be"),
    (["--tiling", "pentagon", "--order", "0"], "--tiling"),
    (["--order", "0", "--nodes", "5"], "--nodes"),
    (["--order", "0", "--plot", "x.xyz"], "unknown figure type"),
])
def test_bad_input_is_one_line_naming_the_option(extra, match, capsys):
    assert main(BASE + extra) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    import re

    assert re.search(match, err), err


def test_triangle_too_tall_for_its_arches_is_refused_in_one_line(capsys):
    assert main(["sheet", "--tiling", "triangle", "--L", "100", "--h", "60", "--t", "0.5",
                 "--w", "5", "--order", "0"]) == 2
    assert "h (arch apex height, m) must be <=" in capsys.readouterr().err


@pytest.mark.slow
def test_one_cell_sheet_runs_and_writes_its_states(tmp_path, capsys):
    import xarray as xr

    nc, png = tmp_path / "states.nc", tmp_path / "sheet.png"
    status = main(BASE + ["--cells", "1x1", "--order", "0", "--out", str(nc), "--plot", str(png)])
    out = capsys.readouterr().out
    assert status == 0, out
    assert "F_cr (N)" in out and "wrote" in out
    ds = xr.open_dataset(nc)
    assert ds["positions"].shape[0] == 2 and ds["positions"].attrs["units"] == "m"
    assert ds["F_cr"].attrs["units"] == "N" and "long_name" in ds["snapped"].attrs
    assert int(ds["snapped"][1, 0]) == 1 and int(ds["snapped"][0, 0]) == 0
    assert png.stat().st_size > 10_000
