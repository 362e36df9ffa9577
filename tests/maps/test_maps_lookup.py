"""Interpolated lookup: exactness on fields the scheme reproduces, masking, ranges, inverse."""

import numpy as np
import pytest

from maps_synthetic import (FAILED, GRID, H_STANDING, RELEASED_TURN, F_cr, S, S_released, boundary,
                            shape, theta, theta_released)
from snapmorph.maps import MapDomainError

rng = np.random.default_rng(42)


def random_bistable_points(n):
    """Off-grid points whose cells are all bistable and away from the failed point."""
    out = []
    while len(out) < n:
        t = rng.uniform(0.0025, 0.01)
        w = rng.uniform(0.02, 0.08)
        h = rng.uniform(0.25, 0.5)
        if abs(h - 0.35) < 0.05 + 1e-9 and t < 0.0075 and 0.02 < w:  # cells touching FAILED
            continue
        out.append((h, t, w))
    return np.array(out)


def test_reproduces_linear_and_log_linear_fields_off_grid(dm):
    h, t, w = random_bistable_points(200).T
    v = dm.at(h, t, w, state="actuated")
    np.testing.assert_allclose(v["theta"], theta(h, t, w), rtol=0, atol=1e-10)
    np.testing.assert_allclose(v["S"], S(h, t, w), rtol=0, atol=1e-12)
    np.testing.assert_allclose(v["F_cr"], F_cr(h, t, w), rtol=1e-12)
    np.testing.assert_allclose(v["d_second"], 1.7 * h, rtol=1e-12)
    assert v["bistable"].dtype == np.int8 and np.all(v["bistable"] == 1)


def test_grid_nodes_return_the_stored_values(dm):
    ds = dm.dataset
    v = dm.at(0.4, 0.0075, 0.08, state="actuated")
    assert v["theta"] == ds.theta.sel(h_over_L=0.4, t_over_L=0.0075, w_over_L=0.08).item()
    assert v["self_standing"] == 1 and isinstance(v["theta"], np.floating)


def test_inputs_broadcast(dm):
    h = np.array([[0.3], [0.45]])
    t = np.array([0.008, 0.009, 0.01])
    v = dm.at(h, t, 0.05, state="actuated")
    assert v["theta"].shape == (2, 3) and v["bistable"].shape == (2, 3)
    np.testing.assert_allclose(v["theta"], theta(h, t, 0.05), atol=1e-10)


@pytest.mark.parametrize("query, match", [
    ((0.55, 0.005, 0.05), r"h_over_L = 0\.55 is outside the map's range 0\.05 <= h_over_L <= 0\.5"),
    ((0.3, 0.002, 0.05), r"t_over_L = 0\.002 is outside the map's range 0\.0025 <= t_over_L <= 0\.01"),
    ((0.3, 0.005, 0.1), r"w_over_L = 0\.1 is outside the map's range 0\.02 <= w_over_L <= 0\.08"),
    ((np.nan, 0.005, 0.05), r"h_over_L = nan is outside"),
])
def test_out_of_range_queries_name_the_parameter_and_range(dm, query, match):
    with pytest.raises(MapDomainError, match=match):
        dm.at(*query)
    with pytest.raises(ValueError):
        dm.at(*query, allow_nan=True)  # allow_nan is about holes, not about the grid's edges


def test_failed_point_does_not_smear_into_neighbours(dm):
    h0, t0, w0 = FAILED
    # every cell around the failed point refuses, naming the query and the cause
    for dh, dt, dw in [(0.01, 0.001, 0.01), (-0.01, -0.001, -0.01), (0.02, 0.0, 0.0)]:
        q = (h0 + dh, t0 + dt, w0 + dw)
        with pytest.raises(MapDomainError, match=rf"h/L={q[0]:.6g}, t/L={q[1]:.6g}, .*not_converged"):
            dm.at(*q, state="actuated")
        v = dm.at(*q, allow_nan=True, state="actuated")
        assert np.isnan(v["theta"]) and np.isnan(v["F_cr"]) and v["bistable"] == -1
    # cells next to them, and the grid lines that bound them, are exact
    for q in [(0.41, 0.005, 0.05), (0.4, 0.005, 0.05), (0.3, 0.005, 0.05), (0.35, 0.0075, 0.06),
              (0.32, 0.005, 0.08), (0.4, 0.006, 0.03), (0.4 - 1e-14, 0.005, 0.05)]:
        v = dm.at(*q, state="actuated")
        assert v["theta"] == pytest.approx(theta(*q), abs=1e-10), q
        assert v["F_cr"] == pytest.approx(F_cr(*q), rel=1e-12), q


def test_monostable_cells_have_force_but_no_shape(dm):
    q = (0.14, 0.004, 0.05)  # between monostable h=0.10 and bistable h=0.15 (h_b ~ 0.157 at t=0.004)
    with pytest.raises(MapDomainError, match=r"S, theta.*not defined at h/L=0\.14.*monostable"):
        dm.at(*q, state="actuated")
    v = dm.at(*q, allow_nan=True, state="actuated")
    assert np.isnan(v["S"]) and np.isnan(v["theta"]) and v["bistable"] == -1
    assert v["F_cr"] == pytest.approx(F_cr(*q), rel=1e-12)  # F_cr exists at monostable points
    assert dm.value("F_cr", 0.07, 0.005, 0.05) == pytest.approx(F_cr(0.07, 0.005, 0.05), rel=1e-12)


def test_inverse_lookup_round_trip(dm):
    for t, w in [(0.0025, 0.02), (0.008, 0.07), (0.01, 0.08), (0.009, 0.05)]:
        lo, hi = dm.theta_range(t, w, state="actuated")
        targets = np.linspace(lo, hi, 7)
        h = dm.h_over_L_for_theta(targets, t, w, state="actuated")
        np.testing.assert_allclose(dm.at(h, t, w, state="actuated")["theta"], targets, atol=1e-8)
        np.testing.assert_allclose(h, (targets - 10 - 3 * np.log(t) - 2 * np.log(w)) / 150, atol=1e-10)


def test_inverse_lookup_outside_the_reachable_range(dm):
    lo, hi = dm.theta_range(0.01, 0.08, state="actuated")
    assert lo == pytest.approx(theta(0.25, 0.01, 0.08)) and hi == pytest.approx(theta(0.5, 0.01, 0.08))
    with pytest.raises(MapDomainError, match=rf"theta = 200 deg is outside the range reachable at "
                                              rf"t/L=0\.01, w/L=0\.08 \(actuated state\): {lo:.4g} to "
                                              rf"{hi:.4g} deg \(h/L 0\.25 to 0\.5\)"):
        dm.h_over_L_for_theta(200, 0.01, 0.08, state="actuated")
    with pytest.raises(MapDomainError, match="t_over_L = 0.02 is outside"):
        dm.h_over_L_for_theta(50, 0.02, 0.08)


def test_inverse_lookup_across_a_hole(dm):
    # at (0.006, 0.07) the failed point removes h/L 0.3..0.4 from the map: the error lists the spans
    with pytest.raises(MapDomainError, match=r"reachable at t/L=0\.006, w/L=0\.07 \(actuated state\): "
                                             r".* deg \(h/L 0\.2 to 0\.3\); .* deg \(h/L 0\.4 to 0\.5\)"):
        dm.h_over_L_for_theta(theta(0.35, 0.006, 0.07), 0.006, 0.07, state="actuated")
    h = dm.h_over_L_for_theta(theta(0.45, 0.006, 0.07), 0.006, 0.07, state="actuated")
    assert h == pytest.approx(0.45, abs=1e-10)


def test_bistable_boundary(dm):
    for t, w in [(0.0025, 0.02), (0.005, 0.08), (0.0075, 0.05), (0.01, 0.08)]:
        b = dm.bistable_boundary(t, w, state="actuated")
        assert b == min(h for h in GRID.h_over_L if h >= boundary(t))
        # the released unit is bistable (self-standing) from H_STANDING up
        assert dm.bistable_boundary(t, w) == max(b, H_STANDING)
    # between t grid lines the stencil needs both neighbours bistable
    assert dm.bistable_boundary(0.006, 0.05, state="actuated") == 0.2


def test_base_shape(dm):
    q = (0.45, 0.0075, 0.05)
    act = dict(state="actuated")
    np.testing.assert_allclose(dm.base_shape(0.45, 0.0075, 0.05, **act), shape(*q), atol=1e-12)
    mid = dm.base_shape(0.425, 0.0075, 0.05, **act)
    np.testing.assert_allclose(mid, 0.5 * (shape(0.4, 0.0075, 0.05) + shape(0.45, 0.0075, 0.05)), atol=1e-12)
    assert dm.base_shape([0.3, 0.45], 0.0075, 0.05, **act).shape == (2, 17, 2)
    with pytest.raises(MapDomainError, match="monostable"):
        dm.base_shape(0.14, 0.004, 0.05, **act)
    assert np.all(np.isnan(dm.base_shape(0.14, 0.004, 0.05, allow_nan=True, **act)))
    # the released shape is the default
    np.testing.assert_allclose(dm.base_shape(*q), shape(*q, released=True), atol=1e-12)
    with pytest.raises(MapDomainError, match="self_standing = 1"):
        dm.base_shape(0.27, 0.0075, 0.05)


def test_released_state_is_the_default(dm):
    h, t, w = random_bistable_points(300).T
    keep = h >= H_STANDING + 0.05  # cells whose every corner is self-standing
    h, t, w = h[keep], t[keep], w[keep]
    v = dm.at(h, t, w)
    np.testing.assert_allclose(v["theta"], theta_released(h, t, w), rtol=0, atol=1e-10)
    np.testing.assert_allclose(v["S"], S_released(h, t, w), rtol=0, atol=1e-12)
    np.testing.assert_allclose(v["theta_end"], theta_released(h, t, w) / 2, atol=1e-10)
    a = dm.at(h, t, w, state="actuated")
    np.testing.assert_allclose(a["theta"] - v["theta"], RELEASED_TURN, atol=1e-10)
    np.testing.assert_allclose(a["theta_end"], theta(h, t, w) / 2, atol=1e-10)
    np.testing.assert_allclose(v["F_cr"], a["F_cr"], rtol=0)  # the push does not depend on it
    np.testing.assert_allclose(dm.value("theta_released", h, t, w), v["theta"], rtol=0)
    np.testing.assert_allclose(dm.value("theta", h, t, w, state="actuated"), a["theta"], rtol=0)
    # a unit that is bistable only with the actuator glued has no released state
    with pytest.raises(MapDomainError, match="self_standing = 1"):
        dm.at(0.27, 0.005, 0.05)
    assert np.isfinite(dm.at(0.27, 0.005, 0.05, state="actuated")["theta"])
    with pytest.raises(ValueError, match="state must be one of 'released', 'actuated'"):
        dm.at(0.4, 0.005, 0.05, state="held")


def test_inverse_lookup_of_theta_end_and_released_theta(dm):
    t, w = 0.008, 0.07
    for target_h in (0.33, 0.41, 0.48):
        th = theta_released(target_h, t, w)
        assert dm.h_over_L_for_theta(th, t, w) == pytest.approx(target_h, abs=1e-10)
        assert dm.h_over_L_for_theta_end(th / 2, t, w) == pytest.approx(target_h, abs=1e-10)
        a = theta(target_h, t, w) / 2
        assert dm.h_over_L_for_theta_end(a, t, w, state="actuated") == pytest.approx(target_h, abs=1e-10)
    lo, hi = dm.theta_range(t, w, angle="theta_end")
    assert lo == pytest.approx(theta_released(0.3, t, w) / 2) and hi == pytest.approx(theta_released(0.5, t, w) / 2)


def test_force_newtons(dm):
    h, t, w = 0.3, 0.008, 0.05
    E, L = 2.2e9, 0.1
    expected = F_cr(h, t, w) * E * (w * L) * (t * L) ** 3 / 12 / L**2
    assert dm.force_newtons(h, t, w) == pytest.approx(expected, rel=1e-12)
    # same ratios, twice the size: F = F_norm E w t^3 / (12 L^2) scales like L^2
    assert dm.force_newtons(h, t, w, L=0.2) == pytest.approx(4 * expected, rel=1e-12)
    with pytest.raises(ValueError, match="E must be a finite number > 0"):
        dm.force_newtons(h, t, w, E=-1)
