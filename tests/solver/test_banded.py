"""Banded LDL^T against dense linear algebra: solutions and inertia."""

import numpy as np
import pytest

from snapmorph.solver.banded import band_to_dense, ldlt_factor, ldlt_solve


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


def _envelope_band(rng, n, bw, order="C"):
    """A band whose columns are short except a few that reach far (a ring closing: the
    shape of a frame's stiffness), with zeros inside the band that fill in."""
    band = np.zeros((bw + 1, n), order=order)
    band[0] = 4.0 + rng.random(n)
    band[1, : n - 1] = rng.normal(size=n - 1)
    band[2, : n - 2] = 0.3 * rng.normal(size=n - 2)
    for j in rng.choice(n - bw, 4, replace=False):
        band[bw, j] = rng.normal()
        band[bw // 2, j] = rng.normal()
    band[0] -= 1.5  # a few negative pivots
    return band


@pytest.mark.parametrize("order", ["C", "F"])
def test_envelope_factor_matches_dense_and_the_full_band_loop(rng, order):
    """Stopping each column at its last nonzero (fill included) gives the dense solution
    and inertia, in either memory order, bit for bit what the whole band gives."""
    n, bw = 80, 30
    band = _envelope_band(rng, n, bw, order)
    dense = band_to_dense(band)
    full = band.copy(order=order)
    full[bw, 0] = 1e-300  # a nonzero at the band's edge in column 0: that column runs whole
    status, negative, _ = ldlt_factor(band, 1e-14)
    assert status == 0
    assert negative == int(np.sum(np.linalg.eigvalsh(dense) < 0))
    b = rng.normal(size=(n, 2))
    x = ldlt_solve(band, b.copy())
    np.testing.assert_allclose(dense @ x, b, atol=1e-9 * np.linalg.cond(dense))
    # the same factor as the old whole-band loop: compare with a reference implementation
    ref = band_to_dense(_envelope_band(np.random.default_rng(0), n, bw))
    ref_band = _envelope_band(np.random.default_rng(0), n, bw)
    ldlt_factor(ref_band, 1e-14)
    L = np.eye(n)
    for k in range(1, bw + 1):
        idx = np.arange(n - k)
        L[idx + k, idx] = ref_band[k, : n - k]
    D = np.diag(ref_band[0])
    np.testing.assert_allclose(L @ D @ L.T, ref, atol=1e-12 * np.abs(ref).max())


def test_envelope_heights_bound_the_fill_and_give_the_scanned_factor(rng):
    """Column extents computed once from the elements' DOFs (`envelope_heights`) hold every
    nonzero of the factor, fill included, and the factor and solves that use them equal the
    scanning ones; held DOFs (-1) are skipped."""
    from snapmorph.solver.banded import (envelope_heights, ldlt_factor_envelope, ldlt_solve_envelope,
                               scanned_heights)

    n = 40
    elements = rng.integers(0, n, size=(25, 3))
    elements[:, 1] = np.minimum(elements[:, 0] + rng.integers(0, 6, 25), n - 1)
    elements[3, 2] = -1
    chain = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
    heights = envelope_heights(n, elements, chain)
    bw = int(heights.max())
    band = np.zeros((bw + 1, n), order="F")
    band[0] = 1.0 + 4.0 * rng.random(n)
    for dofs in (elements, chain):
        for e in dofs:
            e = e[e >= 0]
            for a in e:
                for b in e:
                    if a > b:
                        band[a - b, b] += 0.3 * rng.normal()
    scanned = band.copy(order="F")
    enveloped = band.copy(order="F")
    assert ldlt_factor(scanned, 1e-14)[:2] == ldlt_factor_envelope(enveloped, heights, 1e-14)[:2]
    np.testing.assert_array_equal(scanned, enveloped)
    assert np.all(scanned_heights(scanned) <= heights)
    assert np.any(scanned_heights(scanned) > scanned_heights(band))  # there was fill
    b = rng.normal(size=(n, 2))
    np.testing.assert_array_equal(ldlt_solve(scanned, b.copy()),
                                  ldlt_solve_envelope(enveloped, heights, b.copy()))


def _factor_reference(band, pivot_tol):
    """Right-looking LDL^T one column at a time in plain Python over the whole band: the
    operations the compiled factor does, in the same order (column j's update of an entry
    before column j + 1's), so the same bits."""
    bw, n = band.shape[0] - 1, band.shape[1]
    scale = 0.0
    for d in band[0]:
        scale = abs(d) if abs(d) > scale else scale  # (NaN skipped)
    if scale == 0.0 or not np.isfinite(scale):
        return 1, 0, 0.0
    negative, min_ratio = 0, np.inf
    for j in range(n):
        d = band[0, j]
        ratio = abs(d) / scale
        min_ratio = min(min_ratio, ratio)
        if not ratio > pivot_tol:
            return 1, negative, min_ratio
        negative += d < 0.0
        m = min(bw, n - 1 - j)
        for i in range(1, m + 1):
            lij = band[i, j] / d
            for k in range(m - i + 1):
                band[k, j + i] -= band[k + i, j] * lij
            band[i, j] = lij
    return 0, negative, min_ratio


@pytest.mark.parametrize("cap", [2, 5, 9, 12])
def test_paired_and_windowed_columns_give_the_reference_factor_bit_for_bit(rng, cap):
    """Columns factorised two at a time in written-out windows (`_pair5`, `_pair9`), one at
    a time in fixed windows or along their envelope: the plain loop's factor, status,
    inertia and smallest pivot ratio, bit for bit, also where a pivot fails (the first of a
    pair, the second, NaN)."""
    from snapmorph.solver.banded import envelope_heights, ldlt_factor_envelope

    for trial in range(60):
        n = int(rng.integers(2, 50))
        reach = rng.integers(0, cap + 1, size=n)
        dofs = np.stack([np.maximum(np.arange(n) - reach, 0), np.arange(n)], axis=1)
        heights = envelope_heights(n, dofs)
        bw = max(int(heights.max()), int(rng.choice([1, 5, 9, 12])))
        band = np.zeros((bw + 1, n), order="F")
        for lo, hi in dofs:
            if hi > lo:
                band[hi - lo, lo] = rng.normal() * (rng.random() > 0.1)
        band[0] = rng.uniform(-4.0, 4.0, n) + (8.0 if trial % 3 else 0.0)
        if trial % 5 == 0:
            band[0, rng.integers(n)] = 0.0 if trial % 2 else np.nan
        tol = float(rng.choice([0.0, 1e-3, 0.2]))
        ref = band.copy(order="F")
        expected = _factor_reference(ref, tol)
        got = band.copy(order="F")
        status, negative, ratio = ldlt_factor_envelope(got, heights, tol)
        assert (status, negative) == expected[:2]
        assert ratio == expected[2] or (np.isnan(ratio) and np.isnan(expected[2]))
        if status == 0:  # (a failed factor's band is scratch)
            np.testing.assert_array_equal(got, ref)


def test_the_written_out_pairs_are_their_generator():
    import inspect

    from snapmorph.solver import banded

    for w in (5, 9):
        kernel = getattr(banded, f"_pair{w}")
        src = inspect.getsource(getattr(kernel, "py_func", kernel))  # (plain without numba)
        assert src[src.index("def "):] == banded._pair_source(w)


def _solve_reference(band, heights, b):
    """The column sweeps in plain Python: forward L y = b column by column (a zero y_j
    skipped), y / d, back L^T x = y by column dot products: the order of operations of
    every entry that the compiled solves keep."""
    n = band.shape[1]
    for j in range(n):
        for c in range(b.shape[1]):
            v = b[j, c]
            if v != 0.0:
                for k in range(heights[j]):
                    b[j + 1 + k, c] -= band[k + 1, j] * v
    b /= band[0][:, None]
    for j in range(n - 1, -1, -1):
        for c in range(b.shape[1]):
            s = b[j, c]
            for i in range(1, heights[j] + 1):
                s -= band[i, j] * b[j + i, c]
            b[j, c] = s
    return b


@pytest.mark.parametrize("cap", [3, 9, 14])
def test_solves_by_rows_give_the_column_sweeps_bit_for_bit(rng, cap):
    """One and two right-hand sides of a band of 9 rows or more are solved by rows forward
    (`_rows1`, `_rows2`): the column sweeps' values, bit for bit, with columns within the
    9-row window, reaching past it, and zero entries in the right-hand sides; three sides
    go by columns."""
    from snapmorph.solver.banded import envelope_heights, ldlt_factor_envelope, ldlt_solve_envelope

    for trial in range(20):
        n = int(rng.integers(10, 60))
        reach = rng.integers(0, cap + 1, size=n)
        dofs = np.stack([np.maximum(np.arange(n) - reach, 0), np.arange(n)], axis=1)
        heights = envelope_heights(n, dofs)
        bw = max(int(heights.max()), 9 + int(rng.integers(0, 3)))
        band = np.zeros((bw + 1, n), order="F")
        for lo, hi in dofs:
            if hi > lo:
                band[hi - lo, lo] = rng.normal()
        band[0] = rng.uniform(-4.0, 4.0, n) + 8.0 * np.sign(rng.uniform(-1, 1, n))
        assert ldlt_factor_envelope(band, heights, 0.0)[0] == 0
        for m in (1, 2, 3):
            rhs = rng.normal(size=(n, m))
            rhs[rng.random(size=(n, m)) < 0.2] = 0.0
            if trial == 0:
                rhs[:, 0] = 0.0
            expected = _solve_reference(band, heights, rhs.copy())
            got = ldlt_solve_envelope(band, heights, rhs.copy())
            np.testing.assert_array_equal(got, expected)
            strided = np.zeros((n, 4))  # the fused iterations' right-hand sides: a view
            strided[:, 1:1 + m] = rhs
            np.testing.assert_array_equal(
                ldlt_solve_envelope(band, heights, strided[:, 1:1 + m]), expected)
