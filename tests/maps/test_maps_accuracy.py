"""pipeline.accuracy: the measurement of interpolation error against direct simulation."""

import numpy as np
import pytest

from maps_synthetic import FAILED, F_cr, S, boundary, shape, theta
from snapmorph.pipeline.accuracy import measure


def exact_solve(h, t, w, b, resolution, samples, bias=0.0):
    """A 'solver' returning the synthetic map's formulas (theta shifted by `bias` degrees)."""
    rec = {"F_cr": F_cr(h, t, w), "d_cr": 0.3 * h, "d_unstable": 0.9 * h, "d_second": 1.7 * h,
           "S": S(h, t, w), "theta": theta(h, t, w) + bias, "energy_barrier": 2 * h, "energy_stored": h,
           "bistable": 1, "self_standing": 1, "bifurcation": 0, "base_shape": shape(h, t, w, samples),
           "status": 0, "message": ""}
    if np.allclose((h, t, w), FAILED):
        rec["status"] = 2
    elif h < boundary(t):
        rec["status"] = 1
    return rec


def test_exact_fields_measure_zero_error(dm):
    acc = measure(dm, n=30, seed=3, solve=exact_solve)
    assert len(acc.points) == 30 and acc.skipped == 0
    assert np.max(np.abs(acc.theta_err)) < 1e-9
    assert np.max(np.abs(acc.S_rel)) < 1e-12 and np.max(np.abs(acc.F_rel)) < 1e-12
    # "away from the boundary": at least one h step (0.05) above the first bistable grid h/L
    # of the cell's larger t (the boundary rises with t)
    for h, t, w in acc.points:
        t_up = dm.t_over_L[np.searchsorted(dm.t_over_L, t)]
        first = min(x for x in dm.h_over_L if x >= boundary(t_up))
        assert h >= first + 0.05 - 1e-12, (h, t, w)
    assert "theta: max |error|" in acc.summary()


def test_a_solver_that_changed_since_the_build_is_detected(dm):
    with pytest.raises(ValueError, match="the solver changed since the map was built"):
        measure(dm, n=5, solve=lambda *a: exact_solve(*a, bias=0.01))
