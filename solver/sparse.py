"""Sparse symmetric LDL^T with its inertia, for structures whose band is hopeless (sheets).

The banded LDL^T of `solver.banded` costs what the envelope of K holds: linear in the DOFs
for a rod structure that is long in one direction (a unit), but a sheet tiled from units in
two directions has an envelope of width ~ its side, and the factor grows like n^2. Here the
same matrix is factorised in compressed sparse column form after a fill-reducing ordering
(approximate minimum degree), with QDLDL (`qdldl` on PyPI: a wheel, no system library) —
LDL^T without pivoting, like the banded path, so Sylvester's count of negative pivots is the
number of negative eigenvalues (the stability count) for free.

Pattern once, values many times:

- `SparseLDLT(n, *element_dofs)` builds the upper-triangular CSC pattern of K from the same
  reduced element DOF lists (arrays (n_elements, k), -1 for held DOFs) as
  `solver.banded.envelope_heights`, plus one entry map per element array: for every element
  e and local pair (a, b) the index into ``data`` that the band scatter would have added
  ``h[a, b]`` to (``band[ra - rb, rb]`` for rb <= ra becomes ``data[maps[e, a, b]]``; -1
  where nothing is added), for a compiled assembly that writes straight into ``data``
  (`scatter_element`); the systems assemble K in their band and copy it (`from_band`).
- The constructor also runs the ordering and the symbolic analysis (elimination tree,
  column counts: ``nnz_factor``, ``factor_flops``) once, on stand-in values (the identity on
  the pattern, so that no value of K can make it fail); every `factor()` is numeric only.
- `factor()` returns (status, negative pivots, min pivot ratio) as `solver.banded.ldlt_factor`
  does and sets ``negative_eigenvalues``; `solve(rhs)` for (n,) or (n, m).

`choose_factorisation` decides between the banded and the sparse path by the measured
crossover (bench/bench_sparse.py, docs/sparse.md); `system_factorisation` is what every
`solver.system.BandedSystem` asks when it is built (the one choice point: its `factor` and
`solve` then use the path chosen), and `use_factorisation("banded"|"sparse")` overrides it
for the systems built inside a ``with`` block (tests, benchmarks).
"""

from __future__ import annotations

import contextlib

import numpy as np
import scipy.sparse
from numba import njit


#: a pivot smaller than this times the largest diagonal entry of K: numerically singular
#: (the banded path's `solver.system.PIVOT_TOL`)
PIVOT_TOL = 1e-13

#: cost model of the two factorisations, used by `choose_factorisation` (fitted to
#: bench/bench_sparse.py on the units and sheets: 2-core AMD EPYC, one thread): the banded
#: LDL^T of `solver.banded` costs BANDED_NS_PER_FLOP per flop of its envelope (sum over the
#: columns of height^2 / 2; ~5 GF/s, vectorised) plus BANDED_NS_PER_DOF per column; QDLDL
#: costs SPARSE_NS_PER_FLOP per flop (sum over the columns of L of their count^2; ~3 GF/s)
#: plus SPARSE_NS_PER_ENTRY per entry of L (its scalar up-looking loops, the copy of D) plus
#: SPARSE_CALL_NS per call
BANDED_NS_PER_FLOP = 0.2
BANDED_NS_PER_DOF = 80.0
SPARSE_NS_PER_FLOP = 0.34
SPARSE_NS_PER_ENTRY = 13.0
SPARSE_CALL_NS = 20_000.0
#: `choose_factorisation` without a sparse analysis: "sparse" above both (measured crossover:
#: the 3-D unit has 80-150 envelope flops per entry of K and stays banded, a strip of cells
#: ~75, sheets of 2 x 2 cells ~120 (a tie), 2 x 16 ~230 (sparse 1.4x faster), 4 x 4 ~430)
SPARSE_WITHOUT_ANALYSIS_FLOPS = 2e6
ENVELOPE_FLOPS_PER_NNZ = 200.0


# ---------------------------------------------------------------------------- pattern


#: the patterns (and entry maps) of the last few DOF lists: a sheet's push builds several
#: systems of the same structure (rig, release, stability), each of which would otherwise
#: count, sort and map the same pattern again (~40 ms per system on a 3 x 3 sheet)
_PATTERNS: dict = {}
_PATTERNS_KEPT = 8


def _cached_pattern(n, dofs):
    """(indptr, indices, maps) of `csc_pattern` and `entry_map` for the int64 DOF lists
    ``dofs``, from the cache when the same lists were seen (compared byte for byte); the
    arrays are shared: nobody writes to them."""
    key = (int(n),) + tuple((d.shape, d.tobytes()) for d in dofs)
    hit = _PATTERNS.get(key)
    if hit is None:
        indptr, indices = csc_pattern(n, *dofs)
        hit = (indptr, indices, tuple(entry_map(d, indptr, indices) for d in dofs))
        if len(_PATTERNS) >= _PATTERNS_KEPT:
            _PATTERNS.pop(next(iter(_PATTERNS)))
        _PATTERNS[key] = hit
    return hit


def csc_pattern(n, *element_dofs):
    """(indptr, indices) int64 of the upper triangle (row <= column, rows sorted within each
    column, every diagonal entry present) of an n x n matrix assembled from elements with
    the reduced DOF lists ``element_dofs`` (arrays (n_elements, k), -1 for held DOFs)."""
    dofs = [np.ascontiguousarray(d, dtype=np.int64) for d in element_dofs if np.size(d)]
    counts = np.ones(n, dtype=np.int64)  # the diagonal
    none = np.zeros(0, dtype=np.int64)
    for d in dofs:
        _walk_entries(d, counts, none, none, False)
    start = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(counts, out=start[1:])
    rows = np.empty(start[-1], dtype=np.int64)
    fill = start[:-1].copy()
    rows[fill] = np.arange(n)
    fill += 1
    for d in dofs:
        _walk_entries(d, counts, rows, fill, True)
    return _compact_columns(start, rows)


@njit(cache=True)
def _walk_entries(dofs, counts, rows, fill, write):
    """Every upper-triangle entry (row rb <= column ra) the elements ``dofs`` touch: counted
    per column into ``counts`` (``write`` False) or its row written at ``fill[ra]``."""
    for e in range(dofs.shape[0]):
        for a in range(dofs.shape[1]):
            ra = dofs[e, a]
            if ra < 0:
                continue
            for b in range(dofs.shape[1]):
                rb = dofs[e, b]
                if 0 <= rb <= ra:
                    if write:
                        rows[fill[ra]] = rb
                        fill[ra] += 1
                    else:
                        counts[ra] += 1


@njit(cache=True)
def _compact_columns(start, rows):
    """Sort every column's rows and drop repeats: the CSC arrays."""
    n = start.shape[0] - 1
    indptr = np.zeros(n + 1, dtype=np.int64)
    out = np.empty(rows.shape[0], dtype=np.int64)
    m = 0
    for c in range(n):
        col = np.sort(rows[start[c]:start[c + 1]])
        last = -1
        for r in col:
            if r != last:
                out[m] = r
                m += 1
                last = r
        indptr[c + 1] = m
    return indptr, out[:m].copy()


@njit(cache=True)
def _find(indptr, indices, row, col):
    lo = indptr[col]
    hi = indptr[col + 1]
    while lo < hi:  # binary search: rows are sorted within a column
        mid = (lo + hi) >> 1
        if indices[mid] < row:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def entry_map(dofs, indptr, indices):
    """(n_elements, k, k) int64: for element e and local coordinates (a, b) with reduced DOFs
    ra = dofs[e, a], rb = dofs[e, b] >= 0 and rb <= ra, the index into the CSC data of the
    upper-triangle entry (row rb, column ra); -1 otherwise. The banded scatter adds h[a, b]
    to ``band[ra - rb, rb]`` under the same condition, so both store the same W^T K W
    (tied DOFs inside one element included: both (a, b) and (b, a) reach the diagonal)."""
    ne, k = dofs.shape
    out = -np.ones((ne, k, k), dtype=np.int64)
    for e in range(ne):
        for a in range(k):
            ra = dofs[e, a]
            if ra < 0:
                continue
            for b in range(k):
                rb = dofs[e, b]
                if rb < 0 or rb > ra:
                    continue
                out[e, a, b] = _find(indptr, indices, rb, ra)
    return out


@njit(cache=True)
def scatter_element(data, emap, h, scale_a, scale_b):
    """data[emap[a, b]] += scale_a[a] scale_b[b] h[a, b] for every mapped local pair: the
    element scatter of an assembly that writes straight into the CSC values."""
    k = emap.shape[0]
    for a in range(k):
        for b in range(k):
            i = emap[a, b]
            if i >= 0:
                data[i] += scale_a[a] * scale_b[b] * h[a, b]


@njit(cache=True)
def band_to_csc_data(band, indptr, indices, data):
    """The CSC values (upper triangle) of a matrix held in lower band storage
    (``band[k, j] = K[j + k, j]``); entries outside the band are zero."""
    bw = band.shape[0] - 1
    n = indptr.shape[0] - 1
    for c in range(n):
        for p in range(indptr[c], indptr[c + 1]):
            k = c - indices[p]
            data[p] = band[k, indices[p]] if k <= bw else 0.0
    return data


# ---------------------------------------------------------------------------- factorisation


class SparseLDLT:
    """LDL^T without pivoting of a symmetric sparse K (reduced DOFs) with a fill-reducing
    ordering, its inertia and solves; the pattern and the symbolic analysis are built once.

    ``n``: reduced DOFs; ``element_dofs``: the element DOF lists of the assembly (arrays
    (n_elements, k) int, -1 for held DOFs), as for `solver.banded.envelope_heights`.

    Members: ``indptr``, ``indices`` (upper-triangle CSC pattern, diagonal last in each
    column), ``data`` (its values: the assembly writes here, through ``maps[i]`` for
    ``element_dofs[i]``, see `entry_map`), ``negative_eigenvalues``, ``factor_ok``,
    ``min_pivot_ratio`` (min |D| / max |diag K| of the last factorisation), ``nnz_factor``
    (entries of L below the diagonal) and ``factor_flops`` (sum of L's column counts squared).

    Uses QDLDL (package `qdldl`): approximate minimum degree ordering, elimination tree and
    column counts once (at construction, on a stand-in matrix of the same pattern, so that
    no value of K can make the analysis fail), then an up-looking numeric LDL^T per
    `factor`. Deterministic and single-threaded: the same K gives the same bits (not the
    banded path's bits: another elimination order).
    """

    def __init__(self, n, *element_dofs):
        import qdldl  # noqa: PLC0415 - imported where used: a dependency of this path only

        self.n = int(n)
        if self.n < 1:
            raise ValueError(f"n (reduced DOFs) must be >= 1; got {n!r}")
        dofs = tuple(np.ascontiguousarray(d, dtype=np.int64).reshape(len(d), -1 if len(d) else 0)
                     for d in element_dofs)
        self.indptr, self.indices, self.maps = _cached_pattern(self.n, dofs)
        self.diagonal = self.indptr[1:] - 1
        # the matrix handed to QDLDL shares ``data``; QDLDL reads only its values on refactor
        self._U = scipy.sparse.csc_matrix(
            (np.zeros(self.indices.shape[0]), self.indices, self.indptr), shape=(self.n, self.n))
        self.data = self._U.data
        self.data[self.diagonal] = 1.0  # stand-in values: the identity on the pattern
        self._solver = qdldl.Solver(self._U, upper=True)
        L, _, _ = self._solver.factors()
        counts = np.diff(L.indptr).astype(float)
        self.nnz_factor = int(L.nnz)
        self.factor_flops = float(np.dot(counts, counts))
        self.data[:] = 0.0
        self.negative_eigenvalues = 0
        self.factor_ok = False
        self.min_pivot_ratio = 0.0

    @classmethod
    def for_system(cls, system):
        """The sparse factorisation of a `solver.system.ReducedSystem` or a
        `solver.system3d.RodSystem3D` (its element DOF lists; not wired into the system)."""
        if hasattr(system, "element_dofs"):  # 3-D: (stretch full, stretch red, pair full, pair red)
            return cls(system.n, system.element_dofs[1], system.element_dofs[3])
        return cls(system.n, *system.dofs)

    # ------------------------------------------------------------------ values
    def clear(self):
        """Zero the values (before an assembly that adds into ``data``)."""
        self.data[:] = 0.0

    def from_band(self, band):
        """Take the values of a matrix in lower band storage (`solver.banded`) on this
        pattern (entries of the band outside the pattern must be zero)."""
        band_to_csc_data(band, self.indptr, self.indices, self.data)

    def from_dense(self, K):
        """Take the values of a dense symmetric (n, n) matrix on this pattern (tests)."""
        K = np.asarray(K, dtype=float)
        cols = np.repeat(np.arange(self.n), np.diff(self.indptr))
        self.data[:] = K[self.indices, cols]

    def matrix(self):
        """The full symmetric K (scipy CSC) of the current values."""
        U = scipy.sparse.csc_matrix((self.data.copy(), self.indices, self.indptr),
                                    shape=(self.n, self.n))
        return (U + scipy.sparse.triu(U, k=1).T).tocsc()

    # ------------------------------------------------------------------ factor / solve
    def factor(self, pivot_tol=PIVOT_TOL):
        """Factorise the current values (the pattern's analysis is reused).

        Returns (status, negative_pivots, min_abs_pivot_ratio) as `solver.banded.ldlt_factor`:
        status 0 done (``negative_eigenvalues`` is the inertia count); 1 a pivot below
        ``pivot_tol`` times the largest diagonal entry, or a non-finite one (numerically
        singular without pivoting: the count is then unreliable and the caller falls back,
        e.g. to a shifted factorisation or a dense eigensolver for small n)."""
        diag = self.data[self.diagonal]
        scale = float(np.max(np.abs(diag)))
        self.factor_ok = False
        if not (scale > 0.0 and np.isfinite(scale)) or not np.all(np.isfinite(self.data)):
            self.min_pivot_ratio = 0.0
            return 1, 0, 0.0
        self._solver.update(self._U, upper=True)
        D = self._solver.factors()[1]
        negative = int(np.count_nonzero(D < 0.0))
        # an exact zero pivot stops QDLDL's factorisation (later pivots are stale): it shows
        # as a ratio of 0 here; NaN also fails the test
        ratio = float(np.min(np.abs(D))) / scale
        self.min_pivot_ratio = ratio
        if not ratio > pivot_tol:
            return 1, negative, ratio
        self.negative_eigenvalues = negative
        self.factor_ok = True
        return 0, negative, ratio

    def solve(self, rhs):
        """Solve K X = rhs for rhs (n,) or (n, m) with the last factorisation; a new array."""
        if not self.factor_ok:
            raise RuntimeError("solve needs a successful factor() first")
        b = np.asarray(rhs, dtype=float)
        if b.shape[0] != self.n or b.ndim not in (1, 2):
            raise ValueError(f"rhs must have shape ({self.n},) or ({self.n}, m); got {b.shape}")
        if b.ndim == 1:
            return self._solver.solve(np.ascontiguousarray(b))
        out = np.empty_like(b)
        for c in range(b.shape[1]):
            out[:, c] = self._solver.solve(np.ascontiguousarray(b[:, c]))
        return out


# ---------------------------------------------------------------------------- the choice


def envelope_flops(heights):
    """Flops of the banded LDL^T within the envelope ``heights`` (sum of height^2 / 2, as
    `solver.ordering.envelope_cost`)."""
    h = np.asarray(heights)
    if h.dtype.kind in "iu":
        # integer heights: the integer dot, without the conversion (asked by every new
        # system); below 2^53 the float dot's partial sums are exact integers too
        total = int(np.dot(h.astype(np.int64, copy=False), h.astype(np.int64, copy=False)))
        if total < 2**53:
            return 0.5 * float(total)
    h = np.asarray(heights, dtype=float)
    return 0.5 * float(np.dot(h, h))


def factorisation_costs(n, heights, factor_flops, nnz_factor):
    """(banded s, sparse s): the cost model's estimate of one factorisation by each path."""
    banded = 1e-9 * (BANDED_NS_PER_FLOP * envelope_flops(heights) + BANDED_NS_PER_DOF * n)
    sparse = 1e-9 * (SPARSE_NS_PER_FLOP * factor_flops + SPARSE_NS_PER_ENTRY * nnz_factor
                     + SPARSE_CALL_NS)
    return banded, sparse


def choose_factorisation(n, heights, nnz=None, factor_flops=None, nnz_factor=None):
    """"banded" or "sparse" for a system of ``n`` reduced DOFs whose banded envelope has the
    column ``heights`` (`solver.banded.envelope_heights`).

    With the sparse factor's size known (``factor_flops``, ``nnz_factor``: the members of a
    `SparseLDLT`, whose analysis costs about one factorisation) the cheaper path by the
    measured cost model (`factorisation_costs`; the banded path wins ties, it has the
    compiled fused iterations). Without them, from the envelope alone: "sparse" when the
    banded factor would cost more than SPARSE_WITHOUT_ANALYSIS_FLOPS flops and more than
    ENVELOPE_FLOPS_PER_NNZ flops per entry of K (``nnz``, upper triangle; default ~12 n):
    rod structures long in one direction (units, strips of cells) have a thin envelope and
    stay banded, sheets of cells in two directions go sparse."""
    if factor_flops is not None and nnz_factor is not None:
        banded, sparse = factorisation_costs(n, heights, factor_flops, nnz_factor)
        return "sparse" if sparse < banded else "banded"
    work = envelope_flops(heights)
    nnz = 12 * n if nnz is None else nnz
    if work > SPARSE_WITHOUT_ANALYSIS_FLOPS and work > ENVELOPE_FLOPS_PER_NNZ * nnz:
        return "sparse"
    return "banded"



#: the factorisations a system can use (`use_factorisation`)
FACTORISATIONS = ("banded", "sparse")
_override = [None]  # the kind forced by `use_factorisation` (None: chosen by size)


@contextlib.contextmanager
def use_factorisation(kind):
    """Systems built inside the ``with`` block use the factorisation ``kind`` ("banded" or
    "sparse"; None: chosen by size and structure, the default) whatever their size: the
    explicit override of `system_factorisation` for tests and benchmarks."""
    if kind is not None and kind not in FACTORISATIONS:
        raise ValueError(f"kind (factorisation) must be one of {FACTORISATIONS} or None; "
                         f"got {kind!r}")
    before = _override[0]
    _override[0] = kind
    try:
        yield
    finally:
        _override[0] = before


def system_factorisation(n, heights, *element_dofs):
    """"banded" or "sparse": the factorisation of a system of ``n`` reduced DOFs whose banded
    envelope has the column ``heights`` and whose elements have the reduced DOF lists
    ``element_dofs`` (the override of `use_factorisation` first). The pattern is counted
    only when the envelope alone could make the sparse path worth it (a unit's systems are
    built many times: they pay nothing for the question), and then `choose_factorisation`
    decides from the envelope and the pattern's size."""
    if _override[0] is not None:
        return _override[0]
    if n < 2 or envelope_flops(heights) <= SPARSE_WITHOUT_ANALYSIS_FLOPS:
        return "banded"
    dofs = [np.ascontiguousarray(d, dtype=np.int64) for d in element_dofs if np.size(d)]
    nnz = int(_cached_pattern(int(n), dofs)[1].shape[0])
    return choose_factorisation(int(n), heights, nnz)
