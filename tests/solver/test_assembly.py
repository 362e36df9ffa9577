"""The planar assembly (`solver.assembly`) against a plain dense reference: K_red = W^T K W,
the reduced and the full gradient and the energy, element by element in numpy, with the
bending terms from the quotient rule on kappa = 2 f / g (the formula the kernels replaced
by the turning angle's derivatives). Units with tied nodes, a rigid actuator group and tie
springs, at random states."""

import numpy as np
import pytest

from snapmorph.solver.assembly import assemble_banded, assemble_system, stiff_second_difference
from snapmorph.solver.banded import band_to_dense
from snapmorph.solver.energies import bending_lower, bending_terms, curvature_terms
from snapmorph.units import UnitGeometry
from snapmorph.units.geometry import build_unit

G = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)


def _curvature_quotient_rule(x):
    """(kappa, dkappa (6,), d2kappa (6, 6)) of kappa = 2 f / g, f = e0 x e1,
    g = |e0||e1| + e0 . e1, differentiated in the edge vectors by the quotient rule."""
    e = np.array([x[2] - x[0], x[3] - x[1], x[4] - x[2], x[5] - x[3]])
    a0, b0, a1, b1 = e
    n0, n1 = np.hypot(a0, b0), np.hypot(a1, b1)
    t0, t1 = e[:2] / n0, e[2:] / n1
    f = a0 * b1 - b0 * a1
    g = n0 * n1 + a0 * a1 + b0 * b1
    fe = np.array([b1, -a1, -b0, a0])
    ge = np.concatenate([n1 * t0 + e[2:], n0 * t1 + e[:2]])
    fee = np.zeros((4, 4))
    fee[0, 3] = fee[3, 0] = 1.0
    fee[1, 2] = fee[2, 1] = -1.0
    gee = np.zeros((4, 4))
    gee[:2, :2] = n1 / n0 * (np.eye(2) - np.outer(t0, t0))
    gee[2:, 2:] = n0 / n1 * (np.eye(2) - np.outer(t1, t1))
    gee[:2, 2:] = np.outer(t0, t1) + np.eye(2)
    gee[2:, :2] = gee[:2, 2:].T
    ke = 2.0 * (fe - f * ge / g) / g
    kee = 2.0 / g * (fee - (np.outer(fe, ge) + np.outer(ge, fe)) / g - f * gee / g
                     + 2.0 * f * np.outer(ge, ge) / g ** 2)
    J = np.zeros((4, 6))  # e = J x
    J[:2, 0:2], J[:2, 2:4] = -np.eye(2), np.eye(2)
    J[2:, 2:4], J[2:, 4:6] = -np.eye(2), np.eye(2)
    return 2.0 * f / g, J.T @ ke, J.T @ kee @ J


def _element_terms(kind, x, p):
    """(E, gradient, Hessian) of one element in numpy."""
    if kind == "stretch":
        e = x[2:] - x[:2]
        length = np.linalg.norm(e)
        k, t = p[0] / p[1], e / length
        he = k * np.outer(t, t) + k * (length - p[1]) / length * (np.eye(2) - np.outer(t, t))
        ge = k * (length - p[1]) * t
        return (0.5 * k * (length - p[1]) ** 2, np.concatenate([-ge, ge]),
                np.block([[he, -he], [-he, he]]))
    if kind == "bend":
        kappa, dk, d2k = _curvature_quotient_rule(x)
        dev = kappa - p[1]
        return 0.5 * p[0] * dev ** 2, p[0] * dev * dk, p[0] * (dev * d2k + np.outer(dk, dk))
    d = x[:2] - x[2:] - p[1:3]
    return (0.5 * p[0] * d @ d, p[0] * np.concatenate([d, -d]),
            p[0] * np.block([[np.eye(2), -np.eye(2)], [-np.eye(2), np.eye(2)]]))


def _reference(system, q):
    """(E, K_red dense, reduced gradient, full gradient) of the system's elements at q."""
    st_n, st_p, b_n, b_p, sp_n, sp_p = system.elements
    nf = system.dof_map.shape[0]
    K, grad, energy = np.zeros((nf, nf)), np.zeros(nf), 0.0
    for kind, conn, params in (("stretch", st_n, st_p), ("bend", b_n, b_p), ("spring", sp_n, sp_p)):
        for nodes, p in zip(conn, params):
            full = (2 * nodes[:, None] + np.arange(2)).ravel()
            e, g, h = _element_terms(kind, q[full], p)
            energy += e
            grad[full] += g
            K[np.ix_(full, full)] += h
    W = np.zeros((nf, system.n))
    free = system.dof_map >= 0
    W[np.flatnonzero(free), system.dof_map[free]] = 1.0
    return energy, W.T @ K @ W, W.T @ grad, grad


def _random_state(system, rng):
    """A state near the stress-free one: the rods bent, stretched and jiggled."""
    q = system.reference.copy()
    q[1::2] *= rng.uniform(0.5, 1.0)
    q[0::2] *= rng.uniform(0.98, 1.02)
    return q + rng.normal(size=q.shape) * 2e-4


def _system(tie):
    model = build_unit(G, nodes=21, tie=tie)
    system = model.structure.reduced_system(normalized=True)
    X = model.structure.reference_positions.ravel()
    # ghost nodes of clamps (if any) at their stress-free places: the reference's own
    ref = np.zeros(system.dof_map.shape[0])
    ref[: X.size] = X
    system.reference = ref
    return system


@pytest.mark.parametrize("tie", ["exact", "spring"])
def test_banded_assembly_is_the_dense_reference(tie):
    rng = np.random.default_rng(3)
    system = _system(tie)
    slots = system.slots
    # the units have pairs of coordinates sharing one reduced DOF (rigid actuator group)
    assert any(np.any((s >= 0) & (s & 1 == 1)) for s in slots)
    for _ in range(5):
        q = _random_state(system, rng)
        energy, K, grad, grad_full = _reference(system, q)
        e = system.evaluate(q)
        scale = np.max(np.abs(K))
        assert abs(e - energy) <= 1e-13 * abs(energy)
        np.testing.assert_allclose(band_to_dense(system.band)[: system.n, : system.n], K,
                                   rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(system.grad[: system.n], grad,
                                   rtol=0, atol=1e-13 * np.max(np.abs(grad)))
        np.testing.assert_allclose(system.grad_full, grad_full,
                                   rtol=0, atol=1e-13 * np.max(np.abs(grad_full)))
        # the general assembler (any band) agrees with the system's
        band, g, gf = np.zeros(system.band.shape), np.zeros(system.n), np.zeros_like(grad_full)
        e2 = assemble_system(q, system.elements, system.dofs, band, g, gf)
        assert abs(e2 - e) <= 1e-14 * abs(e)
        np.testing.assert_allclose(band, system.band, rtol=0, atol=1e-14 * scale)
        np.testing.assert_allclose(g, system.grad, rtol=0, atol=1e-14 * np.max(np.abs(grad)))


def test_assembly_after_a_factorisation_clears_what_it_must():
    """The system's assembly clears the factor's envelope only: a band assembled over a
    factorised one is the band assembled afresh, and the rest of the band stays zero."""
    rng = np.random.default_rng(4)
    system = _system("exact")
    q = _random_state(system, rng)
    system.evaluate(q)
    fresh = system.band.copy()
    system.factor()
    system.evaluate(q)
    np.testing.assert_array_equal(system.band, fresh)
    outside = np.arange(system.band.shape[0])[:, None] > system.heights[None, :]
    assert not np.any(system.band[outside])


@pytest.mark.parametrize("trial", range(10))
def test_bending_kernels_are_the_quotient_rule(rng, trial):
    """The turning-angle form of the curvature's derivatives is the quotient rule's, to
    round-off, from nearly straight to sharply turned stencils."""
    x0 = rng.normal(size=2)
    a = rng.uniform(-np.pi, np.pi)
    turn = (rng.uniform(-2.8, 2.8), 1e-6 * rng.normal(), 0.0)[trial % 3]
    l0, l1 = 10.0 ** rng.uniform(-3, 0, size=2)
    x1 = x0 + l0 * np.array([np.cos(a), np.sin(a)])
    x2 = x1 + l1 * np.array([np.cos(a + turn), np.sin(a + turn)])
    x = np.concatenate([x0, x1, x2])
    kappa, dk, d2k = _curvature_quotient_rule(x)
    g, h = np.empty(6), np.empty((6, 6))
    assert abs(curvature_terms(x, g, h) - kappa) <= 1e-14 * max(abs(kappa), 1e-300)
    np.testing.assert_allclose(g, dk, rtol=0, atol=1e-13 * np.max(np.abs(dk)))
    np.testing.assert_allclose(h, d2k, rtol=0, atol=1e-13 * np.max(np.abs(d2k)))
    S, kb = rng.uniform(0.5, 3.0), rng.uniform(-1.0, 1.0)
    e = bending_terms(x, S, kb, g, h)
    ref = _element_terms("bend", x, (S, kb))
    assert abs(e - ref[0]) <= 1e-13 * ref[0]
    np.testing.assert_allclose(g, ref[1], rtol=0, atol=1e-13 * np.max(np.abs(ref[1])))
    np.testing.assert_allclose(h, ref[2], rtol=0, atol=1e-13 * np.max(np.abs(ref[2])))
    # the packed lower triangle the assembler scatters
    g2, hl = np.empty(6), np.empty(21)
    assert bending_lower(x, S, kb, g2, hl) == e
    np.testing.assert_array_equal(hl, h[np.tril_indices(6)])
    np.testing.assert_array_equal(g2, g)


def test_stiff_second_difference_of_a_tied_unit():
    """The stiff terms' second difference (gradients only) against the dense reference's
    stretching and spring gradients, on a unit with springs and a rigid group."""
    rng = np.random.default_rng(5)
    system = _system("spring")
    q = _random_state(system, rng)
    du = rng.normal(size=system.n) * 1e-4
    plus, minus = q.copy(), q.copy()
    system.increment(plus, du)
    system.increment(minus, du, -1.0)
    stiff = list(system.elements)
    stiff[2] = stiff[2][:0]  # no bending
    system_elements = tuple(stiff)

    def reduced_stiff_gradient(state):
        W_grad = np.zeros(system.n)
        nf = system.dof_map.shape[0]
        grad = np.zeros(nf)
        for kind, conn, params in (("stretch", system_elements[0], system_elements[1]),
                                   ("spring", system_elements[4], system_elements[5])):
            for nodes, p in zip(conn, params):
                full = (2 * nodes[:, None] + np.arange(2)).ravel()
                grad[full] += _element_terms(kind, state[full], p)[1]
        free = system.dof_map >= 0
        np.add.at(W_grad, system.dof_map[free], grad[free])
        return W_grad

    want = (reduced_stiff_gradient(plus) + reduced_stiff_gradient(minus)
            - 2.0 * reduced_stiff_gradient(q))
    out = np.empty(system.n)
    stiff_second_difference(q, plus, minus, system.elements, system.dofs, out)
    scale = np.max(np.abs(reduced_stiff_gradient(q)))
    np.testing.assert_allclose(out, want, rtol=0, atol=1e-13 * scale)


def test_a_non_finite_factorisation_leaves_no_trace():
    """A factor of a band with a NaN (a degenerate state) may write outside the envelope
    (a short column's fixed window, `solver.banded._eliminate`): the next assembly clears
    it all."""
    from snapmorph.solver.banded import _MEDIUM, _SHORT

    rng = np.random.default_rng(6)
    system = _system("exact")
    q = _random_state(system, rng)
    system.evaluate(q)
    fresh = system.band.copy()
    h, n, bw = system.heights, system.n, system.band.shape[0] - 1
    # an entry whose step reaches below the envelope of the column it updates
    hits = [(i, j) for j in range(n) for w in (_SHORT, _MEDIUM)
            if h[j] <= w <= bw and j + w < n and (w == _SHORT or h[j] > _SHORT)
            for i in range(1, h[j] + 1) if h[j + i] < w - i]
    assert hits
    system.band[hits[0]] = np.nan
    system.factor()
    assert np.isnan(system.band[h[hits[0][1] + hits[0][0]] + 1:, hits[0][1] + hits[0][0]]).any()
    system.evaluate(q)
    np.testing.assert_array_equal(system.band, fresh)


@pytest.mark.parametrize("tie", ["exact", "spring"])
def test_banded_assembly_is_the_element_by_element_one_bit_for_bit(tie):
    """`assemble_banded` (each kind in two passes, edges shared by consecutive bending
    stencils, scalars straight to the slots) against `assemble_system` (one element at a
    time through the packed-lower kernels): the same energy, band and full gradient, bit
    for bit, on units with tied nodes, a rigid group and tie springs; the reduced gradient
    to round-off (summed per reduced DOF in another order where DOFs are tied). Also a
    stencil order that shares no edge."""
    rng = np.random.default_rng(8)
    system = _system(tie)
    for trial in range(6):
        q = _random_state(system, rng)
        elements, dofs, slots = system.elements, system.dofs, system.slots
        if trial % 2:  # the bending stencils in another order: no edge to share
            order = rng.permutation(elements[2].shape[0])
            elements = elements[:2] + (np.ascontiguousarray(elements[2][order]),
                                       np.ascontiguousarray(elements[3][order])) + elements[4:]
            dofs = (dofs[0], np.ascontiguousarray(dofs[1][order]), dofs[2])
            slots = (slots[0], np.ascontiguousarray(slots[1][order]), slots[2])
        band = np.zeros(system.band.shape, order="F")
        g, gf = np.zeros(system.n), np.zeros_like(system.grad_full)
        e = assemble_banded(q, elements, dofs, slots, system.dof_map, band, system.heights,
                            g, gf)
        band2 = np.zeros(system.band.shape, order="F")
        g2, gf2 = np.zeros(system.n), np.zeros_like(system.grad_full)
        e2 = assemble_system(q, elements, dofs, band2, g2, gf2)
        assert e == e2
        np.testing.assert_array_equal(band, band2)
        np.testing.assert_array_equal(gf, gf2)
        np.testing.assert_allclose(g, g2, rtol=0, atol=1e-15 * np.max(np.abs(g2)))
