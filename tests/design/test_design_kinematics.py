"""Forward kinematics on the synthetic map (θ and S known in closed form there)."""

import math

import numpy as np
import pytest

import synthetic_map as sm
from snapmorph.design import Unit, chain, forward_kinematics
from snapmorph.design import all_snap_patterns as all_states
from snapmorph.design import parse_snapped as parse_state
from snapmorph.design.shapes import normalise_base, snapped_shape

T, W = 0.5e-3, 5e-3


def unit(L=0.1, h=0.02, side=1):
    return Unit(L=L, h=h, t=T, w=W, side=side)


def test_straight_array(design_map):
    """Nothing snapped: a straight line along +x of the summed lengths."""
    units = [unit(0.1), unit(0.12, 0.03, -1), Unit(L=0.05, h=0, t=T, w=W)]
    xy = forward_kinematics(units, snapped=[False, False, False], design_map=design_map)
    assert np.allclose(xy[:, 1], 0.0)
    assert np.all(np.diff(xy[:, 0]) > 0)
    assert xy[-1, 0] == pytest.approx(0.27)
    assert np.allclose(xy[0], 0.0)


def test_one_snapped_unit_matches_the_map(design_map):
    """A snapped unit's chord is S and its end tangent turns by θ (synthetic: circular arc)."""
    u = unit(0.1, 0.025)  # h/L = 0.25: a grid node (and t/L = 0.005), w/L = 0.05
    ch = chain([u], [True], lookup=_lookup(design_map))
    theta = sm.theta_deg(0.25, 0.005, 0.05)
    res = design_map.at(h_over_L=0.25, t_over_L=0.005, w_over_L=0.05)
    assert math.degrees(ch.angles[-1]) == pytest.approx(res["theta"], rel=1e-9)
    assert res["theta"] == pytest.approx(theta, rel=1e-3)
    assert np.hypot(*ch.joints[-1]) == pytest.approx(res["S"] * 0.1, rel=1e-6)
    assert math.atan2(ch.joints[-1][1], ch.joints[-1][0]) == pytest.approx(math.radians(theta) / 2, rel=1e-3)


def test_end_tangent_matches_shape(design_map):
    """The polyline's last segment points along the end tangent used for the next unit."""
    xy = snapped_shape(unit(), lookup=_lookup(design_map)).xy
    d = xy[-1] - xy[-2]
    end = math.degrees(math.atan2(d[1], d[0]))
    theta = design_map.at(h_over_L=0.2, t_over_L=0.005, w_over_L=0.05)["theta"]
    assert end == pytest.approx(theta, abs=0.5 * theta / (len(xy) - 1) + 0.05)


def test_mirrored_side(design_map):
    a = forward_kinematics([unit(side=1), unit(0.09, 0.015, 1)], design_map=design_map)
    b = forward_kinematics([unit(side=-1), unit(0.09, 0.015, -1)], design_map=design_map)
    assert np.allclose(a[:, 0], b[:, 0]) and np.allclose(a[:, 1], -b[:, 1])
    assert a[-1, 1] > 0  # side +1 curls to the left (+z)


def test_rotation_and_translation_invariance(design_map):
    units = [unit(), unit(0.12, 0.03, -1), unit(0.09, 0.015)]
    snapped = [True, False, True]
    base = forward_kinematics(units, snapped, design_map=design_map)
    ang, p0 = 0.7, np.array([0.3, -0.2])
    moved = forward_kinematics(units, snapped, design_map=design_map, start=p0, start_angle=ang)
    c, s = math.cos(ang), math.sin(ang)
    assert np.allclose(moved, base @ np.array([[c, s], [-s, c]]) + p0, atol=1e-12)


def test_closure(design_map):
    """n identical units turning 360°/n each close into a ring (symmetric units: a regular
    polygon of chords), and the end tangent comes back to the start direction."""
    lk = _lookup(design_map)
    n = 6
    L, h = lk.unit_for_arc(360.0 / n, 0.1, T, W)
    ch = chain([Unit(L=L, h=h, t=T, w=W, side=1)] * n, None, lookup=lk)
    assert math.degrees(ch.angles[-1]) == pytest.approx(360.0, abs=1e-6)
    assert np.hypot(*ch.joints[-1]) < 1e-9
    assert np.allclose(np.hypot(*np.diff(ch.joints, axis=0).T), 0.1, rtol=1e-8)


def test_all_states(design_map):
    units = [unit(), Unit(L=0.05, h=0, t=T, w=W), unit(0.12, 0.03, -1), unit(0.09, 0.015)]
    states = all_states(units, design_map=design_map)
    assert len(states) == 2 ** 3
    assert sorted(states) == sorted(set(states))
    assert all(k[1] == "0" for k in states)  # the spacer has one state
    assert np.allclose(states["0000"][:, 1], 0)
    ends = np.array([xy[-1] for xy in states.values()])
    assert len(np.unique(ends.round(9), axis=0)) == 8
    one = forward_kinematics(units, "1001", design_map=design_map)
    assert np.allclose(states["1001"], one)


def test_parse_state():
    assert parse_state("101", 3) == [True, False, True]
    assert parse_state(None, 2) == [True, True]
    with pytest.raises(ValueError, match="3 characters"):
        parse_state("10", 3)
    with pytest.raises(ValueError, match="0/1"):
        parse_state("1x1", 3)
    with pytest.raises(ValueError, match="one entry per unit"):
        parse_state([True], 3)


def test_map_b_mismatch_is_an_error(design_map):
    u = Unit(L=0.1, h=0.02, t=T, w=W, side=1, b=5e-3)
    with pytest.raises(ValueError, match="b/L"):
        forward_kinematics([u], design_map=design_map)


def test_outside_map_is_an_error(design_map):
    with pytest.raises(ValueError, match="not bistable|not defined|outside"):
        forward_kinematics([unit(0.1, 0.006)], design_map=design_map)  # h/L = 0.06: monostable


def test_normalise_base():
    """A simulated shape in any frame comes out from (0, 0), start tangent +x, per unit L."""
    xy = sm.arc_shape(30.0, 0.9) * 0.1
    c, s = math.cos(0.4), math.sin(0.4)
    moved = xy @ np.array([[c, s], [-s, c]]) + [0.02, 0.03]
    back = normalise_base(moved, 30.0, 0.1)
    assert np.allclose(back, xy / 0.1, atol=1e-12)


def _lookup(dm):
    from snapmorph.design.lookup import MapLookup

    return MapLookup(dm)


# ------------------------------------------------------------------ released vs actuated
RELEASE_DEG = 5.0  # the test map's released units turn this much less


@pytest.fixture(scope="module")
def two_state_map(tmp_path_factory):
    """The synthetic map with a released state that turns RELEASE_DEG less (circular arcs)."""
    from snapmorph.maps import DesignMap

    ds = sm.make_dataset()
    th = ds["theta"].values - RELEASE_DEG
    base = ds["base_shape_released"].values.copy()
    for idx in np.ndindex(th.shape):
        if np.isfinite(th[idx]):
            base[idx] = sm.arc_shape(th[idx], sm.base_length(float(ds.h_over_L[idx[0]])))
    # new arrays: the synthetic map shares its actuated arrays with the released variables
    dims = ds["theta"].dims
    ds["theta_released"] = (dims, th, ds["theta_released"].attrs)
    ds["theta_end_released"] = (dims, th / 2, ds["theta_end_released"].attrs)
    ds["S_released"] = (dims, base[..., -1, 0] / np.cos(np.radians(th) / 2),
                        ds["S_released"].attrs)
    ds["base_shape_released"] = (ds["base_shape_released"].dims, base,
                                 ds["base_shape_released"].attrs)
    path = tmp_path_factory.mktemp("two") / "two_state.nc"
    ds.to_netcdf(path)
    return DesignMap.load(path)


def test_forward_kinematics_defaults_to_the_released_state(two_state_map):
    u = unit(0.1, 0.025)
    units = [u, u.mirrored(), u]
    rel = chain(units, "111", lookup=_lookup(two_state_map))
    act = chain(units, "111", lookup=_lookup(two_state_map), state="actuated")
    theta = two_state_map.at(0.25, 0.005, 0.05, state="actuated")["theta"]
    turns_rel = np.degrees(np.diff(rel.angles))
    turns_act = np.degrees(np.diff(act.angles))
    np.testing.assert_allclose(turns_act, [theta, -theta, theta], rtol=1e-9)
    np.testing.assert_allclose(turns_rel, [theta - RELEASE_DEG, -(theta - RELEASE_DEG),
                                           theta - RELEASE_DEG], rtol=1e-9)
    xy = forward_kinematics(units, "111", design_map=two_state_map)
    np.testing.assert_allclose(xy, rel.xy, atol=1e-15)
    xy_act = forward_kinematics(units, "111", design_map=two_state_map, state="actuated")
    np.testing.assert_allclose(xy_act, act.xy, atol=1e-15)
    states = all_states(units, design_map=two_state_map, state="actuated")
    np.testing.assert_allclose(states["111"], act.xy, atol=1e-15)
    with pytest.raises(ValueError, match="state must be 'released'"):
        forward_kinematics(units, "111", design_map=two_state_map, state="held")


def test_lookup_state_and_theta_end(two_state_map):
    from snapmorph.design.lookup import MapLookup

    lk = MapLookup(two_state_map)
    th_r, _ = lk.theta_S(0.25, 0.005, 0.05)
    th_a, _ = lk.theta_S(0.25, 0.005, 0.05, state="actuated")
    assert th_a - th_r == pytest.approx(RELEASE_DEG, abs=1e-9)
    assert lk.theta_end(0.25, 0.005, 0.05) == pytest.approx(th_r / 2, abs=1e-9)
    h = lk.h_over_L_for_theta_end(th_r / 2, 0.005, 0.05)
    assert h == pytest.approx(0.25, abs=1e-9)
    assert MapLookup(two_state_map, state="actuated").theta_S(0.25, 0.005, 0.05)[0] == th_a
