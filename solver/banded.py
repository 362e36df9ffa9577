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


def envelope_heights(n, *element_dofs):
    """(n,) int64: for every column j of the factor L of a matrix assembled from elements
    with the reduced DOF lists ``element_dofs`` (arrays (n_elements, k), -1 for held DOFs),
    the offset below the diagonal of its last entry that can be nonzero, fill included.

    Fill stays inside the envelope: row i of L starts at the smallest DOF f_i sharing an
    element with i, so column j reaches down to max{i : f_i <= j}. The factor and the solves
    then neither scan for it nor touch the zeros below it."""
    first = np.arange(n, dtype=np.int64)
    for dofs in element_dofs:
        d = np.asarray(dofs, dtype=np.int64)
        if d.size:
            _row_starts(np.ascontiguousarray(d), first)
    return profile_heights(first)


@njit(cache=True)
def _row_starts(dofs, first):
    """Lower ``first[i]`` to the smallest DOF of every element (row of ``dofs``, -1 held)
    that holds DOF i (a compiled loop: computed for every new DOF ordering, several per
    unit, where the vectorised sort it replaces cost 0.1 ms)."""
    for e in range(dofs.shape[0]):
        lo = -1
        for a in range(dofs.shape[1]):
            r = dofs[e, a]
            if r >= 0 and (lo < 0 or r < lo):
                lo = r
        for a in range(dofs.shape[1]):
            r = dofs[e, a]
            if r >= 0 and lo < first[r]:
                first[r] = lo


def profile_heights(first):
    """(n,) int64: the extent below the diagonal of every column of the factor of a matrix
    whose row i starts at column ``first[i]`` (<= i): column j reaches down to the last row
    i with first[i] <= j (fill stays inside this envelope)."""
    return _profile(np.ascontiguousarray(first, dtype=np.int64))


@njit(cache=True)
def _profile(first):
    n = first.shape[0]
    last = np.arange(n)
    for i in range(n):  # the last row that starts at each column
        if i > last[first[i]]:
            last[first[i]] = i
    heights = np.empty(n, dtype=np.int64)
    reach = -1
    for j in range(n):  # ... or at any column before it
        if last[j] > reach:
            reach = last[j]
        heights[j] = reach - j
    return heights


@njit(cache=True)
def scanned_heights(band):
    """(n,) int64: the offset of the last nonzero below the diagonal of every column of an
    assembled band (no fill: a bound for the factor only where fill cannot pass it)."""
    bw = band.shape[0] - 1
    n = band.shape[1]
    heights = np.empty(n, dtype=np.int64)
    for j in range(n):
        heights[j] = _column_height(band, j, bw, n)
    return heights


@njit(cache=True)
def ldlt_factor(band, pivot_tol):
    """Factorise in place; returns (status, negative_pivots, min_abs_pivot_ratio).

    status 0: done; 1: a pivot was below ``pivot_tol`` times the largest diagonal entry
    (numerically singular: the caller falls back to a pivoting solver). Each column stops
    at its last nonzero, found by a scan when the column is reached (fill included).
    """
    return _factor(band, np.empty(0, dtype=np.int64), pivot_tol)


@njit(cache=True)
def ldlt_factor_envelope(band, heights, pivot_tol):
    """`ldlt_factor` with every column's extent given (`envelope_heights`): no scans. The
    same operations on the same nonzeros, so the same factor (up to the sign of zeros)."""
    return _factor(band, heights, pivot_tol)


# Fixed windows for short columns (`_eliminate`): a planar rod's columns reach 5 rows
# below the diagonal (bending couples 3 nodes), two bonded rods' (a unit) mostly 8-9.
_SHORT = 5
_MEDIUM = 9


@njit(cache=True, inline="always")
def written_extent(heights, j, bw):
    """The last row of column j of a band (bandwidth ``bw``, envelope ``heights``) that the
    factor may write: the envelope, or a short column's fixed window (`_eliminate`), where
    it adds zeros outside the envelope (or, factorising a non-finite band, non-finite
    values). An assembly that clears this much leaves no trace of a factor."""
    return max(heights[j], min(_MEDIUM, bw))


@njit(cache=True)
def _eliminate(band, j, d, w):
    """The factor's step at column j (pivot d) for a column whose nonzeros lie within ``w``
    rows below the diagonal, ``w`` a constant at each call (the loops unroll once the call
    is inlined; a plain call, not numba's inlining, which keeps them rolled). The same
    operations as the general loop on the nonzeros; the rows below the column's envelope
    are zeros and only add zeros (x - 0 l = x, up to the sign of a zero) to entries that
    stay zero."""
    for i in range(1, w + 1):
        lij = band[i, j] / d
        c = j + i
        for k in range(w - i + 1):
            band[k, c] -= band[k + i, j] * lij
        band[i, j] = lij


@njit(cache=True, inline="always")
def _factor(band, heights, pivot_tol):
    bw = band.shape[0] - 1
    n = band.shape[1]
    known = heights.shape[0] == n
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
        m = heights[j] if known else _column_height(band, j, bw, n)
        # a short column within a fixed window (its rows below m are zeros, outside the
        # envelope): loops of constant length, unrolled (most columns of planar rods)
        if m <= _SHORT and bw >= _SHORT and j + _SHORT < n:
            _eliminate(band, j, d, _SHORT)
            continue
        if m <= _MEDIUM and bw >= _MEDIUM and j + _MEDIUM < n:
            _eliminate(band, j, d, _MEDIUM)
            continue
        # right-looking update of the trailing band with the unscaled column; the inner
        # loop counts from 0 so that its indices are provably non-negative: without
        # negative-index wraparound LLVM vectorises it (2x on the 3-D unit, same bits).
        # Step i reads rows i..m of column j: row i is scaled right after it (one division
        # per entry, not two)
        for i in range(1, m + 1):
            lij = band[i, j] / d
            if lij != 0.0:
                c = j + i
                for k in range(m - i + 1):
                    band[k, c] -= band[k + i, j] * lij
            band[i, j] = lij
    return 0, negative, min_ratio


@njit(cache=True)
def ldlt_solve(band, b):
    """Solve K X = B in place for B of shape (n, m), with a factor from ``ldlt_factor``."""
    return _solve(band, scanned_heights(band), b)


@njit(cache=True)
def ldlt_solve_envelope(band, heights, b):
    """`ldlt_solve` with every column's extent given (`envelope_heights`)."""
    return _solve(band, heights, b)


@njit(cache=True, inline="always")
def _solve(band, heights, b):
    # all right-hand sides in one sweep over the factor: each column of L is read once
    n = band.shape[1]
    nc = b.shape[1]
    if nc == 2:
        return _solve2(band, heights, b)
    for j in range(n):
        m = heights[j]
        for c in range(nc):
            v = b[j, c]
            if v != 0.0:
                for k in range(m):  # from 0: vectorised (see `_factor`)
                    b[j + 1 + k, c] -= band[k + 1, j] * v
    for j in range(n):
        d = band[0, j]
        for c in range(nc):
            b[j, c] /= d
    for j in range(n - 1, -1, -1):
        m = heights[j]
        for c in range(nc):
            s = b[j, c]
            for i in range(1, m + 1):
                s -= band[i, j] * b[j + i, c]
            b[j, c] = s
    return b


@njit(cache=True)
def _solve2(band, heights, b):
    """`_solve` for two right-hand sides (an MGDC corrector's): both in the same loops, so
    that the back substitution runs two independent sums at once (it waits on the latency
    of each subtraction otherwise). The same operations in the same order per right-hand
    side (a zero entry of one side is carried along when the other's is not: x - l 0 = x)."""
    n = band.shape[1]
    for j in range(n):
        m = heights[j]
        v0 = b[j, 0]
        v1 = b[j, 1]
        if v0 != 0.0 or v1 != 0.0:
            for k in range(m):
                lk = band[k + 1, j]
                b[j + 1 + k, 0] -= lk * v0
                b[j + 1 + k, 1] -= lk * v1
    for j in range(n):
        d = band[0, j]
        b[j, 0] /= d
        b[j, 1] /= d
    for j in range(n - 1, -1, -1):
        m = heights[j]
        s0 = b[j, 0]
        s1 = b[j, 1]
        for i in range(1, m + 1):
            li = band[i, j]
            s0 -= li * b[j + i, 0]
            s1 -= li * b[j + i, 1]
        b[j, 0] = s0
        b[j, 1] = s1
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
