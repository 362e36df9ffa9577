"""design.fabrication_tolerance (the function `design.tolerance`): Monte Carlo of fabrication
errors through the map, and its envelope checked against whole-array simulations of randomly
perturbed arrays."""

import math
from pathlib import Path

import numpy as np
import pytest

from snapmorph.design import Unit
from snapmorph.design.fabrication_tolerance import check_sigma, perturbed_units, tolerance

T, W = 0.5e-3, 5e-3
THREE = [Unit(L=0.1, h=0.02, t=T, w=W, side=1)] * 3


def test_same_seed_same_result_and_nominal_inside(design_map):
    a = tolerance(THREE, n=200, seed=3, design_map=design_map)
    b = tolerance(THREE, n=200, seed=3, design_map=design_map)
    np.testing.assert_array_equal(a.free_end, b.free_end)
    np.testing.assert_array_equal(a.lo, b.lo)
    assert a.n_ok == 200 and np.all(a.p_bistable == 1.0)
    assert a.envelope_contains(a.nominal)
    # the nominal all-snapped shape is forward kinematics of the nominal units
    from snapmorph.design import forward_kinematics

    fk = forward_kinematics(THREE, "111", design_map=design_map)
    assert np.hypot(*(fk[-1] - a.nominal[-1])) < 1e-12
    c = tolerance(THREE, n=200, seed=4, design_map=design_map)
    assert not np.array_equal(a.free_end, c.free_end)


def test_zero_sigma_gives_a_zero_width_envelope(design_map):
    r = tolerance(THREE, sigma={"h": 0.0}, n=20, design_map=design_map)
    assert np.max(np.abs(r.hi[..., 1] - r.lo[..., 1])) < 1e-12
    assert np.max(np.hypot(*(r.free_end - r.nominal[-1]).T)) < 1e-12


def test_a_curve_outside_the_envelope_is_detected(design_map):
    r = tolerance(THREE, n=300, design_map=design_map)
    assert r.envelope_contains(r.nominal)
    bent = r.nominal.copy()
    width = np.max(r.hi[..., 1] - r.lo[..., 1])
    bent[len(bent) // 2:, 1] += 3 * width  # the second half lifted off the band
    assert not r.envelope_contains(bent)
    assert 0.5 < r.held_out_coverage <= 1.0


def test_units_that_may_stop_being_bistable(design_map):
    # synthetic map: defined from the grid's h/L = 0.1 up; a unit at h/L = 0.104 with
    # sigma_h = 1 mm (0.01 L) falls below it with probability P(z < -0.4) = 0.34
    units = [Unit(L=0.1, h=0.0104, t=T, w=W, side=1), Unit(L=0.1, h=0.02, t=T, w=W, side=1)]
    r = tolerance(units, sigma={"h": 1e-3}, n=400, design_map=design_map)
    assert 0.58 < r.p_bistable[0] < 0.73 and r.p_bistable[1] == 1.0
    assert r.n_ok == pytest.approx(r.p_bistable[0] * r.n, abs=1)


@pytest.mark.parametrize("kw,match", [
    (dict(sigma={"h": -1e-3}), r"sigma\['h'\] \(standard deviation of h, m\) must be in \[0, 0.01\]"),
    (dict(sigma={"E": 1e-3}), r"sigma keys must be among L, h, t, w"),
    (dict(sigma={"h": "big"}), r"must be a real number"),
    (dict(sigma=[0.5e-3]), r"sigma must be a dict"),
    (dict(n=5), r"n \(number of samples\) must be an integer in \[10, 1000000\]"),
    (dict(seed=-1), r"seed must be an integer >= 0"),
    (dict(state="glued"), r"state must be 'released'"),
])
def test_bad_arguments(design_map, kw, match):
    with pytest.raises(ValueError, match=match):
        tolerance(THREE, design_map=design_map, **kw)


def test_perturbed_units_follow_the_draws():
    us = perturbed_units(THREE, {"h": 0.5e-3}, k=4, seed=2)
    assert len(us) == 4 and all(len(row) == 3 for row in us)
    assert all(u.L == 0.1 and u.t == T for row in us for u in row)
    assert len({u.h for row in us for u in row}) == 12
    assert check_sigma(None) == {"h": 0.5e-3, "L": 0.3e-3, "t": 0.02e-3}


def test_plot_and_cli(tmp_path, synthetic_map_path, capsys):
    from snapmorph.design.units import write_units_csv
    from snapmorph.cli import main

    csv = write_units_csv(THREE, tmp_path / "units.csv")
    out = tmp_path / "tol.png"
    code = main(["tolerance", str(csv), "--map", str(synthetic_map_path), "--n", "200",
                 "--plot", str(out), "--json", str(tmp_path / "t.json")])
    text = capsys.readouterr().out
    assert code == 0 and out.stat().st_size > 10_000
    assert "free end" in text and "P(bistable)" in text
    assert main(["tolerance", str(csv), "--sigma-h", "-1"]) == 2
    assert "argument --sigma-h" in capsys.readouterr().err
    assert main(["tolerance", str(tmp_path / "missing.csv")]) == 2


# ------------------------------------------------------------------ against whole arrays
def test_envelope_contains_perturbed_whole_array_simulations():
    """50 randomly perturbed three-unit arrays (independent of the Monte Carlo's samples),
    each simulated whole (design.arrays, released): at least 95 % inside the envelope."""
    from snapmorph.design.arrays import simulate_array
    from snapmorph.maps import DesignMap

    dm = DesignMap.load()
    units = [Unit(L=0.1, h=0.02, t=T, w=W, side=1, b=0.0)] * 3
    r = tolerance(units, n=1000, seed=0, design_map=dm)
    inside, worst = [], 0.0
    for us in perturbed_units(units, r.sigma, k=50, seed=12345):
        sim = simulate_array(us, "111")
        assert sim.status == "ok", sim.status
        inside.append(r.envelope_contains(sim.base))
    assert sum(inside) >= 48, f"{sum(inside)} of 50 inside"
    assert r.held_out_coverage >= 0.95


# ------------------------------------------------------------- the envelope's own nominal
README_UNITS = Path(__file__).resolve().parents[2] / "examples" / "units_M.csv"


def _in_drawn_band(r, curve, near=0.05e-3) -> bool:
    """Does `curve` lie in the band as `plot_tolerance` draws it (one polygon per unit through
    the stations moved to the band's bounds along the normal): every vertex inside, or within
    `near` (m) of the outline, up to the band's end (a longer array's end beyond the last
    station is the free end's scatter, drawn as such)? Between stations a drawn edge is a chord: over the
    4 mm between two stations a curve bending as the M does near the clamp leaves the chord of
    the 0.1 mm band by up to 0.02 mm, a thirtieth of a pixel of the 150 dpi figure."""
    from matplotlib.path import Path as Polygon

    from snapmorph.design.targets import distances_to_polyline

    lo, hi = r.band()
    rings = [np.vstack([r.stations[j] + lo[j, :, None] * r.frames[j, :, 1],
                        (r.stations[j] + hi[j, :, None] * r.frames[j, :, 1])[::-1]])
             for j in range(len(r.units))]
    pts = np.asarray(curve)
    pts = pts[(pts - r.stations[-1, -1]) @ r.frames[-1, -1, 0] <= 0]
    hit = np.zeros(len(pts), bool)
    for ring in rings:
        hit |= Polygon(ring).contains_points(pts)
        hit |= distances_to_polyline(pts, np.vstack([ring, ring[:1]])) <= near
    return bool(hit.all())


@pytest.mark.slow
def test_nominal_array_inside_its_own_envelope():
    """The README's M array (examples/units_M.csv): the Monte Carlo's range is about a
    micrometre wide next to the clamp (every sample starts at the same point), the band
    keeps a half-width of at least 0.05 mm; the nominal, forward kinematics and simulated as
    a whole array, lies inside it."""
    from snapmorph.design.arrays import simulate_array
    from snapmorph.design.fabrication_tolerance import ENVELOPE_FLOOR_MM
    from snapmorph.design.units import read_units_csv

    units = read_units_csv(README_UNITS)
    r = tolerance(units, n=1000, seed=0)
    raw = (r.hi[..., 1] - r.lo[..., 1]) / 2
    assert raw[0, 1] < 2e-6  # the range next to the clamp: ~1 um (why the band has a floor)
    assert np.all(r.lo[..., 1] <= 0) and np.all(r.hi[..., 1] >= 0)  # the nominal is a sample
    lo, hi = r.band()
    assert np.min(hi - lo) / 2 == pytest.approx(ENVELOPE_FLOOR_MM * 1e-3)
    assert r.envelope_contains(r.nominal) and _in_drawn_band(r, r.nominal)
    sim = simulate_array(units, "111")
    assert sim.status == "ok"
    assert r.envelope_contains(sim.base) and _in_drawn_band(r, sim.base)


@pytest.mark.slow
def test_simulate_counts_agree_with_the_plot(tmp_path, capsys, monkeypatch):
    """`snapmorph tolerance examples/units_M.csv --simulate 4` (it said "0 of 4" while its plot
    showed all four inside): each simulated array is counted inside exactly when it lies in
    the band as drawn; an array lifted off the band is outside both ways."""
    import json

    import snapmorph.design.fabrication_tolerance as ft
    from snapmorph.cli import main

    drawn = {}
    real_plot = ft.plot_tolerance

    def plot_tolerance(result, path, target=None, simulated=None):
        drawn.update(result=result, simulated=simulated)
        return real_plot(result, path, target=target, simulated=simulated)

    monkeypatch.setattr(ft, "plot_tolerance", plot_tolerance)
    code = main(["tolerance", str(README_UNITS), "--simulate", "4", "--plot",
                 str(tmp_path / "tol.png"), "--json", str(tmp_path / "tol.json")])
    out = capsys.readouterr().out
    assert code == 0 and "4 of 4 inside the envelope" in out
    counted = json.loads((tmp_path / "tol.json").read_text())["simulated_inside"]
    r, curves = drawn["result"], drawn["simulated"]
    assert counted == [_in_drawn_band(r, c) for c in curves] == [True] * 4
    lifted = curves[0] + 3 * np.max(r.hi[..., 1] - r.lo[..., 1]) * np.array([0.0, 1.0]) * \
        (np.hypot(*curves[0].T) > 0.5 * np.hypot(*curves[0][-1]))[:, None]
    assert not r.envelope_contains(lifted) and not _in_drawn_band(r, lifted)
