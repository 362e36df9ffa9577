"""The load-bearing metrics of the planar unit (issue 23): F_min against displacement-controlled
paths, the snap-back load against a direct push of the released unit, the released stiffness
against finite differences, the surface strain against the path's own curvature and its
scaling with t."""

from __future__ import annotations

import math

import numpy as np
import pytest

from snapmorph.solver.states import DisplacementProbe
from snapmorph.units import UnitGeometry, simulate_unit
from snapmorph.units.geometry import build_unit
from snapmorph.units.metrics import UP, on_rollers, strain_place, surface_strain

#: relative accuracy of a solved force: Newton's residual tolerance (1e-9 of the force
#: scale EI/L^2) with room for the two solves compared
FORCE_TOL = 1e-8
#: off the maps' grids (h/L 0.237, t/L 0.0061, w/L 0.043, b/L 0.021)
OFF_GRID = dict(L=0.1, h=0.0237, t=0.61e-3, w=4.3e-3, b=2.1e-3)


@pytest.fixture(scope="module")
def off_grid():
    g = UnitGeometry(**OFF_GRID)
    return g, simulate_unit(g)


def _full_positions(model, shape):
    pos = np.zeros((model.structure.n_nodes, 2))
    pos[model.arch_nodes], pos[model.base_nodes] = shape["arch"], shape["base"]
    return pos


def test_the_metrics_exist_with_their_units_on_a_bistable_unit(off_grid):
    g, r = off_grid
    assert r.status == "ok" and r.self_standing
    assert r.F_min < 0 < r.F_back and r.d_cr < r.d_Fmin < r.d_second
    assert r.stiffness_released > 0 and 0 < r.strain_max_released <= r.strain_max < 0.1
    assert r.strain_where.startswith(("arch, ", "base, "))
    s = r.summary()
    for k in ("F_min", "d_Fmin", "F_back", "stiffness_released", "strain_max",
              "strain_max_released", "strain_where"):
        assert k in s


def test_a_monostable_unit_has_no_F_min_nor_snap_back_load():
    r = simulate_unit(UnitGeometry(L=0.1, h=0.001, t=0.5e-3, w=5e-3))
    assert r.status == "monostable"
    assert math.isnan(r.F_min) and math.isnan(r.F_back) and math.isnan(r.stiffness_released)
    assert math.isnan(r.strain_max_released) and r.strain_max > 0


@pytest.mark.parametrize("geometry", [OFF_GRID, dict(L=0.1, h=0.0313, t=0.71e-3, w=5e-3, b=0.0)])
def test_F_min_against_a_displacement_controlled_path(geometry):
    g = UnitGeometry(**geometry)
    r = simulate_unit(g)
    rig = simulate_unit(g, method="displacement", steps=400, check_self_standing=False)
    d, F = rig.curve
    i = int(np.argmin(F))
    # the rig's finest sample lies above the minimum (by at most F'' (spacing)^2 / 8), up to
    # the forces' own accuracy: Newton stops at residuals of 1e-9 of the force scale
    assert r.F_min <= F[i] + FORCE_TOL * abs(F[i])
    assert r.F_min == pytest.approx(F[i], rel=2e-4)
    assert r.d_Fmin == pytest.approx(d[i], abs=2.0 * (d[i + 1] - d[i - 1]))


def _released_on_rollers(g, r):
    """The released unit on the rollers (actuator off, base middle held in x) and its
    state (iii) there: (model, positions, apex d)."""
    back = build_unit(g, actuator=False)
    back.structure.fix(back.base_mid, "x")
    rel = _full_positions(back, {"arch": r.released["arch"], "base": r.released["base_shape"]})
    start = on_rollers(rel, back.supports, back.structure.reference_positions)
    start, _ = back.structure.solve_equilibrium(start, node=None)
    X = back.structure.reference_positions
    return back, start, float(start[back.apex, 1] - X[back.apex, 1])


def test_F_back_against_a_direct_push_of_the_released_unit(off_grid):
    g, r = off_grid
    back, start, d0 = _released_on_rollers(g, r)

    def past_peak(rows):  # 5 % below the largest force so far
        return max(rows["F"]) > 0 and rows["F"][-1] < 0.95 * max(rows["F"])

    # a displacement-controlled rig in fine steps, not MGDC and the peak search
    path = back.structure.push(back.apex, UP, d0 + 2.0 * g.h, method="displacement",
                               start=start, steps=300, critical=False, stop=past_peak)
    i = int(np.argmax(path.force))
    assert 0 < i < len(path.force) - 1  # a maximum inside the push
    assert r.F_back >= path.force[i] * (1.0 - FORCE_TOL)  # the peak, up to the forces' accuracy
    assert r.F_back == pytest.approx(path.force[i], rel=1e-3)


def test_stiffness_released_against_finite_differences(off_grid):
    g, r = off_grid
    back, start, d0 = _released_on_rollers(g, r)
    probe = DisplacementProbe(back.structure, back.apex, UP)
    dd = 1e-6 * g.h
    Fp, Fm = probe.solve(start, d0 + dd)[1], probe.solve(start, d0 - dd)[1]
    assert r.stiffness_released == pytest.approx((Fp - Fm) / (2 * dd), rel=1e-5)


def _independent_strain(P, X, t):
    """|eps| + |dkappa| t / 2 from the turning angles by atan2 (a second implementation)."""
    def kappa(Q):
        e = np.diff(Q, axis=0)
        ang = np.unwrap(np.arctan2(e[:, 1], e[:, 0]))
        return 2.0 * np.tan(0.5 * np.diff(ang))

    e, e0 = np.linalg.norm(np.diff(P, axis=0), axis=1), np.linalg.norm(np.diff(X, axis=0), axis=1)
    eps = e / e0 - 1.0
    node_eps = np.r_[eps[0], 0.5 * (eps[:-1] + eps[1:]), eps[-1]]
    bend = np.r_[0.0, np.abs(kappa(P) - kappa(X)) / (0.5 * (e0[:-1] + e0[1:])) * t / 2, 0.0]
    return np.abs(node_eps) + bend


def test_strain_is_kappa_t_over_2_of_the_paths_own_curvature(off_grid):
    g, r = off_grid
    m = build_unit(g)
    X = m.structure.reference_positions
    released = [(r.released["arch"], m.arch_nodes), (r.released["base_shape"], m.base_nodes)]
    worst = max(float(np.max(_independent_strain(P, X[nodes], g.t))) for P, nodes in released)
    assert r.strain_max_released == pytest.approx(worst, rel=1e-10)
    for P, nodes in released:
        np.testing.assert_allclose(surface_strain(P, X[nodes], g.t),
                                   _independent_strain(P, X[nodes], g.t), rtol=1e-10, atol=1e-15)
    # along the path: the largest over the states (iii) and (i) is a lower bound
    for k in ("i", "iii"):
        sh = r.shapes[k]
        for P, nodes in ((sh["arch"], m.arch_nodes), (sh["base"], m.base_nodes)):
            assert np.max(_independent_strain(P, X[nodes], g.t)) <= r.strain_max * (1 + 1e-12)


def test_strain_of_a_bent_circle_and_its_scaling_with_t():
    # a straight rod of edges ds bent into a polygon inscribed in a circle of radius R, edges
    # unstretched: turning angle a = 2 asin(ds / 2R) at every node, so the surface strain is
    # 2 tan(a / 2) / ds * t / 2 = t / (2 R cos(a / 2)) exactly (-> t / 2R as ds -> 0)
    n, ds, R, t = 201, 5e-4, 0.05, 1e-3
    X = np.stack([np.arange(n) * ds, np.zeros(n)], 1)
    a = 2 * np.arcsin(ds / (2 * R))
    ang = np.arange(n) * a
    P = np.stack([R * np.sin(ang), R * (1 - np.cos(ang))], 1)
    strain = surface_strain(P, X, t)
    np.testing.assert_allclose(strain[1:-1], t / (2 * R * np.cos(a / 2)), rtol=1e-9)
    assert abs(strain[0]) < 1e-12 and abs(strain[-1]) < 1e-12  # no axial strain
    # linear in t for a given shape: the bending part doubles, the axial part stays
    assert np.allclose(surface_strain(P, X, 2 * t)[1:-1], 2 * strain[1:-1], rtol=1e-9)


def test_strain_max_of_the_unit_scales_with_t():
    # thinner sheets: nearly the same shapes (inextensible bending), strain ~ t
    g1 = UnitGeometry(L=0.1, h=0.02, t=0.4e-3, w=5e-3, b=5e-3)
    g2 = UnitGeometry(L=0.1, h=0.02, t=0.2e-3, w=5e-3, b=5e-3)
    r1, r2 = simulate_unit(g1), simulate_unit(g2)
    assert r1.status == r2.status == "ok"
    assert r1.strain_max / r2.strain_max == pytest.approx(2.0, rel=0.03)
    assert r1.strain_max_released / r2.strain_max_released == pytest.approx(2.0, rel=0.03)


def test_strain_place_names_the_rod_and_the_part():
    assert strain_place("arch", 0.05, 0.1) == "arch, apex (x = 0.500 L)"
    assert strain_place("base", 0.05, 0.1) == "base, middle (x = 0.500 L)"
    assert strain_place("arch", 0.01, 0.1).startswith("arch, left end")
    assert strain_place("base", 0.09, 0.1).startswith("base, right end")
    assert strain_place("arch", 0.035, 0.1).startswith("arch, left flank")


def test_the_metrics_scale_with_E_and_L(off_grid):
    g, r = off_grid
    k, e = 10.0, 3.0
    g2 = UnitGeometry(**{n: v * k for n, v in OFF_GRID.items()}, E=e * g.E,
                      joint_length=g.joint_length * k)
    r2 = simulate_unit(g2)
    force = e * k * k
    assert r2.F_min == pytest.approx(r.F_min * force, rel=1e-12)
    assert r2.d_Fmin == pytest.approx(r.d_Fmin * k, rel=1e-12)
    assert r2.F_back == pytest.approx(r.F_back * force, rel=1e-12)
    assert r2.stiffness_released == pytest.approx(r.stiffness_released * force / k, rel=1e-12)
    assert r2.strain_max == pytest.approx(r.strain_max, rel=1e-12)
    assert r2.strain_where == r.strain_where


def test_the_strain_searchs_state_strain_is_largest_strains_value(off_grid):
    """The strain search reads each solve's largest strain with the rods' stress-free data
    taken once (`_StateStrain`): the value of `largest_strain`, bit for bit, on the path's
    special states and the released one."""
    from snapmorph.units.metrics import _StateStrain, largest_strain

    g, r = off_grid
    m = build_unit(g)
    X = m.structure.reference_positions
    rods = {"arch": m.arch_nodes, "base": m.base_nodes}
    read = _StateStrain(X, rods, g.t)
    shapes = [r.shapes[k] for k in ("i", "ii", "iii")]
    shapes.append({"arch": r.released["arch"], "base": r.released["base_shape"]})
    for sh in shapes:
        pos = _full_positions(m, {"arch": sh["arch"], "base": sh["base"]})
        assert read(pos) == largest_strain(pos, X, rods, g.t)[0]
