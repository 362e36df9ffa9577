"""The 2-D unit (issue 14): square frame, crossing arches, bonds, supports, actuator (no solver
needed); edge metrics against closed forms; the push when `solver.Structure3D` exists."""

from __future__ import annotations

import math

import numpy as np
import pytest

from unit_checks import assert_supports_hold_only_rigid_motion, require_solver_3d as _solver
from snapmorph.units.frame3d import UnitGeometry
from snapmorph.units.unit2d import SIDES, build_unit_mesh_2d, edge_metrics

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
    (G, dict(overlaps="point"), "overlaps"),
    (UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, joint_length=0.0), {}, "joint_length"),
])
def test_bad_input_names_the_parameter(g, kwargs, name):
    with pytest.raises(ValueError, match=name):
        build_unit_mesh_2d(g, **kwargs)


@pytest.mark.parametrize("nodes", [21, 41, 81, 161])
def test_overlaps_are_one_edge_of_fixed_length_whatever_the_mesh(nodes):
    """Where strips meet at right angles the joint couples the edges next to the node: they
    span the w x w overlap (w/2 on each rod; at the apex the actuator's edges), so that the
    joint's compliance does not shrink with the mesh (it did: the released state converged
    at first order, its curl not at all in practice)."""
    m = build_unit_mesh_2d(G40, nodes=nodes)
    X = m.mesh.positions
    half = 0.5 * G40.w
    for name in SIDES:
        e = np.linalg.norm(np.diff(X[m.sides[name]], axis=0), axis=1)
        mid = len(e) // 2
        assert e[[0, mid - 1, mid, -1]] == pytest.approx(np.full(4, half), rel=1e-12)
        inner = np.delete(e, [0, mid - 1, mid, len(e) - 1])
        assert np.max(inner) <= G40.L / (nodes - 1) * (1 + 1e-9)
    for a in ("x", "y"):
        p = X[m.arches[a]]
        e = np.linalg.norm(np.diff(p, axis=0), axis=1)
        assert e[0] == pytest.approx(half) and e[-1] == pytest.approx(half)
        k = int(np.argmax(p[:, 2]))
        # the apex's edges and the straddling ones (arc lengths; the chords are ~0.1 % shorter)
        jl = G40.joint_length
        assert e[k - 2: k + 2] == pytest.approx([jl / 2, jl / 4, jl / 4, jl / 2], rel=2e-3)
    assert m.overlaps == "elastic"
    assert all(np.ndim(r.thickness) == 0 for r in m.mesh.rods)


def test_rigid_overlaps_are_thick_edges_over_the_w_by_w_squares():
    m = build_unit_mesh_2d(G40, nodes=81, overlaps="rigid")
    X = m.mesh.positions
    from snapmorph.units.unit2d import RIGID_OVERLAP_THICKNESS

    thick = RIGID_OVERLAP_THICKNESS * G40.t
    for rod in m.mesh.rods:
        t = np.asarray(rod.thickness)
        mids = 0.5 * (rod.xyz[1:] + rod.xyz[:-1])
        if rod.name in SIDES:
            along = np.linalg.norm(mids - rod.xyz[0], axis=1)
            inside = (along < 0.5 * G40.w) | (along > G40.L - 0.5 * G40.w) | (
                np.abs(along - 0.5 * G40.L) < 0.5 * G40.w)
        else:
            u = mids[:, 0] if rod.name == "arch_x" else mids[:, 1]
            inside = (u < 0.5 * G40.w) | (u > G40.L - 0.5 * G40.w) | (
                np.abs(u - 0.5 * G40.L) < 0.5 * G40.w)
        assert np.array_equal(t == thick, inside) and np.all(t[~inside] == G40.t)
    # the actuator holds the crossing: the apex and the nodes w/2 (arc) each side of it
    (group,) = m.mesh.rigid
    assert len(group) == 5 and m.push_node in group
    assert np.max(np.abs(X[group, :2] - 0.5 * G40.L), axis=0).max() == pytest.approx(
        0.5 * G40.w, rel=2e-2)  # w/2 of arc


# --------------------------------------------------------------------------- with the solver
G40 = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)


@pytest.fixture(scope="module")
def tall21():
    """The tall 2-D unit pushed through at 21 nodes per side (the tests below share it)."""
    _solver()
    from snapmorph.units.unit2d import simulate_unit_2d

    return simulate_unit_2d(G40, nodes=21)


def test_tall_2d_unit_released_state(tall21):
    """Released (actuator and supports removed, rigid-body motion held), state (iii) of the
    tall 2-D unit stays snapped: its arches stay inverted. The symmetric equilibrium next to
    (iii) is unstable (one negative eigenvalue: the frame warps), so the released state is
    the stable one found by leaving it along that mode, in which one pair of opposite
    sides curls much more than the other (measured at 21 nodes: 63.6 deg against -8.0 deg;
    61.7 / -7.1 at 41, 61.3 / -6.9 at 81: `test_released_warp_converges_with_the_mesh`)."""
    r = tall21
    assert r.self_standing is True and r.stability["released"] == 0
    assert r.stability["iii"].negative_force == 0
    rel = r.released
    assert rel["first_negative_eigenvalues"] >= 1
    assert rel["apex_height"] < 0  # the arches stay inverted
    for side in SIDES:
        m = rel["edges"][side]
        assert all(np.isfinite(v) for v in m.values())
        assert 0.9 * G40.L < m["S"] < G40.L
    thetas = sorted(rel["edges"][s]["theta_deg"] for s in SIDES)
    assert thetas[-1] > r.theta_deg + 10 and thetas[0] < r.theta_deg  # warped
    # placed level (`units.push3d.level`): opposite sides alike, the apex over the centre
    e = rel["edges"]
    assert e["south"]["theta_deg"] == pytest.approx(e["north"]["theta_deg"], abs=1e-6)
    assert e["east"]["theta_deg"] == pytest.approx(e["west"]["theta_deg"], abs=1e-6)
    apex = rel["shapes"]["arch_x"][np.argmax(r.shapes["0"]["arch_x"][:, 2])]
    assert apex[:2] == pytest.approx([0.5 * G40.L, 0.5 * G40.L], abs=1e-6)
    assert r.S_released == pytest.approx(np.mean([rel["edges"][s]["S"] for s in SIDES]))
    assert r.theta_released_deg == pytest.approx(np.mean(thetas))
    assert np.isfinite(r.curvature_released)
    s = r.summary()
    assert s["self_standing"] is True and s["theta_released_deg"] == r.theta_released_deg
    assert s["south_theta_deg_released"] == rel["edges"]["south"]["theta_deg"]


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


def test_released_supports_hold_only_rigid_motion():
    from snapmorph.units.unit2d import released_supports_2d

    free = build_unit_mesh_2d(G, nodes=21, actuator=False, supports=False)
    act = build_unit_mesh_2d(G, nodes=21)
    assert not free.mesh.rigid and not free.mesh.fixes
    assert [r.name for r in free.mesh.rods] == [r.name for r in act.mesh.rods]
    assert np.array_equal(free.mesh.positions, act.mesh.positions)
    assert_supports_hold_only_rigid_motion(free.mesh.positions, released_supports_2d(free))


def test_low_2d_unit_is_monostable():
    _solver()
    from snapmorph.units.unit2d import simulate_unit_2d

    r = simulate_unit_2d(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3), nodes=21)
    assert r.status == "monostable" and not r.bistable and r.F_cr > 0
    assert "iii" not in r.edges and np.isnan(r.theta_deg)
    assert r.reason and r.self_standing is None and r.released == {}
    assert np.isnan(r.S_released) and np.isnan(r.theta_released_deg)


def test_an_unstable_second_state_is_reported_as_such(monkeypatch):
    """The stability check of (iii) made to see two negative eigenvalues: not bistable,
    status "second state unstable", no edge metrics of (iii), map status 5."""
    _solver()
    from snapmorph.solver.stability import StateStability
    from snapmorph.units import push3d
    from snapmorph.pipeline.kinds.unit2d import solve_map_point
    from snapmorph.units.unit2d import simulate_unit_2d

    real = push3d._state_stability

    def unstable_iii(st, q, node, system):
        s = real(st, q, node, system)
        return StateStability(2, 2) if s is not None and s.negative_force == 0 else s

    monkeypatch.setattr(push3d, "_state_stability", unstable_iii)
    r = simulate_unit_2d(G40, nodes=21)
    assert r.status.startswith("second state unstable") and "negative eigenvalue" in r.reason
    assert not r.bistable and "iii" not in r.edges and "iii" in r.shapes
    assert np.isnan(r.theta_deg) and r.self_standing is None and not r.released
    rec = solve_map_point(0.4, 0.005, resolution=21)
    assert rec["status"] == 5 and rec["bistable"] == 0 and rec["self_standing"] == -1


@pytest.mark.parametrize("kwargs, name", [
    (dict(steps=0), "steps"), (dict(steps="a"), "steps"), (dict(critical=1), "critical"),
    (dict(check_self_standing=None), "check_self_standing"), (dict(nodes=2.0), "nodes"),
    (dict(nu="x"), "nu"), (dict(nu=True), "nu"),
])
def test_simulate_bad_input_names_the_parameter(kwargs, name):
    from snapmorph.units.unit2d import simulate_unit_2d

    with pytest.raises(ValueError, match=name):
        simulate_unit_2d(G40, **kwargs)


def test_map_point_is_dimensionless_and_never_raises(tall21):
    from snapmorph.pipeline.kinds.unit2d import solve_map_point

    rec = solve_map_point(0.4, 0.005, resolution=21)
    EI = G40.E * G40.w * G40.t**3 / 12
    assert rec["status"] == 0
    assert rec["F_cr"] == pytest.approx(tall21.F_cr * G40.L**2 / EI)
    assert rec["theta"] == pytest.approx(tall21.theta_deg)
    assert rec["theta_spread"] < 1e-6
    assert rec["bistable"] == 1 and rec["self_standing"] == 1
    assert rec["theta_released"] == pytest.approx(tall21.theta_released_deg)
    assert rec["S_released"] == pytest.approx(tall21.S_released / G40.L)
    assert rec["edge_theta_released"] == pytest.approx(
        [tall21.released["edges"][s]["theta_deg"] for s in SIDES])
    assert rec["theta_spread_released"] > 10.0
    from snapmorph.pipeline.kinds.unit2d import SPEC as MAP_SPEC

    clean = MAP_SPEC.finalise_record(rec, MAP_SPEC.options)
    assert clean["status"] == 0 and clean["self_standing"] == 1
    low = solve_map_point(0.2, 0.005, resolution=21)
    assert low["status"] == 1 and low["bistable"] == 0 and low["self_standing"] == -1
    assert np.all(np.isnan(low["edge_theta_released"])) and np.isnan(low["theta_released"])
    bad = solve_map_point(2.0, 0.005, resolution=21)
    assert bad["status"] == 3 and "h" in bad["message"]


def test_cli_unit2d(tmp_path, capsys):
    _solver()
    from snapmorph.cli import main

    assert main(["unit2d", "--L", "100", "--h", "40", "--t", "0.5", "--w", "5", "--nodes", "21",
                 "--json", str(tmp_path / "u.json")]) == 0
    out = capsys.readouterr().out
    assert "bistable" in out and "north" in out
    assert "self-standing" in out and "sides in the released state (iii)" in out
    import json

    data = json.loads((tmp_path / "u.json").read_text())
    assert data["self_standing"] is True and np.isfinite(data["north_theta_deg_released"])


def test_released_warp_converges_with_the_mesh():
    """The released warped state at 21 / 41 / 81 nodes (measured: curled pair 63.63 / 61.75 /
    61.25 deg, 61.13 at 161; flat pair -7.96 / -7.10 / -6.88 deg; F_cr 1.2471 / 1.2505 /
    1.2511 N): second order, the differences falling ~4x per halving. With joints coupling
    edges of the mesh spacing it was 41.6 / 61.7 / 72.2 / 77.5 deg at 21 / 41 / 81 / 161."""
    _solver()
    from snapmorph.units.unit2d import simulate_unit_2d

    curled, flat, S, F = [], [], [], []
    for nodes in (21, 41, 81):
        r = simulate_unit_2d(G40, nodes=nodes)
        assert r.self_standing is True and r.stability["released"] == 0
        th = np.array([r.released["edges"][s]["theta_deg"] for s in SIDES])
        curled.append(th.max())
        flat.append(th.min())
        S.append(min(r.released["edges"][s]["S"] for s in SIDES))
        F.append(r.F_cr)
    assert curled[1] > 45.0 and flat[1] < 0.0
    d1, d2 = curled[0] - curled[1], curled[1] - curled[2]
    assert abs(d2) < 1.0 and abs(d1) > 2.5 * abs(d2)  # converging at ~second order
    assert abs(flat[1] - flat[2]) < 0.5 and abs(S[1] - S[2]) < 1e-3 * G40.L
    assert F[1] == pytest.approx(F[2], rel=2e-3) and F[0] == pytest.approx(F[2], rel=5e-3)


def test_rigid_overlaps_option():
    """overlaps="rigid" (diagnostic): the w x w overlaps rigid. Stiffer (measured at 41 nodes:
    F_cr 1.3324 N against 1.2505, theta in (iii) 16.04 deg against 13.79), the released warp
    alike (61.6 / -5.5 deg)."""
    _solver()
    from snapmorph.units.unit2d import simulate_unit_2d

    r = simulate_unit_2d(G40, nodes=41, overlaps="rigid")
    assert r.status == "ok" and r.bistable and r.self_standing is True
    assert r.F_cr == pytest.approx(1.3324, rel=5e-3)
    assert r.theta_deg == pytest.approx(16.04, abs=0.1)
    th = sorted(r.released["edges"][s]["theta_deg"] for s in SIDES)
    assert th[-1] == pytest.approx(61.6, abs=1.0) and th[0] < 0


@pytest.mark.slow
def test_2d_unit_mesh_convergence_within_one_percent():
    """Default mesh (41 nodes per side) against 81: F_cr 1.2505 / 1.2511 N (0.05 %), theta of
    the sides 13.79 / 13.89 deg, d_second 65.10 / 65.24 mm (measured)."""
    _solver()
    from snapmorph.units.unit2d import DEFAULT_NODES_2D, simulate_unit_2d

    coarse = simulate_unit_2d(G40, nodes=DEFAULT_NODES_2D, check_self_standing=False)
    fine = simulate_unit_2d(G40, nodes=2 * DEFAULT_NODES_2D - 1, check_self_standing=False)
    assert coarse.F_cr == pytest.approx(fine.F_cr, rel=0.01)
    assert coarse.theta_deg == pytest.approx(fine.theta_deg, rel=0.01)
    assert coarse.d_second == pytest.approx(fine.d_second, rel=0.01)


def test_a_shallow_dip_strided_over_by_the_steps_is_refined():
    """h/L = 0.4, t/L = 0.0075 is marginally bistable: F dips to about -0.02 N between
    samples that are both above zero (0.066 and 0.051 N at d = 56.2 and 63.6 mm with the
    units' step size). Refining the sampled minimum by displacement-controlled solves finds
    the dip, hence states (ii) and (iii) 4 mm apart; without it the unit read monostable."""
    from snapmorph.units.unit2d import simulate_unit_2d

    g = UnitGeometry(L=0.1, h=0.04, t=0.75e-3, w=5e-3)
    r = simulate_unit_2d(g, check_self_standing=False)
    assert r.status == "ok" and r.bistable
    d, F = r.curve
    assert F.min() < 0.0
    assert -0.1 < F.min() / r.F_cr < 0.0  # shallow
    assert 0.0 < r.d_second - r.d_unstable < 0.01
