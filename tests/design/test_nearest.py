"""`nearest_state`: the snap pattern of an array closest to a target (issue 24).

The branch and bound is checked against brute force (every one of the 2ⁿ states) on random
arrays and targets, and `nearest_state` must find the state a target was made from (moved
rigidly and perturbed) for arrays of up to 20 units.
"""


import numpy as np
import pytest

from snapmorph.design import Unit, chain, nearest_state
from snapmorph.design.lookup import MapLookup
from snapmorph.design.nearest import (_reference, branch_and_bound, matched_costs,
                                      table_for_units)
from snapmorph.design.targets import Target, deviation, place_rigid, resample

T, W = 0.5e-3, 5e-3


def _random_units(rng, n, spacers=0.15):
    out = []
    for _ in range(n):
        L = float(rng.uniform(0.06, 0.15))
        if rng.random() < spacers:
            out.append(Unit(L=L, h=0.0, t=T, w=W, side=0))
        else:
            out.append(Unit(L=L, h=L * float(rng.uniform(0.08, 0.4)), t=T, w=W,
                            side=int(rng.choice([-1, 1]))))
    return out


def _random_state(rng, units):
    return [bool(rng.random() < 0.5) and not u.is_spacer for u in units]


def _all_masks(units):
    arched = [i for i, u in enumerate(units) if not u.is_spacer]
    return np.array([sum(1 << arched[j] for j in range(len(arched)) if (k >> j) & 1)
                     for k in range(2 ** len(arched))], dtype=np.int64)


@pytest.mark.parametrize("seed", range(6))
def test_branch_and_bound_is_exact_against_brute_force(dm, seed):
    """In a fixed frame the search returns the three states of smallest matched distance,
    the same as evaluating all 2ⁿ states; for targets made from a state and for a target
    that is no state of the array at all."""
    rng = np.random.default_rng(seed)
    units = _random_units(rng, int(rng.integers(6, 11)))
    lookup = MapLookup(dm)
    if seed % 2:
        xy = chain(units, _random_state(rng, units), lookup=lookup).xy
        xy = xy + 0.004 * np.sin(np.linspace(0, 9, len(xy)))[:, None]
    else:
        length = sum(u.L for u in units)
        xy = np.array([[0, 0], [0.3, 0.15], [0.6, -0.1], [1.0, 0.2]]) * length / 1.2
    target = Target.from_polyline(xy) if seed % 2 else Target.from_points(xy)
    table = table_for_units(units, lookup)
    frame = (float(rng.uniform(-0.01, 0.01)), float(rng.uniform(-0.01, 0.01)),
             float(rng.uniform(-0.1, 0.1)))
    Q, Qj = _reference(table, target, frame)
    brute = np.sort(matched_costs(table, Q, _all_masks(units)))[:3]
    found, nodes, exact = branch_and_bound(table, Q, Qj, top=3)
    assert exact
    assert [c for c, _ in found] == pytest.approx(list(brute), rel=1e-12)
    # the search prunes: it does not expand the whole tree
    assert nodes < 2 ** (table.n + 1)


@pytest.mark.parametrize("n, seed", [(8, 1), (12, 2), (16, 3), (20, 4)])
def test_nearest_state_finds_the_state_a_target_was_made_from(dm, n, seed):
    """A target drawn from one state of a random array, moved rigidly and perturbed by
    about 2 mm: nearest_state finds that state (best placement), deviation about the
    perturbation, placement close to the rigid motion."""
    rng = np.random.default_rng(seed)
    units = _random_units(rng, n)
    state = _random_state(rng, units)
    lookup = MapLookup(dm)
    xy = chain(units, state, lookup=lookup).xy
    move = (0.05, -0.02), 0.7
    wobble = 0.002 * np.sin(np.linspace(0, 11, len(xy)))[:, None]
    target = Target.from_polyline(place_rigid(xy + wobble, *move))
    r = nearest_state(units, target, design_map=dm)
    assert r.pattern == tuple(state)
    assert r.state == "".join("1" if s else "0" for s in state)
    assert r.deviation == r.deviations["best"]
    assert r.deviation[0] * target.length < 0.004
    assert r.placement[2] == pytest.approx(0.7, abs=0.02)
    x0, y0, a0 = r.placement
    fk = chain(units, list(r.pattern), lookup=lookup, start=(x0, y0), start_angle=a0).xy
    assert np.allclose(fk, r.predicted, atol=1e-12)
    assert deviation(fk, target.xy)[0] == pytest.approx(r.deviation[0], rel=1e-9)
    # the searches prune: together they expand fewer nodes than one full tree (2^(n + 1) - 1
    # nodes), and a small part of it at 20 units
    tree = 2 ** (sum(not u.is_spacer for u in units) + 1)
    assert r.exact and r.nodes < (tree if n < 20 else 0.05 * tree), r.nodes


def test_clamped_placement_and_file_targets(dm, tmp_path):
    """placement='clamped' measures with unit 1 on the target's start; a CSV file (mm) gives
    the same answer as the points."""
    units = [Unit(L=L, h=0.15 * L, t=T, w=W, side=s)
             for L, s in ((0.08, 1), (0.12, -1), (0.1, 1), (0.09, 1), (0.11, -1), (0.1, -1))]
    state = [True, True, False, True, False, True]
    xy = chain(units, state, lookup=MapLookup(dm)).xy
    np.savetxt(tmp_path / "t.csv", resample(xy, 200) * 1e3, delimiter=",", header="x_mm,y_mm",
               comments="")
    r = nearest_state(units, tmp_path / "t.csv", design_map=dm, placement="clamped")
    assert r.pattern == tuple(state) and r.placement_mode == "clamped"
    assert r.placement[:2] == pytest.approx((0.0, 0.0), abs=1e-9)
    assert r.deviation == r.deviations["clamped"]


def test_length_mismatch_warns(dm):
    units = [Unit(L=0.1, h=0.02, t=T, w=W, side=1)] * 4
    target = np.array([[0.0, 0.0], [0.5, 0.0]])  # 500 mm against 400 mm
    with pytest.warns(UserWarning, match="500.0 mm long, the array 400.0 mm"):
        r = nearest_state(units, target, design_map=dm)
    assert r.state == "0000"


@pytest.mark.parametrize("args, kw, word", [
    (([], [[0, 0], [1, 0]]), {}, "units"),
    (("abc", [[0, 0], [1, 0]]), {}, "units"),
    (([Unit(L=0.1, h=0.02, t=T, w=W)], "missing.svg"), {}, "not found"),
    (([Unit(L=0.1, h=0.02, t=T, w=W)], np.zeros((3, 3))), {}, "target"),
    (([Unit(L=0.1, h=0.02, t=T, w=W)], [[0, 0], [1, 0]]), {"placement": "any"}, "placement"),
    (([Unit(L=0.1, h=0.02, t=T, w=W)], [[0, 0], [1, 0]]), {"top": 0}, "top"),
    (([Unit(L=0.1, h=0.02, t=T, w=W)], [[0, 0], [1, 0]]), {"state": "x"}, "state"),
])
def test_bad_inputs_name_the_parameter(dm, args, kw, word):
    with pytest.raises(ValueError, match=word):
        nearest_state(*args, design_map=dm, **kw)
