"""`snapmorph design` and `snapmorph fk`: outputs, and one-line errors for bad input."""

import csv

import numpy as np
import pytest

from design import read_units_csv
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
                             str(out), "--map", str(synthetic_map_path), "--bed", "300")
    assert code == 0, err
    for name in ("units.csv", "predicted.csv", "design.png", "design.txt", "base.dxf",
                 "base.svg", "arches.dxf", "arches.svg", "molds.dxf", "molds.svg"):
        assert (out / name).is_file(), name
    with (out / "units.csv").open() as fh:
        assert next(csv.reader(fh)) == ["unit", "L_mm", "h_mm", "t_mm", "w_mm", "side"]
    units = read_units_csv(out / "units.csv")
    assert all(u.t == pytest.approx(0.5e-3) and u.w == pytest.approx(5e-3) for u in units)
    assert "deviation: max" in stdout and "L_mm" in stdout

    state = "".join("1" if i % 2 == 0 else "0" for i in range(len(units)))
    code, stdout, err = _run(capsys, "fk", "--units", str(out / "units.csv"), "--state", state,
                             "--map", str(synthetic_map_path), "--plot", str(tmp_path / "s.png"),
                             "--csv", str(tmp_path / "s.csv"))
    assert code == 0, err
    assert f"state {state}" in stdout and (tmp_path / "s.png").is_file()
    xy = np.loadtxt(tmp_path / "s.csv", delimiter=",", skiprows=1)
    assert np.allclose(xy[0], 0.0)
    assert np.sum(np.hypot(*np.diff(xy, axis=0).T)) == pytest.approx(
        sum(u.L for u in units) * 1e3, rel=0.02)


def test_fk_all_states(tmp_path, capsys, synthetic_map_path):
    units = tmp_path / "units.csv"
    units.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n2,50,0,0.5,5,0\n"
                     "3,100,20,0.5,5,-1\n")
    code, stdout, err = _run(capsys, "fk", "--units", str(units), "--all", "--map",
                             str(synthetic_map_path), "--plot", str(tmp_path / "all.png"))
    assert code == 0, err
    assert "4 states" in stdout and (tmp_path / "all.png").is_file()


@pytest.mark.parametrize("content, message", [
    ("0,0\n100,10\n", "at least 3 points"),
    ("0,0\n100,nan\n200,0\n", "not finite"),
    ("0,0\n100,40\n50,80\n200,0\n", "give control points with their tangents"),
    ("0,0\n10,2\n20,0\n", "outside the map"),
    ("0,0\nabc,1\n2,2\n", "not a number"),
])
def test_design_bad_input_is_one_line(tmp_path, capsys, synthetic_map_path, content, message):
    target = tmp_path / "bad.csv"
    target.write_text(content)
    code, stdout, err = _run(capsys, "design", str(target), "--t", "0.5", "--w", "5", "--out",
                             str(tmp_path / "o"), "--map", str(synthetic_map_path))
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_missing_files_are_one_line(tmp_path, capsys, synthetic_map_path):
    code, _, err = _run(capsys, "design", str(tmp_path / "none.csv"), "--t", "0.5", "--w", "5",
                        "--map", str(synthetic_map_path))
    assert code == 2 and "not found" in err and len(err.strip().splitlines()) == 1
    code, _, err = _run(capsys, "fk", "--units", str(tmp_path / "none.csv"), "--map",
                        str(synthetic_map_path))
    assert code == 2 and "not found" in err
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
