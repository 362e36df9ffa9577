"""The shared command-line helpers (`snapmorph.commands._common`), the units.csv placement line
and the one frame convention of `fk` / `array`."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from snapmorph.design.units import Unit, read_placement, read_units_csv, write_units_csv
from snapmorph.commands._common import (CommandError, input_file, integer, length_mm, number,
                                        output_dir, output_file, plot_file)


# ----------------------------------------------------------------------------- typed options
@pytest.mark.parametrize("text,words", [
    ("-1", [">", "0 mm", "'-1'"]), ("0", ["> 0 mm"]), ("nan", ["finite", "mm"]),
    ("inf", ["finite"]), ("abc", ["number", "mm", "'abc'"]), ("", ["number"]),
])
def test_length_mm_refuses_with_unit_and_range(text, words):
    with pytest.raises(argparse.ArgumentTypeError) as err:
        length_mm(what="sheet thickness")(text)
    for w in words:
        assert w in str(err.value)
    assert "sheet thickness" in str(err.value)


def test_number_bounds_and_values():
    frac = number("", 0.0, 0.5, low_inclusive=True, high_inclusive=False)
    assert frac("0") == 0.0 and frac("0.25") == 0.25
    for bad in ("0.5", "-0.1", "1e9"):
        with pytest.raises(argparse.ArgumentTypeError, match=r"\[0, 0.5\)"):
            frac(bad)
    assert length_mm(0.0, low_inclusive=True)("0") == 0.0
    assert length_mm()("2.5") == 2.5
    pa = number("Pa", 0.0)
    with pytest.raises(argparse.ArgumentTypeError, match="> 0 Pa"):
        pa("-3")


def test_integer():
    nodes = integer(11, 100)
    assert nodes("41") == 41
    for bad in ("3", "101", "1.5", "x"):
        with pytest.raises(argparse.ArgumentTypeError, match=r"integer in \[11, 100\]"):
            nodes(bad)


# ----------------------------------------------------------------------------- path rules
def test_output_file_creates_parents_and_leaves_nothing(tmp_path):
    target = tmp_path / "a" / "b" / "out.csv"
    assert output_file(target, "--csv") == target
    assert target.parent.is_dir() and not target.exists()  # the probe is removed again
    target.write_text("keep")
    output_file(target, "--csv")
    assert target.read_text() == "keep"  # an existing file is not truncated by the probe


def test_output_paths_refused(tmp_path):
    f = tmp_path / "file.txt"
    f.write_text("x")
    with pytest.raises(CommandError, match=r"--plot .*is a file, not a folder"):
        output_file(f / "deep" / "x.png", "--plot")
    with pytest.raises(CommandError, match=r"--csv .*is a folder"):
        output_file(tmp_path, "--csv")
    with pytest.raises(CommandError, match=r"--out .*is a file"):
        output_dir(f, "--out")
    with pytest.raises(CommandError, match=r"--out .*is a file"):
        output_dir(f / "sub", "--out")
    with pytest.raises(CommandError, match=r"--plot .*figure type '.txt'"):
        plot_file(tmp_path / "x.txt", "--plot")
    # Unwritable even for root: /proc refuses new folders and files.
    with pytest.raises(CommandError, match="--csv .*cannot create the folder"):
        output_file("/proc/snapmorph-test/x.csv", "--csv")
    with pytest.raises(CommandError, match="--csv .*cannot write"):
        output_file("/proc/snapmorph-test.csv", "--csv")
    with pytest.raises(CommandError, match="--out .*(cannot create|not writable)"):
        output_dir("/proc/snapmorph-test", "--out")


def test_output_dir_creates(tmp_path):
    d = tmp_path / "x" / "y"
    assert output_dir(d, "--out") == d and d.is_dir() and not list(d.iterdir())


def test_input_file(tmp_path):
    with pytest.raises(CommandError, match="--units .*no such file"):
        input_file(tmp_path / "none.csv", "--units")
    with pytest.raises(CommandError, match="--units .*is a folder"):
        input_file(tmp_path, "--units")
    f = tmp_path / "u.csv"
    f.write_text("x")
    assert input_file(f, "--units") == f


# ----------------------------------------------------------------------------- units.csv
UNITS = [Unit(L=0.1358, h=0.0453, t=5e-4, w=5e-3, side=-1),
         Unit(L=0.06, h=0.0, t=5e-4, w=5e-3, side=0),
         Unit(L=0.1719, h=0.0366, t=5e-4, w=5e-3, side=1)]


def test_placement_round_trip(tmp_path):
    placement = (0.012345, -0.0031, math.radians(68.4292690215))
    path = write_units_csv(UNITS, tmp_path / "units.csv", placement=placement)
    first = path.read_text().splitlines()[0]
    assert first.startswith("# placement x0_mm=12.345 y0_mm=-3.1 angle_deg=68.42926902")
    back = read_placement(path)
    assert np.allclose(back, placement, rtol=0, atol=1e-12)
    assert read_units_csv(path) == UNITS or all(
        abs(a.L - b.L) < 1e-9 and a.side == b.side for a, b in zip(read_units_csv(path), UNITS))
    plain = write_units_csv(UNITS, tmp_path / "plain.csv")
    assert read_placement(plain) is None
    assert not plain.read_text().startswith("#")


def test_placement_refused(tmp_path):
    with pytest.raises(ValueError, match="placement"):
        write_units_csv(UNITS, tmp_path / "u.csv", placement=(0.0, float("nan"), 0.0))
    with pytest.raises(ValueError, match="placement"):
        write_units_csv(UNITS, tmp_path / "u.csv", placement=(0.0, 0.0))
    p = tmp_path / "bad.csv"
    p.write_text("# placement x0_mm=1 y0_mm=2\nunit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n")
    with pytest.raises(ValueError, match="line 1.*angle_deg"):
        read_placement(p)


@pytest.mark.parametrize("row,words", [
    ("1,100,0,0.5,5,1", ["h_mm = 0", "spacer", "side must be 0"]),
    ("1,100,0,0.5,5,-1", ["h_mm = 0", "side must be 0"]),
    ("1,100,20,0.5,5,0", ["side = 0", "h_mm must be 0"]),
    ("1,100,20,0.5,5,1.5", ["side must be 1, -1", "'1.5'"]),
    ("1,100,20,0.5,5,+", ["side", "'+'"]),
    ("1,100,-3,0.5,5,1", ["h_mm must be >= 0 mm"]),
])
def test_spacer_rule(tmp_path, row, words):
    p = tmp_path / "u.csv"
    p.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n" + row + "\n")
    with pytest.raises(ValueError) as err:
        read_units_csv(p)
    assert "line 2" in str(err.value)
    for w in words:
        assert w in str(err.value)


def test_comments_and_blank_lines_skipped(tmp_path):
    p = tmp_path / "u.csv"
    p.write_text("# made by hand\n\nunit,L_mm,h_mm,t_mm,w_mm,side\n# a comment\n"
                 "1,100,20,0.5,5,1\n\n2,60,0,0.5,5,0\n")
    units = read_units_csv(p)
    assert [u.side for u in units] == [1, 0] and units[1].is_spacer


# ----------------------------------------------------------------------------- one frame
def test_fk_csv_is_in_the_targets_frame(tmp_path, capsys):
    """`fk --csv` of a units.csv with a placement line is the same shape as without it,
    rotated by the placement angle and moved to its start point."""
    from snapmorph.cli import main
    from tests.design import synthetic_map

    dm = synthetic_map.write(tmp_path / "synthetic.nc")
    units = [Unit(L=0.1, h=0.02, t=5e-4, w=5e-3, side=1), Unit(L=0.06, h=0.0, t=5e-4, w=5e-3),
             Unit(L=0.1, h=0.02, t=5e-4, w=5e-3, side=-1)]
    placement = (0.05, -0.02, math.radians(54.0))
    placed = write_units_csv(units, tmp_path / "placed.csv", placement=placement)
    plain = write_units_csv(units, tmp_path / "plain.csv")
    for path, out in ((placed, "a.csv"), (plain, "b.csv")):
        assert main(["fk", "--units", str(path), "--state", "100", "--map", str(dm),
                     "--csv", str(tmp_path / out)]) == 0
    text = capsys.readouterr().out
    assert "target's frame" in text and "array frame" in text
    a = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1) * 1e-3
    b = np.loadtxt(tmp_path / "b.csv", delimiter=",", skiprows=1) * 1e-3
    c, s = math.cos(placement[2]), math.sin(placement[2])
    expected = b @ np.array([[c, s], [-s, c]]) + np.array(placement[:2])
    assert np.allclose(a, expected, atol=2e-7)  # the CSV has 0.1 µm resolution
    assert np.allclose(a[0], placement[:2], atol=1e-7)
    direction = math.atan2(*(a[1] - a[0])[::-1])
    assert abs(direction - placement[2]) < 0.05  # unit 1 leaves along the placement angle
    # --no-placement gives the array frame back
    assert main(["fk", "--units", str(placed), "--state", "100", "--map", str(dm),
                 "--no-placement", "--csv", str(tmp_path / "c.csv")]) == 0
    assert np.allclose(np.loadtxt(tmp_path / "c.csv", delimiter=",", skiprows=1) * 1e-3, b)


def test_plot_transform_matches_chain_placement():
    """The frame transform the array plots use is the one `chain` uses for its start."""
    from snapmorph.design import chain
    from snapmorph.plotting.arrays import transform

    units = [Unit(L=0.1, h=0.0, t=5e-4, w=5e-3), Unit(L=0.05, h=0.0, t=5e-4, w=5e-3)]
    pl = (0.1, 0.2, 1.1)
    a = chain(units, [False, False], source="simulate").xy
    b = chain(units, [False, False], source="simulate", start=pl[:2], start_angle=pl[2]).xy
    assert np.allclose(transform(a, pl), b, atol=1e-12)
