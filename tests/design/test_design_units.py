"""Unit validation and the units.csv round trip."""

import csv

import pytest

from snapmorph.design import Unit, read_units_csv, spacer, write_units_csv


def test_defaults_and_spacer():
    u = Unit(L=0.1, h=0.02, t=0.5e-3, w=5e-3)
    assert u.side == 1 and u.b == 0.0 and not u.is_spacer
    s = spacer(0.05, 0.5e-3, 5e-3)
    assert s.side == 0 and s.is_spacer and s.h == 0.0
    assert Unit(L=0.05, h=0, t=0.5e-3, w=5e-3).side == 0
    assert u.mirrored().side == -1


@pytest.mark.parametrize("kwargs, word", [
    (dict(L=-0.1, h=0.02), "Unit.L"),
    (dict(L=0.1, h=-0.02), "Unit.h"),
    (dict(L=0.1, h=0.02, t=0.0), "Unit.t"),
    (dict(L=0.1, h=0.02, w=float("nan")), "Unit.w"),
    (dict(L=0.1, h=0.02, side=2), "Unit.side"),
    (dict(L=0.1, h=0.02, side=0), "Unit.side"),
    (dict(L=0.1, h=0.0, side=1), "Unit.side"),
    (dict(L=0.1, h=0.02, side=True), "Unit.side"),
    (dict(L=0.0095, h=0.002), "flat ends"),
    (dict(L=0.1, h="x"), "Unit.h"),
])
def test_bad_units_name_the_parameter(kwargs, word):
    full = dict(t=0.5e-3, w=5e-3) | kwargs
    with pytest.raises(ValueError, match=word):
        Unit(**full)


def test_frozen():
    u = Unit(L=0.1, h=0.02, t=0.5e-3, w=5e-3)
    with pytest.raises(Exception):
        u.L = 0.2


def test_csv_round_trip(tmp_path):
    units = [Unit(L=0.0726, h=0.0069, t=0.5e-3, w=5e-3, side=1),
             Unit(L=0.06731234, h=0.0, t=0.5e-3, w=5e-3, side=0),
             Unit(L=0.1332, h=0.0313, t=0.5e-3, w=5e-3, side=-1)]
    path = write_units_csv(units, tmp_path / "units.csv")
    with path.open() as fh:
        header = next(csv.reader(fh))
    assert header == ["unit", "L_mm", "h_mm", "t_mm", "w_mm", "side"]
    back = read_units_csv(path)
    assert len(back) == 3
    for a, b in zip(units, back):
        for name in ("L", "h", "t", "w"):
            assert getattr(b, name) == pytest.approx(getattr(a, name), abs=1e-9)
        assert a.side == b.side


def test_csv_errors(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        read_units_csv(tmp_path / "nope.csv")
    bad = tmp_path / "bad.csv"
    bad.write_text("unit,L_mm,h_mm\n1,100,20\n")
    with pytest.raises(ValueError, match="missing column"):
        read_units_csv(bad)
    bad.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,0\n")
    with pytest.raises(ValueError, match="line 2.*side"):
        read_units_csv(bad)
    bad.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,abc,20,0.5,5,1\n")
    with pytest.raises(ValueError, match="line 2: not a number"):
        read_units_csv(bad)
