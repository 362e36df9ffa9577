"""Maps with b/L as a fourth axis (schema 3): 4-D lookups, their errors, the unit metrics, and
the three-axis maps (schema 2) still readable."""

import math

import numpy as np
import pytest

import maps_synthetic as syn
from snapmorph.maps import REFERENCE_MAP, DesignMap, MapDomainError
from snapmorph.pipeline.batch import new_block
from snapmorph.pipeline.dataset import assemble, write_netcdf
from snapmorph.pipeline.kinds.unit import SPEC, Grid

B_AXIS = (0.0, 0.05, 0.1)
GRID_B = Grid(h_over_L=syn.GRID.h_over_L, t_over_L=syn.GRID.t_over_L, w_over_L=syn.GRID.w_over_L,
              b_over_L=B_AXIS, samples=17)
THETA_PER_B = 40.0  # degrees per unit b/L: theta is linear in b/L too, so lookups are exact
F_MIN_PER_F = -0.3  # the synthetic F_min, a fraction of F_cr (linear in b through F_cr's b factor)


def theta(h, t, w, b):
    return syn.theta(h, t, w) + THETA_PER_B * b


def F_cr(h, t, w, b):
    return syn.F_cr(h, t, w) * np.exp(0.5 * b)  # log-linear in b as well


def F_min(h, t, w, b):
    return F_MIN_PER_F * (1.0 + h + b)  # linear in (h, b): interpolated exactly


def dataset_b():
    """A synthetic 4-axis map: the fields of `maps_synthetic`, shifted linearly in b/L; F_min
    at every point with a force peak, strain_where "arch" below h = 0.3 and "base" above;
    the other metrics left NaN (a unit model that does not report them yet)."""
    pts = GRID_B.points()
    total = new_block(SPEC, np.arange(GRID_B.size), GRID_B.options)
    for i, (h, t, w, b) in enumerate(pts):
        if np.allclose((h, t, w), syn.FAILED):
            total["status"][i] = 2
            continue
        total["F_cr"][i] = F_cr(h, t, w, b)
        total["d_cr"][i] = 0.3 * h
        total["F_min"][i] = F_min(h, t, w, b)
        total["strain_where"][i] = "arch" if h < 0.3 else "base"
        total["bifurcation"][i] = 0
        if h < syn.boundary(t):
            total["status"][i] = 1
            continue
        total["status"][i] = 0
        total["bistable"][i] = 1
        total["self_standing"][i] = 1
        total["theta"][i] = theta(h, t, w, b)
        total["theta_end"][i] = theta(h, t, w, b) / 2
        total["S"][i] = syn.S(h, t, w)
        total["theta_released"][i] = theta(h, t, w, b) - syn.RELEASED_TURN
        total["theta_end_released"][i] = total["theta_released"][i] / 2
        total["S_released"][i] = syn.S_released(h, t, w)
        for name, k in (("d_unstable", 0.9), ("d_second", 1.7), ("energy_barrier", 2.0),
                        ("energy_stored", 1.0)):
            total[name][i] = k * h
        total["base_shape"][i] = syn.shape(h, t, w, GRID_B.samples)
        total["base_shape_released"][i] = syn.shape(h, t, w, GRID_B.samples, released=True)
    total["solve_time"][:] = 0.01
    prov = {"created": "unknown", "package_version": "0.1.0", "git_commit": "test"}
    return assemble(SPEC, GRID_B, total, GRID_B.options, prov)


@pytest.fixture(scope="module")
def dm_b(tmp_path_factory):
    path = tmp_path_factory.mktemp("maps-b") / "b.nc"
    write_netcdf(dataset_b(), path)
    return DesignMap.load(path)


def test_a_map_with_a_b_axis_interpolates_in_4d(dm_b):
    assert dm_b.dims[-1] == "b_over_L" and dm_b.schema_version == 3
    assert dm_b.ranges["b_over_L"] == (0.0, 0.1) and dm_b.fixed_b_over_L is None
    rng = np.random.default_rng(3)
    h = rng.uniform(0.4, 0.5, 20)  # bistable everywhere in this band
    t = np.exp(rng.uniform(np.log(0.0025), np.log(0.0075), 20))
    w = np.exp(rng.uniform(np.log(0.02), np.log(0.08), 20))
    b = rng.uniform(0.0, 0.1, 20)
    r = dm_b.at(h, t, w, b_over_L=b, state="actuated")
    np.testing.assert_allclose(r["theta"], theta(h, t, w, b), rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["F_cr"], F_cr(h, t, w, b), rtol=1e-12)
    np.testing.assert_allclose(r["F_min"], F_min(h, t, w, b), rtol=0, atol=1e-12)
    assert np.all(r["strain_where"] == "base")
    # a lookup without b_over_L is at b/L = 0, the b/L of the maps before schema 3
    np.testing.assert_allclose(dm_b.at(h, t, w, state="actuated")["theta"],
                               theta(h, t, w, 0.0), rtol=0, atol=1e-9)
    # the inverse lookup in h at a given b
    hb = dm_b.h_over_L_for_theta(float(theta(0.45, 0.005, 0.05, 0.07)), 0.005, 0.05,
                                 state="actuated", b_over_L=0.07)
    assert hb == pytest.approx(0.45, abs=1e-9)


def test_b_over_L_outside_the_map_names_it_and_its_range(dm_b):
    with pytest.raises(MapDomainError, match=r"b_over_L = 0\.2 is outside the map's range "
                                             r"0 <= b_over_L <= 0\.1"):
        dm_b.at(0.4, 0.005, 0.05, b_over_L=0.2)
    with pytest.raises(MapDomainError, match=r"b_over_L = -0\.01 is outside"):
        dm_b.value("theta", 0.4, 0.005, 0.05, b_over_L=-0.01)
    with pytest.raises(ValueError, match=r"b_over_L \(extra flat length"):
        dm_b.at(0.4, 0.005, 0.05, b_over_L="wide")


def test_unit_metrics_the_unit_does_not_report_yet_leave_lookups_alone(dm_b):
    """F_back etc. are NaN everywhere (a unit model without them): `at` returns NaN for them
    and every other value as before; `value` refuses them with the usual error."""
    r = dm_b.at(0.45, 0.005, 0.05, b_over_L=0.05)
    assert math.isfinite(r["theta"]) and math.isnan(r["F_back"]) and math.isnan(r["strain_max"])
    with pytest.raises(MapDomainError, match="F_back not defined"):
        dm_b.value("F_back", 0.45, 0.005, 0.05, b_over_L=0.05)
    # F_min exists at monostable points too (the path has a force minimum there)
    assert dm_b.value("F_min", 0.1, 0.005, 0.05) == pytest.approx(F_min(0.1, 0.005, 0.05, 0.0))
    # strain_where is the cell's common text, "" where the cell's points differ
    assert dm_b.at(0.27, 0.005, 0.05, allow_nan=True)["strain_where"] == ""
    assert dm_b.at(0.2, 0.005, 0.05, allow_nan=True)["strain_where"] == "arch"


def test_the_three_axis_map_stays_readable_at_its_own_b():
    old = DesignMap.load(REFERENCE_MAP)
    assert old.schema_version == 2 and old.fixed_b_over_L == 0.0 and "b_over_L" not in old.ranges
    a = old.at(0.2, 0.005, 0.05)
    assert old.at(0.2, 0.005, 0.05, b_over_L=0.0) == a  # the map's own b/L is accepted
    assert old.metrics == ()  # schema 2 has no unit metrics
    with pytest.raises(MapDomainError, match=r"b_over_L = 0\.05 is outside the map's range: it "
                                             r"was built at the one value b_over_L = 0 "):
        old.at(0.2, 0.005, 0.05, b_over_L=0.05)
    with pytest.raises(MapDomainError, match="b_over_L = 0.05"):
        old.h_over_L_for_theta(60.0, 0.005, 0.05, b_over_L=0.05)
