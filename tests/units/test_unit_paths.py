"""The planar unit's push: no bifurcation on the paper's Table 1 units, stable states, and the
same metrics whichever path follower or branch option pushes it."""

import pytest

from snapmorph.units import UnitGeometry, simulate_unit

MM = 1e-3


TABLE1 = [(9.11, 99.2, 0.50), (9.10, 99.0, 0.75), (19.24, 99.5, 0.50), (19.96, 99.7, 0.75),
          (40.68, 99.4, 0.50), (39.85, 99.5, 0.75)]


@pytest.mark.parametrize("h,L,t", TABLE1)
def test_table1_units_meet_no_bifurcation_and_state_iii_is_stable(h, L, t):
    g = UnitGeometry(L=L * MM, h=h * MM, t=t * MM, w=5 * MM, b=5 * MM)
    r = simulate_unit(g, check_self_standing=False)
    assert r.status == "ok" and r.bifurcation is False
    states = r.stability["states"]
    assert states["iii"].stable_displacement and states["iii"].stable_force
    assert states["ii"].stable_displacement and not states["ii"].stable_force
    assert states["i"].stable_displacement
    kinds = [(c.kind, c.control) for c in r.stability["critical_points"]]
    assert kinds[:2] == [("limit", "force"), ("limit", "force")]


def test_unit_primary_and_bare_paths_agree_with_the_followed_one():
    g = UnitGeometry(L=99.5 * MM, h=19.24 * MM, t=0.5 * MM, w=5 * MM, b=5 * MM)
    follow = simulate_unit(g, check_self_standing=False)
    primary = simulate_unit(g, check_self_standing=False, branch="primary")
    bare = simulate_unit(g, check_self_standing=False, critical=False)
    assert primary.F_cr == follow.F_cr == bare.F_cr
    assert bare.bifurcation is None and "states" not in bare.stability


@pytest.mark.slow
def test_unit_at_three_heights_mgdc_and_displacement_control_agree():
    for h in (0.015, 0.02, 0.025):
        g = UnitGeometry(L=0.1, h=h, t=0.5e-3, w=5e-3, b=5e-3)
        a = simulate_unit(g, method="mgdc")
        b = simulate_unit(g, method="displacement")
        assert a.status == "ok" and b.status == "ok", (h, a.status, b.status)
        assert abs(a.F_cr / b.F_cr - 1) < 0.01
        assert abs(a.S / b.S - 1) < 0.01
