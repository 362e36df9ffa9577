"""DOF orderings for the banded LDL^T of `solver.banded`: reverse Cuthill–McKee started where
the envelope comes out smallest.

The factorisation costs what the envelope of K holds (each column up to its last nonzero),
so the order is chosen by that cost, not by the bandwidth. A frame of rods is a graph with
rings (rails and arch closing through the end regions); there the start node decides how many
fronts the Cuthill–McKee levels sweep at once, and scipy's choice (a node of least degree) can
cost several times the best one. Pseudo-peripheral nodes (the furthest from the furthest node)
are the natural candidates; each is tried and the cheapest order kept. Deterministic: ties go to the lowest
node index.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph
from numba import njit

from snapmorph.solver.banded import profile_heights

#: at most this many peripheral start nodes are tried (spread over the candidates)
MAX_STARTS = 8


@njit(cache=True)
def cuthill_mckee(indptr, indices, degree, start, n):
    """Cuthill–McKee order of the connected component of ``start`` (neighbours by increasing
    degree, then index: ``indices`` sorted within each row), followed by the other
    components from their lowest node."""
    seen = np.zeros(n, dtype=np.bool_)
    order = np.empty(n, dtype=np.int64)
    count = 0
    for r in range(-1, n):
        root = start if r < 0 else r
        if seen[root]:
            continue
        seen[root] = True
        level = count
        order[count] = root
        count += 1
        while level < count:
            v = order[level]
            level += 1
            lo = indptr[v]
            m = 0
            nb = np.empty(indptr[v + 1] - lo, dtype=np.int64)
            for k in range(lo, indptr[v + 1]):
                u = indices[k]
                if not seen[u]:
                    nb[m] = u
                    m += 1
            if m:
                nb = nb[:m]
                # stable: equal degrees keep the row's increasing index order
                nb = nb[np.argsort(degree[nb], kind="mergesort")]
                for u in nb:
                    seen[u] = True
                    order[count] = u
                    count += 1
    return order


def envelope_cost(order, indptr, indices, sizes):
    """Flop estimate of the banded LDL^T in the order ``order`` of the groups: sum over
    columns of their height (to the last row whose envelope reaches them) squared, over 2.

    ``sizes``: DOFs of each group (they stay together in the order)."""
    n = len(order)
    pos = np.empty(n, dtype=np.int64)
    pos[order] = np.arange(n)
    start = np.concatenate([[0], np.cumsum(sizes[order])])
    # first DOF reached by each group's row: its own start or its earliest neighbour's
    first_pos = pos.copy()
    counts = np.diff(indptr)
    has = counts > 0
    if has.any():
        nb_pos = pos[indices]
        mins = np.minimum.reduceat(nb_pos, indptr[:-1][has])
        first_pos[has] = np.minimum(first_pos[has], mins)
    first = start[first_pos]
    # every DOF of a group shares the group's first column
    h = profile_heights(np.repeat(first[order], sizes[order])).astype(float)
    return float(0.5 * np.dot(h, h))


def _levels(g, source):
    """(n,) BFS distance of every node from ``source`` (-1: another component)."""
    d = scipy.sparse.csgraph.shortest_path(g, unweighted=True, directed=False,
                                           indices=[int(source)])[0]
    d[~np.isfinite(d)] = -1.0
    return d


def _peripheral_nodes(g):
    """Pseudo-peripheral start nodes: the node furthest from node 0, and every node furthest
    from it (two breadth-first searches, O(edges); on the 3-D unit the same best start as
    all 28 nodes of largest eccentricity, whose all-pairs distances cost n^2 memory)."""
    d0 = _levels(g, 0)
    a = int(np.argmax(d0))
    da = _levels(g, a)
    return np.concatenate([[a], np.flatnonzero(da == da.max())])


def envelope_order(graph, sizes):
    """Order of the groups (nodes of ``graph``, a symmetric scipy sparse adjacency) whose
    banded LDL^T is cheapest among reverse Cuthill–McKee orders started at peripheral nodes.

    ``sizes`` (n_groups,) int: DOFs per group. Returns the group order (int64)."""
    g = scipy.sparse.csr_matrix(graph)
    g = ((g + g.T) != 0).astype(np.int8).tocsr()
    g.setdiag(0)
    g.eliminate_zeros()
    g.sort_indices()
    n = g.shape[0]
    sizes = np.asarray(sizes, dtype=np.int64)
    if n <= 2:
        return np.arange(n, dtype=np.int64)
    indptr, indices = g.indptr, g.indices.astype(np.int64)
    indptr = indptr.astype(np.int64)
    degree = np.diff(indptr)
    candidates = _peripheral_nodes(g)
    if len(candidates) > MAX_STARTS:
        candidates = candidates[np.linspace(0, len(candidates) - 1, MAX_STARTS).astype(int)]
    best, best_cost = None, np.inf
    for s in candidates:
        order = cuthill_mckee(indptr, indices, degree, int(s), n)[::-1]
        c = envelope_cost(order, indptr, indices, sizes)
        if c < best_cost:
            best, best_cost = order, c
    return np.ascontiguousarray(best)
