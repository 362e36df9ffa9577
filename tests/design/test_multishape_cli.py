"""`snapmorph design T1 T2 ...` and `snapmorph fk --nearest` (issue 24): files written, the
nearest state of a design's own target is its pattern, one-line errors in mm."""

import csv

import numpy as np
import pytest

from snapmorph.cli import main
from snapmorph.design.target_sets import turning_curve


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _svg(path, xy_m):
    """An SVG path through points (m), drawn in mm with y down (as `read_target` expects)."""
    d = "M " + " L ".join(f"{x * 1e3:.3f},{-y * 1e3:.3f}" for x, y in xy_m)
    path.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="800mm" height="800mm" '
                    f'viewBox="-100 -400 800 800"><path d="{d}" fill="none"/></svg>')
    return path


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    d = tmp_path_factory.mktemp("targets")
    a = _svg(d / "C.svg", turning_curve([(1, 90)], 0.5, 121))
    b = _svg(d / "Cmirror.svg", turning_curve([(1, -90)], 0.5, 121))
    return a, b


@pytest.mark.slow
def test_design_two_svg_targets_writes_everything_and_fk_finds_each_pattern(tmp_path, capsys,
                                                                             pair):
    a, b = pair
    out = tmp_path / "out"
    code, stdout, err = _run(capsys, "design", a, b, "--t", "0.5", "--w", "5", "--tol", "0.02",
                             "--out", out, "--no-progress")
    assert code == 0, err + stdout
    for name in ("units.csv", "patterns.csv", "target_1.png", "target_2.png", "patterns.png",
                 "morph.png", "design.txt", "simulated_1.csv", "simulated_2.csv", "base.dxf",
                 "base.svg", "arches.dxf", "molds.svg"):
        assert (out / name).is_file(), name
    assert "pattern" in stdout and "simulated (ok" in stdout and "met" in stdout
    with (out / "patterns.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["name"] for r in rows] == ["C.svg", "Cmirror.svg"]
    assert all(r["met"] == "yes" and float(r["simulated_best_pct"]) <= 2.5 for r in rows)
    for row, target in zip(rows, (a, b)):
        code, stdout, err = _run(capsys, "fk", "--units", out / "units.csv", "--nearest", target,
                                 "--plot", tmp_path / "n.png", "--csv", tmp_path / "n.csv")
        assert code == 0, err
        assert f"nearest state {row['pattern']}" in stdout
        assert (tmp_path / "n.png").is_file()
        assert np.loadtxt(tmp_path / "n.csv", delimiter=",", skiprows=1).shape[1] == 2


@pytest.mark.slow
def test_design_refuses_unequal_lengths_in_mm(tmp_path, capsys):
    a = _svg(tmp_path / "a.svg", turning_curve([(1, 90)], 0.40, 61))
    b = _svg(tmp_path / "b.svg", turning_curve([(1, -90)], 0.45, 61))
    code, stdout, err = _run(capsys, "design", a, b, "--t", "0.5", "--w", "5", "--out",
                             tmp_path / "o", "--no-progress", "--no-verify")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "400.0 mm and 450.0 mm" in err


@pytest.mark.parametrize("extra, word", [
    (("--controls", "100"), "--controls"),
    (("--refine",), "--refine"),
    (("--theta-convention", "paper"), "--theta-convention"),
    (("--tol", "2"), "--tol"),
])
def test_design_multi_bad_options_one_line(tmp_path, capsys, pair, extra, word):
    code, stdout, err = _run(capsys, "design", *pair, "--t", "0.5", "--w", "5", "--out",
                             tmp_path / "o", "--no-progress", *extra)
    assert code == 2 and len(err.strip().splitlines()) == 1 and word in err


def test_design_multi_missing_file_names_it(tmp_path, capsys, pair):
    code, _, err = _run(capsys, "design", pair[0], tmp_path / "nope.svg", "--t", "0.5", "--w",
                        "5", "--out", tmp_path / "o")
    assert code == 2 and "target 2" in err and "nope.svg" in err


def test_fk_nearest_bad_combinations(tmp_path, capsys, pair):
    units = tmp_path / "units.csv"
    units.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n2,100,20,0.5,5,-1\n")
    for extra, word in ((("--all",), "--all"), (("--state", "10"), "--state"),
                        (("--source", "simulate"), "--source")):
        code, _, err = _run(capsys, "fk", "--units", units, "--nearest", pair[0], *extra)
        assert code == 2 and word in err and len(err.strip().splitlines()) == 1
    code, _, err = _run(capsys, "fk", "--units", units, "--nearest", tmp_path / "none.svg")
    assert code == 2 and "--nearest" in err
