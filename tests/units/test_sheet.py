"""Sheets tiled from 2-D units (`units.sheet`, `units.sheet_mesh`): the tilings' topology,
input checks, a 1 x 1 sheet against the 2-D unit, and a 3 x 3 sheet snapped cell by cell
with every released state checked as an equilibrium and its stability checked by the
eigenvalues of its reduced stiffness (dense, numpy), independently of the LDL^T count."""

import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

from snapmorph.units.frame3d import UnitGeometry
from snapmorph.units.sheet import (apex_heights, build_sheet, explore_orders, shape_distance,
                                   sheet_structure, simulate_sheet)
from snapmorph.units.unit2d import edge_metrics, simulate_unit_2d

G = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)


def _lowest_eigenvalues(band, k=6):
    """The k eigenvalues nearest zero of the symmetric K in lower band storage
    (``band[i, j] = K[j + i, j]``), by ARPACK shift-invert about 0 on scipy's own sparse
    matrix: independent of both LDL^T factorisations."""
    n = band.shape[1]
    lower = scipy.sparse.diags([band[i, : n - i] for i in range(band.shape[0])],
                               [-i for i in range(band.shape[0])], shape=(n, n), format="csc")
    K = lower + scipy.sparse.triu(lower.T, k=1)
    vals = scipy.sparse.linalg.eigsh(K.tocsc(), k=k, sigma=0.0, which="LM",
                                     return_eigenvectors=False)
    return np.sort(vals)


@pytest.mark.parametrize("tiling, cells, n_edges, interior", [
    ("square", (3, 3), 24, 12), ("square", (1, 1), 4, 0), ("hexagon", (2, 2), 19, 5),
    ("triangle", (2, 3), 13, 5), ("square", 6, 17, 7)])
def test_tilings_share_their_edge_strips(tiling, cells, n_edges, interior):
    sheet = build_sheet(G if tiling != "triangle" else UnitGeometry(L=0.1, h=0.02, t=0.5e-3,
                                                                   w=5e-3),
                        tiling, cells, nodes=11)
    assert len(sheet.edge_nodes) == n_edges
    assert sum(len(c) == 2 for c in sheet.edge_cells) == interior
    assert all(len(c) in (1, 2) for c in sheet.edge_cells)
    sides = {"square": 4, "triangle": 3, "hexagon": 6}[tiling]
    assert all(len(e) == sides for e in sheet.edges)
    # the released structure has no rigid-body mode: K at the stress-free state is definite
    st = sheet_structure(sheet)
    system = st.reduced_system()
    system.evaluate(st.initial_state())
    assert system.factor() and system.negative_eigenvalues == 0
    assert _lowest_eigenvalues(system.band, 1)[0] > 0
    assert np.allclose(apex_heights(sheet, sheet.mesh.positions), sheet.geometry.h)


def test_a_rigid_motion_of_a_state_keeps_its_energy_and_its_equilibrium():
    """`rigid_motion` turns positions and material frames together: the energy of a strained
    state is unchanged under proper rotations (to round-off), and an equilibrium stays one;
    turning the positions alone (the twists as they were) changes the energy."""
    from snapmorph.units.sheet import placed_for_push, rigid_motion

    sheet = build_sheet(G, "square", (1, 2), nodes=11)
    st = sheet_structure(sheet)
    system = st.reduced_system()
    q = np.array(st.initial_state(), dtype=float)
    rng = np.random.default_rng(11)
    system.increment(q, rng.standard_normal(system.n), 3e-4)  # strained, twisted
    system.reset_frames()
    energy = system.evaluate(q)
    assert energy > 1e-6
    n3 = 3 * st.n_nodes
    for _ in range(3):
        R = np.linalg.qr(rng.standard_normal((3, 3)))[0]
        R *= np.sign(np.linalg.det(R))
        moved = rigid_motion(system, q, R, rng.standard_normal(3))
        system.reset_frames()
        assert system.evaluate(moved) == pytest.approx(energy, rel=1e-9)
        naive = q.copy()
        naive[:n3] = (q[:n3].reshape(-1, 3) @ R.T).ravel()
        system.reset_frames()
        assert abs(system.evaluate(naive) - energy) > 1e-3 * energy
    # an equilibrium (the stress-free state, turned) placed for a push: feet where made
    tilted = rigid_motion(system, np.array(st.initial_state(), dtype=float),
                          np.array([[1.0, 0.0, 0.0], [0.0, 0.6, -0.8], [0.0, 0.8, 0.6]]),
                          np.array([0.1, 0.0, 0.2]))
    placed = placed_for_push(sheet, st, tilted, 1)
    assert np.allclose(st.positions_of(placed), sheet.mesh.positions, atol=1e-12)


@pytest.mark.parametrize("tiling", ["square", "triangle", "hexagon"])
def test_apex_heights_are_a_property_of_the_shape_not_of_its_placement(tiling):
    """A cell's apex height is measured along its own normal: a sheet turned over (a proper
    rotation by 180 degrees about an in-plane axis) or rolled on its side keeps every
    height, and a cell whose apex sits below its sides' plane reads negative, in any
    placement (the global z alone read a turned-over sheet's as-made cells as snapped)."""
    sheet = build_sheet(G, tiling, (2, 2), nodes=11)
    X = np.array(sheet.mesh.positions, dtype=float)
    # a made-up shape: every other cell's apex pushed through to -h/2, the sheet bent
    P = X.copy()
    for k in range(0, sheet.n_cells, 2):
        P[sheet.apex[k], 2] = -0.5 * G.h
    P[:, 2] += 0.5 * (P[:, 0] - P[:, 0].mean()) ** 2  # a curvature of 1 / m along x
    h = apex_heights(sheet, P)
    assert np.all(h[0::2] < 0.0) and np.all(h[1::2] > 0.0)
    rng = np.random.default_rng(7)
    for R in (np.diag([1.0, -1.0, -1.0]),  # turned over
              np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),  # on its side
              np.linalg.qr(rng.standard_normal((3, 3)))[0]):
        R = R * np.sign(np.linalg.det(R))  # proper rotations only
        moved = P @ R.T + np.array([0.3, -0.1, 0.2])
        assert np.allclose(apex_heights(sheet, moved), h, atol=1e-12)
    # and on a flat sheet, as made, the height above the midpoints' mean is h
    assert np.allclose(apex_heights(sheet, X + 1.0), G.h)


@pytest.mark.parametrize("kwargs, match", [
    ({"tiling": "pentagon"}, "tiling must be one of"),
    ({"cells": (0, 3)}, "cells must be"),
    ({"cells": 1000}, r"cells \(number of cells\)"),
    ({"cells": "3x3"}, "cells must be"),
    ({"nodes": 5}, r"nodes \(resolution"),
])
def test_bad_sheets_are_refused_naming_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        build_sheet(G, **{"tiling": "square", "cells": (2, 2), **kwargs})


def test_bad_orders_and_boundaries_are_refused():
    sheet = build_sheet(G, "square", (2, 2), nodes=11)
    with pytest.raises(ValueError, match=r"order must be .* in \[0, 3\]"):
        simulate_sheet(sheet, [4])
    with pytest.raises(ValueError, match="order must be"):
        simulate_sheet(sheet, [])
    with pytest.raises(ValueError, match="boundary must be one of"):
        simulate_sheet(sheet, [0], boundary="pinned")
    with pytest.raises(ValueError, match="distinct"):
        explore_orders(sheet, [0, 0], orders=2)


def test_shape_distance_ignores_rigid_motion():
    X = np.random.default_rng(0).normal(size=(50, 3))
    c, s = np.cos(0.3), np.sin(0.3)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    assert shape_distance(X, X @ R.T + [1.0, 2.0, 3.0]) < 1e-12
    Y = X.copy()
    Y[0] += [0.0, 0.0, 0.1]
    assert 0.05 < shape_distance(X, Y) <= 0.1


@pytest.mark.slow
def test_one_by_one_square_sheet_is_the_2d_unit():
    """F_cr and every side's curvature in state (iii) within 1 % of `simulate_unit_2d`
    (same mesh resolution; the sheet's rods are numbered and oriented differently)."""
    unit = simulate_unit_2d(G, nodes=21, check_self_standing=False)
    sheet = build_sheet(G, "square", (1, 1), nodes=21)
    step = simulate_sheet(sheet, [0]).final
    assert step.push_status == "ok" and unit.status == "ok"
    assert step.F_cr == pytest.approx(unit.F_cr, rel=0.01)
    sides = ("south", "east", "north", "west")  # edges 0-3 of the 1 x 1 tiling
    for e, side in enumerate(sides):
        k = edge_metrics(step.pushed[sheet.edge_nodes[e]])["curvature"]
        assert k == pytest.approx(unit.edges["iii"][side]["curvature"], rel=0.01), side
    assert step.snapped.tolist() == [True] and step.stable


@pytest.fixture(scope="module")
def snapped_3x3():
    """The centre, then two opposite corners (all nine cells: bench/bench_sheet.py; the
    mesh convergence of the final shape: studies/sheets.py, docs/sheets.md)."""
    sheet = build_sheet(G, "square", (3, 3), nodes=21)
    return sheet, simulate_sheet(sheet, [4, 0, 8])


@pytest.mark.slow
def test_3x3_sheet_every_step_is_an_equilibrium_with_its_stability_checked(snapped_3x3):
    sheet, result = snapped_3x3
    st = sheet_structure(sheet)
    system = st.reduced_system()
    length = st.scales()[0]
    assert len(result.steps) == 3
    for step in result.steps:
        assert np.isfinite(step.F_cr), step
        # an equilibrium under no load: the Newton correction from it is below 1e-9 L (the
        # drivers converge on 1e-11 L; the stiff stretching terms keep the residual itself
        # at round-off of their forces)
        system.evaluate(step.state)
        assert system.factor()
        assert np.max(np.abs(system.solve(system.grad))) <= 1e-9 * length
        system.evaluate(step.state)
        eig = _lowest_eigenvalues(system.band)  # the 6 nearest zero, where a snap shows
        assert step.stable == (eig[0] > 0)
        if step.stable:
            assert step.negative_eigenvalues == 0
        else:
            assert step.negative_eigenvalues == int(np.sum(eig < 0))
        assert step.snapped[step.cell] or not step.stable
    assert result.final is result.steps[-1]
    assert result.final.stable


@pytest.mark.slow
def test_3x3_sheet_snaps_the_pushed_cells(snapped_3x3):
    sheet, result = snapped_3x3
    first = result.steps[0]
    assert first.cell == 4 and first.snapped[4]
    assert np.isfinite(first.F_cr) and first.F_cr > 0
    assert first.d.shape == first.F.shape and first.positions.shape == (sheet.mesh.n_nodes, 3)
    heights = apex_heights(sheet, result.final.positions)
    assert np.array_equal(heights < 0, result.final.snapped)


def test_fast_prediction_sums_the_unit_curvatures_of_the_snapped_cells():
    from snapmorph.units.sheet import predict_edge_curvatures

    sheet = build_sheet(G, "square", (1, 2), nodes=11)  # cells 0 | 1, sharing one edge
    k = np.array([1.0, 2.0, 3.0, 4.0])  # south, east, north, west of a unit
    shared = set(sheet.edges[0]) & set(sheet.edges[1])
    assert len(shared) == 1
    (e,) = shared
    p = predict_edge_curvatures(sheet, [True, False], k)
    assert p[e] == 2.0  # cell 0's east side
    assert p[sheet.edges[1][0]] == 0.0  # cell 1's south: not snapped
    p = predict_edge_curvatures(sheet, [True, True], k)
    assert p[e] == 2.0 + 4.0  # cell 0's east plus cell 1's west
    assert np.count_nonzero(p) == len(p)


@pytest.mark.slow
def test_explore_orders_runs_every_order_and_groups_the_finals():
    sheet = build_sheet(G, "square", (1, 2), nodes=21)
    out = explore_orders(sheet, [0, 1], orders=2)
    assert out["orders"] == [[0, 1], [1, 0]]
    assert len(out["results"]) == 2 and out["distances"].shape == (2, 2)
    d = out["distances"][0, 1]
    grouped = sum(len(g["orders"]) for g in out["groups"])
    assert grouped == 2
    assert len(out["groups"]) == (1 if d <= 0.01 * G.L else 2)
    for g in out["groups"]:
        final = out["results"][g["orders"][0]].final
        assert g["snapped"] == np.flatnonzero(final.snapped).tolist()
        assert g["stable"] == final.stable
    assert out["distinct"] == sum(g["stable"] for g in out["groups"])


@pytest.mark.slow
def test_explore_orders_pushes_a_shared_prefix_once_with_the_same_bits():
    """Orders that begin alike share those steps, and the orders run one after the other
    on one released structure: the results are bit-identical to running each order alone
    (`simulate_sheet`), with fewer pushes."""
    sheet = build_sheet(G, "square", (1, 2), nodes=21)
    out = explore_orders(sheet, [0, 1], orders=[[0, 1], [1, 0], [0, 1]])
    assert out["pushes"] == 4  # [0], [0, 1], [1], [1, 0]: the third order pushes nothing
    assert out["results"][2].final is out["results"][0].final
    for i in (0, 1):
        alone = simulate_sheet(sheet, out["orders"][i])
        for a, b in zip(out["results"][i].steps, alone.steps):
            assert np.array_equal(a.state, b.state) and a.F_cr == b.F_cr


def test_a_step_cut_short_or_a_failed_release_is_not_complete():
    """A released shape reached through a push stopped at its step cap (or a release that
    found no stable state) is where the protocol let go, not a result of the sheet:
    `SheetStep.complete` / `SheetResult.complete` say so, and explore_orders counts the
    shapes reached by complete orders apart ("distinct_complete")."""
    import dataclasses

    from snapmorph.units.sheet import SheetResult, SheetStep

    z = np.zeros(1)

    def step(status, stable=True, reason=""):
        return SheetStep(0, z, z, 1.0, status, np.zeros(1, bool), stable, 0, False, z, z, z,
                         0.0, reason, 0.0, z)

    assert step("ok").complete and step("monostable: F does not fall below zero").complete
    assert step("second state unstable: x").complete
    assert not step("not converged: stopped: more than 300 steps").complete
    assert not step("timeout: wall-time limit").complete
    assert not step("ok", stable=False).complete
    assert not step("ok", reason="no stable equilibrium found without the actuator").complete
    r = SheetResult(None, "free", [0, 1], [step("ok"), step("ok")])
    assert r.complete
    assert not dataclasses.replace(r, steps=[step("ok"), step("not converged: x")]).complete
    assert not SheetResult(None, "free", []).complete


@pytest.mark.slow
def test_steps_after_a_release_without_equilibrium_are_not_run(monkeypatch):
    """A release that finds no equilibrium leaves the pushed state, which no later push can
    start from: the order's later steps are recorded as not run (a failure, not complete),
    carrying that state on, in `simulate_sheet` and in `explore_orders` alike."""
    import snapmorph.units.sheet as sheet_module

    calls = []

    def no_release(st, q, max_iter=400, descent=None):
        calls.append(1)
        return None, None, float("nan"), "no stable equilibrium found (test)", None

    monkeypatch.setattr(sheet_module, "relax_released", no_release)
    sheet = build_sheet(G, "square", (1, 2), nodes=11)
    r = simulate_sheet(sheet, [0, 1])
    first, second = r.steps
    assert not first.equilibrium and not first.complete
    assert second.push_status.startswith("not converged: not run")
    assert not second.complete and not r.complete and not second.equilibrium
    assert np.array_equal(second.state, first.state) and len(calls) == 1
    out = explore_orders(sheet, [0, 1], orders=[[0, 1]])
    assert out["results"][0].steps[1].push_status.startswith("not converged: not run")
    assert len(calls) == 2 and out["distinct_complete"] == 0
