"""Clamped–clamped column under end shortening: the force plateau is Euler's 4 pi^2 EI / L^2.

A perfect column stays straight on the primary path; a small imperfection in the first
buckling mode (amplitude 3e-4 L) lets the path follower find the buckled branch.
The elastica of the clamped–clamped column (equivalent to a pinned column of half the
length) gives P / P_cr = (2 K(m) / pi)^2 and end shortening Delta / L = 2 (1 - E(m) / K(m)).
"""

import numpy as np

from validation.column import L, P_CR, column, elastica_force


def test_force_plateau_is_euler_load():
    path = column().push(100, direction=(-1.0, 0.0), distance=0.03 * L, method="mgdc")
    assert path.status == "ok"
    window = (path.displacement > 0.005 * L) & (path.displacement < 0.02 * L)
    plateau = path.force[window]
    assert abs(plateau.mean() / P_CR - 1) < 0.01
    assert np.ptp(plateau) / P_CR < 0.02  # flat: a plateau, not a ramp


def test_post_buckling_follows_the_elastica():
    path = column().push(100, direction=(-1.0, 0.0), distance=0.05 * L, method="mgdc")
    for d, F in zip(path.displacement, path.force):
        if 0.01 * L < d < 0.05 * L:
            assert abs(F / elastica_force(d) - 1) < 0.01
