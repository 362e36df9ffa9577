"""The 3-D unit's mesh options of issue 25: ``joints="node"`` (the rods meeting at a node hang
off one node frame, `units.junctions3d`) and ``foot_refinement`` (short edges at the arch
feet): meshes, errors, symmetry and the mesh convergence they buy (docs/unit3d.md, "The
default mesh against the converged theta")."""

from __future__ import annotations

import numpy as np
import pytest

from snapmorph.units.frame3d import UnitGeometry
from snapmorph.units.unit3d import build_unit_mesh_3d, simulate_unit_3d

SPECIMEN = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
TALL = UnitGeometry(L=0.1, h=0.04068, t=0.5e-3, w=5e-3, b=5e-3)  # Table 1, h = 40.68 mm


@pytest.mark.parametrize("options,name", [
    (dict(joints="pairs"), "joints"), (dict(joints=None), "joints"),
    (dict(foot_refinement=0), "foot_refinement"), (dict(foot_refinement=2.0), "foot_refinement"),
    (dict(foot_refinement=True), "foot_refinement"), (dict(foot_refinement=65), "foot_refinement"),
])
def test_bad_options_name_the_parameter(options, name):
    with pytest.raises(ValueError, match=name):
        build_unit_mesh_3d(SPECIMEN, **options)
    with pytest.raises(ValueError, match=name):
        simulate_unit_3d(SPECIMEN, **options)


@pytest.mark.parametrize("k", [2, 4, 8])
def test_foot_refinement_grades_the_edges_at_the_arch_feet(k):
    g = SPECIMEN
    spacing = g.L / 40
    m = build_unit_mesh_3d(g, nodes=41, foot_refinement=k)
    x = m.mesh.rod("rail_left").xyz[:, 0]
    e = np.diff(x)
    x0 = g.flat_length
    i = int(np.argmin(np.abs(0.5 * (x[:-1] + x[1:]) - x0)))
    assert 0.5 * (x[i] + x[i + 1]) == pytest.approx(x0, rel=1e-12)  # x0 mid-edge, as before
    assert e[i] == pytest.approx(spacing / k, rel=1e-12)
    assert np.all(e <= spacing * (1 + 1e-9))
    assert np.all(e[1:] / e[:-1] <= 2.0 * (1 + 1e-9)) and np.all(e[:-1] / e[1:] <= 2.0 * (1 + 1e-9))
    assert x + x[::-1] == pytest.approx(np.full_like(x, g.L), abs=1e-15)  # mirror symmetric
    widths = [r.width[0] for r in m.mesh.rods if r.name.startswith("bar_left") and
              r.name.endswith("_m")]
    assert np.sum(widths) == pytest.approx(x0)
    # the default mesh is foot_refinement=8 (issue 25; before it: 1, the uniform mesh)
    plain = build_unit_mesh_3d(g, nodes=41)
    assert np.array_equal(build_unit_mesh_3d(g, nodes=41, foot_refinement=8).mesh.positions,
                          plain.mesh.positions)


def test_node_joints_replace_the_bar_bonds_by_junctions():
    g = SPECIMEN
    bond = build_unit_mesh_3d(g, nodes=41, joints="bond")
    node = build_unit_mesh_3d(g, nodes=41)  # the default since issue 25
    assert node.junctions == build_unit_mesh_3d(g, nodes=41, joints="node").junctions
    assert np.array_equal(node.mesh.positions, bond.mesh.positions)
    assert not bond.junctions
    names = {int(n): r.name for r in node.mesh.rods for n in r.nodes}
    X = node.mesh.positions
    for nodes in node.junctions:
        assert np.ptp(X[nodes], axis=0).max() < 1e-12
        assert names[nodes[0]].startswith(("rail", "centre"))
    # no pair joint left between a bar and anything (only the actuator head's)
    for a, b in node.mesh.joints:
        assert "bar" not in names[a] + names[b] and "brace" not in names[a] + names[b]
    assert len(node.mesh.joints) < len(bond.mesh.joints)


def test_node_joints_keep_the_perfect_unit_in_its_plane():
    r = simulate_unit_3d(SPECIMEN, nodes=21, joints="node")
    assert r.status == "ok" and r.bistable and r.self_standing
    for state in ("i", "ii", "iii"):
        assert r.arch_lateral[state] < 1e-12
        base = r.shapes[state]["base"]
        assert np.allclose(base[:, 2], base[::-1, 2], atol=1e-9)
    again = simulate_unit_3d(SPECIMEN, nodes=21, joints="node")
    assert again.F_cr == r.F_cr and again.theta_deg == r.theta_deg


def _theta(nodes, **options):
    return simulate_unit_3d(TALL, nodes=nodes, check_self_standing=False, **options).theta_deg


@pytest.mark.slow
def test_graded_feet_converge_the_stiff_plates_at_a_coarse_mesh():
    """Stiff plates, h = 40.68 mm, with the bonds (joints="bond"): uniform meshes move theta by 0.73 deg from 41 to 81 nodes
    (124.16 / 123.44 deg; about 122.75 converged), edges 4 (8) times shorter at the feet by
    0.24 deg (123.06 / 122.82 deg; 122.79 at 161 nodes with 16)."""
    uniform = [_theta(n, end_plate="stiff", joints="bond", foot_refinement=1) for n in (41, 81)]
    graded = [_theta(n, end_plate="stiff", joints="bond", foot_refinement=k)
              for n, k in ((41, 4), (81, 8))]
    assert uniform[0] - uniform[1] > 0.6
    assert 0 < graded[0] - graded[1] < 0.3
    assert abs(graded[0] - uniform[1]) < abs(uniform[0] - uniform[1])


@pytest.mark.slow
def test_node_joints_and_graded_feet_converge_both_plates_at_the_default_mesh():
    """h = 40.68 mm: with the bonds and a uniform mesh, elastic plates move theta by 0.66 deg
    from 41 to 81 nodes (129.66 / 130.32 deg); with joints="node" and foot_refinement=8 by
    0.12 deg (129.78 / 129.90; about 130.1 converged), stiff plates by 0.15 deg (123.08 /
    122.93; about 122.75 converged)."""
    bond = [_theta(n, joints="bond", foot_refinement=1) for n in (41, 81)]
    assert bond[1] - bond[0] > 0.5
    for plate in ("elastic", "stiff"):
        node = [_theta(n, end_plate=plate, joints="node", foot_refinement=8) for n in (41, 81)]
        assert abs(node[1] - node[0]) < 0.2


@pytest.mark.slow
@pytest.mark.parametrize("plate", ["elastic", "stiff"])
def test_the_default_mesh_is_within_half_a_degree_of_the_converged_theta(plate):
    """Issue 25: theta (iii) of the default mesh (41 nodes, node joints, feet 8 times finer)
    within 0.5 deg of the same model's converged theta, extrapolated from 41, 81 and 161
    nodes (each mesh half the last's spacing) with their own ratio of differences r, so at
    the order they show (limit = theta_161 + (theta_161 - theta_81) r / (1 - r)). Measured at
    h = 40.68 mm: elastic 129.781 / 129.905 / 129.986 deg, r = 0.65 (order 0.6), limit
    130.14 (-0.36 deg); stiff 123.077 / 122.926 / 122.865, r = 0.41, limit 122.82 (+0.25
    deg). The old default (bonds, uniform) fails it: -1.07 deg (elastic), +1.39 deg (stiff)."""
    default, n81, n161 = (_theta(n, end_plate=plate) for n in (None, 81, 161))
    r = (n161 - n81) / (n81 - default)
    assert 0.0 < r < 0.75  # monotone and converging: the extrapolation's tail is bounded
    converged = n161 + (n161 - n81) * r / (1.0 - r)
    assert abs(default - converged) < 0.5


def test_the_release_reuses_the_junction_fit_of_the_pushed_mesh():
    """The fit is done once per mesh (`Unit3DModel.junction_pairs`); the released unit's mesh
    (no actuator, no rollers) has the same junction rods, so the pushed mesh's fit is its own."""
    from snapmorph.units.junctions3d import junction_pairs

    pushed = build_unit_mesh_3d(SPECIMEN, nodes=21, tilt_deg=2.0)
    pushed.to_structure()
    free = build_unit_mesh_3d(SPECIMEN, nodes=21, tilt_deg=2.0, actuator=False, supports=False)
    assert free.junctions == pushed.junctions
    st = free.mesh.to_structure()
    assert [junction_pairs(st, nodes) for nodes in free.junctions] == pushed.junction_pairs
