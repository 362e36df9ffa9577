"""`snapmorph design` and `snapmorph fk`: outputs, and one-line errors for bad input."""

import csv
import math

import numpy as np
import pytest

from snapmorph.design import read_units_csv
from snapmorph.design.units import read_placement
from snapmorph.cli import main

M_POINTS = "x_mm,y_mm\n0,0\n100,40\n200,15\n300,50\n400,0\n"


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_design_writes_everything(tmp_path, capsys, synthetic_map_path):
    target = tmp_path / "M.csv"
    target.write_text(M_POINTS)
    out = tmp_path / "build"
    code, stdout, err = _run(capsys, "design", str(target), "--t", "0.5", "--w", "5", "--out",
                             str(out), "--map", str(synthetic_map_path), "--bed", "300",
                             "--min-barrier", "0", "--no-verify")
    assert code == 0, err
    for name in ("units.csv", "predicted.csv", "design.png", "design.txt", "base.dxf",
                 "base.svg", "arches.dxf", "arches.svg", "molds.dxf", "molds.svg"):
        assert (out / name).is_file(), name
    with (out / "units.csv").open() as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].startswith("#")]
        assert rows[0] == ["unit", "L_mm", "h_mm", "t_mm", "w_mm", "side"]
    units = read_units_csv(out / "units.csv")
    assert all(u.t == pytest.approx(0.5e-3) and u.w == pytest.approx(5e-3) for u in units)
    assert "best rigid placement" in stdout and "start clamped" in stdout and "L_mm" in stdout

    state = "".join("1" if i % 2 == 0 else "0" for i in range(len(units)))
    code, stdout, err = _run(capsys, "fk", "--units", str(out / "units.csv"), "--state", state,
                             "--map", str(synthetic_map_path), "--plot", str(tmp_path / "s.png"),
                             "--csv", str(tmp_path / "s.csv"))
    assert code == 0, err
    assert f"state {state}" in stdout and (tmp_path / "s.png").is_file()
    xy = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1)
    assert np.allclose(xy[0], np.array(read_placement(out / "units.csv")[:2]) * 1e3, atol=1e-3)
    # all snapped, `fk` draws what the design predicted (same map, same placement)
    every = "".join("0" if u.is_spacer else "1" for u in units)
    code, stdout, err = _run(capsys, "fk", "--units", str(out / "units.csv"), "--state", every,
                             "--map", str(synthetic_map_path), "--csv", str(tmp_path / "a.csv"))
    assert code == 0, err
    xy = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)
    predicted = np.loadtxt(out / "predicted.csv", delimiter=",", skiprows=1)
    assert xy.shape == predicted.shape and np.allclose(xy, predicted, atol=0.05)  # mm, rounding


def test_fk_all_states(tmp_path, capsys, synthetic_map_path):
    units = tmp_path / "units.csv"
    units.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n2,50,0,0.5,5,0\n"
                     "3,100,20,0.5,5,-1\n")
    code, stdout, err = _run(capsys, "fk", "--units", str(units), "--all", "--map",
                             str(synthetic_map_path), "--plot", str(tmp_path / "all.png"))
    assert code == 0, err
    assert "4 states" in stdout and (tmp_path / "all.png").is_file()


@pytest.mark.parametrize("content, message", [
    ("0,0\n", "at least 2 points"),
    ("0,0\n100,nan\n200,0\n", "not finite"),
    ("0,0\n200,0\n200,100\n100,-100\n", "crosses itself"),
    ("5,5\n5,5\n5,5\n", "zero length"),
    ("0,0\nabc,1\n2,2\n", "not a number"),
])
def test_design_bad_input_is_one_line(tmp_path, capsys, synthetic_map_path, content, message):
    target = tmp_path / "bad.csv"
    target.write_text(content)
    code, stdout, err = _run(capsys, "design", str(target), "--t", "0.5", "--w", "5", "--out",
                             str(tmp_path / "o"), "--map", str(synthetic_map_path),
                             "--min-barrier", "0", "--no-verify")
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_missing_files_are_one_line(tmp_path, capsys, synthetic_map_path):
    code, _, err = _run(capsys, "design", str(tmp_path / "none.csv"), "--t", "0.5", "--w", "5",
                        "--map", str(synthetic_map_path))
    assert code == 2 and "not found" in err and len(err.strip().splitlines()) == 1
    code, _, err = _run(capsys, "fk", "--units", str(tmp_path / "none.csv"), "--map",
                        str(synthetic_map_path))
    assert code == 2 and ("not found" in err or "no such file" in err)
    target = tmp_path / "ok.csv"
    target.write_text(M_POINTS)
    code, _, err = _run(capsys, "design", str(target), "--t", "0.5", "--w", "5",
                        "--map", str(tmp_path / "none.nc"))
    assert code == 2 and "design map not found" in err


def test_fk_bad_state(tmp_path, capsys, synthetic_map_path):
    units = tmp_path / "units.csv"
    units.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n")
    code, _, err = _run(capsys, "fk", "--units", str(units), "--state", "10", "--map",
                        str(synthetic_map_path))
    assert code == 2 and "1 characters" in err


SVG_ARC = ('<svg xmlns="http://www.w3.org/2000/svg" width="400mm" height="300mm" viewBox="0 0 400 300">'
           '<path d="M 0 250 A 200 200 0 0 0 200 50" fill="none" stroke="black"/></svg>')


def test_design_svg_with_verification(tmp_path, capsys):
    """`snapmorph design target.svg --t 0.5 --w 5 --tol 0.01 --out DIR` on the default map: a
    quarter circle of R = 200 mm drawn as an SVG arc; the design meets 1 %, the whole array is
    simulated, both deviations are printed for both, units.csv has the placement line."""
    target = tmp_path / "arc.svg"
    target.write_text(SVG_ARC)
    out = tmp_path / "svg"
    code, stdout, err = _run(capsys, "design", str(target), "--t", "0.5", "--w", "5", "--tol",
                             "0.01", "--out", str(out), "--no-drawings")
    assert code == 0, err + stdout
    assert stdout.count("best rigid placement") == 2 and stdout.count("start clamped") == 2
    assert "simulated array (ok" in stdout and "met" in stdout
    for name in ("units.csv", "predicted.csv", "simulated.csv", "design.png", "design.txt"):
        assert (out / name).is_file(), name
    x0, y0, a0 = read_placement(out / "units.csv")
    assert math.hypot(x0, y0 + 0.25) < 0.02  # near the arc's start: SVG (0, 250) is y-up (0, -0.25 m)
    units = read_units_csv(out / "units.csv")
    assert any(not u.is_spacer for u in units)


def test_design_missed_tolerance_exit_1(tmp_path, capsys, synthetic_map_path):
    """A tolerance the units cannot meet: exit status 1, the best design written and marked."""
    target = tmp_path / "M.csv"
    target.write_text(M_POINTS)
    out = tmp_path / "missed"
    code, stdout, err = _run(capsys, "design", str(target), "--t", "0.5", "--w", "5", "--tol",
                             "0.0001", "--out", str(out), "--map", str(synthetic_map_path),
                             "--min-barrier", "0", "--no-verify", "--no-drawings",
                             "--max-units", "6")  # few layouts to try: a quick miss
    assert code == 1
    assert "TOLERANCE MISSED" in stdout
    assert "TOLERANCE MISSED" in (out / "design.txt").read_text()
    assert "TOLERANCE MISSED" in (out / "units.csv").read_text()
    assert read_units_csv(out / "units.csv")  # still readable


@pytest.mark.parametrize("argv, message", [
    (["--tol", "1"], "--tol is a fraction"),
    (["--tol", "0"], "--tol is a fraction"),
    (["--L-range", "100"], "--L-range (mm) must be MIN,MAX"),
    (["--L-range", "200,100"], "0 < MIN < MAX"),
    (["--L-range", "300,400"], "no valid unit"),
    (["--max-units", "0"], "--max-units must be >= 1"),
    (["--max-units", "1"], "> max_units = 1"),
])
def test_design_option_errors_one_line(tmp_path, capsys, synthetic_map_path, argv, message):
    target = tmp_path / "M.csv"
    target.write_text(M_POINTS)
    code, _, err = _run(capsys, "design", str(target), "--t", "0.5", "--w", "5", "--out",
                        str(tmp_path / "o"), "--map", str(synthetic_map_path), "--min-barrier",
                        "0", "--no-verify", *argv)
    assert code == 2 and message in err, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
