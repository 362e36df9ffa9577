"""The failure classes of issue 26, each a case that the code of ecfa12b answered wrongly
(tests/units/reference_check.py runs the same cases there): a path cut before its distance
called "monostable", a snap-back crossing read as a stable state, a second state beyond the
3 h push, overflow and underflow at extreme L and E."""

from __future__ import annotations

import math

import numpy as np
import pytest

from snapmorph.solver.stability import state_stability
from snapmorph.units import UnitGeometry, simulate_unit
from snapmorph.units import status as statuses
from snapmorph.units.geometry import build_unit
from snapmorph.units.planar import push_limit
from snapmorph.units.push_through import no_second_state, snap_crossings, zero_crossings

SPECIMEN = dict(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
#: b/L = 0.31: MGDC's path turns back in d past the peak (a snap-back) and crosses F = 0
#: on the way back (unstable: one negative eigenvalue); the rig jumps on and F rises through
#: zero again at d = 3.55 h, beyond the old 3 h push (ecfa12b: "monostable")
SNAP_BACK = dict(L=0.1, h=0.017120933, t=0.48361934e-3, w=5e-3, b=0.031255470)


# ------------------------------------------------------------------ cut paths
def test_a_path_cut_by_the_step_cap_is_not_monostable(monkeypatch):
    from snapmorph.solver import structure

    push = structure.Structure.push
    monkeypatch.setattr(structure.Structure, "push",
                        lambda self, *a, **k: push(self, *a, **dict(k, max_steps=12)))
    r = simulate_unit(UnitGeometry(**SPECIMEN))
    assert r.status.startswith("not converged") and "12 steps" in r.status, r.status
    assert not statuses.answered(r.status) and statuses.exit_status(r.status) == 1


@pytest.mark.parametrize("path_status", [
    "stopped: more than 20000 steps", "stopped: the path wanders: ...",
    "not converged: MGDC step size underflow near d = 0.01 m, F = 1 N"])
def test_no_second_state_on_a_cut_path_is_a_failure_not_an_answer(path_status):
    for j in (None, 5):  # F never below zero, or below zero and not back
        status, reason = no_second_state(path_status, j, 0.05)
        assert status.startswith("not converged") and path_status in status
        assert statuses.status_code(status) == statuses.NOT_CONVERGED
    assert no_second_state("ok", None, 0.05)[0] == "monostable"


def test_a_path_cut_by_the_time_limit_is_a_timeout():
    r = simulate_unit(UnitGeometry(**SNAP_BACK), time_limit=0.05)
    assert r.status.startswith("timeout") and r.status_code == statuses.TIMEOUT


# ------------------------------------------------------------------ crossings
def test_a_snap_back_crossing_is_classified_by_the_inertia_count():
    # past the peak d turns back (a snap-back) and F falls through zero while d shrinks:
    # the chord's slope dF/dd > 0 looks like a stable state; MGDC's force-control count
    # says one negative eigenvalue: unstable (ii)
    d = np.array([0.0, 1.0, 2.0, 3.0, 2.8, 2.6, 2.4, 3.5, 4.0])
    F = np.array([0.0, 1.0, 0.8, 0.2, 0.1, -0.1, -0.3, -0.2, 0.4])
    neg = np.array([0, 0, 1, 1, 1, 1, 1, 0, 0])
    assert zero_crossings(d, F) == [(5, 1), (8, 1)]  # the slope rule: both "stable"
    assert zero_crossings(d, F, neg=neg) == [(5, -1), (8, 1)]
    assert snap_crossings(d, F) == (1, None, None)
    assert snap_crossings(d, F, neg) == (1, 5, 8)
    # an unknown count (-1) falls back on the slope
    assert zero_crossings(d, F, neg=np.full(len(F), -1)) == zero_crossings(d, F)


def test_a_stable_zero_behind_the_unstable_state_is_not_the_second_state():
    # the path comes back towards d = 0 and meets a stable zero there: the first state
    d = np.array([0.0, 1.0, 2.0, 1.5, 0.5, 0.05])
    F = np.array([0.0, 1.0, 0.5, -0.5, -0.2, 0.1])
    neg = np.array([0, 0, 1, 1, 1, 0])
    assert snap_crossings(d, F, neg) == (1, 3, None)


def test_the_snap_back_unit_has_its_second_state_beyond_3h():
    g = UnitGeometry(**SNAP_BACK)
    r = simulate_unit(g)
    assert r.status == "ok" and r.bistable, r.status
    assert 3.0 * g.h < r.d_second < push_limit(g)
    assert r.F_min < -0.05 * r.F_cr
    # state (iii) rechecked: an equilibrium at F = 0, stable with the apex unloaded
    m = build_unit(g)
    pos = np.zeros((m.structure.n_nodes, 2))
    pos[m.arch_nodes], pos[m.base_nodes] = r.shapes["iii"]["arch"], r.shapes["iii"]["base"]
    st = state_stability(m.structure, pos, m.apex)
    assert st.negative_force == 0
    assert r.S == pytest.approx(0.0519, rel=0.01) and r.theta_deg == pytest.approx(133.8, abs=0.5)


def test_the_geometric_limit_is_beyond_the_push_and_stated():
    g = UnitGeometry(**SPECIMEN)
    # h + half the sinusoid's arc length + (b + w - 0.03 L)
    expected = g.h + 0.5 * g.arch_length + (g.b + g.w - 0.03 * g.L)
    assert push_limit(g) == pytest.approx(expected, rel=1e-12)
    assert push_limit(g) > 3.0 * g.h


def test_a_tall_arch_answers_at_its_geometric_limit():
    # h/L = 0.82: the limit (2.2 h) lies below the old 3 h push, past which MGDC crawled on
    # stretching rods until a time limit (ecfa12b: "timeout" at 20 s)
    g = UnitGeometry(L=0.1, h=0.08188, t=0.928e-3, w=5e-3, b=0.00388)
    r = simulate_unit(g, time_limit=300)
    assert r.status == "monostable" and "geometric limit" in r.reason, r.status
    d_end = r.curve[0][-1]
    assert push_limit(g) <= d_end < 3.0 * g.h
    assert push_limit(g) == pytest.approx(2.225 * g.h, rel=1e-3)


# ------------------------------------------------------------------ extreme scales
@pytest.mark.parametrize("L, E", [(1e153, 2.2e9), (1e-300, 2.2e9), (0.1, 1e-300),
                                  (0.1, 1e300), (1e100, 1e100)])
def test_extreme_L_and_E_are_refused_with_a_clear_error(L, E):
    with pytest.raises(ValueError, match=r"^L and E \(base length and Young's modulus\)"):
        UnitGeometry(L=L, h=0.2 * L, t=0.005 * L, w=0.05 * L, b=0.05 * L, E=E,
                     joint_length=0.03175 * L)


@pytest.mark.parametrize("L, E", [(1e60, 1e-20), (1e-40, 1e80), (10.0, 1e200)])
def test_extreme_L_and_E_inside_the_domain_scale_exactly(L, E):
    ref = simulate_unit(UnitGeometry(**SPECIMEN), check_self_standing=False)
    k = L / 0.1
    g = UnitGeometry(**{n: v * k for n, v in SPECIMEN.items()}, E=E, joint_length=3.175e-3 * k)
    r = simulate_unit(g, check_self_standing=False)
    assert r.status == "ok"
    assert r.F_cr == pytest.approx(ref.F_cr * (E / 2.2e9) * k * k, rel=1e-12)
    assert r.S == pytest.approx(ref.S * k, rel=1e-12) and math.isfinite(r.energy_stored)
    assert r.theta_deg == pytest.approx(ref.theta_deg, abs=1e-9)
