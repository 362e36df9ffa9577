"""The 3-D unit (issue 14): mesh topology, widths, bonds, supports and imperfections (no solver
needed), metrics against closed forms, and — when `solver.Structure3D` exists — the push."""

from __future__ import annotations

import math

import numpy as np
import pytest

from unit_checks import (assert_supports_hold_only_rigid_motion, make_second_state_unstable,
                         require_solver_3d as _solver)
from snapmorph.units.frame3d import UnitGeometry
from snapmorph.units.shapes import end_tangent_angle
from snapmorph.units.planar import simulate_unit
from snapmorph.units.unit3d import (
    STIFF_PLATE_FACTOR,
    arch_lean_deg,
    build_unit_3d,
    build_unit_mesh_3d,
    section_rotation_deg,
    simulate_unit_3d,
)

MM = 1e-3
SPECIMEN = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)


def _rods_crossing(mesh, x):
    """Rods along x (rails, centre strips) whose span covers abscissa x, with their width."""
    out = []
    for r in mesh.rods:
        if not r.name.startswith(("rail", "centre")):
            continue
        xs = r.xyz[:, 0]
        lo, hi = np.minimum(xs[:-1], xs[1:]), np.maximum(xs[:-1], xs[1:])
        k = np.nonzero((lo < x) & (x < hi))[0]
        if len(k):
            out.append((r.name, float(r.width[k[0]]), float(r.xyz[k[0], 1])))
    return out


@pytest.fixture(scope="module")
def unit():
    return build_unit_mesh_3d(SPECIMEN, nodes=101)


@pytest.fixture(scope="module")
def bond_unit():
    """The mesh of `Mesh3D.bond` joints (the default before issue 25), whose pairs of edges
    the topology tests check."""
    return build_unit_mesh_3d(SPECIMEN, nodes=101, joints="bond")


def test_frame_widths_solid_ends_and_hollow_middle(unit):
    g = SPECIMEN
    mesh = unit.mesh
    for x in (0.23 * g.flat_length, 0.71 * g.flat_length, g.L - 0.47 * g.flat_length):
        rods = _rods_crossing(mesh, x)
        assert sum(w for _, w, _ in rods) == pytest.approx(4 * g.w)
        # together they tile [-2w, 2w] without overlap
        spans = sorted((y - 0.5 * w, y + 0.5 * w) for _, w, y in rods)
        assert spans[0][0] == pytest.approx(-2 * g.w) and spans[-1][1] == pytest.approx(2 * g.w)
        for a, b in zip(spans[:-1], spans[1:]):
            assert a[1] == pytest.approx(b[0])
    for x in (0.3037 * g.L, 0.5 * g.L - 1e-4, 0.8037 * g.L):
        rods = _rods_crossing(mesh, x)
        assert sorted(n for n, _, _ in rods) == ["rail_left", "rail_right"]
        assert sum(w for _, w, _ in rods) == pytest.approx(2 * g.w)
        assert sorted(y for _, _, y in rods) == pytest.approx([-1.5 * g.w, 1.5 * g.w])


def test_cross_bars_stand_for_the_end_plates_length(unit):
    g = SPECIMEN
    plus = [r for r in unit.mesh.rods if r.name.startswith("bar_left") and r.name.endswith("_p")]
    minus = [r for r in unit.mesh.rods if r.name.startswith("bar_left") and r.name.endswith("_m")]
    assert len(plus) == len(minus) == len(unit.mesh.groups["centre_left"]) - 1
    widths = np.array([r.width[0] for r in plus])
    xs = np.array([r.xyz[0, 0] for r in plus])
    # together the bars stand for the plate from the end to x0, and stop before x0
    assert np.sum(widths) == pytest.approx(g.flat_length)
    assert xs[0] == 0.0 and xs[-1] < g.flat_length
    for p, m in zip(plus, minus):  # from the centre line out to each rail, along y
        assert p.xyz[0, 1] == 0.0 and p.xyz[-1, 1] == pytest.approx(1.5 * g.w)
        assert np.array_equal(m.xyz, p.xyz * [1, -1, 1])
        assert np.ptp(p.xyz[:, 0]) == 0.0 and np.all(np.diff(p.xyz[:, 1]) > 0)
        assert np.all(p.width == p.width[0]) and p.thickness == g.t
        assert p.plate and m.plate and p.E_factor == 1.0  # strips of a plate: J = w t^3 / 3
    stiff = build_unit_mesh_3d(SPECIMEN, nodes=41, end_plate="stiff")
    bars = [r for r in stiff.mesh.rods if r.name.startswith("bar")]
    assert all(r.thickness == g.t and r.E_factor == STIFF_PLATE_FACTOR for r in bars)
    assert all(r.E_factor == 1.0 for r in stiff.mesh.rods if not r.name.startswith("bar"))
    # the solver gets the plate's torsion constant, not the narrow strip's
    st = build_unit_3d(SPECIMEN, nodes=41).structure
    rods = dict(zip([r.name for r in unit.mesh.rods], st.rods))
    bar = rods[plus[0].name]
    assert np.allclose(bar.GJ, bar.E / (2 * (1 + bar.nu)) * bar.width * g.t**3 / 3)
    rail = rods["rail_left"]
    assert np.all(rail.GJ < rail.E / (2 * (1 + rail.nu)) * rail.width * g.t**3 / 3)


def test_a_stiff_end_plate_gives_the_planar_model_as_the_mesh_is_refined():
    """With end plates rigid across their width (the planar model's assumption) the frame
    converges to the planar model: on the uniform mesh with the bonds (the default before
    issue 25) the residual is O(1/N) (docs/unit3d.md). h = 19.24 mm: theta +0.94 / +0.50
    deg, F_cr -2.3 / -1.3 % at 41 / 81 nodes against the planar model at 641 nodes."""
    g = UnitGeometry(L=0.1, h=0.01924, t=0.5e-3, w=5e-3, b=5e-3)
    p = simulate_unit(g, nodes=641)
    errs = []
    for n in (41, 81):
        r = simulate_unit_3d(g, nodes=n, end_plate="stiff", check_self_standing=False,
                             joints="bond", foot_refinement=1)
        errs.append((r.theta_deg - p.theta_deg, r.F_cr / p.F_cr - 1))
    (dth41, df41), (dth81, df81) = errs
    assert abs(dth81) < 1.0 and abs(df81) < 0.03
    assert 1.6 < dth41 / dth81 < 2.4 and 1.4 < df41 / df81 < 2.4  # O(1/N)


def test_braces_span_each_end_plate(unit):
    g = SPECIMEN
    braces = [r for r in unit.mesh.rods if r.name.startswith("brace")]
    assert len(braces) == 8
    for r in braces:
        assert len(r.xyz) == 2 and r.width[0] == pytest.approx(g.flat_length)
        dx = abs(r.xyz[1, 0] - r.xyz[0, 0])
        assert g.flat_length - g.L / 100 <= dx < g.flat_length
        assert abs(r.xyz[1, 1] - r.xyz[0, 1]) == pytest.approx(1.5 * g.w)


def test_joints_join_coincident_nodes_and_connect_everything(bond_unit):
    mesh = bond_unit.mesh
    X = mesh.positions
    for a, b in mesh.joints + mesh.ties:
        assert a != b
        assert np.array_equal(X[a], X[b])  # bit-identical coordinates
    # one connected assembly (rods through their edges, joints between rods)
    parent = list(range(mesh.n_nodes))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    pairs = list(mesh.joints)
    for r in mesh.rods:
        pairs += list(zip(r.nodes[:-1], r.nodes[1:]))
    for a, b in pairs:
        parent[find(int(a))] = find(int(b))
    assert len({find(i) for i in range(mesh.n_nodes)}) == 1
    # every bar half is jointed to the centre strip, to the other half and to one rail, in
    # both orders (mirror-symmetric coupling)
    names = {int(n): r.name for r in mesh.rods for n in r.nodes}
    for r in mesh.rods:
        if r.name.startswith("bar"):
            partners = sorted({names[b if a in r.nodes else a] for a, b in mesh.joints
                               if a in r.nodes or b in r.nodes})
            side = "left" if "left" in r.name else "right"
            rail = "rail_right" if r.name.endswith("_p") else "rail_left"
            other = r.name[:-1] + ("m" if r.name.endswith("_p") else "p")
            assert partners == sorted([rail, f"centre_{side}", other])
            assert sum(1 for a, b in mesh.joints if a in r.nodes or b in r.nodes) == 6


def test_arch_bonded_over_end_regions_and_raised_through_the_hole(bond_unit):
    g = SPECIMEN
    mesh = bond_unit.mesh
    X = mesh.positions
    arch = bond_unit.arch
    names = {int(n): r.name for r in mesh.rods for n in r.nodes}
    pairs = {tuple(sorted(p)) for p in mesh.joints + mesh.ties
             if {names[int(p[0])][:4], names[int(p[1])][:4]} == {"arch", "cent"}}
    bonded = sorted(a if names[a] == "arch" else b for a, b in pairs)
    xa = X[bonded, 0]
    xa_left = np.sort(xa[xa < 0.5 * g.L])
    # bonded from the end to half an edge past x0; x0 is the midpoint of the last bonded edge
    assert xa_left[0] == 0.0
    assert 0.5 * (xa_left[-1] + xa_left[-2]) == pytest.approx(g.flat_length)
    assert len(bonded) == 2 * len(xa_left)
    # orientations coupled (joints) where both neighbouring edges are bonded, ties elsewhere
    jointed = {a for a, b in mesh.joints} | {b for a, b in mesh.joints}
    inner = [n for n in bonded if 0 < X[n, 0] < xa_left[-1] or g.L - xa_left[-1] < X[n, 0] < g.L]
    assert set(inner) <= jointed
    assert not ({n for n in bonded if n not in inner} & jointed)
    raised = X[arch][(X[arch, 0] > xa_left[-1]) & (X[arch, 0] < g.L - xa_left[-1])]
    assert np.allclose(raised[:, 2], g.arch_z(raised[:, 0]), atol=1e-12)
    assert np.all(raised[:, 1] == 0.0)
    assert np.max(X[arch, 2]) == pytest.approx(g.h)
    assert mesh.rod("arch").width == pytest.approx(np.full(len(arch) - 1, g.w))
    # the arch passes through the hole: its raised part is between the rails' inner edges
    assert np.all(np.abs(X[arch, 1]) + 0.5 * g.w <= 1.0 * g.w + 1e-15)


def test_rollers_hold_z_along_a_line_across_the_width(unit):
    g = SPECIMEN
    X = unit.mesh.positions
    fixed = {}
    for n, comps in unit.mesh.fixes:
        fixed.setdefault(n, set()).update(comps)
    z_fixed = np.array([n for n, c in fixed.items() if c == {"z"}])
    xs = np.unique(np.round(X[z_fixed, 0], 12))
    assert xs == pytest.approx([0.03 * g.L, 0.97 * g.L])
    for x in xs:  # every base node on the line x = 0.03 L
        on_line = np.nonzero((np.abs(X[:, 0] - x) < 1e-12) & (X[:, 2] == 0))[0]
        on_line = [n for n in on_line if n not in unit.arch]
        assert set(on_line) <= set(z_fixed.tolist())
        assert np.ptp(X[on_line, 1]) == pytest.approx(4 * g.w - g.w)


def test_actuator_is_a_rigid_segment_of_the_joint_length(unit):
    g = SPECIMEN
    X = unit.mesh.positions
    assert len(unit.mesh.rigid) == 1
    group = [n for n in unit.mesh.rigid[0] if n in set(unit.arch.tolist())]
    assert unit.push_node in group
    assert X[unit.push_node] == pytest.approx([0.5 * g.L, 0.0, g.h])
    assert (unit.push_node, "xy") in unit.mesh.fixes
    # the group spans the joint plus half a straddling edge at each end (arc length)
    seg = X[group]
    arc = np.sum(np.linalg.norm(np.diff(seg, axis=0), axis=1))
    edge = np.linalg.norm(seg[1] - seg[0])
    assert arc == pytest.approx(g.joint_length + edge, rel=0.02)
    assert np.allclose(seg[:, 0] - 0.5 * g.L, -(seg[::-1, 0] - 0.5 * g.L))
    # the head across the arch (holds its roll) moves with the group, jointed at the push node
    head = unit.mesh.groups["actuator_head"]
    assert len(head) == 4 and set(head[[1, 3]].tolist()) <= set(unit.mesh.rigid[0])
    assert np.allclose(X[head[[0, 2]]], X[unit.push_node])
    assert np.ptp(X[head][:, 1]) == pytest.approx(g.w)


def test_mesh_is_mirror_symmetric_and_reproducible(unit):
    g = SPECIMEN
    X = unit.mesh.positions
    mirrored = X * [-1, 1, 1] + [g.L, 0, 0]
    key = {tuple(np.round(p, 12)) for p in X}
    assert all(tuple(np.round(p, 12)) in key for p in mirrored)
    again = build_unit_mesh_3d(SPECIMEN, nodes=101)
    assert np.array_equal(again.mesh.positions, X)
    assert again.mesh.joints == unit.mesh.joints and again.mesh.fixes == unit.mesh.fixes


def test_tilt_rotates_the_raised_arch_about_the_base_axis():
    g = SPECIMEN
    m = build_unit_mesh_3d(g, nodes=61, tilt_deg=5.0)
    X = m.mesh.positions[m.arch]
    top = X[np.argmax(np.hypot(X[:, 1], X[:, 2]))]
    assert math.degrees(math.atan2(top[1], top[2])) == pytest.approx(5.0)
    assert np.hypot(top[1], top[2]) == pytest.approx(g.h)
    n_end = len(m.mesh.groups["centre_left"])  # bonded nodes at each end (flat)
    raised = slice(n_end, len(X) - n_end)
    assert np.allclose(np.hypot(X[raised, 1], X[raised, 2]), g.arch_z(X[raised, 0]), atol=1e-12)
    flat = X[:, 0] <= g.flat_length
    assert np.all(X[flat, 1:] == 0.0)
    # and the lean metric reads it back
    foot = int(np.count_nonzero(m.mesh.groups["centre_left"] >= 0)) - 1
    assert arch_lean_deg(X, g.h, foot, len(X) - 1 - foot) == pytest.approx(5.0)
    assert arch_lean_deg(X * [1, -1, -1], g.h, foot, len(X) - 1 - foot) == pytest.approx(-5.0)


def test_apex_offset_and_actuator_offset():
    g = SPECIMEN
    m = build_unit_mesh_3d(g, nodes=61, apex_offset=1.5 * MM)
    X = m.mesh.positions
    assert X[m.push_node] == pytest.approx([0.5 * g.L, 1.5 * MM, g.h])
    assert np.allclose(X[m.arch, 1], 1.5 * MM * X[m.arch, 2] / g.h)
    m = build_unit_mesh_3d(g, nodes=61, actuator_offset=4 * MM)
    X = m.mesh.positions
    assert X[m.push_node, 0] == pytest.approx(0.5 * g.L + 4 * MM)
    assert X[m.push_node, 2] == pytest.approx(g.arch_z(0.5 * g.L + 4 * MM))
    assert m.push_node in m.mesh.rigid[0]


@pytest.mark.parametrize("kwargs, name", [
    (dict(tilt_deg=60.0), "tilt_deg"), (dict(tilt_deg="x"), "tilt_deg"),
    (dict(tilt_deg=float("nan")), "tilt_deg"), (dict(apex_offset=0.05), "apex_offset"),
    (dict(actuator_offset=0.03), "actuator_offset"), (dict(nodes=10), "nodes"),
    (dict(nodes=50.5), "nodes"), (dict(nu=0.7), "nu"), (dict(bar_divisions=0), "bar_divisions"),
])
def test_bad_input_names_the_parameter(kwargs, name):
    with pytest.raises(ValueError, match=name):
        build_unit_mesh_3d(SPECIMEN, **kwargs)


def test_section_rotation_and_end_tangent_angle_closed_forms():
    # a base line bent into a circular arc of angle phi rising at both ends: theta = phi
    R, phi = 0.05, math.radians(80)
    a = np.linspace(-phi / 2, phi / 2, 201)
    pts = np.stack([R * np.sin(a), np.zeros_like(a), R * (1 - np.cos(a))], 1)
    # (edge directions are the tangents at the edge midpoints, as in the planar unit)
    assert end_tangent_angle(pts) == pytest.approx(80.0 * 199 / 200, rel=1e-12)
    assert end_tangent_angle(pts * [1, 1, -1]) == pytest.approx(-80.0 * 199 / 200, rel=1e-12)
    turned = pts @ np.array([[0.6, 0.8, 0], [-0.8, 0.6, 0], [0, 0, 1]])  # any heading
    assert end_tangent_angle(turned) == pytest.approx(80.0 * 199 / 200, rel=1e-12)
    # rails at y = -/+ 7.5 mm, the right one lifted by 7.5 tan(3 deg) * 2
    x = np.linspace(0, 0.1, 5)
    left = np.stack([x, -7.5e-3 + 0 * x, 0 * x], 1)
    right = np.stack([x, 7.5e-3 + 0 * x, 15e-3 * math.tan(math.radians(3)) + 0 * x], 1)
    assert section_rotation_deg(left, right) == pytest.approx(np.full(5, 3.0))


# --------------------------------------------------------------------------- with the solver
@pytest.fixture(scope="module")
def perfect21():
    _solver()
    from snapmorph.units.unit3d import simulate_unit_3d

    return simulate_unit_3d(SPECIMEN, nodes=21)


def test_perfect_unit_snaps_in_its_plane(perfect21):
    r = perfect21
    assert r.status == "ok" and r.bistable and r.exact_states
    assert 0 < r.d_cr < r.d_unstable < r.d_second
    for state in ("i", "ii", "iii"):
        assert abs(r.arch_tilt_deg[state]) < 1e-6
        assert r.rail_twist_deg[state] < 1e-6
        assert r.arch_lateral[state] < 1e-12
        base = r.shapes[state]["base"]
        # mirror symmetric about mid-span: x -> L - x
        assert np.allclose(base[:, 0] + base[::-1, 0], base[0, 0] + base[-1, 0], atol=1e-9)
        assert np.allclose(base[:, 2], base[::-1, 2], atol=1e-9)
    assert r.theta_deg > 0 and r.S < SPECIMEN.L


def test_identical_inputs_give_identical_outputs(perfect21):
    from snapmorph.units.unit3d import simulate_unit_3d

    again = simulate_unit_3d(SPECIMEN, nodes=21)
    assert np.array_equal(again.curve[0], perfect21.curve[0])
    assert np.array_equal(again.curve[1], perfect21.curve[1])
    assert again.F_cr == perfect21.F_cr and again.theta_deg == perfect21.theta_deg


def test_tilt_knocks_down_F_cr_and_is_mirror_symmetric(perfect21):
    from snapmorph.units.unit3d import simulate_unit_3d

    plus = simulate_unit_3d(SPECIMEN, nodes=21, tilt_deg=5.0)
    minus = simulate_unit_3d(SPECIMEN, nodes=21, tilt_deg=-5.0)
    assert plus.status == "ok" and minus.status == "ok"
    assert plus.F_cr < perfect21.F_cr
    # a tilt to -y is the mirror image of a tilt to +y
    assert minus.F_cr == pytest.approx(plus.F_cr, rel=1e-6)
    assert minus.theta_deg == pytest.approx(plus.theta_deg, rel=1e-6)
    for state in ("i", "iii"):
        assert minus.arch_tilt_deg[state] == pytest.approx(-plus.arch_tilt_deg[state], rel=1e-5)
    assert plus.arch_tilt_deg["i"] > 5.0  # the push makes the leaning arch lean further
    assert plus.rail_twist_deg["i"] > 1e-3  # and twists the frame


@pytest.mark.slow
def test_stiff_end_plates_reproduce_the_planar_model():
    """With end plates that keep their shape across the width (the planar model's
    assumption) the 3-D unit agrees with the planar model (issue 14: 3 % in F_cr, 1 deg in
    theta; measured -2.2 % and +0.8 deg at 81 nodes)."""
    _solver()
    from snapmorph.units import simulate_unit
    from snapmorph.units.unit3d import simulate_unit_3d

    g = UnitGeometry(L=99.5 * MM, h=19.24 * MM, t=0.5 * MM, w=5 * MM, b=5 * MM)
    planar = simulate_unit(g)
    r = simulate_unit_3d(g, nodes=81, end_plate="stiff")
    assert r.F_cr == pytest.approx(planar.F_cr, rel=0.03)
    assert r.theta_deg == pytest.approx(planar.theta_deg, abs=1.0)
    assert r.d_second == pytest.approx(planar.d_second, rel=0.03)


@pytest.mark.slow
def test_elastic_end_plates_lower_F_cr_by_bending_near_the_bond():
    """The mechanism the planar model lacks: the 0.5 mm end plates bend across their width
    next to the bond, which lowers F_cr by ~15 % (measured at 41 and 81 nodes: -15.4 %,
    -16.6 %); stiffening the plates removes it."""
    _solver()
    from snapmorph.units.unit3d import simulate_unit_3d

    g = UnitGeometry(L=99.5 * MM, h=19.24 * MM, t=0.5 * MM, w=5 * MM, b=5 * MM)
    elastic = simulate_unit_3d(g, nodes=41)
    stiff = simulate_unit_3d(g, nodes=41, end_plate="stiff")
    assert elastic.F_cr < 0.9 * stiff.F_cr
    assert elastic.theta_deg > stiff.theta_deg + 2.0


def test_cli_unit3d_reports_and_writes_json(tmp_path, capsys):
    _solver()
    import json

    from snapmorph.cli import main

    out = tmp_path / "u.json"
    assert main(["unit3d", "--L", "100", "--h", "20", "--t", "0.5", "--w", "5", "--b", "5",
                 "--nodes", "21", "--tilt", "2", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["status"] == "ok" and data["imperfection_tilt_deg"] == 2.0
    assert data["F_cr"] > 0 and data["arch_tilt_deg_i"] > 2.0
    assert data["self_standing"] is True and 0 < data["S_released"] < 0.1
    assert data["arch_tilt_deg_released"] > 2.0 and data["reason"] == ""
    out = capsys.readouterr().out
    assert "theta released" in out and "rail twist (released)" in out


# --------------------------------------------------------------------------- issue 14: the
# crossing rule, the stability of state (iii), the released state (no solver needed first)
def _old_rule(F):
    """The rule units/push3d.py used before: (ii) the first change of sign of F from >= 0 to
    < 0 after the peak, (iii) the next one from <= 0 to > 0, whatever the slope."""
    i_pk = next(i for i in range(1, len(F) - 1) if F[i] > 0 and F[i] >= F[i - 1]
                and F[i] > F[i + 1])
    j = next(i for i in range(i_pk + 1, len(F)) if F[i - 1] >= 0.0 > F[i])
    k = next(i for i in range(j + 1, len(F)) if F[i - 1] <= 0.0 < F[i])
    return j, k


#: a push that snaps back: F falls through zero as d grows (ii), the path turns back in d
#: and F rises through zero while d shrinks (slope dF/dd < 0: unstable), F falls through zero
#: while d still shrinks (slope > 0: the second stable state, at d = 2.25), then both grow
SNAP_BACK_D = np.array([0.0, 1.0, 2.0, 3.0, 2.5, 2.0, 4.0])
SNAP_BACK_F = np.array([0.0, 1.0, -1.0, -0.5, 0.5, -0.5, 1.0])


def test_zero_crossings_are_classified_by_slope_on_a_path_that_snaps_back():
    import snapmorph.units.planar as planar
    from snapmorph.units import push3d

    # one rule for every unit: push3d uses the planar unit's helpers, no copies of its own
    assert push3d._zero_crossings is planar._zero_crossings
    assert push3d._first_peak is planar._first_peak
    assert not hasattr(push3d, "first_crossing") and not hasattr(push3d, "first_peak")
    i_pk, j, k = push3d.snap_crossings(SNAP_BACK_D, SNAP_BACK_F)
    assert (i_pk, j, k) == (1, 2, 5)
    # the old rule took the unstable crossing on the way back (d from 3 to 2.5) for (iii)
    assert _old_rule(SNAP_BACK_F) == (2, 4)
    # and the push stops after the stable crossing, not at the first rise of F through zero
    stops = [push3d._stop_at_second_state({"d": list(SNAP_BACK_D[:n]),
                                            "F": list(SNAP_BACK_F[:n])})
             for n in range(3, len(SNAP_BACK_F) + 1)]
    assert stops == [False, False, False, True, True]


class _ReplayPath:
    def __init__(self, d, F):
        self.displacement, self.force = np.asarray(d, float), np.asarray(F, float)
        self.positions = np.zeros((len(d), 1, 3))
        self.positions[:, 0, 2] = -self.displacement  # one node, pushed down by d
        self.fields, self.status = {}, "ok"


class _ReplayStructure:
    """One node whose push replays a given F–d curve up to where the stop test ends it; every
    state is an equilibrium (solve_equilibrium returns its guess)."""

    def __init__(self, d, F):
        self.d, self.F = d, F

    def initial_state(self):
        return np.zeros(3)

    def push(self, node, direction, distance, method, stop, steps, critical, **options):
        for n in range(3, len(self.F) + 1):
            if stop({"d": list(self.d[:n]), "F": list(self.F[:n])}):
                break
        return _ReplayPath(self.d[:n], self.F[:n])

    def solve_equilibrium(self, q, node=None):
        q = np.asarray(q, float)
        return q.reshape(-1, 3), {"state": q}

    def reduced_system(self):
        return None


def test_push_through_finds_the_second_state_of_a_path_that_snaps_back(monkeypatch):
    from snapmorph.solver.stability import StateStability
    from snapmorph.units import push3d

    monkeypatch.setattr(push3d, "_state_stability",
                        lambda st, q, node, system: StateStability(0, 0))
    out = push3d.push_through(_ReplayStructure(SNAP_BACK_D, SNAP_BACK_F), 0, 10.0)
    assert out.status == "ok" and out.bistable and out.exact_states
    assert out.d_unstable == pytest.approx(1.5)  # between d = 1 and 2
    assert out.d_second == pytest.approx(2.25)  # the old rule: 2.75, an unstable state
    assert len(out.curve[1]) == 6  # stopped after the stable crossing


def test_released_model_shares_the_rods_and_its_supports_hold_only_rigid_motion():
    from snapmorph.units.unit3d import released_supports

    act = build_unit_mesh_3d(SPECIMEN, nodes=41)
    free = build_unit_mesh_3d(SPECIMEN, nodes=41, actuator=False, supports=False)
    assert not free.mesh.rigid and not free.mesh.fixes
    heads = [r.name for r in act.mesh.rods if r.name.startswith("actuator_head")]
    kept = [r.name for r in act.mesh.rods if r.name not in heads]
    assert kept == [r.name for r in free.mesh.rods]
    n = free.mesh.n_nodes
    assert np.array_equal(act.mesh.positions[:n], free.mesh.positions)
    assert_supports_hold_only_rigid_motion(free.mesh.positions, released_supports(free))


def test_perfect_unit_released_state(perfect21):
    r = perfect21
    assert r.self_standing is True and r.stability["released"] == 0
    assert r.stability["iii"].negative_force == 0 and r.stability["ii"].negative_force >= 1
    rel = r.released
    assert np.isfinite(r.S_released) and np.isfinite(r.theta_released_deg)
    assert rel["first_negative_eigenvalues"] == 0 and 0 < rel["moved"] < 0.25 * SPECIMEN.h
    # released, the base uncurls a little: the actuator held the arch's tangent at the apex
    assert r.theta_deg - 2.0 < r.theta_released_deg < r.theta_deg
    assert r.S < r.S_released < SPECIMEN.L
    assert abs(rel["arch_tilt_deg"]) < 1e-6 and rel["rail_twist_deg"] < 1e-6
    base = rel["base_shape"]
    assert np.allclose(base[:, 2], base[::-1, 2], atol=1e-9)  # still mirror symmetric
    s = r.summary()
    assert s["self_standing"] is True and s["theta_released_deg"] == r.theta_released_deg
    assert s["S_released"] == r.S_released and "rail_twist_deg_released" in s


def test_released_state_does_not_depend_on_where_the_actuator_was(perfect21):
    """Released, the unit no longer knows where it was pushed: an actuator 4 mm off centre
    changes the actuated theta by 0.83 deg, the released one by 0.08 deg (measured at 21
    nodes; 0.74 and 0.01 deg at 41): what is left is the mesh, which differs a little (the
    arch is meshed around the actuator)."""
    from snapmorph.units.unit3d import simulate_unit_3d

    off = simulate_unit_3d(SPECIMEN, nodes=21, actuator_offset=4 * MM)
    assert off.bistable and off.self_standing
    moved = abs(off.theta_deg - perfect21.theta_deg)
    assert moved > 0.5
    assert abs(off.theta_released_deg - perfect21.theta_released_deg) < 0.2 * moved
    assert off.S_released == pytest.approx(perfect21.S_released, abs=3e-5)


def test_released_state_against_the_planar_model():
    """The paper's specimen at the default resolution: the released state (iii) is
    self-standing, and releasing it turns the base back by about a degree, as in the planar
    model (planar 81.05 -> 79.53 deg, S 91.44 -> 91.63 mm). With stiff end plates (the
    planar model's assumption) the 3-D unit does what the planar one does (measured: 81.26 ->
    79.75 deg, S 91.48 -> 91.67 mm). With the default elastic plates its own theta is ~5.4
    deg above the planar one (see test_elastic_end_plates_lower_F_cr...) and it opens less
    on release (86.45 -> 85.12 deg, S 91.94 -> 92.07 mm): the comparison is of what
    releasing changes. Re-derived for issue 25's default mesh (node joints, feet 8 times
    finer): on the old one (bonds, uniform) the elastic unit's S grew by 0.179 mm, within
    30 % of the planar 0.198 mm, and this test compared the elastic unit; the node joints no
    longer stiffen the end plates across their width, and the elastic S grows by 0.129 mm."""
    _solver()
    from snapmorph.units.planar import simulate_unit
    from snapmorph.units.unit3d import simulate_unit_3d

    p = simulate_unit(SPECIMEN)
    d_theta_p, d_S_p = p.theta_released_deg - p.theta_deg, p.S_released - p.S
    assert p.self_standing and -2.0 < d_theta_p < 0.0
    for plate in ("elastic", "stiff"):
        r = simulate_unit_3d(SPECIMEN, end_plate=plate)
        assert r.bistable and r.self_standing
        d_theta, d_S = r.theta_released_deg - r.theta_deg, r.S_released - r.S
        assert -2.0 < d_theta < 0.0
        assert abs(d_theta - d_theta_p) < 1.0
        assert 0.0 < d_S < 0.5 * MM
    assert d_S == pytest.approx(d_S_p, rel=0.3)  # stiff plates: the planar model's release


@pytest.mark.slow
def test_released_state_of_the_tall_unit():
    """h = 40 mm (measured: 3-D theta 129.08 -> 128.20 deg, S 80.49 -> 80.81 mm; planar
    121.85 -> 120.15 deg, 80.24 -> 80.56 mm)."""
    _solver()
    from snapmorph.units.planar import simulate_unit
    from snapmorph.units.unit3d import simulate_unit_3d

    g = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3, b=5e-3)
    r = simulate_unit_3d(g)
    p = simulate_unit(g)
    assert r.bistable and r.self_standing and p.self_standing
    d_theta, d_theta_p = r.theta_released_deg - r.theta_deg, p.theta_released_deg - p.theta_deg
    assert -2.0 < d_theta < 0.0 and abs(d_theta - d_theta_p) < 1.0
    assert (r.S_released - r.S) == pytest.approx(p.S_released - p.S, rel=0.3)


def test_tilted_unit_released_state_is_mirror_symmetric_in_the_tilt():
    _solver()
    from snapmorph.units.unit3d import simulate_unit_3d

    plus = simulate_unit_3d(SPECIMEN, nodes=21, tilt_deg=5.0)
    minus = simulate_unit_3d(SPECIMEN, nodes=21, tilt_deg=-5.0)
    assert plus.self_standing and minus.self_standing
    assert minus.theta_released_deg == pytest.approx(plus.theta_released_deg, rel=1e-6)
    assert minus.released["arch_tilt_deg"] == pytest.approx(-plus.released["arch_tilt_deg"],
                                                            rel=1e-5)
    assert plus.released["arch_tilt_deg"] > 5.0 and plus.released["rail_twist_deg"] > 0.1


def test_an_unstable_second_state_is_reported_as_such(monkeypatch):
    """No 3-D geometry found keeps a state (iii) with negative eigenvalues, so the report is
    checked by making the stability check of (iii) see two (the planar unit's test)."""
    _solver()
    from snapmorph.units import push3d
    from snapmorph.units.unit3d import simulate_unit_3d

    make_second_state_unstable(monkeypatch, push3d)
    r = simulate_unit_3d(SPECIMEN, nodes=21)
    assert r.status.startswith("second state unstable") and "negative eigenvalue" in r.reason
    assert not r.bistable and math.isnan(r.S) and math.isnan(r.theta_deg)
    assert r.self_standing is None and not r.released and math.isnan(r.S_released)
    assert np.isfinite(r.F_cr) and np.isfinite(r.d_second) and "iii" in r.shapes


@pytest.mark.parametrize("kwargs, name", [
    (dict(steps=0), "steps"), (dict(steps=2.5), "steps"), (dict(critical="yes"), "critical"),
    (dict(check_self_standing=1), "check_self_standing"), (dict(nodes=10), "nodes"),
    (dict(tilt_deg=90.0), "tilt_deg"), (dict(nu="x"), "nu"),
])
def test_simulate_bad_input_names_the_parameter(kwargs, name):
    from snapmorph.units.unit3d import simulate_unit_3d

    with pytest.raises(ValueError, match=name):
        simulate_unit_3d(SPECIMEN, **kwargs)
    with pytest.raises(ValueError, match="UnitGeometry"):
        simulate_unit_3d("not a geometry")
