"""Grid presets and validation."""

import json

import numpy as np
import pytest

from snapmorph.pipeline import Grid, preset


def test_default_preset_covers_the_required_ranges():
    g = preset("default")
    assert len(g.h_over_L) >= 46 and (g.h_over_L[0], g.h_over_L[-1]) == (0.05, 0.50)
    assert len(g.t_over_L) >= 9 and (g.t_over_L[0], g.t_over_L[-1]) == (0.0025, 0.0125)
    assert len(g.w_over_L) >= 9 and (g.w_over_L[0], g.w_over_L[-1]) == (0.02, 0.10)
    assert g.b_over_L == (0.0, 0.05)  # schema 3: b/L is an axis, the paper's b = w on it
    # the paper's parametric maps sit on grid lines
    assert 0.005 in g.t_over_L and 0.0075 in g.t_over_L and 0.05 in g.w_over_L


def test_ci_preset_is_small():
    g = preset("ci")
    assert g.size <= 48 and min(g.shape) >= 2 and g.dims[-1] == "b_over_L"


def test_points_are_in_c_order():
    g = Grid(h_over_L=(0.1, 0.2, 0.3), t_over_L=(0.004, 0.006), w_over_L=(0.03, 0.05, 0.07))
    pts = g.points()
    assert pts.shape == (g.size, 3)
    i_h, i_t, i_w = 2, 1, 0
    assert tuple(pts[(i_h * 2 + i_t) * 3 + i_w]) == (0.3, 0.006, 0.03)


def test_dict_round_trip_survives_json():
    g = preset("default").with_resolution(40)
    assert Grid.from_dict(json.loads(json.dumps(g.to_dict()))) == g
    assert g.resolution == 40


@pytest.mark.parametrize("kwargs, match", [
    (dict(h_over_L=(0.0, 0.2)), r"h_over_L = 0\.0 is outside the valid range 0\.0 < h_over_L <= 1\.0"),
    (dict(h_over_L=(0.2, 1.5)), r"h_over_L = 1\.5 .*h_over_L <= 1\.0"),
    (dict(t_over_L=(0.005, 0.2)), r"t_over_L = 0\.2 .*t_over_L <= 0\.05"),
    (dict(w_over_L=(-0.1, 0.05)), r"w_over_L = -0\.1 .*0\.0 < w_over_L < 0\.5"),
    (dict(h_over_L=(0.3, 0.2)), r"h_over_L values must be strictly increasing"),
    (dict(h_over_L=(0.2,)), r"h_over_L needs at least 2 values"),
    (dict(t_over_L=(0.005, np.nan)), r"t_over_L values must be finite"),
    (dict(b_over_L=-0.01), r"b_over_L must be a finite number >= 0"),
    (dict(b_over_L=0.45), r"b_over_L \+ w_over_L must be < 0\.5.*b_over_L must be < 0\.44"),
    (dict(resolution=2), r"resolution must be None or an integer >= 5"),
    (dict(resolution=10.5), r"resolution must be None or an integer"),
    (dict(samples=1), r"samples must be an integer >= 2"),
])
def test_invalid_grids_name_the_parameter_and_range(kwargs, match):
    base = dict(h_over_L=(0.1, 0.2), t_over_L=(0.005, 0.01), w_over_L=(0.03, 0.06))
    with pytest.raises(ValueError, match=match):
        Grid(**{**base, **kwargs})


def test_unknown_preset():
    with pytest.raises(ValueError, match=r"grid must be one of \['ci', 'default'\]"):
        preset("huge")
