"""DXF targets on small ezdxf drawings: every curve entity, blocks, OCS, units, chaining,
candidates and refusals."""

import math

import ezdxf
import numpy as np
import pytest

from snapmorph.design.target_io import read_target, read_target_file
from snapmorph.design.targets_pieces import TargetError


def _doc(units=4):
    doc = ezdxf.new("R2000", units=units)
    return doc, doc.modelspace()


def _save(doc, tmp_path, name="t.dxf"):
    f = tmp_path / name
    doc.saveas(f)
    return f


def test_line_and_arc_chain(tmp_path):
    """FreeCAD's hook: a LINE then an ARC (always counter-clockwise, here it has to be walked
    backwards), chained by shared ends: 150 + 60π mm."""
    doc, msp = _doc()
    msp.add_line((0, 0), (150, 0))
    msp.add_arc((150, 60), 60, -90, 90)  # from (150, 0) round to (150, 120)
    tf = read_target_file(_save(doc, tmp_path))
    assert tf.length_mm == pytest.approx(150 + 60 * math.pi, rel=2e-6)  # chords 1e-4 mm off
    assert tf.points[0] * 1e3 == pytest.approx([0, 0])
    assert tf.points[-1] * 1e3 == pytest.approx([150, 120], abs=1e-6)
    r = np.hypot(tf.points[1:, 0] * 1e3 - 150, tf.points[1:, 1] * 1e3 - 60)
    assert np.allclose(r, 60, atol=1e-9)  # points on the arc itself, not a Bézier of it


def test_reversed_piece_keeps_the_first_ones_direction(tmp_path):
    doc, msp = _doc()
    msp.add_arc((0, 100), 100, 270, 360)  # (0, 0) to (100, 100), first in the file
    msp.add_arc((200, 100), 100, 90, 180)  # (200, 200) to (100, 100): walked backwards
    tf = read_target_file(_save(doc, tmp_path))
    assert tf.length_mm == pytest.approx(100 * math.pi, rel=2e-6)
    assert tf.points[0] * 1e3 == pytest.approx([0, 0], abs=1e-9)
    assert tf.points[-1] * 1e3 == pytest.approx([200, 200], abs=1e-9)


def test_ellipse_spline_and_polylines(tmp_path):
    doc, msp = _doc()
    msp.add_ellipse((0, 0), major_axis=(150, 0), ratio=80 / 150, start_param=0,
                    end_param=math.pi / 2)
    from scipy.integrate import quad

    want = quad(lambda t: math.hypot(150 * math.sin(t), 80 * math.cos(t)), 0, math.pi / 2)[0]
    assert read_target_file(_save(doc, tmp_path, "e.dxf")).length_mm == pytest.approx(want, 2e-6)
    doc, msp = _doc()
    fit = [(x, 15 * math.sin(2 * math.pi * x / 200)) for x in np.linspace(0, 200, 21)]
    msp.add_spline(fit)
    sp = read_target_file(_save(doc, tmp_path, "s.dxf"))
    assert sp.points[0] * 1e3 == pytest.approx([0, 0], abs=1e-9)
    assert sp.points[-1] * 1e3 == pytest.approx([200, 0], abs=1e-6)
    assert 200 < sp.length_mm < 212
    doc, msp = _doc()
    msp.add_polyline3d([(0, 0, 5), (100, 0, 5), (100, 50, 5)])  # planar, at z = 5
    assert read_target_file(_save(doc, tmp_path, "p.dxf")).length_mm == pytest.approx(150)
    doc, msp = _doc()
    msp.add_polyline2d([(0, 0), (100, 0), (200, 0)], format="xy").vertices[0].dxf.bulge = 1.0
    assert read_target_file(_save(doc, tmp_path, "p2.dxf")).length_mm == pytest.approx(
        50 * math.pi + 100, rel=2e-6)


def test_insert_with_block_transform(tmp_path):
    """An INSERT at (200, 20), rotated 90°, scaled 1.5: WCS = insert + R(90)·1.5·block."""
    doc, msp = _doc()
    block = doc.blocks.new("HOOK")
    block.add_line((0, 0), (100, 0))
    msp.add_blockref("HOOK", (200, 20), dxfattribs={"rotation": 90, "xscale": 1.5,
                                                     "yscale": 1.5})
    tf = read_target_file(_save(doc, tmp_path))
    assert tf.length_mm == pytest.approx(150)
    assert tf.points[-1] * 1e3 == pytest.approx([200, 170], abs=1e-9)
    assert "HOOK" in tf.source


def test_mirrored_ocs_is_mirrored(tmp_path):
    """An ARC with extrusion (0, 0, -1), as CAD mirroring leaves it: OCS x is -WCS x."""
    doc, msp = _doc()
    msp.add_arc((100, 0), 50, 0, 90, dxfattribs={"extrusion": (0, 0, -1)})
    tf = read_target_file(_save(doc, tmp_path))
    assert tf.points[0] * 1e3 == pytest.approx([-150, 0], abs=1e-9)
    assert tf.points[-1] * 1e3 == pytest.approx([-100, 50], abs=1e-9)
    seg = np.diff(tf.points[:2], axis=0)[0]
    assert seg[1] > 0 and abs(seg[0]) < 0.01 * seg[1]  # leaves (-150, 0) upwards: clockwise in WCS


@pytest.mark.parametrize("code, mm", [(1, 25.4), (4, 1.0), (5, 10.0), (6, 1000.0), (0, 1.0)])
def test_insunits(tmp_path, code, mm):
    doc, msp = _doc(units=code)
    msp.add_line((0, 0), (0.5, 0))
    tf = read_target_file(_save(doc, tmp_path))
    assert tf.length_mm == pytest.approx(0.5 * mm)
    assert any("taken as mm" in n for n in tf.notes) == (code == 0)
    assert tf.frame.insunits == code


def test_units_override(tmp_path):
    doc, msp = _doc(units=0)
    msp.add_line((0, 0), (0.3, 0))
    assert read_target_file(_save(doc, tmp_path), units="m").length_mm == pytest.approx(300)
    doc, msp = _doc(units=4)
    msp.add_line((0, 0), (10, 0))
    tf = read_target_file(_save(doc, tmp_path, "b.dxf"), units="in")
    assert tf.length_mm == pytest.approx(254)
    assert any("read as in" in n for n in tf.notes)


def test_candidates_by_layer_and_handle(tmp_path):
    doc, msp = _doc()
    doc.layers.add("TARGET")
    doc.layers.add("AUX")
    a = msp.add_line((0, 0), (100, 0), dxfattribs={"layer": "TARGET"})
    msp.add_line((0, 50), (40, 50), dxfattribs={"layer": "AUX"})
    msp.add_circle((0, 0), 300, dxfattribs={"layer": "AUX"})  # a border: closed, not a candidate
    f = _save(doc, tmp_path)
    with pytest.raises(TargetError) as info:
        read_target(f)
    assert info.value.reason == "several-candidates"
    assert f"LINE {a.dxf.handle} on layer TARGET, 100.00 mm" in str(info.value)
    assert read_target_file(f, select="AUX").length_mm == pytest.approx(40)
    tf = read_target_file(f, select=a.dxf.handle)
    assert tf.length_mm == pytest.approx(100)
    assert any("closed curves are not targets" in n for n in tf.notes)


def test_hidden_layers_and_paper_space_not_read(tmp_path):
    doc, msp = _doc()
    doc.layers.add("OFF").off()
    doc.layers.add("FROZEN").freeze()
    msp.add_line((0, 0), (100, 0))
    msp.add_line((0, 50), (40, 50), dxfattribs={"layer": "OFF"})
    msp.add_line((0, 70), (40, 70), dxfattribs={"layer": "FROZEN"})
    doc.layout("Layout1").add_line((0, 0), (500, 0))
    tf = read_target_file(_save(doc, tmp_path))
    assert tf.length_mm == pytest.approx(100)
    assert any("hidden layer" in n for n in tf.notes)


@pytest.mark.parametrize("build, reason", [
    (lambda m: m.add_polyline3d([(0, 0, 0), (100, 0, 0), (100, 100, 60)]), "non-planar"),
    (lambda m: m.add_lwpolyline([(0, 0), (100, 0), (100, 100)], close=True), "closed"),
    (lambda m: (m.add_line((0, 0), (100, 0)), m.add_line((102, 0), (200, 0))),
     "several-candidates"),  # a 2 mm gap is two curves
    (lambda m: (m.add_line((0, 0), (50, 0)), m.add_line((50, 0), (100, 0)),
                m.add_line((50, 0), (50, 50))), "branched"),
    (lambda m: m.add_text("nothing"), "no-curve"),
])
def test_refusals(tmp_path, build, reason):
    doc, msp = _doc()
    build(msp)
    with pytest.raises(TargetError) as info:
        read_target(_save(doc, tmp_path))
    assert info.value.reason == reason
    assert "\n" not in str(info.value)


def test_small_gaps_are_joined(tmp_path):
    doc, msp = _doc()
    msp.add_line((0, 0), (100, 0))
    msp.add_line((100.03, 0), (200, 0))  # within JOIN_TOL_MM = 0.05 mm: the joint at (100, 0)
    tf = read_target_file(_save(doc, tmp_path))
    assert tf.length_mm == pytest.approx(200.0, abs=1e-9)
    assert len(tf.points) == 3
