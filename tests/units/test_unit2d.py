"""The 2-D unit (issue 14): square frame, crossing arches, bonds, supports, actuator (no solver
needed); edge metrics against closed forms; the push when `solver.Structure3D` exists."""

from __future__ import annotations

import math

import numpy as np
import pytest

from units.frame3d import UnitGeometry
from units.unit2d import SIDES, build_unit_mesh_2d, edge_metrics

G = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3)


@pytest.fixture(scope="module")
def unit():
    return build_unit_mesh_2d(G, nodes=41)


def test_square_frame_of_four_strips_jointed_at_the_corners(unit):
    X = unit.mesh.positions
    corners = []
    for name in SIDES:
        nodes = unit.sides[name]
        p = X[nodes]
        assert np.linalg.norm(p[-1] - p[0]) == pytest.approx(G.L)
        assert np.all(p[:, 2] == 0.0)
        assert unit.mesh.rod(name).width == pytest.approx(np.full(len(nodes) - 1, G.w))
        corners.append(p[0])
        # the midpoint of the side is a node
        assert np.any(np.all(np.isclose(p, 0.5 * (p[0] + p[-1]), atol=1e-15), axis=1))
    assert sorted(map(tuple, np.round(corners, 12))) == sorted(
        [(0, 0, 0), (G.L, 0, 0), (G.L, G.L, 0), (0, G.L, 0)])
    joints = set(unit.mesh.joints)
    for a, b in zip(SIDES, SIDES[1:] + SIDES[:1]):
        assert (int(unit.sides[a][-1]), int(unit.sides[b][0])) in joints
    for a, b in unit.mesh.joints:
        assert np.array_equal(X[a], X[b])


def test_arches_join_opposite_midpoints_and_cross_bonded_at_the_apex(unit):
    X = unit.mesh.positions
    ax, ay = unit.arches["x"], unit.arches["y"]
    assert X[ax[0]] == pytest.approx([0, 0.5 * G.L, 0])
    assert X[ax[-1]] == pytest.approx([G.L, 0.5 * G.L, 0])
    assert X[ay[0]] == pytest.approx([0.5 * G.L, 0, 0])
    assert X[ay[-1]] == pytest.approx([0.5 * G.L, G.L, 0])
    assert np.max(X[ax, 2]) == pytest.approx(G.h) and np.max(X[ay, 2]) == pytest.approx(G.h)
    apex_x = int(ax[np.argmax(X[ax, 2])])
    apex_y = int(ay[np.argmax(X[ay, 2])])
    assert apex_x == unit.push_node
    assert (apex_x, apex_y) in unit.mesh.joints
    # the arches are the same curve turned by 90 degrees
    assert np.allclose(X[ax][:, [0, 2]], X[ay][:, [1, 2]])
    # sinusoid between the flat ends of length b + w/2
    x0 = G.b + 0.5 * G.w
    span = G.L - 2 * x0
    u = X[ax, 0]
    inside = (u > x0) & (u < G.L - x0)
    expected = 0.5 * G.h * (1 - np.cos(2 * np.pi * (u[inside] - x0) / span))
    assert np.allclose(X[ax, 2][inside], expected)
    assert np.all(X[ax, 2][~inside] == 0.0)
    # feet rigidly jointed to the side midpoints, which carry the supports
    feet = {int(ax[0]), int(ax[-1]), int(ay[0]), int(ay[-1])}
    jointed = {a for a, b in unit.mesh.joints} | {b for a, b in unit.mesh.joints}
    assert feet <= jointed
    z_fixed = sorted(n for n, c in unit.mesh.fixes if c == "z")
    assert sorted(unit.supports.tolist()) == z_fixed
    assert np.allclose(sorted(map(tuple, np.round(X[z_fixed], 12))), sorted(
        [(0.5 * G.L, 0, 0), (G.L, 0.5 * G.L, 0), (0.5 * G.L, G.L, 0), (0, 0.5 * G.L, 0)]))


def test_actuator_moves_both_arches_near_the_apex_as_one(unit):
    X = unit.mesh.positions
    (group,) = unit.mesh.rigid
    assert unit.push_node in group and (unit.push_node, "xy") in unit.mesh.fixes
    centre = np.array([0.5 * G.L, 0.5 * G.L, G.h])
    members_x = [n for n in group if n in set(unit.arches["x"].tolist())]
    members_y = [n for n in group if n in set(unit.arches["y"].tolist())]
    assert len(members_x) >= 3 and len(members_y) >= 2
    assert np.max(np.linalg.norm(X[group] - centre, axis=1)) < G.joint_length


def test_mesh_has_the_square_symmetry():
    m = build_unit_mesh_2d(G, nodes=31)
    X = m.mesh.positions
    c = np.array([0.5 * G.L, 0.5 * G.L, 0])
    rot = (X - c) @ np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]]) + c  # quarter turn
    key = {tuple(np.round(p, 12)) for p in X}
    assert all(tuple(np.round(p, 12)) in key for p in rot)


def test_edge_metrics_of_a_circular_arc():
    R, phi = 0.08, math.radians(60)
    a = np.linspace(-phi / 2, phi / 2, 401)
    pts = np.stack([R * np.sin(a), 0.0 * a, R * (1 - np.cos(a))], 1)
    m = edge_metrics(pts)
    assert m["S"] == pytest.approx(2 * R * math.sin(phi / 2))
    assert m["arc_length"] == pytest.approx(R * phi, rel=1e-5)
    assert m["theta_deg"] == pytest.approx(60.0 * 399 / 400, rel=1e-12)
    assert m["curvature"] == pytest.approx(1 / R, rel=3e-3)
    assert m["sag"] == pytest.approx(R * (1 - math.cos(phi / 2)))
    flat = edge_metrics(np.stack([np.linspace(0, 1, 5), 0 * np.ones(5), np.zeros(5)], 1))
    assert flat["theta_deg"] == 0.0 and flat["curvature"] == 0.0


@pytest.mark.parametrize("g, kwargs, name", [
    (UnitGeometry(L=0.1, h=0.0, t=0.5e-3, w=5e-3), {}, "h"),
    (G, dict(nodes=5), "nodes"), (G, dict(nodes=True), "nodes"), (G, dict(nu=-1.5), "nu"),
])
def test_bad_input_names_the_parameter(g, kwargs, name):
    with pytest.raises(ValueError, match=name):
        build_unit_mesh_2d(g, **kwargs)


# --------------------------------------------------------------------------- with the solver
def _solver():
    try:
        from solver import Structure3D  # noqa: F401
    except ImportError:  # pragma: no cover
        pytest.skip("solver.Structure3D is not available")


G40 = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)


@pytest.fixture(scope="module")
def tall21():
    _solver()
    from units.unit2d import simulate_unit_2d

    return simulate_unit_2d(G40, nodes=21)


def test_tall_2d_unit_is_bistable_with_four_equal_curled_sides(tall21):
    r = tall21
    assert r.status == "ok" and r.bistable and r.exact_states
    assert 0 < r.d_cr < r.d_unstable < r.d_second
    sides = r.edges["iii"]
    thetas = np.array([sides[s]["theta_deg"] for s in SIDES])
    assert np.all(thetas > 1.0)  # the corners rise: each side curls toward the arches' side
    assert np.ptp(thetas) < 1e-6 * np.max(thetas)  # the square's symmetry is kept
    for s in SIDES:
        m = sides[s]
        assert m["S"] < G40.L and m["curvature"] > 0 and m["sag"] > 0


def test_low_2d_unit_is_monostable():
    _solver()
    from units.unit2d import simulate_unit_2d

    r = simulate_unit_2d(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3), nodes=21)
    assert r.status == "monostable" and not r.bistable and r.F_cr > 0
    assert "iii" not in r.edges and np.isnan(r.theta_deg)


def test_map_point_is_dimensionless_and_never_raises(tall21):
    from units.unit2d import solve_map_point

    rec = solve_map_point(0.4, 0.005, resolution=21)
    EI = G40.E * G40.w * G40.t**3 / 12
    assert rec["status"] == 0
    assert rec["F_cr"] == pytest.approx(tall21.F_cr * G40.L**2 / EI)
    assert rec["theta"] == pytest.approx(tall21.theta_deg)
    assert rec["theta_spread"] < 1e-6
    bad = solve_map_point(2.0, 0.005, resolution=21)
    assert bad["status"] == 3 and "h" in bad["message"]


def test_cli_unit2d(tmp_path, capsys):
    _solver()
    from snapmorph.cli import main

    assert main(["unit2d", "--L", "100", "--h", "40", "--t", "0.5", "--w", "5", "--nodes", "21",
                 "--json", str(tmp_path / "u.json")]) == 0
    out = capsys.readouterr().out
    assert "bistable" in out and "north" in out


@pytest.mark.slow
def test_2d_unit_mesh_convergence_within_one_percent():
    """Default mesh (41 nodes per side) against 81: F_cr 1.2505 / 1.2396 N (0.9 %), theta of
    the sides 13.79 / 13.86 deg, d_second 65.10 / 64.71 mm (measured)."""
    _solver()
    from units.unit2d import DEFAULT_NODES_2D, simulate_unit_2d

    coarse = simulate_unit_2d(G40, nodes=DEFAULT_NODES_2D)
    fine = simulate_unit_2d(G40, nodes=2 * DEFAULT_NODES_2D - 1)
    assert coarse.F_cr == pytest.approx(fine.F_cr, rel=0.01)
    assert coarse.theta_deg == pytest.approx(fine.theta_deg, rel=0.01)
    assert coarse.d_second == pytest.approx(fine.d_second, rel=0.01)
