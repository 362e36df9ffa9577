"""Every energy kernel's gradient and Hessian against central finite differences."""

import numpy as np
import pytest

from snapmorph.solver import Structure
from snapmorph.solver.energies import bending_terms, curvature_terms, spring_terms, stretch_terms


def fd_gradient(fun, x, h=1e-7):
    g = np.zeros_like(x)
    for i in range(len(x)):
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        g[i] = (fun(xp) - fun(xm)) / (2 * h)
    return g


def fd_jacobian(fun, x, h=1e-7):
    cols = []
    for i in range(len(x)):
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        cols.append((fun(xp) - fun(xm)) / (2 * h))
    return np.stack(cols, axis=1)


def _kernel(kernel, n, *params):
    def energy(x):
        return kernel(x, *params, np.empty(n), np.empty((n, n)))

    def grad(x):
        g = np.empty(n)
        kernel(x, *params, g, np.empty((n, n)))
        return g

    def hess(x):
        h = np.empty((n, n))
        kernel(x, *params, np.empty(n), h)
        return h

    return energy, grad, hess


def _check(kernel, n, x, *params):
    energy, grad, hess = _kernel(kernel, n, *params)
    g = grad(x)
    scale_g = max(np.max(np.abs(g)), 1e-12)
    np.testing.assert_allclose(g, fd_gradient(energy, x), atol=2e-6 * scale_g + 1e-12)
    H = hess(x)
    np.testing.assert_allclose(H, H.T, atol=1e-12 * np.max(np.abs(H)))
    scale_h = max(np.max(np.abs(H)), 1e-12)
    np.testing.assert_allclose(H, fd_jacobian(grad, x), atol=2e-6 * scale_h)


@pytest.mark.parametrize("trial", range(20))
def test_stretch_gradient_and_hessian(rng, trial):
    x = rng.normal(size=4)
    rest = np.hypot(x[2] - x[0], x[3] - x[1]) * rng.uniform(0.7, 1.3)
    _check(stretch_terms, 4, x, rng.uniform(0.5, 5.0), rest)


@pytest.mark.parametrize("trial", range(30))
def test_bending_gradient_and_hessian_curved_states(rng, trial):
    # random three-node stencils, turning angles up to ~130 degrees, random rest curvature
    x0 = rng.normal(size=2)
    a = rng.uniform(-np.pi, np.pi)
    turn = rng.uniform(-2.3, 2.3)
    l0, l1 = rng.uniform(0.3, 2.0, size=2)
    x1 = x0 + l0 * np.array([np.cos(a), np.sin(a)])
    x2 = x1 + l1 * np.array([np.cos(a + turn), np.sin(a + turn)])
    x = np.concatenate([x0, x1, x2])
    _check(bending_terms, 6, x, rng.uniform(0.5, 3.0), rng.uniform(-1, 1))


def test_curvature_is_two_tan_half_turning_angle(rng):
    for _ in range(20):
        turn = rng.uniform(-2.5, 2.5)
        a = rng.uniform(-3, 3)
        x1 = np.array([0.3, -0.2])
        x0 = x1 - 0.7 * np.array([np.cos(a), np.sin(a)])
        x2 = x1 + 1.3 * np.array([np.cos(a + turn), np.sin(a + turn)])
        kappa = curvature_terms(np.concatenate([x0, x1, x2]), np.empty(6), np.empty((6, 6)))
        assert kappa == pytest.approx(2 * np.tan(turn / 2), rel=1e-12, abs=1e-14)


@pytest.mark.parametrize("trial", range(10))
def test_spring_gradient_and_hessian(rng, trial):
    _check(spring_terms, 4, rng.normal(size=4), rng.uniform(1, 100), *rng.normal(size=2))


def test_bending_energy_is_zero_and_stationary_at_rest(rng):
    x = rng.normal(size=6)
    kbar = curvature_terms(x, np.empty(6), np.empty((6, 6)))
    g = np.empty(6)
    assert bending_terms(x, 2.0, kbar, g, np.empty((6, 6))) == pytest.approx(0.0, abs=1e-14)
    np.testing.assert_allclose(g, 0.0, atol=1e-12)


def _curved_structure(rng):
    """Two curved rods, one with per-edge widths, bonded by a spring; a random deformation."""
    st = Structure()
    s = np.linspace(0, 1, 12)
    a = st.add_rod(np.stack([s, 0.2 * np.sin(3 * s)], 1), width=rng.uniform(0.01, 0.03, 11),
                   thickness=0.01, E=1e5)
    b = st.add_rod(np.stack([s, 0.3 + 0.1 * s**2], 1), width=0.02,
                   thickness=rng.uniform(0.005, 0.015, 11), E=2e5)
    st.tie(a.nodes[3], b.nodes[4], method="spring", stiffness=50.0)
    X = st.reference_positions
    return st, X + 0.03 * rng.normal(size=X.shape)


def test_structure_gradient_and_tangent_stiffness_against_fd(rng):
    st, pos = _curved_structure(rng)
    q = pos.reshape(-1)

    def energy(v):
        return st.energy(v.reshape(-1, 2))

    def grad(v):
        return st.gradient(v.reshape(-1, 2)).reshape(-1)

    g = grad(q)
    np.testing.assert_allclose(g, fd_gradient(energy, q, h=1e-6), atol=1e-5 * np.max(np.abs(g)))
    H = st.hessian(pos)
    np.testing.assert_allclose(H, fd_jacobian(grad, q, h=1e-7), atol=1e-5 * np.max(np.abs(H)))


def test_rigid_motion_costs_no_energy(rng):
    # rods, and a tie spring between coincident nodes (as the unit uses them), are
    # invariant under rigid motion
    st = Structure()
    s = np.linspace(0, 1, 12)
    a = st.add_rod(np.stack([s, 0.2 * np.sin(3 * s)], 1), width=0.02, thickness=0.01, E=1e5)
    b = st.add_rod(np.stack([s, 0.2 * np.sin(3 * s)], 1)[3:9], width=0.01, thickness=0.01, E=1e5)
    st.tie(a.nodes[4], b.nodes[1], method="spring", stiffness=50.0)
    X = st.reference_positions
    c, s = np.cos(0.7), np.sin(0.7)
    moved = X @ np.array([[c, s], [-s, c]]) + np.array([0.3, -1.2])
    assert st.energy(moved) == pytest.approx(0.0, abs=1e-12)


def test_gradient_only_assembly_is_the_full_assemblys_gradient(rng):
    """`assemble_gradient` (a converged state's energy and gradient without the stiffness)
    against the system's own assembly (`assemble_banded`) on a tied, actuated unit (exact
    ties and tie springs): the same energy and reduced and full gradients, bit for bit, and
    the band untouched."""
    from snapmorph.solver.assembly import assemble_banded, assemble_gradient
    from snapmorph.units import UnitGeometry
    from snapmorph.units.geometry import build_unit

    for tie in ("exact", "spring"):
        st = build_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), nodes=41,
                        tie=tie).structure
        s = st.reduced_system()
        q = st.initial_state() + 1e-4 * rng.normal(size=st.initial_state().shape)
        e_full = assemble_banded(q, s.elements, s.dofs, s.slots, s.dof_map, s.band, s.heights,
                                 s.grad, s.grad_full)
        g_full, gf_full = s.grad.copy(), s.grad_full.copy()
        band = s.band.copy()
        e = assemble_gradient(q, s.elements, s.dof_map, s.grad, s.grad_full)
        assert e == e_full
        assert np.array_equal(s.grad, g_full) and np.array_equal(s.grad_full, gf_full)
        assert np.array_equal(s.band, band)  # the stiffness is left as it was
