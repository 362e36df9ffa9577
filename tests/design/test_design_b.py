"""Design at a flat-end length b: `inverse_design(..., b=)`, `snapmorph design --b`, the map
seen at b/L = b / L of every unit, and units.csv's b_mm column (read and written)."""

import math
import warnings

import numpy as np
import pytest

from snapmorph.design import Unit, inverse_design, read_units_csv, write_units_csv
from snapmorph.design.lookup import MapLookup
from snapmorph.design.map_model import map_at_b
from snapmorph.design.shapes import snapped_shape
from snapmorph.maps import CI_MAP, REFERENCE_MAP, DesignMap

T, W = 0.5e-3, 5e-3


@pytest.fixture(scope="module")
def ci():
    dm = DesignMap.load(CI_MAP)
    assert "b_over_L" in dm.dims, "the committed CI map has a b/L axis (schema 3)"
    return dm


def test_the_map_at_b_reads_every_unit_at_its_own_b_over_L(ci):
    view = map_at_b(ci, 1e-3, W)
    h, tL, wL = 0.3, 0.006, np.array([0.045, 0.055])
    got = view.at(h, tL, wL)
    want = ci.at(h, tL, wL, b_over_L=1e-3 / W * wL)  # b / L = (b / w) (w / L)
    for k in ("theta", "S", "F_cr"):
        np.testing.assert_array_equal(got[k], want[k])
    assert not np.allclose(got["theta"], ci.at(h, tL, wL)["theta"])  # b moves the shape


def test_unit_for_arc_solves_the_fixed_point_with_b_over_L_varying_with_L(ci):
    """L = chord / (S/L) with t/L, w/L and now b/L all depending on L: the unit found turns by
    θ over the chord at its own b/L."""
    b = 1.5e-3
    lookup = MapLookup(map_at_b(ci, b, W))
    L, h = lookup.unit_for_arc(70.0, 0.088, T, W)
    r = ci.at(h / L, T / L, W / L, b_over_L=b / L)
    assert r["theta"] == pytest.approx(70.0, abs=1e-6)
    assert r["S"] * L == pytest.approx(0.088, rel=1e-8)
    L0, h0 = MapLookup(ci).unit_for_arc(70.0, 0.088, T, W)
    assert abs(h - h0) > 1e-6  # another b, another unit


def test_a_map_without_a_b_axis_takes_only_its_own_b():
    old = DesignMap.load(REFERENCE_MAP)  # schema 2, b/L = 0
    assert map_at_b(old, 0.0, W) is old
    with pytest.raises(ValueError, match=r"b = 2 mm .*no b/L axis .*b/L = 0"):
        map_at_b(old, 2e-3, W)
    for bad in (-1e-3, math.nan, "5", True):
        with pytest.raises(ValueError, match=r"b \(extra flat length of the arch ends, m\)"):
            map_at_b(old, bad, W)


def test_inverse_design_with_b(ci, tmp_path):
    th = np.linspace(0, 1.2, 40)
    pts = np.column_stack([0.25 * np.sin(th), 0.25 * (1 - np.cos(th))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = inverse_design(pts, t=T, w=W, design_map=ci, b=1e-3)
    arched = [u for u in d.units if not u.is_spacer]
    assert arched and all(u.b == 1e-3 for u in arched)
    # the prediction is the map's at each unit's b/L: forward kinematics of the units agrees
    lookup = MapLookup(ci, state=d.state)
    for u in arched:
        shape = snapped_shape(u, lookup=lookup)
        theta = ci.at(u.h / u.L, T / u.L, W / u.L, b_over_L=u.b / u.L, state=d.state)["theta"]
        assert math.degrees(abs(shape.end_angle)) == pytest.approx(theta, abs=1e-9)
    # units.csv carries b (b_mm) and reads back to the same units
    path = write_units_csv(d.units, tmp_path / "units.csv")
    assert path.read_text().splitlines()[0] == "unit,L_mm,h_mm,t_mm,w_mm,side,b_mm"
    back = read_units_csv(path)
    assert [u.b for u in back] == pytest.approx([u.b for u in d.units], abs=1e-12)


def test_units_csv_b_mm_is_honoured_and_checked(tmp_path):
    p = tmp_path / "units.csv"
    p.write_text("unit,L_mm,h_mm,t_mm,w_mm,side,b_mm\n1,100,20,0.5,5,1,5\n2,60,0,0.5,5,0,0\n")
    arch, spacer = read_units_csv(p, b_over_L=0.0)
    assert arch.b == pytest.approx(5e-3) and spacer.b == 0.0
    # without the column, b = b_over_L L as before
    p.write_text("unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n")
    assert read_units_csv(p, b_over_L=0.03)[0].b == pytest.approx(3e-3)
    p.write_text("unit,L_mm,h_mm,t_mm,w_mm,side,b_mm\n1,100,20,0.5,5,1,-2\n")
    with pytest.raises(ValueError, match=r"line 2: b_mm .* >= 0 mm; got '-2'"):
        read_units_csv(p)
    p.write_text("unit,L_mm,h_mm,t_mm,w_mm,side,b_mm\n1,100,20,0.5,5,1,wide\n")
    with pytest.raises(ValueError, match=r"line 2: not a number in b_mm"):
        read_units_csv(p)
    units = [Unit(L=0.1, h=0.02, t=T, w=W, side=1, b=5e-3)]
    assert write_units_csv(units, p).read_text().splitlines()[1] == "1,100,20,0.5,5,1,5"


def test_design_command_takes_b_in_mm(capsys):
    from snapmorph.cli import main

    assert main(["design", "examples/drawing.svg", "--t", "0.5", "--w", "5", "--b", "-1"]) == 2
    err = capsys.readouterr().err
    assert "--b" in err and "mm" in err and len(err.strip().splitlines()) == 1
