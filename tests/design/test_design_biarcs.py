"""Biarcs: end points and tangents matched, G1 at the junction, circles reproduced."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snapmorph.design.biarcs import Arc, arc_from_tangent, biarc, biarcs, sample_arcs


def _check_biarc(p0, a0, p1, a1, first, second):
    assert np.allclose(first.p, p0, atol=1e-12)
    assert first.a == pytest.approx(a0)
    assert np.allclose(first.end, second.p, atol=1e-9)                 # G0 at the junction
    assert math.remainder(first.end_angle - second.a, 2 * math.pi) == pytest.approx(0, abs=1e-9)
    assert np.allclose(second.end, p1, atol=1e-9 * max(1, np.hypot(*np.subtract(p1, p0))))
    assert math.remainder(second.end_angle - a1, 2 * math.pi) == pytest.approx(0, abs=1e-7)
    assert first.s > 0 and second.s > 0


def test_biarc_simple():
    p0, p1 = (0.0, 0.0), (1.0, 0.2)
    a, b = biarc(p0, 0.3, p1, -0.5)
    _check_biarc(p0, 0.3, p1, -0.5, a, b)
    assert a.k > 0 > b.k  # an S: turns left then right


@settings(max_examples=200, deadline=None)
@given(x=st.floats(0.05, 2.0), y=st.floats(-1.0, 1.0), a0=st.floats(-1.2, 1.2),
       a1=st.floats(-1.2, 1.2))
def test_biarc_properties(x, y, a0, a1):
    """For every forward-going configuration: ends and tangents matched, tangent continuous."""
    p0, p1 = (0.0, 0.0), (x, y)
    chord = math.atan2(y, x)
    if abs(a0 - chord) > 1.4 or abs(a1 - chord) > 1.4:
        return  # tangents pointing backwards: not a case inverse design produces
    first, second = biarc(p0, a0, p1, a1)
    _check_biarc(p0, a0, p1, a1, first, second)
    # the sampled curve is G1: turning between consecutive samples stays small
    xy = sample_arcs([first, second], 200)
    d = np.diff(xy, axis=0)
    turn = np.diff(np.unwrap(np.arctan2(d[:, 1], d[:, 0])))
    assert np.max(np.abs(turn)) < 0.1


def test_points_on_a_circle_give_that_circle():
    R = 0.2
    th = np.radians([5.0, 30.0, 70.0])
    pts = np.stack([R * np.sin(th), R - R * np.cos(th)], axis=-1)
    arcs = biarcs(pts, th)
    assert len(arcs) == 2  # one arc per interval, not two
    for arc in arcs:
        assert arc.k == pytest.approx(1 / R)
    assert arcs[1].turn == pytest.approx(th[2] - th[1])
    assert np.allclose(arcs[1].end, pts[2])
    # without merging, the equal-tangent-length biarc of co-circular data lies on the circle
    a, b = biarc(pts[0], th[0], pts[1], th[1])
    assert a.k == pytest.approx(1 / R) and b.k == pytest.approx(1 / R)


def test_straight():
    arcs = biarcs([(0, 0), (1, 1)], [math.pi / 4, math.pi / 4])
    assert len(arcs) == 1 and arcs[0].k == 0.0 and arcs[0].s == pytest.approx(math.sqrt(2))


def test_u_turn_is_an_error():
    with pytest.raises(ValueError, match="U-turn"):
        biarc((0, 0), 0.0, (0, 1), 0.0)


def test_split_and_arc_from_tangent():
    arc = arc_from_tangent((0, 0), 0.0, (1.0, 0.5))
    parts = arc.split(3)
    assert sum(p.s for p in parts) == pytest.approx(arc.s)
    assert np.allclose(parts[-1].end, arc.end)
    assert parts[1].a == pytest.approx(arc.a + arc.turn / 3)
    assert Arc((0, 0), 0.0, 0.0, 2.0).chord == pytest.approx(2.0)
