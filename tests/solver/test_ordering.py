"""DOF ordering for the banded LDL^T: the envelope cost it minimises, and its effect on the
3-D unit's frame (rings through the end regions)."""

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph

from snapmorph.solver.ordering import cuthill_mckee, envelope_cost, envelope_order


def _ring_with_spokes(n_ring=60, n_spokes=6):
    """A ring (a frame's rails and arch closing through its ends) with short spokes."""
    rows, cols = [], []
    for i in range(n_ring):
        rows.append(i)
        cols.append((i + 1) % n_ring)
    k = n_ring
    for s in range(n_spokes):
        rows.append(s * (n_ring // n_spokes))
        cols.append(k)
        k += 1
    g = scipy.sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(k, k))
    return (g + g.T).tocsr()


def _brute_cost(order, graph, sizes):
    """Flop estimate of the envelope factorisation from a dense reconstruction."""
    pos = np.empty(len(order), dtype=int)
    pos[order] = np.arange(len(order))
    start = np.concatenate([[0], np.cumsum(sizes[order])])
    n = start[-1]
    A = np.zeros((n, n), dtype=bool)
    g = graph.tocoo()
    for i, j in zip(g.row, g.col):
        A[start[pos[i]]:start[pos[i] + 1], start[pos[j]]:start[pos[j] + 1]] = True
    for i in range(len(order)):
        A[start[pos[i]]:start[pos[i] + 1], start[pos[i]]:start[pos[i] + 1]] = True
    first = np.array([np.flatnonzero(A[r, : r + 1])[0] for r in range(n)])
    h = np.array([max([r for r in range(n) if first[r] <= j]) - j for j in range(n)], float)
    return 0.5 * float(h @ h)


def test_envelope_cost_matches_a_dense_reconstruction():
    g = _ring_with_spokes(24, 4)
    sizes = np.where(np.arange(g.shape[0]) % 3 == 0, 3, 1).astype(np.int64)
    rng = np.random.default_rng(1)
    for _ in range(3):
        order = rng.permutation(g.shape[0])
        assert envelope_cost(order, g.indptr, g.indices.astype(np.int64), sizes) == \
            _brute_cost(order, g, sizes)


def test_envelope_order_beats_scipy_rcm_and_is_deterministic():
    g = _ring_with_spokes()
    sizes = np.full(g.shape[0], 3, dtype=np.int64)
    ind = g.indices.astype(np.int64)
    ours = envelope_order(g, sizes)
    assert sorted(ours.tolist()) == list(range(g.shape[0]))
    rcm = scipy.sparse.csgraph.reverse_cuthill_mckee(g, symmetric_mode=True)
    assert envelope_cost(ours, g.indptr, ind, sizes) <= envelope_cost(rcm, g.indptr, ind, sizes)
    assert np.array_equal(ours, envelope_order(g, sizes))


def test_cuthill_mckee_visits_every_component():
    g = scipy.sparse.csr_matrix(np.array([[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1],
                                          [0, 0, 1, 0]], dtype=float))
    order = cuthill_mckee(g.indptr, g.indices.astype(np.int64), np.diff(g.indptr), 2, 4)
    assert order.tolist() == [2, 3, 0, 1]


def test_the_3d_unit_factorises_a_small_envelope():
    """The frame unit's ordering: the factorisation's work (column heights to the last row
    reaching them, fill included) is a small part of the band's n bw^2 / 2 (measured 0.6 M
    against 3.2 M at 41 nodes; scipy's RCM order gave 3.1 M in a band of 192). Measured on
    the mesh before issue 25 (bonds, uniform); on the default since then (node joints, feet
    8 x finer, 827 DOFs) it is 0.98 M against 3.5 M, 0.28 of the band."""
    from snapmorph.units.frame3d import UnitGeometry
    from snapmorph.units.unit3d import build_unit_3d

    st = build_unit_3d(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), joints="bond",
                       foot_refinement=1).structure
    sysm = st.reduced_system()
    sysm.evaluate(st.initial_state())
    band = sysm.band
    n, bw = band.shape[1], band.shape[0] - 1
    first = np.arange(n)
    for k in range(1, bw + 1):
        nz = np.flatnonzero(band[k, : n - k] != 0)
        first[nz + k] = np.minimum(first[nz + k], nz)
    reach = np.full(n, -1)
    np.maximum.at(reach, first, np.arange(n))
    h = (np.maximum.accumulate(reach) - np.arange(n)).astype(float)
    assert 0.5 * float(h @ h) < 0.25 * 0.5 * n * bw * bw
    assert bw < 120


def test_cached_layout_follows_the_structure():
    """Node counts, supernodes, reference positions and the systems' element layout are kept
    between calls; they follow every rod, tie or support added afterwards."""
    import numpy as np

    from snapmorph.solver.structure import Structure

    st = Structure()
    st.add_rod(np.stack([np.linspace(0, 1, 5), np.zeros(5)], 1), E=1e9, width=0.01,
               thickness=0.001)
    st.fix(0, "xz")
    a = st.reduced_system()
    assert st.n_nodes == 5 and st.reference_positions.shape == (5, 2)
    assert not st.reference_positions.flags.writeable and not st.supernodes().flags.writeable
    b = st.reduced_system()
    assert b.dofs[0] is a.dofs[0] and b.heights is a.heights  # the layout reused
    st.add_rod(np.stack([np.linspace(0, 1, 3), np.full(3, 0.1)], 1), E=1e9, width=0.01,
               thickness=0.001)
    assert st.n_nodes == 8 and st.reference_positions.shape == (8, 2)
    st.tie(4, 7)
    rep = st.supernodes()
    assert rep[4] == rep[7] and len(rep) == 8
    c = st.reduced_system()
    assert c.n == 2 * 8 - 2 - 2 and c.dofs[0] is not a.dofs[0]


def test_structure_copies_share_elements_not_constraints():
    """`Structure.copy`: the variants of one mesh share its element arrays and orderings
    (keyed on the constraints: a copy with other supports or ties gets its own DOF map),
    while supports, ties, rigid groups and rods added to one leave the other as it was;
    each copy's systems are the ones a fresh structure with the same constraints builds."""
    from snapmorph.solver import Structure

    def rods():
        st = Structure()
        x = np.linspace(0.0, 0.1, 21)
        a = st.add_rod(np.stack([x, 0.01 * np.sin(np.pi * x / 0.1)], 1), 5e-3, 5e-4, 2.2e9)
        b = st.add_rod(np.stack([x, np.zeros_like(x)], 1), 1e-2, 5e-4, 2.2e9)
        for k in (0, 1, 19, 20):
            st.tie(int(a.nodes[k]), int(b.nodes[k]))
        return st, a, b

    bare, a, b = rods()
    bare.elements()
    rigged = bare.copy()
    rigged.fix(int(b.nodes[1]), "z")
    rigged.fix(int(b.nodes[19]), "z")
    rigged.rigid([int(n) for n in a.nodes[9:12]])
    rigged.fix(int(a.nodes[10]), "x")
    free = bare.copy()
    free.fix(int(b.nodes[10]), "xz")
    free.fix(int(b.nodes[0]), "z")
    assert bare._fixed == {} and len(bare._merges) == 4 and bare._rigid_groups == []
    assert rigged.elements() is bare.elements() and free.elements() is bare.elements()
    for copy_, steps in ((rigged, (("fix", (int(b.nodes[1]), "z")), ("fix", (int(b.nodes[19]), "z")),
                                   ("rigid", ([int(n) for n in a.nodes[9:12]],)),
                                   ("fix", (int(a.nodes[10]), "x")))),
                         (free, (("fix", (int(b.nodes[10]), "xz")), ("fix", (int(b.nodes[0]), "z"))))):
        fresh, _, _ = rods()
        for name, args in steps:
            getattr(fresh, name)(*args)
        for extra in (None, [(int(a.nodes[10]), 1)]):
            got, want = copy_.reduced_system(extra), fresh.reduced_system(extra)
            assert np.array_equal(got.dof_map, want.dof_map) and got.n == want.n
    assert rigged.reduced_system().n != free.reduced_system().n
    more = free.copy()
    more.add_rod(np.array([[0.0, 0.02], [0.05, 0.03], [0.1, 0.02]]), 5e-3, 5e-4, 2.2e9)
    assert free.n_nodes == 42 and more.n_nodes == 45 and len(free.rods) == 2


def _old_supernodes(n, pairs):
    """The supernodes as `UnionFind` gave them (the code before `group_minima`)."""
    from snapmorph.solver.constraints import UnionFind

    uf = UnionFind(n)
    for a, b in pairs:
        uf.union(int(a), int(b))
    return np.array([uf.find(i) for i in range(n)], dtype=np.int64)


def _old_numbering(rep, fixed, order_of):
    """group, dof_map and n_reduced as `Structure._build_ordering` numbered them in numpy
    (before `node_groups` and `number_dofs`)."""
    uniq, group = np.unique(rep, return_inverse=True)
    n_groups = len(uniq)
    order = order_of(n_groups)
    group_fixed = np.zeros((n_groups, 2), dtype=bool)
    group_fixed[group] = fixed
    free = ~group_fixed[order]
    group_dof = np.empty((n_groups, 2), dtype=np.int64)
    group_dof[order] = np.where(free, np.cumsum(free.ravel()).reshape(-1, 2) - 1, -1)
    return group, order, group_dof[group].reshape(-1), int(free.sum())


def test_compiled_ordering_bookkeeping_matches_the_numpy_code():
    """Supernodes (`group_minima`), node groups, the DOF numbering and the element DOFs by
    compiled loops: the same arrays as the Python/numpy code they replace, on 300 random
    tie sets, supports and element tables."""
    from snapmorph.solver.assembly import element_dofs
    from snapmorph.solver.constraints import group_minima
    from snapmorph.solver.structure import node_groups, number_dofs

    rng = np.random.default_rng(5)
    for trial in range(300):
        n = int(rng.integers(1, 60))
        pairs = rng.integers(0, n, size=(int(rng.integers(0, 2 * n)), 2))
        rep = group_minima(n, pairs.astype(np.int64))
        assert np.array_equal(rep, _old_supernodes(n, pairs))
        # the held components are the same for every node of a group (fixed_components)
        held = rng.random((n, 2)) < 0.2
        fixed = held[rep]
        perm = rng.permutation(n)
        group, order, want, k_want = _old_numbering(rep, fixed, lambda m: perm[perm < m])
        got_group, n_groups = node_groups(rep)
        assert np.array_equal(got_group, group) and n_groups == len(order)
        dof_map, k = number_dofs(got_group, fixed, order)
        assert np.array_equal(dof_map, want) and k == k_want
        conns = [rng.integers(0, n, size=(int(rng.integers(0, 30)), m)) for m in (2, 3, 2)]
        elements = (conns[0], None, conns[1], None, conns[2], None)
        for got, conn in zip(element_dofs(elements, dof_map), conns):
            full = (2 * conn[:, :, None] + np.arange(2)[None, None, :]).reshape(
                conn.shape[0], 2 * conn.shape[1])
            assert got.dtype == np.int64 and np.array_equal(got, dof_map[full])


def test_supernodes_follow_ties_clamps_and_copies():
    """The supernodes memo is rebuilt when a tie, rigid group or sliding clamp is added, and
    a copy's ties do not reach its original (a copy starts without the memo)."""
    from snapmorph.solver.structure import Structure

    st = Structure()
    x = np.linspace(0.0, 0.1, 6)
    st.add_rod(np.stack([x, np.zeros(6)], 1), 5e-3, 5e-4, 2.2e9)
    st.add_rod(np.stack([x, np.full(6, 0.01)], 1), 5e-3, 5e-4, 2.2e9)
    assert np.array_equal(st.supernodes(), np.arange(12))
    other = st.copy()
    st.tie(0, 6)
    assert st.supernodes()[6] == 0 and other.supernodes()[6] == 6
    other.rigid([11, 3, 7])
    assert list(other.supernodes()[[3, 7, 11]]) == [3, 3, 3] and st.supernodes()[11] == 11
    st.clamp(5, toward=4, hold_position=False)  # a sliding clamp's ghost moves with its node
    rep = st.supernodes()
    assert len(rep) == 13 and rep[12] == 5
    assert np.array_equal(rep[:12], _old_supernodes(12, [(0, 6)]))
    sysm = st.reduced_system()
    assert sysm.n == 2 * (13 - 2)


def test_a_new_orderings_layout_is_what_the_separate_kernels_give():
    """`Structure._build_ordering` computes the element DOFs, bandwidth, envelope heights,
    band slots and representatives of a new ordering in one compiled call: the arrays of
    `element_dofs`, `bandwidth`, `envelope_heights`, `band_slots` and the numpy
    representatives, on unit meshes with and without an extra held DOF and springs; and
    `envelope_flops` of int heights is the float computation's."""
    from snapmorph.solver.assembly import band_slots, element_dofs
    from snapmorph.solver.banded import envelope_heights
    from snapmorph.solver.constraints import bandwidth
    from snapmorph.solver.sparse import envelope_flops
    from snapmorph.units import UnitGeometry
    from snapmorph.units.geometry import build_unit

    for g, nodes, tie in ((UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), 101, "exact"),
                          (UnitGeometry(L=0.1, h=0.04, t=0.375e-3, w=5e-3, b=0), 41, "spring")):
        model = build_unit(g, nodes=nodes, tie=tie)
        for st in (model.structure, model.variant(actuator=False, supports=False).structure):
            st.fix(int(model.base_nodes[0]), "xz")
            for extra in (None, [(model.apex, 1)], [(model.apex, 0), (model.apex, 1)]):
                (dof_map, k, bw), (dofs, heights, slots, rep) = \
                    st._build_ordering(extra, st.elements())
                want = element_dofs(st.elements(), dof_map)
                assert all(np.array_equal(a, b) for a, b in zip(dofs, want))
                assert bw == bandwidth(*want)
                assert np.array_equal(heights, envelope_heights(max(k, 1), *want))
                assert all(np.array_equal(a, b) for a, b in zip(slots, band_slots(want, bw + 1)))
                free = np.flatnonzero(dof_map >= 0)
                old = np.empty(k, dtype=np.int64)
                old[dof_map[free]] = free
                assert np.array_equal(rep, old)
                assert envelope_flops(heights) == 0.5 * float(np.dot(heights.astype(float),
                                                                     heights.astype(float)))
                assert not any(a.flags.writeable for a in (dof_map, *dofs, heights, *slots, rep))


def test_orderings_are_shared_across_structures_of_one_graph_and_supports():
    """Two units meshed alike (another thickness and modulus: the same graph and supports)
    share one DOF ordering and layout (remembered by their inputs' bytes), equal to what a
    fresh ordering gives; other held components get their own."""
    from snapmorph.solver import structure as structure_module
    from snapmorph.units import UnitGeometry
    from snapmorph.units.geometry import build_unit

    a = build_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), nodes=61).structure
    b = build_unit(UnitGeometry(L=0.1, h=0.02, t=0.6e-3, w=5e-3, b=5e-3, E=3e9), nodes=61).structure
    sa, sb = a.reduced_system(), b.reduced_system()
    assert np.shares_memory(sb.dof_map, sa.dof_map)
    assert sb.heights is sa.heights and sb.slots[1] is sa.slots[1] and sb.dofs[0] is sa.dofs[0]
    held = a.reduced_system(extra_fixed=[(5, 0)])
    assert not np.shares_memory(held.dof_map, sa.dof_map) and held.n == sa.n - 1
    # what a fresh computation (no memory) gives, array for array
    structure_module._LAYOUT_MEMO.clear()
    fresh = b.copy()
    fresh._orderings = None
    sf = fresh.reduced_system()
    assert not np.shares_memory(sf.dof_map, sb.dof_map)
    for x, y in ((sf.dof_map, sb.dof_map), (sf.heights, sb.heights), *zip(sf.dofs, sb.dofs),
                 *zip(sf.slots, sb.slots), (sf.representative, sb.representative)):
        np.testing.assert_array_equal(x, y)
    assert not sa.dof_map.flags.writeable
