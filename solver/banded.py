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


# Two columns at a time (`_eliminate_pair`): most columns of a unit's band (two bonded rods)
# reach 8-9 rows, and their steps are short enough that loading and storing the trailing
# entries costs as much as the arithmetic. The pair's code is written out (`_pair_source`).
def _pair_source(w):
    """The source of `_pair5` / `_pair9` (they are this text for w = 5, 9; a test checks
    it): `_eliminate_pair` written out for a window of ``w`` rows, every entry of the two
    columns a named local, so that nothing is stored and loaded back in between."""
    lines = [f"def _pair{w}(band, j, d0, scale, pivot_tol):"]
    add = lines.append
    add(f'    """`_eliminate_pair` for a window of {w} rows (generated by `_pair_source`)."""')
    for i in range(1, w + 1):
        add(f"    u{i} = band[{i}, j]")
    for i in range(1, w + 1):
        add(f"    l{i} = u{i} / d0")
    for i in range(1, w + 1):
        add(f"    band[{i}, j] = l{i}")
    for k in range(w):  # column j + 1 after column j's step
        add(f"    v{k} = band[{k}, j + 1] - u{k + 1} * l1")
    add(f"    v{w} = band[{w}, j + 1]")
    add("    if not (abs(v0) / scale > pivot_tol):  # column j alone (also catches NaN)")
    for k in range(w):
        add(f"        band[{k}, j + 1] = v{k}")
    for i in range(2, w + 1):
        for k in range(w - i + 1):
            add(f"        band[{k}, j + {i}] -= u{k + i} * l{i}")
    add("        return False, v0")
    add("    band[0, j + 1] = v0")
    for i in range(1, w + 1):
        add(f"    m{i} = v{i} / v0")
    for i in range(1, w + 1):
        add(f"    band[{i}, j + 1] = m{i}")
    for i in range(2, w + 2):  # the trailing columns: column j's step, then column j + 1's
        for k in range(w + 2 - i):
            if k <= w - i:
                add(f"    band[{k}, j + {i}] = band[{k}, j + {i}] - u{k + i} * l{i} - v{k + i - 1} * m{i - 1}")
            else:
                add(f"    band[{k}, j + {i}] -= v{k + i - 1} * m{i - 1}")
    add("    return True, v0")
    return "\n".join(lines) + "\n"


@njit(cache=True)
def _eliminate_pair(band, j, d0, w, scale, pivot_tol):
    """The factor's steps at columns j (pivot d0, checked) and j + 1 for two columns whose
    nonzeros lie within ``w`` (5 or 9, a constant at each call) rows below the diagonal,
    j + 1 + w < n: the same operations as two `_eliminate` steps (each trailing entry takes
    column j's update, then column j + 1's), with column j + 1 and the trailing entries
    loaded and stored once for both. Returns (done, d1): d1 the pivot of column j + 1;
    done False when it fails the pivot test (or is NaN): then column j alone is done, as
    `_eliminate` does it, and the caller stops at j + 1."""
    if w == 5:
        return _pair5(band, j, d0, scale, pivot_tol)
    return _pair9(band, j, d0, scale, pivot_tol)


@njit(cache=True, inline="always")
def _pair5(band, j, d0, scale, pivot_tol):
    """`_eliminate_pair` for a window of 5 rows (generated by `_pair_source`)."""
    u1 = band[1, j]
    u2 = band[2, j]
    u3 = band[3, j]
    u4 = band[4, j]
    u5 = band[5, j]
    l1 = u1 / d0
    l2 = u2 / d0
    l3 = u3 / d0
    l4 = u4 / d0
    l5 = u5 / d0
    band[1, j] = l1
    band[2, j] = l2
    band[3, j] = l3
    band[4, j] = l4
    band[5, j] = l5
    v0 = band[0, j + 1] - u1 * l1
    v1 = band[1, j + 1] - u2 * l1
    v2 = band[2, j + 1] - u3 * l1
    v3 = band[3, j + 1] - u4 * l1
    v4 = band[4, j + 1] - u5 * l1
    v5 = band[5, j + 1]
    if not (abs(v0) / scale > pivot_tol):  # column j alone (also catches NaN)
        band[0, j + 1] = v0
        band[1, j + 1] = v1
        band[2, j + 1] = v2
        band[3, j + 1] = v3
        band[4, j + 1] = v4
        band[0, j + 2] -= u2 * l2
        band[1, j + 2] -= u3 * l2
        band[2, j + 2] -= u4 * l2
        band[3, j + 2] -= u5 * l2
        band[0, j + 3] -= u3 * l3
        band[1, j + 3] -= u4 * l3
        band[2, j + 3] -= u5 * l3
        band[0, j + 4] -= u4 * l4
        band[1, j + 4] -= u5 * l4
        band[0, j + 5] -= u5 * l5
        return False, v0
    band[0, j + 1] = v0
    m1 = v1 / v0
    m2 = v2 / v0
    m3 = v3 / v0
    m4 = v4 / v0
    m5 = v5 / v0
    band[1, j + 1] = m1
    band[2, j + 1] = m2
    band[3, j + 1] = m3
    band[4, j + 1] = m4
    band[5, j + 1] = m5
    band[0, j + 2] = band[0, j + 2] - u2 * l2 - v1 * m1
    band[1, j + 2] = band[1, j + 2] - u3 * l2 - v2 * m1
    band[2, j + 2] = band[2, j + 2] - u4 * l2 - v3 * m1
    band[3, j + 2] = band[3, j + 2] - u5 * l2 - v4 * m1
    band[4, j + 2] -= v5 * m1
    band[0, j + 3] = band[0, j + 3] - u3 * l3 - v2 * m2
    band[1, j + 3] = band[1, j + 3] - u4 * l3 - v3 * m2
    band[2, j + 3] = band[2, j + 3] - u5 * l3 - v4 * m2
    band[3, j + 3] -= v5 * m2
    band[0, j + 4] = band[0, j + 4] - u4 * l4 - v3 * m3
    band[1, j + 4] = band[1, j + 4] - u5 * l4 - v4 * m3
    band[2, j + 4] -= v5 * m3
    band[0, j + 5] = band[0, j + 5] - u5 * l5 - v4 * m4
    band[1, j + 5] -= v5 * m4
    band[0, j + 6] -= v5 * m5
    return True, v0


@njit(cache=True, inline="always")
def _pair9(band, j, d0, scale, pivot_tol):
    """`_eliminate_pair` for a window of 9 rows (generated by `_pair_source`)."""
    u1 = band[1, j]
    u2 = band[2, j]
    u3 = band[3, j]
    u4 = band[4, j]
    u5 = band[5, j]
    u6 = band[6, j]
    u7 = band[7, j]
    u8 = band[8, j]
    u9 = band[9, j]
    l1 = u1 / d0
    l2 = u2 / d0
    l3 = u3 / d0
    l4 = u4 / d0
    l5 = u5 / d0
    l6 = u6 / d0
    l7 = u7 / d0
    l8 = u8 / d0
    l9 = u9 / d0
    band[1, j] = l1
    band[2, j] = l2
    band[3, j] = l3
    band[4, j] = l4
    band[5, j] = l5
    band[6, j] = l6
    band[7, j] = l7
    band[8, j] = l8
    band[9, j] = l9
    v0 = band[0, j + 1] - u1 * l1
    v1 = band[1, j + 1] - u2 * l1
    v2 = band[2, j + 1] - u3 * l1
    v3 = band[3, j + 1] - u4 * l1
    v4 = band[4, j + 1] - u5 * l1
    v5 = band[5, j + 1] - u6 * l1
    v6 = band[6, j + 1] - u7 * l1
    v7 = band[7, j + 1] - u8 * l1
    v8 = band[8, j + 1] - u9 * l1
    v9 = band[9, j + 1]
    if not (abs(v0) / scale > pivot_tol):  # column j alone (also catches NaN)
        band[0, j + 1] = v0
        band[1, j + 1] = v1
        band[2, j + 1] = v2
        band[3, j + 1] = v3
        band[4, j + 1] = v4
        band[5, j + 1] = v5
        band[6, j + 1] = v6
        band[7, j + 1] = v7
        band[8, j + 1] = v8
        band[0, j + 2] -= u2 * l2
        band[1, j + 2] -= u3 * l2
        band[2, j + 2] -= u4 * l2
        band[3, j + 2] -= u5 * l2
        band[4, j + 2] -= u6 * l2
        band[5, j + 2] -= u7 * l2
        band[6, j + 2] -= u8 * l2
        band[7, j + 2] -= u9 * l2
        band[0, j + 3] -= u3 * l3
        band[1, j + 3] -= u4 * l3
        band[2, j + 3] -= u5 * l3
        band[3, j + 3] -= u6 * l3
        band[4, j + 3] -= u7 * l3
        band[5, j + 3] -= u8 * l3
        band[6, j + 3] -= u9 * l3
        band[0, j + 4] -= u4 * l4
        band[1, j + 4] -= u5 * l4
        band[2, j + 4] -= u6 * l4
        band[3, j + 4] -= u7 * l4
        band[4, j + 4] -= u8 * l4
        band[5, j + 4] -= u9 * l4
        band[0, j + 5] -= u5 * l5
        band[1, j + 5] -= u6 * l5
        band[2, j + 5] -= u7 * l5
        band[3, j + 5] -= u8 * l5
        band[4, j + 5] -= u9 * l5
        band[0, j + 6] -= u6 * l6
        band[1, j + 6] -= u7 * l6
        band[2, j + 6] -= u8 * l6
        band[3, j + 6] -= u9 * l6
        band[0, j + 7] -= u7 * l7
        band[1, j + 7] -= u8 * l7
        band[2, j + 7] -= u9 * l7
        band[0, j + 8] -= u8 * l8
        band[1, j + 8] -= u9 * l8
        band[0, j + 9] -= u9 * l9
        return False, v0
    band[0, j + 1] = v0
    m1 = v1 / v0
    m2 = v2 / v0
    m3 = v3 / v0
    m4 = v4 / v0
    m5 = v5 / v0
    m6 = v6 / v0
    m7 = v7 / v0
    m8 = v8 / v0
    m9 = v9 / v0
    band[1, j + 1] = m1
    band[2, j + 1] = m2
    band[3, j + 1] = m3
    band[4, j + 1] = m4
    band[5, j + 1] = m5
    band[6, j + 1] = m6
    band[7, j + 1] = m7
    band[8, j + 1] = m8
    band[9, j + 1] = m9
    band[0, j + 2] = band[0, j + 2] - u2 * l2 - v1 * m1
    band[1, j + 2] = band[1, j + 2] - u3 * l2 - v2 * m1
    band[2, j + 2] = band[2, j + 2] - u4 * l2 - v3 * m1
    band[3, j + 2] = band[3, j + 2] - u5 * l2 - v4 * m1
    band[4, j + 2] = band[4, j + 2] - u6 * l2 - v5 * m1
    band[5, j + 2] = band[5, j + 2] - u7 * l2 - v6 * m1
    band[6, j + 2] = band[6, j + 2] - u8 * l2 - v7 * m1
    band[7, j + 2] = band[7, j + 2] - u9 * l2 - v8 * m1
    band[8, j + 2] -= v9 * m1
    band[0, j + 3] = band[0, j + 3] - u3 * l3 - v2 * m2
    band[1, j + 3] = band[1, j + 3] - u4 * l3 - v3 * m2
    band[2, j + 3] = band[2, j + 3] - u5 * l3 - v4 * m2
    band[3, j + 3] = band[3, j + 3] - u6 * l3 - v5 * m2
    band[4, j + 3] = band[4, j + 3] - u7 * l3 - v6 * m2
    band[5, j + 3] = band[5, j + 3] - u8 * l3 - v7 * m2
    band[6, j + 3] = band[6, j + 3] - u9 * l3 - v8 * m2
    band[7, j + 3] -= v9 * m2
    band[0, j + 4] = band[0, j + 4] - u4 * l4 - v3 * m3
    band[1, j + 4] = band[1, j + 4] - u5 * l4 - v4 * m3
    band[2, j + 4] = band[2, j + 4] - u6 * l4 - v5 * m3
    band[3, j + 4] = band[3, j + 4] - u7 * l4 - v6 * m3
    band[4, j + 4] = band[4, j + 4] - u8 * l4 - v7 * m3
    band[5, j + 4] = band[5, j + 4] - u9 * l4 - v8 * m3
    band[6, j + 4] -= v9 * m3
    band[0, j + 5] = band[0, j + 5] - u5 * l5 - v4 * m4
    band[1, j + 5] = band[1, j + 5] - u6 * l5 - v5 * m4
    band[2, j + 5] = band[2, j + 5] - u7 * l5 - v6 * m4
    band[3, j + 5] = band[3, j + 5] - u8 * l5 - v7 * m4
    band[4, j + 5] = band[4, j + 5] - u9 * l5 - v8 * m4
    band[5, j + 5] -= v9 * m4
    band[0, j + 6] = band[0, j + 6] - u6 * l6 - v5 * m5
    band[1, j + 6] = band[1, j + 6] - u7 * l6 - v6 * m5
    band[2, j + 6] = band[2, j + 6] - u8 * l6 - v7 * m5
    band[3, j + 6] = band[3, j + 6] - u9 * l6 - v8 * m5
    band[4, j + 6] -= v9 * m5
    band[0, j + 7] = band[0, j + 7] - u7 * l7 - v6 * m6
    band[1, j + 7] = band[1, j + 7] - u8 * l7 - v7 * m6
    band[2, j + 7] = band[2, j + 7] - u9 * l7 - v8 * m6
    band[3, j + 7] -= v9 * m6
    band[0, j + 8] = band[0, j + 8] - u8 * l8 - v7 * m7
    band[1, j + 8] = band[1, j + 8] - u9 * l8 - v8 * m7
    band[2, j + 8] -= v9 * m7
    band[0, j + 9] = band[0, j + 9] - u9 * l9 - v8 * m8
    band[1, j + 9] -= v9 * m8
    band[0, j + 10] -= v9 * m9
    return True, v0


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
    j = 0
    while j < n:
        d = band[0, j]
        ratio = abs(d) / scale
        if ratio < min_ratio:
            min_ratio = ratio
        if not (ratio > pivot_tol):  # also catches NaN
            return 1, negative, min_ratio
        if d < 0.0:
            negative += 1
        m = heights[j] if known else _column_height(band, j, bw, n)
        # two short columns within a fixed window (their rows below the envelope are
        # zeros): one pass of straight-line code (most columns of a unit); with the
        # envelope known only (the scanning factor does not know column j + 1's extent yet)
        if known and m <= _MEDIUM and bw >= _MEDIUM and j + 1 + _MEDIUM < n \
                and heights[j + 1] <= _MEDIUM:
            w = _SHORT if m <= _SHORT and heights[j + 1] <= _SHORT else _MEDIUM
            done, d1 = _eliminate_pair(band, j, d, w, scale, pivot_tol)
            if done:
                ratio = abs(d1) / scale
                if ratio < min_ratio:
                    min_ratio = ratio
                if d1 < 0.0:
                    negative += 1
                j += 2
            else:
                j += 1
            continue
        # a short column within a fixed window (its rows below m are zeros, outside the
        # envelope): loops of constant length, unrolled (most columns of planar rods)
        if m <= _SHORT and bw >= _SHORT and j + _SHORT < n:
            _eliminate(band, j, d, _SHORT)
            j += 1
            continue
        if m <= _MEDIUM and bw >= _MEDIUM and j + _MEDIUM < n:
            _eliminate(band, j, d, _MEDIUM)
            j += 1
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
        j += 1
    return 0, negative, min_ratio


@njit(cache=True)
def ldlt_solve(band, b):
    """Solve K X = B in place for B of shape (n, m), with a factor from ``ldlt_factor``."""
    return _solve(band, scanned_heights(band), b)


@njit(cache=True)
def ldlt_solve_envelope(band, heights, b):
    """`ldlt_solve` with every column's extent given (`envelope_heights`)."""
    return _solve(band, heights, b)


@njit(cache=True)
def _rows1(band, heights, b):
    """`_solve` for one right-hand side of a band of 9 rows or more below the diagonal.

    Forward by rows: y_i = b_i - sum_j L_ij y_j over the columns j < i in increasing
    order, as the column sweep subtracts them (the same bits); the 9 columns before row
    i give theirs from the band (entries below a column's envelope are zeros: x - 0 y
    = x up to the sign of a zero) with the y_j kept in registers, so that the chain
    from one row to the next is one product and one subtraction; a column reaching
    further than 9 rows pushes the rest of its entries down the right-hand side when
    y_j is known (before any of the rows' own pulls, which come from later columns).
    y_i / d_i is stored as the row is done. Back substitution by columns, x_{j+1} from
    a register, a column within a 9-row window as 9 terms (no varying loop length to
    mispredict). 5.8 -> 3.6 us on the specimen."""
    n = band.shape[1]
    y1 = y2 = y3 = y4 = y5 = y6 = y7 = y8 = y9 = 0.0
    for i in range(n):
        s = b[i, 0]
        if i >= 9:
            s -= band[9, i - 9] * y9
            s -= band[8, i - 8] * y8
            s -= band[7, i - 7] * y7
            s -= band[6, i - 6] * y6
            s -= band[5, i - 5] * y5
            s -= band[4, i - 4] * y4
            s -= band[3, i - 3] * y3
            s -= band[2, i - 2] * y2
            s -= band[1, i - 1] * y1
        elif i >= 1:
            if i >= 8:
                s -= band[8, i - 8] * y8
            if i >= 7:
                s -= band[7, i - 7] * y7
            if i >= 6:
                s -= band[6, i - 6] * y6
            if i >= 5:
                s -= band[5, i - 5] * y5
            if i >= 4:
                s -= band[4, i - 4] * y4
            if i >= 3:
                s -= band[3, i - 3] * y3
            if i >= 2:
                s -= band[2, i - 2] * y2
            s -= band[1, i - 1] * y1
        y9, y8, y7, y6, y5, y4, y3, y2, y1 = y8, y7, y6, y5, y4, y3, y2, y1, s
        m = heights[i]
        if m > 9 and s != 0.0:
            for k in range(10, m + 1):
                b[i + k, 0] -= band[k, i] * s
        b[i, 0] = s / band[0, i]
    x = 0.0
    for j in range(n - 1, -1, -1):
        m = heights[j]
        s = b[j, 0]
        if m <= 9 and j + 9 < n:
            s -= band[1, j] * x
            for i in range(2, 10):
                s -= band[i, j] * b[j + i, 0]
        elif m >= 1:
            s -= band[1, j] * x
            for i in range(2, m + 1):
                s -= band[i, j] * b[j + i, 0]
        b[j, 0] = s
        x = s
    return b


@njit(cache=True)
def _rows2(band, heights, b):
    """`_rows1` for two right-hand sides (an MGDC corrector's), both in the same loops
    (the same operations per side as `_rows1`, a zero entry of one side carried along
    when the other's is not: x - l 0 = x)."""
    n = band.shape[1]
    y1 = y2 = y3 = y4 = y5 = y6 = y7 = y8 = y9 = 0.0
    z1 = z2 = z3 = z4 = z5 = z6 = z7 = z8 = z9 = 0.0
    for i in range(n):
        s0 = b[i, 0]
        s1 = b[i, 1]
        if i >= 9:
            lk = band[9, i - 9]
            s0 -= lk * y9
            s1 -= lk * z9
            lk = band[8, i - 8]
            s0 -= lk * y8
            s1 -= lk * z8
            lk = band[7, i - 7]
            s0 -= lk * y7
            s1 -= lk * z7
            lk = band[6, i - 6]
            s0 -= lk * y6
            s1 -= lk * z6
            lk = band[5, i - 5]
            s0 -= lk * y5
            s1 -= lk * z5
            lk = band[4, i - 4]
            s0 -= lk * y4
            s1 -= lk * z4
            lk = band[3, i - 3]
            s0 -= lk * y3
            s1 -= lk * z3
            lk = band[2, i - 2]
            s0 -= lk * y2
            s1 -= lk * z2
            lk = band[1, i - 1]
            s0 -= lk * y1
            s1 -= lk * z1
        elif i >= 1:
            if i >= 8:
                lk = band[8, i - 8]
                s0 -= lk * y8
                s1 -= lk * z8
            if i >= 7:
                lk = band[7, i - 7]
                s0 -= lk * y7
                s1 -= lk * z7
            if i >= 6:
                lk = band[6, i - 6]
                s0 -= lk * y6
                s1 -= lk * z6
            if i >= 5:
                lk = band[5, i - 5]
                s0 -= lk * y5
                s1 -= lk * z5
            if i >= 4:
                lk = band[4, i - 4]
                s0 -= lk * y4
                s1 -= lk * z4
            if i >= 3:
                lk = band[3, i - 3]
                s0 -= lk * y3
                s1 -= lk * z3
            if i >= 2:
                lk = band[2, i - 2]
                s0 -= lk * y2
                s1 -= lk * z2
            lk = band[1, i - 1]
            s0 -= lk * y1
            s1 -= lk * z1
        y9, y8, y7, y6, y5, y4, y3, y2, y1 = y8, y7, y6, y5, y4, y3, y2, y1, s0
        z9, z8, z7, z6, z5, z4, z3, z2, z1 = z8, z7, z6, z5, z4, z3, z2, z1, s1
        m = heights[i]
        if m > 9 and (s0 != 0.0 or s1 != 0.0):
            for k in range(10, m + 1):
                lk = band[k, i]
                b[i + k, 0] -= lk * s0
                b[i + k, 1] -= lk * s1
        d = band[0, i]
        b[i, 0] = s0 / d
        b[i, 1] = s1 / d
    x0 = 0.0
    x1 = 0.0
    for j in range(n - 1, -1, -1):
        m = heights[j]
        s0 = b[j, 0]
        s1 = b[j, 1]
        if m >= 1:
            lk = band[1, j]
            s0 -= lk * x0
            s1 -= lk * x1
        if m <= 9 and j + 9 < n:
            for i in range(2, 10):
                li = band[i, j]
                s0 -= li * b[j + i, 0]
                s1 -= li * b[j + i, 1]
        else:
            for i in range(2, m + 1):
                li = band[i, j]
                s0 -= li * b[j + i, 0]
                s1 -= li * b[j + i, 1]
        b[j, 0] = s0
        b[j, 1] = s1
        x0 = s0
        x1 = s1
    return b

@njit(cache=True, inline="always")
def _solve(band, heights, b):
    # all right-hand sides in one sweep over the factor: each column of L is read once
    n = band.shape[1]
    nc = b.shape[1]
    if band.shape[0] > 9 and n > 9 and 1 <= nc <= 2:  # (a unit's band: by rows)
        return _rows1(band, heights, b) if nc == 1 else _rows2(band, heights, b)
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
