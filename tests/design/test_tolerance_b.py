"""`design.tolerance` (fabrication_tolerance) at a flat-end length b > 0: on the committed default
map (a b/L axis) every unit is looked up at its own b/L, so the Monte Carlo moves from b = 0 as
the map's θ(b/L) says; a map without a b/L axis, or a b outside the map's range, is refused in
one line naming b and the range (the API and `snapmorph tolerance`)."""

import json
import math

import numpy as np
import pytest

from snapmorph.design import Unit, forward_kinematics, write_units_csv
from snapmorph.design.fabrication_tolerance import _draw, check_sigma, perturbed_units, tolerance
from snapmorph.maps import REFERENCE_MAP, DesignMap

T, W = 0.5e-3, 5e-3


def three(b):
    return [Unit(L=0.1, h=0.02, t=T, w=W, side=1, b=b)] * 3


def _theta_sum(dm, draws, b_over_L):
    """Each sample's end angle (degrees) from the map directly: the sum of its three units' θ at
    their drawn h/L, t/L, w/L and the given b/L (all units on side +1)."""
    L, h, t, w = draws["L"], draws["h"], draws["t"], draws["w"]
    theta = dm.at(h / L, t / L, w / L, b_over_L=np.full(L.shape, b_over_L),
                  state="released")["theta"]
    return np.sum(theta, axis=1)


@pytest.mark.parametrize("b", [3e-3, 5e-3])  # b/L 0.03 (between the map's nodes) and 0.05 (= w)
def test_tolerance_at_b_follows_the_map_at_each_units_b_over_L(dm, b):
    n, seed = 200, 0
    r0 = tolerance(three(0.0), n=n, seed=seed, design_map=dm)
    rb = tolerance(three(b), n=n, seed=seed, design_map=dm)
    theta0 = dm.at(0.2, T / 0.1, W / 0.1, b_over_L=0.0)["theta"]
    theta_b = dm.at(0.2, T / 0.1, W / 0.1, b_over_L=b / 0.1)["theta"]
    assert theta_b - theta0 > 4.0  # the map: b turns each unit several degrees further
    assert r0.nominal_end_angle_deg == pytest.approx(3 * theta0, abs=1e-9)
    assert rb.nominal_end_angle_deg == pytest.approx(3 * theta_b, abs=1e-9)
    # the nominal is forward kinematics of the units at b (design.kinematics, another path)
    fk = forward_kinematics(three(b), "111", design_map=dm)
    assert np.hypot(*(fk[-1] - rb.nominal[-1])) < 1e-12
    assert np.hypot(*(rb.nominal[-1] - r0.nominal[-1])) > 5e-3  # the free end moves > 5 mm
    # every sample: the same draws (same seed), each unit at b/L = its nominal b/L (b follows L)
    assert rb.n_ok == r0.n_ok == n
    draws = _draw(three(b), check_sigma(None), n, np.random.default_rng(seed))
    np.testing.assert_allclose(rb.end_angle_deg, _theta_sum(dm, draws, b / 0.1), atol=1e-9)
    np.testing.assert_allclose(r0.end_angle_deg, _theta_sum(dm, draws, 0.0), atol=1e-9)
    # the whole-array check's perturbed units keep b/L too
    for row in perturbed_units(three(b), k=3, seed=1):
        assert all(u.b / u.L == pytest.approx(b / 0.1, rel=1e-12) for u in row)


def test_b_outside_the_maps_range_is_refused_naming_b_and_the_range(dm):
    with pytest.raises(ValueError, match=r"^unit 1 has b = 6 mm \(b/L = 0.06\), outside the "
                                         r"design map's b range: b/L in \[0, 0.05\], b in "
                                         r"\[0, 5\] mm at its L = 100 mm$"):
        tolerance(three(6e-3), n=20, design_map=dm)


def test_a_map_without_a_b_axis_takes_only_its_own_b():
    old = DesignMap.load(REFERENCE_MAP)  # schema 2, built at b/L = 0
    assert tolerance(three(0.0), n=20, design_map=old).n_ok == 20
    with pytest.raises(ValueError, match=r"^unit 1 has b = 3 mm \(b/L = 0.03\), but the design "
                                         r"map has no b/L axis: it was built at the one b/L = 0 "
                                         r"\(b = 0 mm for this unit\)"):
        tolerance(three(3e-3), n=20, design_map=old)


def test_tolerance_command_reads_b_mm(tmp_path, capsys):
    from snapmorph.cli import main

    out = {}
    for b in (0.0, 5e-3):
        csv = write_units_csv(three(b), tmp_path / f"units{b:g}.csv")
        assert ("b_mm" in csv.read_text().splitlines()[0]) == (b > 0)
        path = tmp_path / f"t{b:g}.json"
        assert main(["tolerance", str(csv), "--n", "100", "--json", str(path)]) == 0
        out[b] = json.loads(path.read_text())["free_end"]
        api = tolerance(three(b), n=100, seed=0).free_end_summary()
        assert out[b]["std_angle_deg"] == pytest.approx(api["std_angle_deg"], rel=1e-12)
    capsys.readouterr()
    assert not math.isclose(out[0.0]["std_angle_deg"], out[5e-3]["std_angle_deg"], rel_tol=1e-3)
    csv = write_units_csv(three(6e-3), tmp_path / "wide.csv")
    assert main(["tolerance", str(csv), "--n", "100"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "b = 6 mm" in err and "b/L in [0, 0.05]" in err
