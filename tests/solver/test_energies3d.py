"""Finite-difference checks of every 3-D rod kernel (`solver.energies3d`, `solver.frames3d`).

Gradients against central differences of the value, Hessians against central differences
of the gradient; states are random and away from the kernels' source frames (the frames are
exact functions of the state between accepted states, so the checks hold anywhere).
"""

import numpy as np
import pytest

from snapmorph.solver.energies3d import (
    bending_terms,
    chain_pair,
    material_curvature,
    pair_edge_scratch,
    pair_frames,
    pair_terms_edges,
    stretch_terms,
    tip_moment_terms,
    twist_angle,
    twist_terms,
)
from snapmorph.solver.frames3d import (
    material_directors,
    material_frame_jet,
    parallel_transport,
    reference_twist,
    space_parallel_frames,
)


def _unit(v):
    return v / np.linalg.norm(v)


def fd_check(fun, x, h, rtol, atol_rel=1e-9):
    """fun(x) -> (value, grad, hess). Checks grad and hess against central differences."""
    v, g, H = fun(x)
    n = x.size
    g_fd = np.empty(n)
    H_fd = np.empty((n, n))
    for i in range(n):
        xp = x.copy()
        xm = x.copy()
        xp[i] += h
        xm[i] -= h
        vp, gp, _ = fun(xp)
        vm, gm, _ = fun(xm)
        g_fd[i] = (vp - vm) / (2 * h)
        H_fd[:, i] = (gp - gm) / (2 * h)
    gs = np.max(np.abs(g)) + 1e-300
    Hs = np.max(np.abs(H)) + 1e-300
    np.testing.assert_allclose(g, g_fd, rtol=rtol, atol=rtol * gs + atol_rel)
    np.testing.assert_allclose(H, H_fd, rtol=rtol, atol=rtol * Hs + atol_rel)
    np.testing.assert_allclose(H, H.T, atol=1e-12 * Hs)
    return g, H


def test_stretch_fd(rng):
    x = rng.normal(size=6) * 1e-2
    EA, rest = 3.0e3, 0.8 * np.linalg.norm(x[3:] - x[:3])

    def fun(y):
        g = np.empty(6)
        H = np.empty((6, 6))
        return stretch_terms(y, EA, rest, g, H), g, H

    fd_check(fun, x, 1e-7, 1e-6)
    # value: 1/2 EA / rest (|e| - rest)^2
    e = np.linalg.norm(x[3:] - x[:3])
    assert fun(x)[0] == pytest.approx(0.5 * EA / rest * (e - rest) ** 2, rel=1e-13)


def _random_source(rng, e):
    """A source tangent 0.4 rad or so away from e and a director normal to it."""
    t_src = _unit(_unit(e) + 0.4 * rng.normal(size=3))
    d = rng.normal(size=3)
    d_src = _unit(d - d @ t_src * t_src)
    return t_src, d_src


@pytest.mark.parametrize("component", range(9))
def test_material_frame_jet_fd(rng, component):
    e = rng.normal(size=3) * 1e-2
    t_src, d_src = _random_source(rng, e)
    p0 = np.append(e, 0.7)

    def fun(p):
        val = np.empty(9)
        jac = np.empty((9, 4))
        hess = np.empty((9, 4, 4))
        material_frame_jet(p[:3], p[3], t_src, d_src, val, jac, hess)
        return val[component], jac[component].copy(), hess[component].copy()

    fd_check(fun, p0, 1e-7 * np.linalg.norm(e), 2e-6)


def test_material_frame_is_orthonormal_and_transports(rng):
    e = rng.normal(size=3)
    t_src, d_src = _random_source(rng, e)
    val = np.empty(9)
    material_frame_jet(e, 0.0, t_src, d_src, val, np.empty((9, 4)), np.empty((9, 4, 4)))
    t, m1, m2 = val[:3], val[3:6], val[6:]
    F = np.stack([t, m1, m2])
    np.testing.assert_allclose(F @ F.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(F) == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(t, _unit(e), atol=1e-15)
    np.testing.assert_allclose(m1, parallel_transport(d_src, t_src, _unit(e)), atol=1e-15)
    np.testing.assert_allclose(m2, np.cross(t, m1), atol=1e-15)



def test_material_frame_at_a_twist_is_the_rotated_transported_director(rng):
    """At any twist angle the jet's frame is the transported director turned by theta about
    the tangent: m1 = cos(theta) d + sin(theta) t x d, m2 = t x m1."""
    for theta in (0.3, -2.5, 4.0):
        e = rng.normal(size=3) * 1e-2
        t_src, d_src = _random_source(rng, e)
        val = np.empty(9)
        material_frame_jet(e, theta, t_src, d_src, val, np.empty((9, 4)), np.empty((9, 4, 4)))
        t = _unit(e)
        d = parallel_transport(d_src, t_src, t)
        m1, m2 = material_directors(d[None], t[None], np.array([theta]))
        np.testing.assert_allclose(val[3:6], m1[0], atol=1e-15)
        np.testing.assert_allclose(val[6:], m2[0], atol=1e-15)

def _random_pair(rng):
    z = np.empty(18)
    for s in range(2):
        F, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        if np.linalg.det(F) < 0:
            F[:, 2] *= -1
        z[9 * s: 9 * s + 9] = F.T.reshape(-1)
    return z


@pytest.mark.parametrize("which", [1, 2])
def test_material_curvature_fd(rng, which):
    z = _random_pair(rng)

    def fun(y):
        g = np.empty(18)
        H = np.empty((18, 18))
        return material_curvature(y, which, g, H), g, H

    fd_check(fun, z, 1e-6, 1e-6)


def test_bending_and_twist_fd(rng):
    z = _random_pair(rng)

    def bend(y):
        g = np.empty(18)
        H = np.empty((18, 18))
        return bending_terms(y, 2.0, 30.0, 0.1, -0.2, g, H), g, H

    def twist(y):
        g = np.empty(18)
        H = np.empty((18, 18))
        return twist_terms(y, 1.5, 0.3, g, H), g, H

    fd_check(bend, z, 1e-6, 1e-6)
    fd_check(twist, z, 1e-6, 1e-6)


def test_twist_angle_is_theta_difference_plus_reference_twist(rng):
    """psi = theta_b - theta_a + reference twist; and a pure rotation of frame b about its
    tangent by alpha changes psi by alpha."""
    ta = _unit(rng.normal(size=3))
    tb = _unit(ta + 0.5 * rng.normal(size=3))
    d = space_parallel_frames(np.stack([ta, tb]), rng.normal(size=3))
    d[1] = _unit(np.cross(tb, d[1]) * 0.3 + d[1])  # some reference twist
    ref = reference_twist(np.stack([ta, tb]), d, [(0, 1)])[0]
    theta_a, theta_b = 0.3, -0.4
    z = np.empty(18)
    for s, (t, dd, th) in enumerate(((ta, d[0], theta_a), (tb, d[1], theta_b))):
        b = np.cross(t, dd)
        m1 = np.cos(th) * dd + np.sin(th) * b
        z[9 * s: 9 * s + 9] = np.concatenate([t, m1, np.cross(t, m1)])
    psi = twist_angle(z, np.empty(18), np.empty((18, 18)))
    assert psi == pytest.approx(theta_b - theta_a + ref, abs=1e-13)


def test_planar_curvature_is_two_tan_half_angle():
    phi = 0.7
    ta = np.array([1.0, 0.0, 0.0])
    tb = np.array([np.cos(phi), 0.0, np.sin(phi)])  # turning toward +z in the x-z plane
    # face normal in the plane of bending: m1 = normal to the tangent in x-z, m2 = t x m1
    z = np.empty(18)
    for s, t in enumerate((ta, tb)):
        m1 = np.array([-t[2], 0.0, t[0]])
        z[9 * s: 9 * s + 9] = np.concatenate([t, m1, np.cross(t, m1)])
    k1 = material_curvature(z, 1, np.empty(18), np.empty((18, 18)))
    k2 = material_curvature(z, 2, np.empty(18), np.empty((18, 18)))
    assert abs(k1) == pytest.approx(2 * np.tan(phi / 2), rel=1e-14)
    assert k2 == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("signs", [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0)])
def test_pair_energy_in_edge_coordinates_fd(rng, signs):
    """Bending + twist of two edges as a function of (e_a, theta_a, e_b, theta_b), through
    the frames' jets and `chain_pair`, against finite differences."""
    sa, sb = signs
    ea = rng.normal(size=3) * 1e-2
    eb = sa * sb * ea + rng.normal(size=3) * 5e-3
    src = [_random_source(rng, ea), _random_source(rng, eb)]
    p0 = np.concatenate([ea, [0.2], eb, [-0.5]])

    def fun(p):
        vals, jacs, hesss = [], [], []
        for s in range(2):
            val = np.empty(9)
            jac = np.empty((9, 4))
            hess = np.empty((9, 4, 4))
            material_frame_jet(p[4 * s: 4 * s + 3], p[4 * s + 3], src[s][0], src[s][1],
                               val, jac, hess)
            vals.append(val)
            jacs.append(jac)
            hesss.append(hess)
        z = np.empty(18)
        pair_frames(vals[0], sa, vals[1], sb, z)
        gz = np.empty(18)
        hz = np.empty((18, 18))
        gt = np.empty(18)
        ht = np.empty((18, 18))
        E = bending_terms(z, 2e-3, 5e-2, 0.05, 0.01, gz, hz)
        E += twist_terms(z, 1e-3, 0.1, gt, ht)
        g8 = np.empty(8)
        h8 = np.empty((8, 8))
        chain_pair(gz + gt, hz + ht, jacs[0], hesss[0], sa, jacs[1], hesss[1], sb, g8, h8)
        return E, g8, h8

    fd_check(fun, p0, 1e-8, 2e-6)


def _pair_jets(p, src):
    vals, jacs, hesss = np.empty((2, 9)), np.empty((2, 9, 4)), np.empty((2, 9, 4, 4))
    for s in range(2):
        material_frame_jet(p[4 * s: 4 * s + 3], p[4 * s + 3], src[s][0], src[s][1],
                           vals[s], jacs[s], hesss[s])
    return vals, jacs, hesss


@pytest.mark.parametrize("signs", [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)])
def test_pair_kernel_in_edge_coordinates_fd_and_equal_to_chained_kernels(rng, signs):
    """`pair_terms_edges` (the assembly's allocation-free pair kernel, formed straight in
    (e_a, theta_a, e_b, theta_b)) against finite differences, and equal to round-off to
    `bending_terms` + `twist_terms` carried by `chain_pair` at random states."""
    sa, sb = signs
    params = (2e-3, 5e-2, 1e-3, 0.05, 0.01, 0.1)  # k1, k2, kt, kappa1_bar, kappa2_bar, psi_bar
    ws = pair_edge_scratch()

    def fun(p, src):
        vals, jacs, hesss = _pair_jets(p, src)
        g8, h8 = np.empty(8), np.empty((8, 8))
        E = pair_terms_edges(vals[0], jacs[0], hesss[0], sa, vals[1], jacs[1], hesss[1], sb,
                             *params, g8, h8, ws)
        return E, g8, h8

    for trial in range(5):
        ea = rng.normal(size=3) * 1e-2
        eb = sa * sb * ea + rng.normal(size=3) * 5e-3
        src = [_random_source(rng, ea), _random_source(rng, eb)]
        p0 = np.concatenate([ea, [rng.normal()], eb, [rng.normal()]])
        if trial == 0:
            fd_check(lambda p: fun(p, src), p0, 1e-8, 2e-6)
        E, g8, h8 = fun(p0, src)
        vals, jacs, hesss = _pair_jets(p0, src)
        _assert_matches_chained_kernels(E, g8, h8, vals, jacs, hesss, sa, sb, params)
        np.testing.assert_array_equal(h8, h8.T)


def _assert_matches_chained_kernels(E, g8, h8, vals, jacs, hesss, sa, sb, params):
    """The pair kernel's energy, gradient and Hessian against the reference route: the
    18-component kernels (`bending_terms`, `twist_terms`) carried by `chain_pair`."""
    z = np.empty(18)
    pair_frames(vals[0], sa, vals[1], sb, z)
    gz, hz, gt, ht = np.empty(18), np.empty((18, 18)), np.empty(18), np.empty((18, 18))
    E_ref = bending_terms(z, params[0], params[1], params[3], params[4], gz, hz)
    E_ref += twist_terms(z, params[2], params[5], gt, ht)
    g_ref, h_ref = np.empty(8), np.empty((8, 8))
    chain_pair(gz + gt, hz + ht, jacs[0], hesss[0], sa, jacs[1], hesss[1], sb, g_ref, h_ref)
    assert E == pytest.approx(E_ref, rel=1e-12)
    np.testing.assert_allclose(g8, g_ref, rtol=0, atol=1e-11 * np.max(np.abs(g_ref)))
    np.testing.assert_allclose(h8, h_ref, rtol=0, atol=1e-11 * np.max(np.abs(h_ref)))



def test_pair_kernel_with_a_clamp_frame(rng):
    """A clamp frame enters with a zero jet (`solver.assembly3d.frame_jets`): the pair
    kernel equals the chained reference kernels and has no gradient or Hessian on it."""
    params = (2e-3, 5e-2, 1e-3, 0.05, 0.01, 0.1)
    ea = rng.normal(size=3) * 1e-2
    t_src, d_src = _random_source(rng, ea)
    vals, jacs, hesss = np.empty((2, 9)), np.zeros((2, 9, 4)), np.zeros((2, 9, 4, 4))
    material_frame_jet(ea, 0.4, t_src, d_src, vals[0], jacs[0], hesss[0])
    tb = _unit(ea + 3e-3 * rng.normal(size=3))
    db = _unit(np.cross(tb, rng.normal(size=3)))
    vals[1] = np.concatenate([tb, db, np.cross(tb, db)])
    for sa, sb in ((1.0, 1.0), (-1.0, -1.0)):
        g8, h8 = np.empty(8), np.empty((8, 8))
        E = pair_terms_edges(vals[0], jacs[0], hesss[0], sa, vals[1], jacs[1], hesss[1], sb,
                             *params, g8, h8, pair_edge_scratch())
        _assert_matches_chained_kernels(E, g8, h8, vals, jacs, hesss, sa, sb, params)
        assert not np.any(g8[4:]) and not np.any(h8[4:]) and not np.any(h8[:, 4:])


def test_tip_moment_fd(rng):
    axis = _unit(rng.normal(size=3))

    def fun(e):
        g = np.empty(3)
        H = np.empty((3, 3))
        return tip_moment_terms(e, 0.3, axis, g, H), g, H

    fd_check(fun, rng.normal(size=3) * 1e-2, 1e-8, 1e-6)
