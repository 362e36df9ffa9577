"""Symmetric banded LDL^T factorisation and solves (no pivoting).

Storage is LAPACK-style lower band: ``band[k, j] = K[j + k, j]`` for ``k = 0 .. bw``
(C or Fortran order; Fortran keeps a column contiguous, which the loops below walk).
The cost is at most O(n bw^2), linear in the number of nodes for a rod structure ordered
along its length. Both loops stop each column at its last nonzero (fill included), so a
matrix whose band is wide in a few columns only (a frame of rods: closing a ring couples a
few far-apart DOFs) costs what its envelope holds, not n bw^2; skipping exact zeros changes no
bit of the result. Without pivoting the factorisation also gives the inertia of K for free (Sylvester's
law): the number of negative pivots is the number of negative eigenvalues — the stability
count the path followers record at every step.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _column_height(band, j, bw, n):
    """Offset of the last nonzero below the diagonal in column j (0 if none)."""
    m = min(bw, n - 1 - j)
    while m > 0 and band[m, j] == 0.0:
        m -= 1
    return m


@njit(cache=True)
def ldlt_factor(band, pivot_tol):
    """Factorise in place; returns (status, negative_pivots, min_abs_pivot_ratio).

    status 0: done; 1: a pivot was below ``pivot_tol`` times the largest diagonal entry
    (numerically singular: the caller falls back to a pivoting solver).
    """
    bw = band.shape[0] - 1
    n = band.shape[1]
    scale = 0.0
    for j in range(n):
        a = abs(band[0, j])
        if a > scale:
            scale = a
    if scale == 0.0 or not np.isfinite(scale):
        return 1, 0, 0.0
    negative = 0
    min_ratio = np.inf
    for j in range(n):
        d = band[0, j]
        ratio = abs(d) / scale
        if ratio < min_ratio:
            min_ratio = ratio
        if not (ratio > pivot_tol):  # also catches NaN
            return 1, negative, min_ratio
        if d < 0.0:
            negative += 1
        m = _column_height(band, j, bw, n)
        # right-looking update of the trailing band with the unscaled column
        for i in range(1, m + 1):
            lij = band[i, j] / d
            if lij == 0.0:
                continue
            for k in range(i, m + 1):
                band[k - i, j + i] -= band[k, j] * lij
        for i in range(1, m + 1):
            band[i, j] /= d
    return 0, negative, min_ratio


@njit(cache=True)
def ldlt_solve(band, b):
    """Solve K X = B in place for B of shape (n, m), with a factor from ``ldlt_factor``."""
    bw = band.shape[0] - 1
    n = band.shape[1]
    heights = np.empty(n, dtype=np.int64)
    for j in range(n):
        heights[j] = _column_height(band, j, bw, n)
    for c in range(b.shape[1]):
        for j in range(n):
            v = b[j, c]
            if v != 0.0:
                m = heights[j]
                for i in range(1, m + 1):
                    b[j + i, c] -= band[i, j] * v
        for j in range(n):
            b[j, c] /= band[0, j]
        for j in range(n - 1, -1, -1):
            m = heights[j]
            s = b[j, c]
            for i in range(1, m + 1):
                s -= band[i, j] * b[j + i, c]
            b[j, c] = s
    return b


def band_to_dense(band):
    """Dense symmetric matrix from lower band storage (for tests and the pivoting fallback)."""
    bw = band.shape[0] - 1
    n = band.shape[1]
    dense = np.zeros((n, n))
    for k in range(bw + 1):
        idx = np.arange(n - k)
        dense[idx + k, idx] = band[k, : n - k]
        dense[idx, idx + k] = band[k, : n - k]
    return dense
