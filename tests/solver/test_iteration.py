"""The fused iterations' small loops (`solver.iteration`)."""

import numpy as np


def test_the_iterations_maxima_are_the_sequential_scans(rng):
    """`solver.iteration._residual` and `max_abs` take their maxima in four running parts:
    the sequential scans' values (a NaN passed over by max_abs, inf for the residual)."""
    from snapmorph.solver.iteration import _residual, max_abs

    for n in (0, 1, 3, 4, 5, 17, 377):
        for case in range(4):
            grad, P = rng.normal(size=n), rng.normal(size=n)
            if n and case == 1:
                grad[rng.integers(n)] = np.nan
            if n and case == 2:
                P[rng.integers(n)] = np.inf
            R = np.empty(n)
            r = _residual(grad, 0.7, P, R)
            want = grad - 0.7 * P
            if not np.all(np.isfinite(want)):
                assert r == np.inf
                continue
            np.testing.assert_array_equal(R, want)
            assert r == (np.max(np.abs(want)) if n else 0.0)
            du = want.copy()
            if n and case == 3:
                du[rng.integers(n)] = np.nan
            finite = np.abs(du[~np.isnan(du)])
            assert max_abs(du) == (np.max(finite) if finite.size else 0.0)
