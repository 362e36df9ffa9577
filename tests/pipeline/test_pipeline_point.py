"""solve_point: normalisation of a UnitResult (via a stand-in `snapmorph.units.planar`) and its error rules."""

import math
import sys
import types
from dataclasses import dataclass

import numpy as np
import pytest

from snapmorph.pipeline.kinds.unit import E_REF, L_REF, finalise_record, resample_shape, solve_point


@dataclass(frozen=True)
class FakeGeometry:
    L: float
    h: float
    t: float
    w: float
    b: float
    E: float
    joint_length: float | None = None

    def __post_init__(self):
        if self.h <= 0:
            raise ValueError("h must be > 0")


def arc(theta_deg, n, length=1.0, nonuniform=True):
    """A circular arc of given length turning by theta, sampled non-uniformly."""
    s = np.linspace(0.0, 1.0, n) ** (1.5 if nonuniform else 1.0) * length
    th = math.radians(theta_deg)
    r = length / th
    return np.column_stack([r * np.sin(th * s / length), r * (1 - np.cos(th * s / length))])


def make_unit_module(behaviour):
    """A stand-in for snapmorph.units.planar whose simulate_unit follows `behaviour(g, nodes)`."""
    mod = types.ModuleType("snapmorph.units.planar")
    mod.UnitGeometry = FakeGeometry
    mod.calls = []

    def simulate_unit(g, nodes=None):
        mod.calls.append((g, nodes))
        return behaviour(g, nodes)

    mod.simulate_unit = simulate_unit
    return mod


def ok_result(g, nodes):
    # base shape in metres: an arc of length L, rotated by 20 deg and shifted, to be undone
    # (fine enough that the first edge is the start tangent to 1e-6)
    raw = arc(35.0, 801) * g.L
    c, s = math.cos(math.radians(20)), math.sin(math.radians(20))
    raw = raw @ np.array([[c, s], [-s, c]]) + np.array([0.003, -0.002])
    return types.SimpleNamespace(
        geometry=g, status="ok", status_code=0, bistable=True, F_cr=2.0, d_cr=0.004,
        d_unstable=0.01, d_second=0.03, S=0.09, theta_deg=35.0, energy_barrier=1e-3,
        energy_stored=4e-4, self_standing=True, bifurcation=None, base_shape=raw,
        released={"S": 0.092, "theta_deg": 33.5, "theta_end_deg": 16.75, "base_shape": arc(33.5, 801) * g.L})


@pytest.fixture
def unit(monkeypatch):
    def install(behaviour):
        mod = make_unit_module(behaviour)
        monkeypatch.setitem(sys.modules, "snapmorph.units.planar", mod)
        return mod
    return install


def test_ok_point_is_normalised(unit):
    mod = unit(ok_result)
    rec = solve_point(0.2, 0.005, 0.05, 0.0, 30, samples=33)
    g, nodes = mod.calls[0]
    assert nodes == 30
    assert (g.L, g.E) == (L_REF, E_REF)
    assert g.h == pytest.approx(0.02) and g.t == pytest.approx(5e-4) and g.w == pytest.approx(5e-3)
    EI = E_REF * g.w * g.t**3 / 12
    assert rec["status"] == 0 and rec["bistable"] == 1
    assert rec["F_cr"] == pytest.approx(2.0 * L_REF**2 / EI, rel=1e-12)
    assert rec["energy_barrier"] == pytest.approx(1e-3 * L_REF / EI, rel=1e-12)
    assert rec["energy_stored"] == pytest.approx(4e-4 * L_REF / EI, rel=1e-12)
    assert rec["d_cr"] == pytest.approx(0.04) and rec["d_unstable"] == pytest.approx(0.1)
    assert rec["d_second"] == pytest.approx(0.3) and rec["S"] == pytest.approx(0.9)
    assert rec["theta"] == 35.0
    assert (rec["self_standing"], rec["bifurcation"]) == (1, -1)
    shape = rec["base_shape"]
    assert shape.shape == (33, 2)
    # starts at the origin along +x, uniform in arc length, and is the same arc (per unit length)
    np.testing.assert_array_equal(shape[0], [0.0, 0.0])
    seg = np.hypot(*np.diff(shape, axis=0).T)
    assert seg.std() / seg.mean() < 1e-3
    np.testing.assert_allclose(shape, arc(35.0, 33, nonuniform=False), atol=2e-5)


def test_monostable_keeps_only_the_force(unit):
    def mono(g, nodes):
        r = ok_result(g, nodes)
        r.status, r.status_code, r.bistable = "monostable", 1, False
        return r
    unit(mono)
    rec = solve_point(0.08, 0.005, 0.05)
    assert rec["status"] == 1 and rec["bistable"] == 0
    assert math.isfinite(rec["F_cr"]) and math.isfinite(rec["d_cr"])
    for name in ("S", "theta", "d_second", "d_unstable", "energy_barrier", "energy_stored"):
        assert math.isnan(rec[name])
    assert np.all(np.isnan(rec["base_shape"]))


def test_not_converged_gives_nan(unit):
    def fail(g, nodes):
        r = ok_result(g, nodes)
        r.status, r.status_code = "not converged: MGDC step too small", 2
        return r
    unit(fail)
    rec = solve_point(0.2, 0.005, 0.05)
    assert rec["status"] == 2 and "not converged" in rec["message"]
    assert all(math.isnan(rec[n]) for n in ("F_cr", "d_cr", "S", "theta"))


def test_exception_in_solver_gives_status_2(unit):
    def boom(g, nodes):
        raise np.linalg.LinAlgError("singular matrix")
    unit(boom)
    rec = solve_point(0.2, 0.005, 0.05)
    assert rec["status"] == 2 and "singular matrix" in rec["message"]


def test_geometry_value_error_gives_status_3(unit):
    mod = unit(ok_result)
    rec = solve_point(-0.1, 0.005, 0.05)
    assert rec["status"] == 3 and "h must be > 0" in rec["message"]
    assert mod.calls == []


def test_ok_with_missing_fields_is_not_trusted(unit):
    def holey(g, nodes):
        r = ok_result(g, nodes)
        r.S = float("nan")
        return r
    unit(holey)
    rec = solve_point(0.2, 0.005, 0.05)
    assert rec["status"] == 2 and "S" in rec["message"]


def test_finalise_record_rejects_malformed_records():
    assert finalise_record(None)["status"] == 2
    assert finalise_record({"status": 7})["status"] == 2
    assert finalise_record({"status": 0, "F_cr": 1.0})["status"] == 2  # missing keys


def test_resample_shape_rejects_degenerate_input():
    with pytest.raises(ValueError, match="zero length"):
        resample_shape(np.zeros((5, 2)), 9)
    with pytest.raises(ValueError, match=r"\(m >= 2, 2\)"):
        resample_shape(np.zeros((1, 2)), 9)
