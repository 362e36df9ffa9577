"""`morph_plan`: the steps between two snap patterns, their order and shapes (issue 24)."""

import itertools

import numpy as np
import pytest

from snapmorph.design import Unit, chain, morph_plan
from snapmorph.design.lookup import MapLookup
from snapmorph.design.reconfigure import _crosses

T, W = 0.5e-3, 5e-3


def _units(rng, n):
    out = []
    for _ in range(n):
        L = float(rng.uniform(0.05, 0.12))
        out.append(Unit(L=L, h=L * float(rng.uniform(0.25, 0.45)), t=T, w=W,
                        side=int(rng.choice([-1, 1]))))
    return out


def test_steps_shapes_and_faces(dm):
    units = [Unit(L=0.1, h=0.02, t=T, w=W, side=s) for s in (1, -1, 1, -1)]
    units.insert(2, Unit(L=0.05, h=0.0, t=T, w=W, side=0))
    plan = morph_plan(units, "11010", "01001", design_map=dm, placement=(0.1, 0.2, 0.3))
    # unit 1 (+) and unit 4 (+) are pushed back, unit 5 (-) snapped; push-backs first
    assert [(s.unit, s.action) for s in plan.steps] == [(0, "push back"), (3, "push back"),
                                                        (4, "snap")]
    assert plan.steps[0].face == "other (not engraved) face"  # arch of 1+ on the engraved face
    assert plan.steps[2].face == "other (not engraved) face"  # 5-: its arch is on the other face
    assert plan.states == ["11010", "01010", "01000", "01001"]
    lookup = MapLookup(dm)
    for state, xy in zip(plan.states, plan.shapes):
        fk = chain(units, state, lookup=lookup, start=(0.1, 0.2), start_angle=0.3).xy
        assert np.allclose(fk, xy)
    assert plan.crossing_free and not plan.reordered
    assert "push back" in plan.table() and "snap" in plan.table()
    assert morph_plan(units, "01001", "01001", design_map=dm).steps == []


@pytest.mark.parametrize("seed", range(8))
def test_reordering_finds_a_crossing_free_order_when_there_is_one(dm, seed):
    """Random arrays of tightly curling units and random start / end patterns: whenever some
    order of the steps keeps every intermediate base free of crossings (brute force over all
    orders), the plan is crossing free; otherwise it flags the crossing steps."""
    rng = np.random.default_rng(100 + seed)
    units = _units(rng, 6)
    a = [bool(x) for x in rng.random(6) < 0.5]
    b = [bool(x) for x in rng.random(6) < 0.7]
    plan = morph_plan(units, a, b, design_map=dm)
    lookup = MapLookup(dm)
    acts = [(i, "snap" if b[i] else "push back") for i in range(6) if a[i] != b[i]]

    def ok(order):
        flags = list(a)
        for i, act in order:
            flags[i] = act == "snap"
            if _crosses(chain(units, flags, lookup=lookup).xy):
                return False
        return True

    exists = any(ok(p) for p in itertools.permutations(acts))
    assert plan.crossing_free == exists
    assert plan.states[-1] == "".join("1" if x else "0" for x in b)
    assert sorted(s.unit for s in plan.steps) == sorted(i for i, _ in acts)


def test_crossing_check_is_not_fooled_by_straight_bases():
    x = np.linspace(0.0, 0.5, 200)
    assert not _crosses(np.stack([x, -0.3 * x + 0.007], axis=-1))
    t = np.linspace(-0.4, 2 * np.pi - 0.4, 400)
    assert _crosses(np.stack([np.sin(t), np.sin(t) * np.cos(t)], axis=-1))  # a figure eight


def test_plot_and_bad_patterns(dm, tmp_path):
    units = [Unit(L=0.1, h=0.02, t=T, w=W, side=1)] * 3
    plan = morph_plan(units, "100", "011", design_map=dm)
    assert plan.plot(tmp_path / "m.png").is_file()
    with pytest.raises(ValueError, match="start must be 3 characters"):
        morph_plan(units, "10", "011", design_map=dm)
    with pytest.raises(ValueError, match="spacer"):
        morph_plan(units + [Unit(L=0.05, h=0.0, t=T, w=W, side=0)], "1000", "0001",
                   design_map=dm)
