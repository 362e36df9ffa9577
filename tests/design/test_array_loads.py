"""Arrays under dead loads (issue 23 part B, `design.array_loads`): physics a mechanic trusts.

- The base alone (a straight spacer strip, clamped on its first edge) under its own weight is
  the heavy elastica (validation.heavy_cantilever: theta'' = -(q/EI)(L - s) cos theta) of
  length L - e/2 (DER holds the tangent on the clamped first edge, whose midpoint is the
  clamp), converging as O(N^-2).
- At small load the response is linear: twice the density, twice the sag.
- A mirror image: the array with every arch on the other side under gravity turned by 180
  degrees sags as the mirror image of the original.
- The snap-back load factor lies between two bracketing runs of follow_load (one carries
  its loads, the other passes the limit), and a unit's snap-back load by displacement
  control equals the limit of a dead apex load (two drivers, one number).
- Surface strain: t / 2R on a circle, the stretch on a stretched rod.
- Interference: none in a flat array, found where an arch is put across a neighbour's base.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from snapmorph.design.array_loads import ArrayLoad, apex_heights, load_array
from snapmorph.design.arrays import _frame, build_array, simulate_array
from snapmorph.design.interference import interference, polyline_gap
from snapmorph.design.strains import rod_surface_strain
from snapmorph.design.unit_margins import UnitMargin, check_margins, snap_back
from snapmorph.design.units import Unit
from snapmorph.solver.materials import PETG, Material

T, W = 0.5e-3, 5e-3
UNIT = Unit(L=0.1, h=0.02, t=T, w=W, side=1, b=W)  # the paper's specimen unit
NODES = 41


@pytest.fixture(scope="module")
def three():
    """The paper's three units, all snapped, coarse mesh."""
    return simulate_array([UNIT] * 3, nodes=NODES)


def test_base_strip_is_the_heavy_elastica():
    from validation.heavy_cantilever import heavy_elastica

    L, E = 0.3, 2.2e9
    A, I = 4 * W * T, 4 * W * T**3 / 12  # a spacer is the solid 4w strip
    errors = []
    for n in (51, 101):
        length = L - 0.5 * L / (n - 1)
        alpha = 1.0  # q length^3 / EI
        rho = alpha * E * I / (length**3 * A * 9.81)
        r = simulate_array([Unit(L=L, h=0.0, t=T, w=W)], nodes=n, gravity=True,
                           material=Material(E=E, density=rho))
        delta, x_tip, _ = heavy_elastica(alpha)
        assert r.loaded.status == "held"
        errors.append(abs(-r.loaded.sag[1] / (delta * length) - 1))
        assert r.loaded.sag[0] == pytest.approx(-(1 - x_tip) * length, rel=2e-3)
    assert errors[0] < 4e-4 and errors[1] < 1e-4
    slope = math.log(errors[0] / errors[1]) / math.log(100 / 50)
    assert 1.8 < slope < 2.2


def test_sag_linear_in_density(three):
    """q L^3 / EI ~ 1e-4: the sag doubles with the density within 0.1 %."""
    rho = 1.0  # kg/m^3: a feather-light PETG
    sags = [load_array(three.model, three.positions, material=Material(E=2.2e9, density=k * rho),
                       max_factor=1.0).sag for k in (1, 2)]
    assert np.hypot(*sags[0]) > 1e-6
    np.testing.assert_allclose(sags[1], 2 * sags[0], rtol=1e-3)


def test_no_loads_change_nothing(three):
    """No gravity and no loads: the result is today's, bit for bit; gravity 0 sags 0 exactly."""
    again = simulate_array([UNIT] * 3, nodes=NODES, gravity=None, loads=None)
    assert again.loaded is None
    assert [x.hex() for x in again.positions.ravel()] == [x.hex() for x in three.positions.ravel()]
    zero = load_array(three.model, three.positions, g=0.0, material=PETG)
    assert zero.status == "no loads" and np.all(zero.sag == 0.0)
    assert np.array_equal(zero.positions, three.positions)


def test_mirror_image_under_reversed_gravity(three):
    mirrored = simulate_array([Unit(L=0.1, h=0.02, t=T, w=W, side=-1, b=W)] * 3, nodes=NODES)
    up = load_array(three.model, three.positions, material=PETG, max_factor=1.0)
    down = load_array(mirrored.model, mirrored.positions, orientation=180.0, material=PETG,
                      max_factor=1.0)
    assert up.sag_m > 1e-3
    np.testing.assert_allclose(down.sag, up.sag * [1, -1], rtol=1e-6, atol=1e-9 * up.sag_m)


def test_snap_back_factor_between_bracketing_runs(three):
    hanging = load_array(three.model, three.positions, orientation=90.0, material=PETG,
                         max_factor=10.0)
    lam = hanging.limit_factor
    assert hanging.holds and lam is not None and 1.0 < lam < 10.0
    assert hanging.limit_kind == "limit point"
    below = load_array(three.model, three.positions, orientation=90.0, material=PETG,
                       max_factor=0.99 * lam)
    above = load_array(three.model, three.positions, orientation=90.0, material=PETG,
                       max_factor=1.01 * lam)
    assert below.search.status == "ok" and below.limit_factor is None
    assert above.limit_factor == pytest.approx(lam, rel=1e-4)  # the locator's, path to path
    assert above.limit_unit == hanging.limit_unit
    # past the limit the unit that goes is the one whose apex moves back towards its side
    h = apex_heights(three.model, above.search.positions[-1])
    assert h[hanging.limit_unit] > hanging.heights[0][hanging.limit_unit]


def test_snap_back_load_two_drivers():
    """F_back by a displacement-controlled pull equals the limit of a dead apex load."""
    model = build_array([UNIT], nodes=NODES)
    r = simulate_array([UNIT], [True], model=model)
    held = r.snaps[0].held
    F_back, _, status = snap_back(model, held, 0)
    assert status == "ok" and 0.1 < F_back < 1.0
    m = model.meshes[0]
    P = _frame(held, held[m.supports[0]].copy(), held[m.supports[1]] - held[m.supports[0]])
    st = model.structure(clamp=False, actuator=0, apex_z=False)
    st.add_load(m.apex, (0.0, 1.0))  # 1 N pulling the apex back up
    path = st.follow_load(1.0, start=P)
    assert path.limit_load_factor == pytest.approx(F_back, rel=5e-4)


def test_surface_strain_closed_forms():
    R, t, n = 0.05, 1e-3, 81
    s = np.linspace(0.0, 1.0, n)  # a straight rod bent into an arc of radius R, no stretch
    X = np.stack([s * R, 0 * s], 1)
    x = np.stack([R * np.sin(s), R * (1 - np.cos(s))], 1)
    strain = rod_surface_strain(x, X, t)
    # 2 tan(phi/2) / l against the arc's 1/R: chord 2 R sin(l / 2R) over arc l
    np.testing.assert_allclose(strain[1:-1], t / (2 * R), rtol=1e-3)
    assert strain[0] == pytest.approx(1 - 2 * np.sin(0.5 / (n - 1)) * (n - 1), abs=1e-6)
    stretched = rod_surface_strain(X * [1.002, 1], X, t)
    np.testing.assert_allclose(stretched, 0.002, rtol=1e-9)


def test_interference():
    model = build_array([UNIT] * 2, nodes=NODES)
    assert interference(model, model.reference, "00") == []
    P = model.reference.copy()
    m0, m1 = model.meshes
    tied = {a for a, _ in model.ties}
    free = [n for n in m0.arch if int(n) not in tied]
    P[free, 0] += m1.offset  # unit 1's arch moved onto unit 2's arch, just above its base
    found = {(o.first, o.second): o for o in interference(model, P, "00")}
    assert set(found) == {(("arch", 0), ("base", 1)), (("arch", 0), ("arch", 1))}
    assert all(o.gap < 0 for o in found.values())
    assert "crosses the arch of unit 2" in str(found[("arch", 0), ("arch", 1)])
    assert "comes within" in str(found[("arch", 0), ("base", 1)])
    gap, _ = polyline_gap(np.array([[0, 0], [1, 1.0]]), np.array([[0, 1], [1, 0.0]]))
    assert gap == 0.0
    gap, _ = polyline_gap(np.array([[0, 0], [1, 0.0]]), np.array([[0, 0.3], [1, 0.3]]))
    assert gap == pytest.approx(0.3)


def test_sideways_and_loads(three):
    side = load_array(three.model, three.positions, orientation="sideways", material=PETG)
    assert side.holds and side.sag_m == 0.0 and "normal" in side.notes[0]
    tip = load_array(three.model, three.positions,
                     loads=[ArrayLoad(2, "end", (0.0, -1e-3))], max_factor=1.0)
    assert tip.status == "held" and tip.total_load == pytest.approx(1e-3)
    assert tip.sag[1] < 0


def test_check_margins():
    margins = [UnitMargin(0, 0.5, 0.01, "arch, end"), UnitMargin(1, 0.05, 0.03, "arch, start"),
               UnitMargin(2, float("nan"), 0.01, "base, middle")]
    why = check_margins(margins, 0.0267, 0.1)
    assert len(why) == 3
    assert "unit 2: strain 3.00 %" in why[0] and "unit 2: snap-back load 0.05" in why[1]
    assert "unit 3: snap-back load not found" in why[2]
    assert check_margins(margins[:1], 0.0267, None) == []


@pytest.mark.parametrize("kwargs, name", [
    (dict(gravity=True, orientation="flat"), "orientation"),
    (dict(gravity=True, orientation=400), "orientation"),
    (dict(gravity=-1.0), "gravity"),
    (dict(gravity=True, material="steel"), "material"),
    (dict(loads=[ArrayLoad(5, "apex", (0, -1))]), "unit"),
    (dict(loads=[ArrayLoad(0, "middle", (0, -1))]), "where"),
    (dict(loads=[ArrayLoad(0, "apex", (0, float("nan")))]), "force"),
])
def test_bad_inputs(kwargs, name):
    with pytest.raises(ValueError, match=name):
        simulate_array([UNIT] * 3, nodes=NODES, **kwargs)


def test_cli_array_gravity(capsys):
    from snapmorph.cli import main

    code = main(["array", "--units", "examples/units_three.csv", "--gravity", "--orientation",
                 "upright", "--material", "petg", "--nodes", "31", "--no-fk",
                 "--load", "2:end:0,-0.001"])
    out = capsys.readouterr().out
    assert code == 0
    for text in ("free end sag", "limit load", "largest strain", "held", "allowable 2.67 %"):
        assert text in out
    for argv, word in ((["--orientation", "flat"], "--orientation"),
                       (["--material", "steel"], "--material"),
                       (["--load", "9:apex:0,-1"], "--load"), (["--load", "1:apex"], "--load"),
                       (["--gravity", "-3"], "--gravity")):
        code = main(["array", "--units", "examples/units_three.csv", "--gravity", *argv])
        err = capsys.readouterr().err
        assert code == 2 and word in err and len(err.strip().splitlines()) == 1, err


def test_design_that_does_not_hold_exits_1(tmp_path, capsys):
    """The M design (committed map) holds upright under PETG, but no unit of it resists a
    1 N pull back: the snap-back margin fails loudly, exit 1 like a missed tolerance."""
    from snapmorph.cli import main

    out = tmp_path / "M"
    code = main(["design", "examples/target_M.csv", "--t", "0.5", "--w", "5", "--out", str(out),
                 "--no-drawings", "--no-progress", "--material", "petg", "--min-backload", "1"])
    stdout = capsys.readouterr().out
    assert code == 1
    assert "under its own weight (PETG, upright): held" in stdout
    assert "DOES NOT HOLD" in stdout and "below min_backload 1 N" in stdout
    assert "VERIFICATION FAILED" in stdout
    backloads = [float(line.split("snap-back load ")[1].split(" N")[0])
                 for line in stdout.splitlines() if line.startswith("  unit ")]
    assert backloads and all(0.01 < f < 1.0 for f in backloads)
    assert "# VERIFICATION FAILED" in (out / "units.csv").read_text()
    for argv, word in ((["--max-strain", "2"], "--max-strain"),
                       (["--orientation", "up"], "--orientation"),
                       (["--min-backload", "-1"], "--min-backload")):
        code = main(["design", "examples/target_M.csv", "--t", "0.5", "--w", "5", "--out",
                     str(out), *argv])
        err = capsys.readouterr().err
        assert code == 2 and word in err and len(err.strip().splitlines()) == 1, err
