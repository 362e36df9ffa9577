"""The planar unit as built and used: joint and bond parameters, the released state, what
"bistable" means (state (iii) stable), time limits, scale-free numbers, argument validation."""

import dataclasses
import math
import time

import numpy as np
import pytest

from unit_checks import make_second_state_unstable
from snapmorph.units import UnitGeometry, simulate_unit
from snapmorph.units.geometry import build_unit
from snapmorph.units.planar import STATUS_CODES, _zero_crossings

MM = 1e-3
PAPER = dict(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)


@pytest.fixture(scope="module")
def paper():
    return simulate_unit(UnitGeometry(**PAPER))


# ------------------------------------------------------------------ the move to units/
def test_old_import_paths_are_the_same_objects():
    with pytest.warns(DeprecationWarning, match="deprecated import name"):
        import solver.unit
        import solver.unit_model
        import units.geometry
        import units.planar

    assert solver.unit.simulate_unit is units.planar.simulate_unit
    assert solver.unit.UnitGeometry is units.geometry.UnitGeometry
    assert solver.unit_model.build_unit is units.geometry.build_unit
    assert solver.unit_model.DEFAULT_NODES == units.geometry.DEFAULT_NODES


# ------------------------------------------------------------------ joint and bond
def test_default_joint_is_an_eighth_of_an_inch_and_bond_the_flat_part():
    g = UnitGeometry(**PAPER)
    assert g.joint_length == pytest.approx(3.175e-3, rel=0, abs=1e-15)
    assert g.bond_length is None and g.bond == pytest.approx(10e-3)
    explicit = simulate_unit(UnitGeometry(**PAPER, joint_length=3.175e-3, bond_length=10e-3),
                             check_self_standing=False)
    default = simulate_unit(g, check_self_standing=False)
    assert explicit.F_cr == default.F_cr and explicit.theta_deg == default.theta_deg


def test_point_clamp_holds_one_edge_centred_on_the_apex():
    g = UnitGeometry(**PAPER, joint_length=0.0)
    m = build_unit(g, nodes=101)
    X = m.structure.reference_positions
    groups = m.structure.supernodes()
    joint = [n for n in m.arch_nodes if groups[n] == groups[m.apex]]
    assert len(joint) == 2  # one rigid edge
    mid = X[joint].mean(axis=0)
    assert mid[0] == pytest.approx(0.05, abs=1e-15)  # centred on the apex
    assert abs(X[joint[0], 1] - X[joint[1], 1]) < 1e-15  # horizontal, as the apex tangent


def test_the_joint_length_moves_the_nodes_held_with_the_apex():
    for jl, expect in ((1e-3, 1e-3), (6e-3, 6e-3)):
        m = build_unit(UnitGeometry(**PAPER, joint_length=jl), nodes=101)
        X = m.structure.reference_positions
        groups = m.structure.supernodes()
        joint = np.array([n for n in m.arch_nodes if groups[n] == groups[m.apex]])
        xs = np.sort(X[joint, 0])
        # the joint's ends are the midpoints of the edges straddling them: arc length ~ jl
        arc = np.sum(np.hypot(*np.diff(X[joint[np.argsort(X[joint, 0])]], axis=0).T))
        edge = 0.1 / 100
        assert abs(arc - expect) <= edge + 1e-12, (jl, arc)
        assert xs[0] < 0.05 < xs[-1]


@pytest.mark.slow
def test_point_clamp_converges_under_refinement():
    g = UnitGeometry(**PAPER, joint_length=0.0)
    rs = [simulate_unit(g, nodes=n, check_self_standing=False) for n in (101, 201, 401)]
    assert all(r.status == "ok" for r in rs)
    F = [r.F_cr for r in rs]
    S = [r.S / g.L for r in rs]
    th = [r.theta_deg for r in rs]
    for v in (F, S, th):
        d1, d2 = abs(v[1] - v[0]), abs(v[2] - v[1])
        assert d2 < d1 or d2 < 1e-9 * abs(v[2])  # the change shrinks with the edge
    assert abs(F[2] / F[1] - 1) < 2e-3
    assert abs(S[2] - S[1]) < 2e-4
    assert abs(th[2] - th[1]) < 0.05


def test_shorter_bonds_soften_the_unit(paper):
    r = simulate_unit(UnitGeometry(**PAPER, bond_length=2e-3), check_self_standing=False)
    assert r.status in ("ok", "monostable", ) or r.status.startswith("second state")
    # a loose flat part lengthens the arch's free span: F_cr drops by tens of per cent
    assert r.F_cr < 0.9 * paper.F_cr


def test_a_loose_flat_part_is_not_bonded():
    g = UnitGeometry(**PAPER, bond_length=4e-3)
    m = build_unit(g, nodes=101)
    X = m.structure.reference_positions
    groups = m.structure.supernodes()
    base_groups = set(groups[m.base_nodes])
    bonded = [n for n in m.arch_nodes if groups[n] in base_groups]
    xb = X[bonded, 0]
    assert np.max(np.minimum(xb, g.L - xb)) == pytest.approx(4e-3, abs=1e-12)


# ------------------------------------------------------------------ released state, theta_end
def test_released_state_and_theta_end(paper):
    r = paper
    assert r.self_standing is True
    assert r.theta_end_deg == pytest.approx(r.theta_deg / 2, abs=0.05)
    rel = r.released
    assert rel["theta_end_deg"] == pytest.approx(rel["theta_deg"] / 2, abs=0.05)
    # the numbers: 81.05 deg held, 79.53 deg released
    assert r.theta_deg == pytest.approx(81.05, abs=0.01)
    assert r.theta_released_deg == pytest.approx(79.53, abs=0.01)
    assert r.S_released == rel["S"]


# ------------------------------------------------------------------ bistable means stable
#: large-b geometries (random ones of the valid domain) whose first positive-slope zero
#: crossing is a state (iii) with 2 negative eigenvalues: reported "ok" and bistable before
LARGE_B = [
    {'L': 0.1, 'h': 0.020913263618982013, 't': 0.0003123495791498756,
     'w': 0.0023167430133136232, 'b': 0.026183881200787133},
    {'L': 0.1, 'h': 0.02373465009450191, 't': 0.001003030207702178,
     'w': 0.00871905216825127, 'b': 0.01911330368500156},
    {'L': 0.1, 'h': 0.03075134707065725, 't': 0.00027449067749336323,
     'w': 0.00915772689756939, 'b': 0.015637364845520918},
]


@pytest.mark.parametrize("kw", LARGE_B)
def test_large_b_units_are_never_bistable_with_an_unstable_second_state(kw):
    """These geometries were reported "ok" and bistable with a state (iii) holding two
    negative eigenvalues. Since the path followers settle past bifurcations as a rig does
    (issue 12), they now end "ok" with a stable state (iii) or "not converged"; whichever,
    a bistable result must survive an independent stability check of its state (iii)."""
    import sys, os
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from fuzz_units import check_one

    problems, status, _ = check_one(kw, time_limit=120.0, nodes=None)
    assert problems == [], (status, problems)
    r = simulate_unit(UnitGeometry(**kw))
    if r.bistable:
        assert r.stability["states"]["iii"].negative_force == 0
    else:
        assert r.reason, "a unit that is not bistable says why"
        assert math.isnan(r.S) and math.isnan(r.theta_deg)


def test_an_unstable_second_state_is_reported_as_such(monkeypatch):
    """No geometry found after the issue-12 driver rework keeps a state (iii) with negative
    eigenvalues, so the reporting is checked by making the stability check of state (iii)
    see two: the unit must then be "second state unstable", not bistable, with no S or θ."""
    import snapmorph.units.planar as planar

    make_second_state_unstable(monkeypatch, planar)
    r = simulate_unit(UnitGeometry(**PAPER), critical=False, check_self_standing=False)
    assert r.status.startswith("second state unstable"), r.status
    assert r.status_code == STATUS_CODES["second_state_unstable"] == 5
    assert not r.bistable and math.isnan(r.S) and math.isnan(r.theta_deg)
    assert "negative eigenvalue" in r.reason
    assert np.isfinite(r.F_cr)


def test_bistable_units_have_a_stable_second_state(paper):
    assert paper.bistable and paper.stability["states"]["iii"].negative_force == 0
    # also without the per-step critical-point machinery
    bare = simulate_unit(UnitGeometry(**PAPER), critical=False, check_self_standing=False)
    assert bare.bistable and bare.theta_deg == paper.theta_deg


def test_zero_crossings_are_classified_by_slope_not_direction():
    d = np.array([0.0, 1.0, 2.0, 3.0, 2.5, 2.0, 4.0])
    F = np.array([0.0, 1.0, -1.0, -0.5, 0.5, -0.5, 1.0])
    # 1->2 down while d grows: slope < 0; 3->4 up while d shrinks (snap-back): slope < 0;
    # 4->5 down while d shrinks: slope > 0; 5->6 up while d grows: slope > 0
    assert _zero_crossings(d, F) == [(2, -1), (4, -1), (5, 1), (6, 1)]


def test_monostable_units_say_why():
    r = simulate_unit(UnitGeometry(L=0.1, h=0.0, t=0.5e-3, w=5e-3))
    assert r.status == "monostable" and r.reason
    r = simulate_unit(UnitGeometry(L=0.1, h=0.001, t=0.5e-3, w=5e-3))
    assert r.status == "monostable" and "no snap-through" in r.reason


# ------------------------------------------------------------------ time, scale
def test_time_limit_ends_with_a_timeout_status():
    t0 = time.perf_counter()
    r = simulate_unit(UnitGeometry(**PAPER), time_limit=1e-3)
    assert time.perf_counter() - t0 < 5.0
    assert r.status.startswith("timeout") and r.status_code == STATUS_CODES["timeout"] == 4
    assert not r.bistable and math.isnan(r.S)


@pytest.mark.parametrize("E", [1.0, 1e200])
def test_E_changes_only_the_force_scale(paper, E):
    r = simulate_unit(UnitGeometry(**{**PAPER, "E": E}))
    assert r.status == "ok"
    k = E / 2.2e9
    assert r.F_cr == pytest.approx(paper.F_cr * k, rel=1e-12)
    assert r.energy_stored == pytest.approx(paper.energy_stored * k, rel=1e-12)
    assert r.theta_deg == paper.theta_deg and r.S == paper.S
    np.testing.assert_array_equal(r.curve[0], paper.curve[0])
    assert r.released["theta_deg"] == paper.released["theta_deg"]


def test_lengths_in_other_units_scale_exactly(paper):
    g = UnitGeometry(**PAPER).scaled(1000.0)  # millimetres as if metres
    r = simulate_unit(g)
    assert r.status == "ok"
    assert r.theta_deg == pytest.approx(paper.theta_deg, abs=1e-9)
    assert r.S == pytest.approx(paper.S * 1000, rel=1e-12)
    assert r.F_cr == pytest.approx(paper.F_cr * 1e6, rel=1e-12)  # F ~ E L^2


def test_identical_inputs_give_bit_identical_results(paper):
    again = simulate_unit(UnitGeometry(**PAPER))
    np.testing.assert_array_equal(again.curve[1], paper.curve[1])
    np.testing.assert_array_equal(again.released["base_shape"], paper.released["base_shape"])


# ------------------------------------------------------------------ validation
BAD_VALUES = [("abc", "a real number"), (None, "a real number"), (1 + 2j, "not complex"),
              (float("nan"), "finite"), (float("inf"), "finite"), (True, "a real number"),
              (np.array([1.0, 2.0]), "one real number")]


@pytest.mark.parametrize("name,unit", [("L", "m"), ("h", "m"), ("t", "m"), ("w", "m"), ("b", "m"),
                                       ("E", "Pa"), ("joint_length", "m"), ("bond_length", "m")])
@pytest.mark.parametrize("value,match", BAD_VALUES)
def test_bad_geometry_values_name_the_parameter_and_unit(name, unit, value, match):
    if name == "bond_length" and value is None:
        return  # None is bond_length's default: the whole flat part
    with pytest.raises(ValueError, match=rf"^{name} \(.*, {unit}\) must be .*{match}"):
        UnitGeometry(**{**PAPER, name: value})


@pytest.mark.parametrize("kw,match", [
    (dict(bond_length=0.0), r"bond_length \(glued length at each end, m\) must be > 0 and <= b \+ w"),
    (dict(bond_length=0.011), r"<= b \+ w = 0.01 m"),
    (dict(joint_length=-1e-3), r"joint_length .* must be >= 0"),
    (dict(joint_length=0.05), r"joint_length .* must be <= half the arch's arc length"),
    (dict(t=1e-8), r"t \(sheet thickness, m\) must be >= 1e-05 L = 1e-06 m \(valid domain"),
    (dict(t=1.05e-6), r"t \(sheet thickness, m\) must be >= the arch rod's length / "),
    (dict(w=1e-9, b=5e-3), r"w \(strip width, m\) must be >= 1e-06 L"),
    (dict(w=1e-6, b=0.0), r"b \+ w \(the flat, bonded end length\) must be >= 0.0001 L"),
    (dict(b=0.0445), r"b \+ w must be <= 0.49 L = 0.049 m \(valid domain"),
])
def test_the_valid_domain_has_clear_edges(kw, match):
    with pytest.raises(ValueError, match=match):
        UnitGeometry(**{**PAPER, **kw})


@pytest.mark.parametrize("kw,match", [
    (dict(nodes=5), r"nodes \(mesh resolution.*\) must be an integer in \[11, 20001\]"),
    (dict(nodes=101.0), r"nodes"), (dict(nodes=True), r"nodes"),
    (dict(method="newton"), r"method must be one of 'mgdc', 'displacement'"),
    (dict(tie="glue"), r"tie must be one of"), (dict(branch=None), r"branch must be one of"),
    (dict(steps=0), r"steps .* must be an integer in \[1, 100000\]"),
    (dict(steps="60"), r"steps"), (dict(critical="yes"), r"critical must be True or False"),
    (dict(tie_stiffness=-1.0), r"tie_stiffness \(bond spring stiffness, N/m\) must be > 0"),
    (dict(time_limit=0.0), r"time_limit \(wall-time limit, s\) must be > 0"),
    (dict(time_limit="1"), r"time_limit \(wall-time limit, s\) must be a real number"),
])
def test_bad_simulation_arguments_are_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        simulate_unit(UnitGeometry(**PAPER), **kw)
    with pytest.raises(ValueError, match="g must be a UnitGeometry"):
        simulate_unit(dict(PAPER))


def _thinnest(L, h, w, b=0.0):
    """The smallest valid t: the arch rod's length / MAX_SLENDERNESS."""
    from snapmorph.units.geometry import MAX_SLENDERNESS

    g = UnitGeometry(L=L, h=h, t=1e-3, w=w, b=b)
    return (g.arch_length + 2 * (b + w)) / MAX_SLENDERNESS * (1 + 1e-9)


@pytest.mark.parametrize("kw", [
    dict(L=0.1, h=0.02, t=_thinnest(0.1, 0.02, 5e-3), w=5e-3),  # the thin edge of the domain
    dict(L=0.1, h=0.02, t=5e-4, w=1e-7, b=5e-3),  # w = 1e-6 L
    dict(L=0.1, h=0.02, t=5e-4, w=1e-5),  # b + w = 1e-4 L
    dict(L=0.1, h=0.001, t=5e-4, w=5e-3, b=0.049 - 5e-3, joint_length=0.0),  # span 0.02 L
    dict(L=0.1, h=0.09, t=5e-4, w=5e-3),  # h equal to the span
])
def test_edges_of_the_valid_domain_are_solved(kw):
    r = simulate_unit(UnitGeometry(**kw), time_limit=60)
    assert r.status in ("ok", "monostable") or r.status.startswith("second state"), r.status
    if r.status == "ok":
        assert np.all(np.isfinite([r.F_cr, r.S, r.theta_deg]))


def test_repr_is_short(paper):
    text = repr(paper)
    assert len(text) < 250 and "\n" not in text
    assert "bistable" in text and "F_cr=1.097 N" in text
    r = simulate_unit(UnitGeometry(L=0.1, h=0.0, t=0.5e-3, w=5e-3))
    assert "not bistable" in repr(r)


def _old_segment_points(breaks, spacing):
    """`units.shapes.segment_points` as a loop over the intervals (the code it replaced)."""
    import math

    pts = [float(breaks[0])]
    for a, b in zip(breaks[:-1], breaks[1:]):
        n = max(1, int(math.ceil((b - a) / spacing - 1e-9)))
        pts.extend(a + (b - a) * np.arange(1, n + 1) / n)
    return np.array(pts)


def test_segment_points_in_one_pass_are_the_loops_points():
    from snapmorph.units.shapes import segment_points

    rng = np.random.default_rng(11)
    for _ in range(300):
        breaks = np.sort(rng.uniform(0.0, rng.uniform(1e-3, 10.0), int(rng.integers(1, 12))))
        if rng.random() < 0.3:  # break points a whole number of spacings apart
            breaks = np.cumsum(np.concatenate([[0.0], rng.integers(1, 5, 4) * 0.01]))
        spacing = rng.uniform(1e-3, 1.0) * (breaks[-1] - breaks[0] + 1e-3)
        got = segment_points(breaks, spacing)
        assert got.tobytes() == _old_segment_points(breaks, spacing).tobytes()


def test_a_unit_at_the_reference_scale_is_solved_on_its_own_geometry():
    """simulate_unit solves a unit given at L = 0.1 m, E = 2.2 GPa on that very geometry
    (validated once); any other is scaled to it."""
    from snapmorph.units.planar import E_INTERNAL, _reference_geometry

    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    assert _reference_geometry(g, 1.0) is g
    other = dataclasses.replace(g, E=1e9)
    assert _reference_geometry(other, 1.0) == dataclasses.replace(g, E=E_INTERNAL)
    big = g.scaled(3.0)
    assert _reference_geometry(big, 3.0) == dataclasses.replace(big.scaled(1 / 3.0), E=E_INTERNAL)
