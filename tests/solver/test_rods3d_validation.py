"""3-D rods against the planar solver and against closed forms.

- Planar parity: the planar benchmarks built from 3-D strips lying in a plane (the strip's
  face normal in that plane, so that in-plane bending is the easy way, EI1) reproduce the
  planar `solver.Structure` paths. The 3-D discretisation reduces exactly to the planar one
  for in-plane motion, so the agreement is that of the solver tolerance, far inside 0.1 %.
- Lateral–torsional buckling of a cantilever strip loaded at the tip in its stiff direction:
  P_cr L^2 / sqrt(EI1 GJ) = 4.013 (Prandtl, Michell) for EI2 -> infinity; with the strip's
  finite EI2 the classical correction divides it by sqrt((1 - EI1/EI2)(1 - GJ/EI2)).
"""

import numpy as np
import pytest
import scipy.optimize

from snapmorph.solver import Structure, Structure3D
from snapmorph.solver.states import DisplacementProbe
from validation.arch import clamped_arch
from validation.cantilever import clamped_rod_nodes
from validation.strip3d import ltb_cantilever

E, NU = 2.2e9, 0.38


def _rotation(rng):
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return Q if np.linalg.det(Q) > 0 else -Q


def _compare(p3, p2, points):
    """Max relative difference of the force at the given displacements."""
    F3 = np.interp(points, p3.displacement, p3.force)
    F2 = np.interp(points, p2.displacement, p2.force)
    return float(np.max(np.abs(F3 - F2) / np.max(np.abs(F2))))


def _planar_to_3d(xz):
    """(x, z) points to (x, 0, z)."""
    return np.stack([xz[:, 0], np.zeros(len(xz)), xz[:, 1]], 1)


def test_elastica_cantilever_parity_in_any_orientation(rng):
    """The planar elastica benchmark (tests/solver/test_elastica.py), and the same strip
    rotated arbitrarily in space with its load: same force-deflection path."""
    L, T, W = 1.0, 5e-4, 1e-2
    Em = 12.0 / (W * T**3)
    n = 41
    s = clamped_rod_nodes(n, L)
    xz = np.stack([s, 0 * s], 1)
    planar = Structure()
    planar.add_rod(xz, width=W, thickness=T, E=Em)
    planar.fix(0, "xz")
    planar.fix(1, "xz")
    p2 = planar.push(n - 1, (0.0, -1.0), 0.8 * L, method="mgdc")
    for R in (np.eye(3), _rotation(rng)):
        st = Structure3D()
        rod = st.add_rod(_planar_to_3d(xz) @ R.T, width=W, thickness=T, E=Em, nu=NU,
                         normal=R @ [0.0, 0.0, 1.0])
        # the planar model's held first edge: node 1 fixed, node 0 clamped along the edge
        st.clamp(rod.nodes[0], toward=rod.nodes[1])
        st.fix(rod.nodes[1], "xyz")
        p3 = st.push(rod.nodes[-1], direction=R @ [0.0, 0.0, -1.0], distance=0.8 * L,
                     method="mgdc")
        assert p3.status == "ok" and p2.status == "ok"
        assert _compare(p3, p2, np.linspace(0.05, 0.79, 30) * L) < 1e-6
        # stays in its plane, untwisted
        out_of_plane = (p3.positions[-1] @ R)[:, 1]
        assert np.max(np.abs(out_of_plane)) < 1e-9 * L
        assert np.max(np.abs(p3.twist)) < 1e-8


def test_euler_column_parity():
    """Clamped–clamped column with a small imperfection (tests/solver/test_column.py)."""
    L, T, W = 0.1, 0.5e-3, 5e-3
    n = 61
    ds = L / (n - 2)
    x = -0.5 * ds + ds * np.arange(n)
    z = 3e-4 * L * 0.5 * (1 - np.cos(2 * np.pi * np.clip(x, 0, L) / L))
    xz = np.stack([x, z], 1)
    planar = Structure()
    planar.add_rod(xz, width=W, thickness=T, E=E)
    planar.fix(0, "xz")
    planar.fix(1, "xz")
    planar.rigid([n - 2, n - 1])
    planar.fix(n - 1, "z")
    p2 = planar.push(n - 1, direction=(-1.0, 0.0), distance=0.03 * L, method="mgdc")
    st = Structure3D()
    rod = st.add_rod(_planar_to_3d(xz), width=W, thickness=T, E=E, nu=NU, normal=(0, 0, 1))
    st.clamp(0, toward=1)
    st.fix(1, "xyz")
    st.rigid([n - 2, n - 1])
    st.fix(n - 1, "yz")
    p3 = st.push(rod.nodes[-1], direction=(-1.0, 0.0, 0.0), distance=0.03 * L, method="mgdc")
    assert p3.status == "ok" and p2.status == "ok"
    assert _compare(p3, p2, np.linspace(0.001, 0.029, 30) * L) < 1e-6
    EI = E * W * T**3 / 12
    window = (p3.displacement > 0.005 * L) & (p3.displacement < 0.02 * L)
    assert abs(p3.force[window].mean() / (4 * np.pi**2 * EI / L**2) - 1) < 0.01


def test_centre_clamped_arch_parity():
    """The clamped–clamped cosine arch pushed at its midpoint through snap-through
    (`validation.arch.clamped_arch`)."""
    h, n = 0.01, 61
    planar, mid, EI = clamped_arch(h, n_nodes=n)
    p2 = planar.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")
    X = planar.reference_positions
    st = Structure3D()
    rod = st.add_rod(_planar_to_3d(X), width=5e-3, thickness=0.5e-3, E=2.2e9, nu=NU,
                     normal=(0, 0, 1))
    st.clamp(0, toward=1)
    st.clamp(n - 1, toward=n - 2)
    for node in (1, n - 2):
        st.fix(node, "xyz")
    st.rigid([mid - 1, mid, mid + 1])
    st.fix(mid, "xy")
    p3 = st.push(rod.nodes[mid], direction=(0.0, 0.0, -1.0), distance=2.2 * h, method="mgdc")
    assert p3.status == "ok" and p2.status == "ok"
    # Equilibria compared at the same displacements, each solved there (not read off the
    # paths: their steps differ with the last bits of the arithmetic, and so would a linear
    # interpolation between them), the path's end and its two limit points included.
    pts = np.append(np.linspace(0.02, 2.15, 40) * h, 2.2 * h)
    probe2 = DisplacementProbe(planar, mid, (0.0, -1.0))
    probe3 = DisplacementProbe(st, rod.nodes[mid], (0.0, 0.0, -1.0))
    F2, F3 = _solved_forces(probe2, p2, pts), _solved_forces(probe3, p3, pts)
    assert np.max(np.abs(F3 - F2)) / np.max(np.abs(F2)) < 1e-6
    for sign in (1.0, -1.0):  # the snap-through maximum and the minimum past it
        e2, e3 = _extreme(probe2, p2, sign), _extreme(probe3, p3, sign)
        assert e3 == pytest.approx(e2, rel=1e-6)


def _solved_forces(probe, path, points):
    """F (N) of the equilibria at the given displacements, each solved from the path's
    nearest state."""
    near = [int(np.argmin(np.abs(path.displacement - d))) for d in points]
    return np.array([probe.solve(path.positions[j], d)[1] for j, d in zip(near, points)])


def _extreme(probe, path, sign):
    """The first local maximum (sign 1) or minimum (-1) of F(d) along a path, located by
    displacement-controlled solves (Brent, to 1e-9 of the path's range in d)."""
    F = sign * path.force
    i = next(k for k in range(1, len(F) - 1) if F[k] >= F[k - 1] and F[k] >= F[k + 1])
    a, b = path.displacement[i - 1], path.displacement[i + 1]
    res = scipy.optimize.minimize_scalar(
        lambda d: -sign * probe.solve(path.positions[i], d)[1], bounds=(a, b),
        method="bounded", options={"xatol": 1e-9 * path.displacement[-1]})
    return -sign * res.fun


def ltb_ratio(n):
    """(P_bif L^2 / sqrt(EI1 GJ), the path) of the LTB cantilever with n nodes."""
    L = 0.1
    st, rod, EI1, EI2, GJ = ltb_cantilever(n, L)
    P_guess = 4.013 * np.sqrt(EI1 * GJ) / L**2
    d_cr = P_guess * L**3 / (3 * EI2)  # stiff-direction tip deflection at P_cr
    path = st.push(rod.nodes[-1], direction=(0.0, 0.0, -1.0), distance=2.0 * d_cr,
                   method="mgdc")
    bif = path.bifurcations
    assert path.status == "ok", path.status
    assert len(bif) >= 1 and bif[0].located and bif[0].switched
    return bif[0].F * L**2 / np.sqrt(EI1 * GJ), path, (EI1, EI2, GJ)


@pytest.mark.slow
def test_lateral_torsional_buckling_of_a_cantilever_strip():
    ratios = {}
    for n in (26, 51, 101):
        ratios[n], path, (EI1, EI2, GJ) = ltb_ratio(n)
    # within 2 % of Prandtl's 4.013 at about 100 nodes
    assert abs(ratios[101] / 4.013 - 1) < 0.02
    # converging: the change halves at least with every doubling (O(N^-2): quarters)
    assert abs(ratios[101] - ratios[51]) < 0.5 * abs(ratios[51] - ratios[26])
    # and to the value with the finite-EI2 correction (Richardson-extrapolated limit)
    limit = ratios[101] + (ratios[101] - ratios[51]) / 3.0
    corrected = 4.013 / np.sqrt((1 - EI1 / EI2) * (1 - GJ / EI2))
    assert abs(limit / corrected - 1) < 2e-3
    # the switched branch buckles sideways and twists; the primary stays planar before it
    before = path.force < 0.99 * path.bifurcations[0].F
    assert np.max(np.abs(path.positions[before][:, :, 1])) < 1e-9
    assert np.max(np.abs(path.positions[-1, -1, 1])) > 1e-3
    assert np.max(np.abs(path.twist[-1])) > 1e-2
    assert np.all(path.negative_eigenvalues[-5:] == 0)  # stable post-buckled branch


@pytest.mark.slow
def test_free_rod_with_natural_curvature_and_twist_relaxes_to_the_helix():
    """A rod with natural curvature kappa (through its thickness) and natural twist tau,
    held only against rigid motion (3-2-1 supports), relaxes from another helix (radius
    +15 %, pitch -15 %) to radius kappa / (kappa^2 + tau^2) and pitch
    2 pi tau / (kappa^2 + tau^2), measured from the screw motion between its edges."""
    kap, tau = 20.0, 10.0
    R0, P0 = kap / (kap**2 + tau**2), 2 * np.pi * tau / (kap**2 + tau**2)
    n, length = 61, 0.3
    R, c = 1.15 * R0, 0.85 * P0 / (2 * np.pi)
    phi = np.linspace(0.0, length, n) / np.hypot(R, c)
    xyz = np.stack([R * np.cos(phi), R * np.sin(phi), c * phi], 1)
    mid = 0.5 * (phi[1:] + phi[:-1])
    normals = np.stack([-np.cos(mid), -np.sin(mid), 0 * mid], 1)  # toward the axis
    st = Structure3D()
    st.add_rod(xyz, width=2e-3, thickness=1e-3, E=2e9, nu=0.4, normal=normals,
               natural_curvature=(kap, 0.0), natural_twist=tau)
    st.fix(0, "xyz")
    st.fix(1, "yz")
    st.fix(2, "z")
    q, info = st.relax()
    assert info["energy"] < 1e-20  # the helix is stress free
    e = np.diff(st.positions_of(q), axis=0)
    k = n // 3
    axis = np.cross(e[k + 1] - e[k], e[k + 2] - e[k + 1])
    axis /= np.linalg.norm(axis)
    rise = e @ axis
    perp = e - np.outer(rise, axis)
    chord = np.linalg.norm(perp, axis=1)
    turn = np.arccos(np.clip(np.sum(perp[1:] * perp[:-1], 1) / (chord[1:] * chord[:-1]), -1, 1))
    radius = chord[:-1] / (2 * np.sin(turn / 2))
    pitch = 2 * np.pi * np.abs(rise[:-1]) / turn
    assert np.max(np.abs(radius / R0 - 1)) < 5e-3
    assert np.max(np.abs(pitch / P0 - 1)) < 5e-3


@pytest.mark.slow
def test_tip_moment_bends_a_strip_into_a_ring_arc():
    """A cantilever strip under a dead tip couple M about its width axis bends into a
    circular arc of radius EI1 / M (here 3/8 of a ring)."""
    n, L = 41, 0.1
    x = np.linspace(0.0, L, n)
    st = Structure3D()
    st.add_rod(np.stack([x, 0 * x, 0 * x], 1), width=5e-3, thickness=0.5e-3, E=E, nu=NU,
               normal=(0.0, 0.0, 1.0))
    st.clamp(0, toward=1)
    EI1 = float(st.rods[0].EI1[0])
    M = 0.75 * np.pi * EI1 / L
    q, info = st.relax(moments=[(n - 2, n - 1, M, (0.0, -1.0, 0.0))], ramp=3)
    X = st.positions_of(q)
    A = np.stack([X[:, 0], X[:, 2], np.ones(n)], 1)
    sol = np.linalg.lstsq(A, X[:, 0] ** 2 + X[:, 2] ** 2, rcond=None)[0]
    xc, zc = sol[0] / 2, sol[1] / 2
    radii = np.hypot(X[:, 0] - xc, X[:, 2] - zc)
    assert np.ptp(radii) < 1e-9 * L  # a circle
    assert np.mean(radii) == pytest.approx(EI1 / M, rel=5e-3)
    assert np.max(np.abs(X[:, 1])) < 1e-12  # in its plane
