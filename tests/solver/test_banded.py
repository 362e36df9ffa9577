"""Banded LDL^T against dense linear algebra: solutions and inertia."""

import numpy as np
import pytest

from solver.banded import band_to_dense, ldlt_factor, ldlt_solve


def _random_band(rng, n, bw, shift):
    band = rng.normal(size=(bw + 1, n))
    band[0] += shift
    for k in range(1, bw + 1):
        band[k, n - k:] = 0.0
    return band


@pytest.mark.parametrize("n,bw,shift", [(30, 3, 8.0), (60, 6, 2.0), (41, 1, 0.5), (10, 9, 0.0)])
def test_ldlt_solves_and_counts_negative_eigenvalues(rng, n, bw, shift):
    band = _random_band(rng, n, bw, shift)
    dense = band_to_dense(band)
    b = rng.normal(size=(n, 2))
    status, negative, _ = ldlt_factor(band, 1e-14)
    assert status == 0
    x = ldlt_solve(band, b.copy())
    np.testing.assert_allclose(dense @ x, b, atol=1e-8 * np.abs(b).max() * np.linalg.cond(dense))
    assert negative == int(np.sum(np.linalg.eigvalsh(dense) < 0))


def test_singular_matrix_is_reported(rng):
    band = np.zeros((2, 5))
    band[0] = [1.0, 1.0, 0.0, 1.0, 1.0]
    status, _, _ = ldlt_factor(band, 1e-13)
    assert status == 1
