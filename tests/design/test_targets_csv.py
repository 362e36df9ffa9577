"""CSV targets: units from the header or units=, the third column only when named, comments,
what spreadsheets write."""

import numpy as np
import pytest

from snapmorph.design.target_io import read_target, read_target_file
from snapmorph.design.targets import read_target_csv
from snapmorph.design.targets_pieces import TargetError

ROWS = "0,0\n100,0\n100,50\n"


def _csv(tmp_path, text, name="t.csv", **kw):
    f = tmp_path / name
    f.write_text(text, **kw)
    return f


@pytest.mark.parametrize("header, mm", [
    ("x_mm,y_mm", 1.0), ("x,y", 1.0), ("", 1.0), ("x (in),y (in)", 25.4), ("x_in,y_in", 25.4),
    ("x_m,y_m", 1000.0), ("x_cm,y_cm", 10.0), ("x [mm],y [mm]", 1.0), ("X mm, Y mm", 1.0),
    ('"x_mm","y_mm"', 1.0),
])
def test_units_from_the_header(tmp_path, header, mm):
    f = _csv(tmp_path, (header + "\n" if header else "") + ROWS)
    pts, tangents = read_target(f)
    assert tangents is None
    assert pts[-1] == pytest.approx(np.array([100, 50]) * mm * 1e-3)
    assert read_target_csv(f)[0] == pytest.approx(pts)  # the old entry point agrees


def test_units_argument(tmp_path):
    f = _csv(tmp_path, ROWS)
    assert read_target(f, units="in")[0][-1] == pytest.approx([2.54, 1.27])
    tf = read_target_file(f)
    assert any("no header" in n and "mm" in n for n in tf.notes)
    g = _csv(tmp_path, "x (in),y (in)\n" + ROWS, name="in.csv")
    with pytest.raises(TargetError, match="the header says in, --units says mm") as info:
        read_target(g, units="mm")
    assert info.value.reason == "units"
    with pytest.raises(TargetError, match="units must be one of"):
        read_target(f, units="ft")
    with pytest.raises(TargetError, match="different units"):
        read_target(_csv(tmp_path, "x_mm,y_in\n" + ROWS, name="mixed.csv"))


def test_tangent_column_only_when_named(tmp_path):
    pts, tangents = read_target(_csv(tmp_path, "x_mm,y_mm,tangent_deg\n0,0,0\n100,50,90\n"))
    assert tangents == pytest.approx([0, 90])
    _, rad = read_target(_csv(tmp_path, "x_mm,y_mm,angle_rad\n0,0,0\n100,50,1.5707963267948966\n",
                              name="rad.csv"))
    assert rad == pytest.approx([0, 90])
    flat, none = read_target(_csv(tmp_path, "x_mm,y_mm,z_mm\n0,0,5\n100,0,5\n100,50,5\n",
                                  name="z.csv"))
    assert none is None and flat[-1] == pytest.approx([0.1, 0.05])
    with pytest.raises(TargetError, match="not planar.*50.00 mm") as info:
        read_target(_csv(tmp_path, "x_mm,y_mm,z_mm\n0,0,0\n100,0,0\n100,50,50\n", name="z2.csv"))
    assert info.value.reason == "non-planar"
    with pytest.raises(TargetError, match="3 columns and no header"):
        read_target(_csv(tmp_path, "0,0,0\n100,50,90\n", name="bare.csv"))
    with pytest.raises(TargetError, match="column 3 is headed 'weight'"):
        read_target(_csv(tmp_path, "x_mm,y_mm,weight\n0,0,1\n100,50,1\n", name="w.csv"))


def test_comments_bom_crlf_semicolons(tmp_path):
    text = "# drawn by hand\n\nx_mm,y_mm\n# the middle\n0,0\n100,0\n\n100,50\n"
    assert read_target(_csv(tmp_path, text))[0][-1] == pytest.approx([0.1, 0.05])
    bom = _csv(tmp_path, "\ufeffx_mm,y_mm\r\n0,0\r\n100,0\r\n100,50\r\n", name="bom.csv",
               encoding="utf-8")
    assert read_target(bom)[0][-1] == pytest.approx([0.1, 0.05])
    de = _csv(tmp_path, "x_mm;y_mm\n0;0\n100,5;0\n100,5;50,25\n", name="de.csv")
    assert read_target(de)[0][-1] == pytest.approx([0.1005, 0.05025])


@pytest.mark.parametrize("text, message, reason", [
    ("x_mm,y_mm\n0,0\n1,two\n", "line 3: not a number", "unreadable"),
    ("x_mm,y_mm\n", "no points", "no-curve"),
    ("x_mm,y_mm\n0,0\n10,0,5\n", "line 3: 3 values where the first point has 2", "unreadable"),
    ("a,b\n0,0\n10,0\n", "first two columns must be x and y", "unreadable"),
    ("x_mm,y_mm\n0,0\n100,0\n100,100\n0,0\n", "closed", "closed"),
])
def test_refusals(tmp_path, text, message, reason):
    with pytest.raises(TargetError, match=message) as info:
        read_target(_csv(tmp_path, text))
    assert info.value.reason == reason
    with pytest.raises(TargetError, match="select is for SVG and DXF"):
        read_target(_csv(tmp_path, ROWS, name="ok.csv"), select="curveA")
