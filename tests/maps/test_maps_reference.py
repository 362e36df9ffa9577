"""How much every variable of the default map moved at every point of the map it replaced.

The three-axis default map (schema 2, b/L = 0, kept as `maps.REFERENCE_MAP`) against the
committed default map at b/L = 0: its h, t, w axes are the old map's, so every old point is a
new one. Run with ``-s`` to see the table of max |delta| per variable (it is also in the
message of a failure).

Accuracy asserted (issue 26): statuses and flags unchanged; S and theta (both states, and
theta_end) to 1e-6 (|delta| <= 1e-6 max(1, |value|)); F_cr and d_cr to what the force peak's
search resolves. The search (`units.push_through.refine_peak`) stops when its bracket in d is
below 2e-3 of the spacing of the path samples around the peak, which is at most the distance
from the start to the peak's next sample, about 1.25 d_cr: each map's d_cr is good to
2e-3 x 2 x 1.25 d_cr = 5e-3 d_cr, two maps agree to 1e-2 d_cr. F is flat at its maximum: an
error e in d costs F'' e^2 / 2 ~ F_cr (e / d_cr)^2 / 2 = 5e-5 F_cr at e = 1e-2 d_cr; F_cr is held
to 1e-4 relative (twice that, for the equilibrium solves' own tolerance).
"""

import numpy as np
import pytest

from snapmorph.maps import DEFAULT_MAP, REFERENCE_MAP, DesignMap
from snapmorph.maps.schema import FLAG_VARS, FLOAT_VARS_V2, SHAPE_VARS

#: variable -> (relative tolerance, floor of the scale): |delta| <= rtol max(floor, |value|)
TOLERANCE = {
    "S": (1e-6, 1.0), "theta": (1e-6, 1.0), "theta_end": (1e-6, 1.0),
    "S_released": (1e-6, 1.0), "theta_released": (1e-6, 1.0), "theta_end_released": (1e-6, 1.0),
    "F_cr": (1e-4, 0.0), "d_cr": (1e-2, 0.0),
}


def _moved(old, new):
    """{variable: (max |delta|, max |delta| / scale, points compared)} over the old grid."""
    table = {}
    for name in (*FLOAT_VARS_V2, *SHAPE_VARS):
        a, b = np.asarray(old[name].values, float), np.asarray(new[name].values, float)
        both = np.isfinite(a) & np.isfinite(b)
        assert np.array_equal(np.isfinite(a), np.isfinite(b)), f"{name}: defined at other points"
        delta = np.abs(b - a)[both]
        rtol, floor = TOLERANCE.get(name, (None, 1.0))
        scale = np.maximum(floor, np.abs(a[both]))
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = delta / scale
        table[name] = (float(delta.max(initial=0.0)), float(np.nanmax(rel, initial=0.0)),
                       int(both.reshape(both.shape[0], -1).size if name in SHAPE_VARS else both.sum()))
    return table


def test_values_moved_within_the_stated_accuracy_at_every_old_point():
    if not REFERENCE_MAP.is_file():
        pytest.fail(f"{REFERENCE_MAP} is missing (the three-axis map the default map replaced)")
    old = DesignMap.load(REFERENCE_MAP)
    new = DesignMap.load(DEFAULT_MAP)
    assert "b_over_L" in new.dims, f"{DEFAULT_MAP} has no b/L axis: rebuild it (`make maps`)"
    b_old = old.fixed_b_over_L
    assert b_old in new.b_over_L, f"the default map has no b/L = {b_old} to compare with"
    o = old.dataset
    n = new.dataset.sel(b_over_L=b_old)
    for dim in ("h_over_L", "t_over_L", "w_over_L"):
        np.testing.assert_array_equal(o[dim].values, n[dim].values, err_msg=dim)
    # statuses and flags unchanged, at every point
    for name in ("status", *FLAG_VARS):
        diff = int(np.count_nonzero(o[name].values != n[name].values))
        assert diff == 0, f"{name} changed at {diff} of {o[name].size} old grid points"
    table = _moved(o, n)
    lines = [f"{'variable':<20} {'max |delta|':>12} {'max rel.':>10} {'tolerance':>10}"]
    for name, (d, r, _) in table.items():
        tol = TOLERANCE.get(name, (None,))[0]
        lines.append(f"{name:<20} {d:12.3e} {r:10.3e} {'-' if tol is None else f'{tol:.0e}':>10}")
    report = "\n".join(lines)
    print(f"\n{DEFAULT_MAP.name} at b/L = {b_old:g} against {REFERENCE_MAP.name} "
          f"({o['status'].size} points):\n{report}")
    for name, (rtol, _) in TOLERANCE.items():
        assert table[name][1] <= rtol, f"{name} moved by more than {rtol:g}:\n{report}"
