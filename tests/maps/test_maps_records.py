"""Schema-2 point records: the released state, theta_end and the new status codes, from the
real unit solver through `pipeline.kinds.unit`."""

import math

import numpy as np
import pytest

from snapmorph.maps.schema import FLOAT_VARS, OPTIONAL_VARS, RELEASED_VARS, SCHEMA_VERSION, SHAPE_VARS
from snapmorph.pipeline.kinds.unit import empty_record, finalise_record, model_options, solve_point
from snapmorph.units.status import NAME as STATUS_CODES


@pytest.fixture(scope="module")
def paper_point():
    return solve_point(0.2, 0.005, 0.05, 0.0, None, 65)


def test_schema_2_knows_timeouts_and_unstable_second_states():
    assert SCHEMA_VERSION == 3
    assert STATUS_CODES[4] == "timeout" and STATUS_CODES[5] == "second_state_unstable"
    assert set(RELEASED_VARS) <= set(FLOAT_VARS) and "theta_end" in FLOAT_VARS
    assert SHAPE_VARS == ("base_shape", "base_shape_released")
    assert model_options() == {"joint_length_over_L": 0.03175, "bond_length_over_L": "b+w"}


def test_the_real_solver_fills_both_states(paper_point):
    from snapmorph.units import UnitGeometry, simulate_unit

    rec = paper_point
    assert rec["status"] == 0 and rec["self_standing"] == 1
    # the point's h = 0.2 * 0.1 m differs from 0.02 m in the last bit
    r = simulate_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3))
    assert rec["theta"] == pytest.approx(r.theta_deg, abs=1e-9)
    assert rec["theta_released"] == pytest.approx(r.theta_released_deg, abs=1e-9)
    assert rec["S_released"] == pytest.approx(r.S_released / 0.1, rel=1e-9)
    assert rec["theta_end"] == pytest.approx(rec["theta"] / 2, abs=0.05)
    assert rec["theta_end_released"] == pytest.approx(rec["theta_released"] / 2, abs=0.05)
    assert rec["theta"] - rec["theta_released"] == pytest.approx(1.3, abs=0.5)
    for name in SHAPE_VARS:
        xy = rec[name]
        assert xy.shape == (65, 2) and np.all(np.isfinite(xy))
        assert np.array_equal(xy[0], [0.0, 0.0])
    # the released shape turns by theta_released: its chord sits at theta_end_released
    xy = rec["base_shape_released"]
    chord = np.degrees(np.arctan2(xy[-1, 1], xy[-1, 0]))
    assert chord == pytest.approx(rec["theta_end_released"], abs=0.1)


def test_a_point_that_is_not_self_standing_has_no_released_state(paper_point):
    rec = dict(paper_point)
    rec["self_standing"] = 0
    out = finalise_record(rec, 65)
    assert out["status"] == 0
    assert all(math.isnan(out[n]) for n in RELEASED_VARS)
    assert np.all(np.isnan(out["base_shape_released"]))
    assert np.isfinite(out["theta"])


def test_a_self_standing_ok_point_without_its_released_values_is_refused(paper_point):
    rec = dict(paper_point)
    rec["theta_released"] = float("nan")
    out = finalise_record(rec, 65)
    assert out["status"] == 2 and "theta_released" in out["message"]


def test_records_of_older_point_solvers_still_load(paper_point):
    rec = {k: v for k, v in paper_point.items()
           if k not in (*OPTIONAL_VARS, "base_shape_released")}
    out = finalise_record(rec, 65)
    assert out["status"] == 0 and math.isnan(out["theta_end"])


@pytest.mark.parametrize("code", [4, 5])
def test_new_status_codes_are_recorded(paper_point, code):
    rec = dict(paper_point)
    rec["status"] = code
    out = finalise_record(rec, 65)
    assert out["status"] == code and out["bistable"] == 0
    assert all(math.isnan(out[n]) for n in ("S", "theta", *RELEASED_VARS))
    if code == 5:  # solved, not bistable: the force peak exists
        assert np.isfinite(out["F_cr"])
    else:
        assert math.isnan(out["F_cr"])
    assert empty_record(65, code)["status"] == code


def test_time_limit_reaches_the_point_record():
    rec = solve_point(0.2, 0.005, 0.05, 0.0, None, 65, time_limit=1e-3)
    assert rec["status"] == 4 and "timeout" in rec["message"]
