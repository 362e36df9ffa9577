"""Clamped–clamped shallow cosine arch pushed at its midpoint (midpoint rotation and horizontal
motion held): the whole snap-through path to 2.2 h, through both limit points.

Reference: Qiu, Lang & Slocum (2004), J. MEMS 13(2): for the centrally clamped arch the
snap-through force is about 740 EI h / l^3 and the minimum about -370 EI h / l^3 (their
approximate closed-form values for large h/t).
"""

import numpy as np
import pytest

from validation.arch import arch_path, first_peak_index


@pytest.mark.parametrize("h_over_t", [6, 10, 20])
def test_snap_through_passes_both_limit_points(h_over_t):
    path, h, unit = arch_path(h_over_t)
    assert path.status == "ok"
    assert path.displacement[-1] >= 2.2 * h * (1 - 1e-9)
    f = path.force / unit
    ipk = first_peak_index(f)
    f_max, f_min = f[ipk], f.min()
    imin = int(np.argmin(f))
    # the curve rises, falls through zero (negative stiffness), and rises again
    assert f_max > 0 and f_min < 0 and ipk < imin < len(f) - 1
    assert np.all(np.diff(f[ipk + 1: imin]) < 0)
    # load control passes the limit points: an unstable stretch (negative eigenvalue) lies
    # between them and the path is stable again after the minimum
    assert path.negative_eigenvalues[ipk + 2: imin - 1].min() >= 1
    assert path.negative_eigenvalues[imin + 2:].max() == 0
    # in the range of the paper's reference (about 740 and -370 EI h / l^3)
    assert 600 < f_max < 800
    assert -400 < f_min < -250


@pytest.mark.parametrize("h_over_t", [10])
def test_mgdc_and_displacement_control_trace_the_same_curve(h_over_t):
    mgdc, h, unit = arch_path(h_over_t, "mgdc")
    disp, _, _ = arch_path(h_over_t, "displacement")
    d = np.linspace(0.02 * h, 2.0 * h, 50)
    f_m = np.interp(d, mgdc.displacement, mgdc.force) / unit
    f_d = np.interp(d, disp.displacement, disp.force) / unit
    # piecewise-linear interpolation of two different step sequences: compare within the
    # interpolation error, relative to the force range
    assert np.max(np.abs(f_m - f_d)) < 0.01 * np.ptp(f_d)
