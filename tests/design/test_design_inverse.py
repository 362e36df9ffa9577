"""Inverse design on the synthetic map: round trips, spacers, splitting, bad input."""

import math

import numpy as np
import pytest

from snapmorph.design import Unit, chain, inverse_design
from snapmorph.design.lookup import MapLookup
from snapmorph.design.paper import s_control_points

# the synthetic map's energy barrier is h/L squared (not physical): no barrier margin here
BARRIER = {"min_barrier": 0.0}

T, W = 0.5e-3, 5e-3
KNOWN = [Unit(L=0.10, h=0.020, t=T, w=W, side=1),
         Unit(L=0.06, h=0.0, t=T, w=W, side=0),
         Unit(L=0.12, h=0.030, t=T, w=W, side=-1),
         Unit(L=0.09, h=0.015, t=T, w=W, side=1)]


@pytest.fixture(scope="module")
def known_chain(design_map):
    return chain(KNOWN, None, lookup=MapLookup(design_map))


def test_round_trip_control_points(design_map, known_chain):
    """Unit end points and tangents of a known array give back exactly those units."""
    d = inverse_design(known_chain.joints, t=T, w=W, tangents=np.degrees(known_chain.angles),
                       design_map=design_map, **BARRIER, placement="clamped")
    assert len(d.units) == len(KNOWN)
    for got, want in zip(d.units, KNOWN):
        assert got.side == want.side
        assert got.L == pytest.approx(want.L, rel=1e-6)
        assert got.h == pytest.approx(want.h, rel=1e-6, abs=1e-12)
    assert d.max_deviation < 1e-4  # the target here is the biarcs, the map's shapes are not arcs
    assert np.allclose(d.predicted, known_chain.xy, atol=1e-8)


def test_round_trip_points(design_map, known_chain):
    """Points sampled on a known array's snapped shape: the tolerance-driven design meets tol
    by least squares over all units at once, and says how far it got."""
    pts = known_chain.xy[::12]
    d = inverse_design(pts, t=T, w=W, design_map=design_map, **BARRIER, tol=0.005)
    assert d.met and d.max_deviation <= 0.005
    assert d.max_deviation == d.deviations["best"][0]
    assert d.deviations["best"][0] <= d.deviations["clamped"][0]
    assert d.rms_deviation <= d.max_deviation
    assert d.refinement["max_after"] < d.refinement["max_before"]
    c = inverse_design(pts, t=T, w=W, design_map=design_map, **BARRIER, tol=0.005, placement="clamped")
    assert c.met and np.allclose(c.predicted[0], pts[0])


def test_given_controls(design_map, known_chain):
    pts = known_chain.xy[::12]
    xs = [0.1, 0.2]
    d = inverse_design(pts, t=T, w=W, design_map=design_map, **BARRIER, controls=xs)
    assert np.allclose(d.control_points[1:-1, 0], xs)  # the paper's procedure
    assert len(d.control_points) == 4


def test_circular_s(design_map):
    """An S of two circular arms joined by a straight, as control points with tangents: every
    arched unit is the same, the arms on opposite sides, one spacer in the middle."""
    R, n, turn = 0.3, 4, 120.0
    pts, ang = _s_shape(R, n, turn, straight=0.1)
    d = inverse_design(pts, t=T, w=W, tangents=ang, design_map=design_map, **BARRIER)
    arched = [u for u in d.units if not u.is_spacer]
    assert len(arched) == 2 * n and sum(u.is_spacer for u in d.units) == 1
    assert d.units[n].is_spacer and d.units[n].L == pytest.approx(0.1)
    assert [u.side for u in arched] == [1] * n + [-1] * n
    for u in arched:
        assert u.L == pytest.approx(arched[0].L, rel=1e-9)
        assert u.h == pytest.approx(arched[0].h, rel=1e-9)
    assert np.allclose(d.joints, pts, atol=1e-9)
    assert d.max_deviation < 1e-3


def test_large_turn_is_split(design_map):
    """A half circle between two control points turns more than the map's largest θ."""
    R = 0.15
    d = inverse_design([(0, 0), (0, 2 * R)], t=T, w=W, tangents=[0.0, 180.0],
                       design_map=design_map, **BARRIER, placement="clamped", refine=False)
    lk = MapLookup(design_map)
    _, tmax, _, _ = lk.theta_range(T / d.units[0].L, W / d.units[0].L)
    assert len(d.units) == math.ceil(180.0 / tmax)
    assert all(u.L == pytest.approx(d.units[0].L) for u in d.units)
    assert np.allclose(d.joints[-1], (0, 2 * R), atol=1e-9)
    assert d.max_deviation < 1e-3


def test_flat_arcs_become_spacers(design_map):
    """The paper's procedure: arcs turning less than the smallest bistable θ (5.4° here) become
    one straight spacer."""
    d = inverse_design([(0, 0), (0.2, 0.0), (0.4, 0.0)], t=T, w=W, tangents=[0, 2.0, 0],
                       design_map=design_map, **BARRIER)
    assert len(d.units) == 1 and d.units[0].is_spacer
    assert d.units[0].L == pytest.approx(0.4, rel=1e-3)
    R, th = 1.0, np.radians([0.0, 10.0, 20.0])  # a gentle circle, 10° per interval
    pts = np.stack([R * np.sin(th), R * (1 - np.cos(th))], axis=-1)
    d = inverse_design(pts, t=T, w=W, tangents=np.degrees(th), design_map=design_map, **BARRIER)
    assert len(d.units) == 2 and not any(u.is_spacer for u in d.units)
    d = inverse_design(pts, t=T, w=W, tangents=np.degrees(th), design_map=design_map, **BARRIER,
                       min_turn_deg=12.0, refine=False)  # the paper's procedure as it is
    assert len(d.units) == 1 and d.units[0].is_spacer


def test_csv_target(design_map, known_chain, tmp_path):
    pts = known_chain.xy[::12]
    path = tmp_path / "target.csv"
    np.savetxt(path, pts * 1e3, delimiter=",", header="x_mm,y_mm", comments="")
    a = inverse_design(path, t=T, w=W, design_map=design_map, **BARRIER)
    b = inverse_design(pts, t=T, w=W, design_map=design_map, **BARRIER)
    assert [u.L for u in a.units] == pytest.approx([u.L for u in b.units], rel=1e-6)


@pytest.mark.parametrize("points, kw, message", [
    ([(0, 0)], {}, "at least 2 points"),
    ([(0, 0), (0.1, float("nan")), (0.2, 0)], {}, "not finite"),
    ([(0, 0), (0.2, 0), (0.2, 0.1), (0.1, -0.1)], {}, "crosses itself"),
    ([(0.1, 0.1), (0.1, 0.1), (0.1, 0.1)], {}, "zero length"),
    ([(0, 0), (0.1, 0.01), (0.1, 0.01), (0.2, 0)], {}, "coincide"),
    ([(0, 0), (1, 0)], {"tangents": [0.0]}, "one angle"),
    ([(0, 0), (1, 0)], {"tangents": [0.0, float("nan")]}, "finite"),
    ([(0, 0), (0.2, 0.01), (0.4, 0)], {"t": -1}, "t must be a positive"),
    ([(0, 0), (0.2, 0.01), (0.4, 0)], {"tol": 0.0}, "tol must be a fraction"),
    ([(0, 0), (0.2, 0.01), (0.4, 0)], {"tol": -0.01}, "tol must be a fraction"),
    ([(0, 0), (0.2, 0.01), (0.4, 0)], {"L_range": (0.3, 0.4)}, "no valid unit"),
    ([(0, 0), (0.2, 0.01), (0.4, 0)], {"hL_range": (0.6, 0.7)}, "no valid unit"),
    ([(0, 0), (0.2, 0.01), (0.4, 0)], {"placement": "middle"}, "placement must be one of"),
    ([(0, 0), (0.2, 0.01), (0.4, 0)], {"state": "held"}, "state must be one of"),
])
def test_bad_input(design_map, points, kw, message):
    kw = {"t": T, "w": W, "min_barrier": 0.0, **kw}
    with pytest.raises(ValueError, match=message):
        inverse_design(points, design_map=design_map, **kw)


def test_out_of_reach_says_so(design_map):
    """A target shorter than the shortest unit, turning 45°: the best design is returned with
    a warning and met = False, never silently."""
    with pytest.warns(UserWarning, match="tolerance missed"):
        d = inverse_design([(0, 0), (0.01, 0.002), (0.02, 0)], t=T, w=W, design_map=design_map,
                           min_barrier=0.0, max_units=2)
    assert d.met is False and d.max_deviation > 0.01
    assert "TOLERANCE MISSED" in d.summary()


def test_missing_file(design_map, tmp_path):
    with pytest.raises(ValueError, match="not found"):
        inverse_design(tmp_path / "nope.csv", t=T, w=W, design_map=design_map, **BARRIER)


def test_self_crossing_target(design_map):
    pts = [(0, 0), (0.2, 0), (0.2, 0.2), (0.1, -0.1)]
    with pytest.raises(ValueError, match="crosses itself|U-turn"):
        inverse_design(pts, t=T, w=W, tangents=[0, 90, 180, -80], design_map=design_map, **BARRIER)


def _s_shape(R, n, turn, straight):
    """Control points (m) and tangents (deg) of the paper-style S (`design.paper`)."""
    return s_control_points(R=R, turn=turn, n=n, straight=straight)


def test_tangent_vectors_and_wrapping(design_map):
    """Tangents as vectors, or as degrees across ±180°, describe the same target."""
    pts, ang = _s_shape(0.15, 2, 90.0, straight=0.05)
    a = inverse_design(pts, t=T, w=W, tangents=ang, design_map=design_map, **BARRIER)
    vec = np.stack([np.cos(np.radians(ang)), np.sin(np.radians(ang))], axis=-1)
    b = inverse_design(pts, t=T, w=W, tangents=vec, design_map=design_map, **BARRIER)
    rot = np.array([[-1.0, 0.0], [0.0, -1.0]])  # the same S turned by 180°: angles wrap
    c = inverse_design(pts @ rot.T, t=T, w=W, tangents=(ang + 180.0 + 180.0) % 360.0 - 180.0,
                       design_map=design_map, **BARRIER)
    for x, y in ((a, b), (a, c)):
        assert [u.L for u in x.units] == pytest.approx([u.L for u in y.units], rel=1e-9)
        assert [u.side for u in x.units] == [u.side for u in y.units]
