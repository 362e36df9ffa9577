"""Targets: any planar curve (arc-length parametrised), SVG paths and DXF polylines, the
rigid placement that minimises the deviation."""

import math

import numpy as np
import pytest

from snapmorph.design.target_io import read_target, svg_path_points
from snapmorph.design.targets import (Target, best_rigid_placement, deviation, example_targets,
                            place_rigid)


# ------------------------------------------------------------------------------- Target
def test_straight_from_two_points():
    t = Target.from_points([(0.1, 0.2), (0.1, 0.5)])
    assert t.length == pytest.approx(0.3)
    assert np.allclose(t.angle, math.pi / 2)
    assert t.total_turn_deg == 0


@pytest.mark.parametrize("turn", [30.0, 180.0, 300.0, -250.0])
def test_arc_turning_and_length(turn):
    """Points on a circle, in either direction and past vertical: length and turning of the
    arc, tangent direction unwrapped."""
    R = 0.2
    a = np.radians(np.linspace(0, abs(turn), 90))
    pts = np.stack([R * np.sin(a), math.copysign(1, turn) * R * (1 - np.cos(a))], axis=-1)
    t = Target.from_points(pts)
    assert t.length == pytest.approx(R * math.radians(abs(turn)), rel=1e-5)
    assert t.total_turn_deg == pytest.approx(turn, abs=0.05)
    assert np.all(np.sign(np.diff(t.angle)) == math.copysign(1, turn))
    # uniform in arc length
    step = np.hypot(*np.diff(t.xy, axis=0).T)
    assert np.ptp(step) < 1e-6 * t.length


def test_spiral_counts_past_360():
    t = Target.from_points(example_targets()["spiral 400°"])
    assert 400 < t.total_turn_deg < 420


def test_at_fraction():
    t = Target.from_points([(0, 0), (1.0, 0)])
    assert np.allclose(t.at_fraction([0, 0.25, 1]), [[0, 0], [0.25, 0], [1, 0]])


@pytest.mark.parametrize("points, message", [
    ([(0, 0)], "at least 2 points"),
    ([], "at least 2 points|shape"),
    ([(0, 0), (np.nan, 1)], "not finite"),
    ([(0, 0), (0, 0)], "zero length"),
    ([(1, 1), (1, 1), (1, 1)], "zero length"),
    ([(0, 0), (0.2, 0), (0.2, 0.1), (0.1, -0.1)], "crosses itself"),
    ([(0, 0), (0.1, 0.1), (0.1, 0.1), (0.3, 0)], "coincide"),
    ([[0, 0, 0]], "shape"),
    ("abc", "array"),
])
def test_refusals(points, message):
    with pytest.raises(ValueError, match=message):
        Target.from_points(points)


def test_best_rigid_placement_recovers_a_motion():
    """A curve moved rigidly is placed back on itself (deviation ~0), from a poor start."""
    a = np.radians(np.linspace(0, 120, 200))
    local = np.stack([0.2 * np.sin(a), 0.2 * (1 - np.cos(a))], axis=-1)  # from 0 heading +x
    target = place_rigid(local, (0.05, -0.03), 0.7)
    (x0, y0), ang = best_rigid_placement(local, target, start=(0.0, 0.0), angle=0.0)
    assert (x0, y0) == pytest.approx((0.05, -0.03), abs=2e-4)
    assert ang == pytest.approx(0.7, abs=2e-3)
    assert deviation(place_rigid(local, (x0, y0), ang), target)[0] < 1e-3


# ------------------------------------------------------------------------------- SVG
def test_svg_lines_and_relative_commands():
    a = svg_path_points("M 10 10 L 60 10 L 60 60 H 0 V 100")
    b = svg_path_points("m10,10 l50,0 l0 50 h-60 v40")
    assert np.allclose(a, b)
    assert np.allclose(a, [[10, 10], [60, 10], [60, 60], [0, 60], [0, 100]])
    c = svg_path_points("M10 10 60 10 60 60")  # implicit lineto after moveto
    assert np.allclose(c, a[:3])


def test_svg_arc_is_a_circle():
    """SVG 1.1 arc from (0, 0) to (100, 100), r = 100, sweep 1: centre (0, 100)."""
    p = svg_path_points("M 0 0 A 100 100 0 0 1 100 100")
    assert np.allclose(np.hypot(p[:, 0] - 0, p[:, 1] - 100), 100, atol=1e-9)
    assert np.allclose(p[-1], (100, 100))
    q = svg_path_points("M 0 0 a 100 100 0 0 0 100 100")  # sweep 0: the other centre
    assert np.allclose(np.hypot(q[:, 0] - 100, q[:, 1]), 100, atol=1e-9)


def test_svg_beziers():
    p = svg_path_points("M 0 0 C 0 100 100 100 100 0")
    mid = (np.array([0, 0]) + 3 * np.array([0, 100]) + 3 * np.array([100, 100])
           + np.array([100, 0])) / 8
    assert np.min(np.hypot(*(p - mid).T)) < 1e-9
    # S reflects the previous control point: this S continues smoothly
    s = svg_path_points("M 0 0 C 0 50 50 50 50 0 S 100 -50 100 0")
    same = svg_path_points("M 0 0 C 0 50 50 50 50 0 C 50 -50 100 -50 100 0")
    assert np.allclose(s, same)
    q = svg_path_points("M 0 0 Q 50 100 100 0 T 200 0")
    q2 = svg_path_points("M 0 0 Q 50 100 100 0 Q 150 -100 200 0")
    assert np.allclose(q, q2)


@pytest.mark.parametrize("d, message", [
    ("L 10 10", "must start with M"),
    ("M 0 0 L 10 10 Z", "closed"),
    ("M 0 0 L 10 10 M 20 20 L 30 30", "more than one subpath"),
    ("M 0 0 L 10", "needs 2 numbers"),
])
def test_svg_refusals(d, message):
    with pytest.raises(ValueError, match=message):
        svg_path_points(d)


def test_read_svg_file_flips_y_to_mm(tmp_path):
    """A mm document (its viewBox makes one user unit one mm; without a viewBox a user unit
    is a px, 1/96 in: test_targets_svg)."""
    f = tmp_path / "t.svg"
    f.write_text('<svg xmlns="http://www.w3.org/2000/svg" width="300mm" height="200mm" '
                 'viewBox="0 0 300 200"><g><path d="M 0 100 L 200 0" stroke="black"/></g></svg>')
    pts, tangents = read_target(f)
    assert tangents is None
    assert np.allclose(pts, [[0, -0.1], [0.2, 0.0]])  # y up, m
    _refused(tmp_path / "none.svg",  # a rect is no target
             '<svg xmlns="http://www.w3.org/2000/svg"><rect width="5" height="5"/></svg>',
             "only closed curves")
    _refused(tmp_path / "text.svg",
             '<svg xmlns="http://www.w3.org/2000/svg"><text>target</text></svg>', "no curve")
    _refused(tmp_path / "broken.svg", "<svg", "not a readable SVG")


def _refused(path, text, match):
    """A target file holding `text` is refused with a ValueError matching `match`."""
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        read_target(path)


# ------------------------------------------------------------------------------- DXF
def test_dxf_polyline_with_bulge(tmp_path):
    """A LWPOLYLINE from (0, 0) to (200, 0) with bulge 1: a half circle of radius 100 mm
    (counter-clockwise, below the chord), then a straight to (300, 0)."""
    import ezdxf

    doc = ezdxf.new("R2000", units=4)  # $INSUNITS = mm (ezdxf's default is metres)
    doc.modelspace().add_lwpolyline([(0, 0, 0, 0, 1.0), (200, 0, 0, 0, 0), (300, 0, 0, 0, 0)],
                                    format="xyseb")
    f = tmp_path / "t.dxf"
    doc.saveas(f)
    pts, _ = read_target(f)
    arc = pts[pts[:, 0] <= 0.2 + 1e-12]
    assert np.allclose(np.hypot(arc[:, 0] - 0.1, arc[:, 1]), 0.1, atol=1e-9)
    assert np.all(arc[1:-1, 1] < 0)  # counter-clockwise from (0, 0) to (200, 0): below
    assert np.allclose(pts[-1], (0.3, 0))
    t = Target.from_polyline(pts)  # drawn curves are taken as drawn (a spline would overshoot)
    assert t.length == pytest.approx(0.1 * math.pi + 0.1, rel=1e-3)


def test_dxf_refusals(tmp_path):
    import ezdxf

    doc = ezdxf.new("R2000")
    doc.modelspace().add_lwpolyline([(0, 0), (100, 0), (100, 100)], close=True)
    f = tmp_path / "closed.dxf"
    doc.saveas(f)
    with pytest.raises(ValueError, match="closed"):
        read_target(f)
    doc = ezdxf.new("R2000")
    doc.modelspace().add_point((0, 0))  # a LINE is read now (test_targets_dxf), a POINT never
    doc.modelspace().add_text("target")
    g = tmp_path / "point.dxf"
    doc.saveas(g)
    with pytest.raises(ValueError, match="no curve"):
        read_target(g)
    _refused(tmp_path / "junk.dxf", "not a dxf", "not a readable DXF")
    with pytest.raises(ValueError, match="not found"):
        read_target(tmp_path / "missing.dxf")
