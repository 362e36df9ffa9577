"""A failed whole-array verification is never "met" (issue 22): the design whose simulation
did not converge, or whose simulated array misses the tolerance, exits 1 and says why, in the
summary, design.txt and units.csv; the multi-target design per target.

The simulator is replaced by one that fails the way the issue saw it (a zig-zag whose
whole-array check ended "not converged", its last arch left unsnapped, far off the target):
forward kinematics from the map of that half-snapped array, with the status a stalled
simulation reports."""

from __future__ import annotations

import csv
from types import SimpleNamespace

import numpy as np
import pytest

from snapmorph.cli import main
from snapmorph.design import forward_kinematics, inverse_design
from snapmorph.design.verification import verify_design

ZIGZAG = "x_mm,y_mm\n0,0\n100,40\n200,0\n300,40\n400,0\n"
STALLED = "not converged: unit {k}: displacement control failed at d = 12.3 mm"


def _stalling_simulator(fail=lambda snapped: True):
    """A stand-in for design.arrays.simulate_array: where `fail(snapped)`, the last snapped
    unit stays unsnapped and the status says the push stalled; elsewhere the map's shape."""

    def simulate_array(units, snapped=None, *args, **kw):
        flags = [not u.is_spacer for u in units] if snapped is None else list(snapped)
        status = "ok"
        if fail(flags):
            k = max(i for i, f in enumerate(flags) if f)
            flags[k] = False
            status = STALLED.format(k=k + 1)
        return SimpleNamespace(status=status, base=forward_kinematics(units, flags),
                               state="".join("1" if f else "0" for f in flags))

    return simulate_array


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.slow
def test_not_converged_verification_exits_1(tmp_path, capsys, monkeypatch):
    target = tmp_path / "zigzag.csv"
    target.write_text(ZIGZAG)
    monkeypatch.setattr("snapmorph.design.arrays.simulate_array", _stalling_simulator())
    out = tmp_path / "zz"
    code, stdout, err = _run(capsys, "design", target, "--t", "0.5", "--w", "5", "--out", out,
                             "--no-progress", "--no-drawings")
    assert code == 1, err
    assert "simulated array (not converged, " in stdout
    assert "predicted within it" in stdout and "): met" not in stdout
    assert "VERIFICATION FAILED: the whole-array simulation ended 'not converged" in stdout
    assert "VERIFICATION FAILED" in (out / "design.txt").read_text()
    marks = [ln for ln in (out / "units.csv").read_text().splitlines() if ln.startswith("#")]
    assert any(ln.startswith("# VERIFICATION FAILED") for ln in marks)
    assert not any("TOLERANCE MISSED" in ln for ln in marks)  # the prediction was within tol


@pytest.mark.slow
def test_simulated_deviation_over_tol_is_not_met(tmp_path, monkeypatch):
    """A simulation that ends ok but off the target by more than tol: not met either."""
    pts = np.array([[0, 0], [100, 40], [200, 0], [300, 40], [400, 0]]) * 1e-3
    d = inverse_design(pts, t=0.5e-3, w=5e-3)
    assert d.met and d.verification_failure is None
    ok_but_off = _stalling_simulator()

    def simulate_array(units, snapped=None, *args, **kw):
        r = ok_but_off(units, snapped)
        r.status = "ok"
        return r

    monkeypatch.setattr("snapmorph.design.arrays.simulate_array", simulate_array)
    v = verify_design(d)
    assert v["status"] == "ok" and v["max_deviation"] > 0.05
    assert d.met is False and "the simulated array deviates" in d.verification_failure
    assert f"{100 * v['max_deviation']:.2f} %" in d.verification_failure
    assert "VERIFICATION FAILED" in d.summary() and "MISSED" in repr(d)
    d.write(tmp_path, drawings=False)
    assert "# VERIFICATION FAILED" in (tmp_path / "units.csv").read_text()
    monkeypatch.undo()  # the real simulator confirms the design again
    assert verify_design(d)["failure"] is None and d.met


@pytest.mark.slow
def test_multi_target_verification_fails_per_target(tmp_path, capsys, monkeypatch):
    """Two targets, the second pattern's simulation stalls: T1 met, T2 not, exit 1."""
    from snapmorph.design.target_sets import turning_curve

    paths = []
    for name, turn in (("C.csv", 90), ("Cmirror.csv", -90)):
        xy = turning_curve([(1, turn)], 0.5, 121) * 1e3
        paths.append(tmp_path / name)
        np.savetxt(paths[-1], xy, delimiter=",", header="x_mm,y_mm", comments="")
    seen = []

    def second(flags):  # the second pattern simulated, at every mesh verify_multi tries
        if tuple(flags) not in seen:
            seen.append(tuple(flags))
        return seen.index(tuple(flags)) == 1

    monkeypatch.setattr("snapmorph.design.arrays.simulate_array", _stalling_simulator(second))
    out = tmp_path / "two"
    code, stdout, err = _run(capsys, "design", *paths, "--t", "0.5", "--w", "5", "--tol",
                             "0.02", "--out", out, "--no-progress", "--no-drawings")
    assert code == 1, err + stdout
    assert "VERIFICATION FAILED for T2" in stdout and "TOLERANCE MISSED" not in stdout
    with (out / "patterns.csv").open() as fh:
        assert [r["met"] for r in csv.DictReader(fh)] == ["yes", "no"]
    assert "# VERIFICATION FAILED for T2" in (out / "units.csv").read_text()
    for k in (1, 2):
        assert (out / f"target_{k}.csv").is_file() and (out / f"overlay_{k}.svg").is_file()
