"""The displacement-controlled rig of a sheet's cell (`units.sheet_rig`, `protocol="rig"`):
its energy descent, its pushes against the load-controlled protocol on a single cell, the
stability of what it records, and the shifted inverse iteration of `units.push3d` that finds
a negative mode where plain inverse iteration meets a positive eigenvalue."""

import numpy as np
import pytest
import scipy.linalg

from snapmorph.solver.states import DisplacementProbe
from snapmorph.units import push3d
from snapmorph.units.frame3d import UnitGeometry
from snapmorph.units.sheet import (PROTOCOLS, build_sheet, shape_distance, sheet_structure,
                                   simulate_sheet)
from snapmorph.units import sheet_rig
from snapmorph.units.sheet_rig import DOWN, canonical, minimize_energy, rig_push, stretch

G = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)


@pytest.fixture(scope="module")
def single():
    return build_sheet(G, "square", (1, 1))


@pytest.fixture(scope="module")
def both(single):
    return {p: simulate_sheet(single, [0], protocol=p) for p in PROTOCOLS}


def test_descent_returns_to_the_stress_free_state_from_a_perturbed_one(single):
    st = sheet_structure(single)
    system = st.reduced_system()
    q0 = np.array(st.initial_state(), dtype=float)
    q = q0.copy()
    system.increment(q, np.random.default_rng(3).standard_normal(system.n), 2e-4)
    assert np.max(np.abs(q - q0)) > 1e-4
    length, fscale = st.scales()
    system.reset_frames()
    it = minimize_energy(system, q, 1e-9 * fscale, 1e-11 * length)
    assert 0 < it < 100
    q = canonical(system, q)
    pos, pos0 = st.positions_of(q), st.positions_of(q0)
    assert np.max(np.abs(pos - pos0)) < 1e-9 * length
    system.reset_frames()
    system.evaluate(q)
    assert system.factor() and system.negative_eigenvalues == 0


def test_rig_push_of_one_cell_equals_the_load_controlled_protocol(both):
    mgdc, rig = both["mgdc"].final, both["rig"].final
    assert mgdc.push_status == "ok" and rig.push_status == "ok"
    # F_cr: the path's limit point (MGDC) against the rig's largest force (2 mm samples,
    # parabola at the top): 1.2471 against 1.2468 N measured
    assert rig.F_cr == pytest.approx(mgdc.F_cr, rel=1e-3)
    assert rig.snapped.tolist() == mgdc.snapped.tolist() == [True]
    assert rig.stable and mgdc.stable
    assert np.max(np.abs(rig.apex_heights - mgdc.apex_heights)) < 1e-4
    # the same released shape (up to the placement a free sheet's holds leave it)
    assert shape_distance(rig.positions, mgdc.positions) < 1e-4


def test_rig_records_stable_held_states_and_its_end_state_is_state_iii(single):
    st = sheet_structure(single, "free", 0)
    q = np.array(st.initial_state(), dtype=float)
    out = rig_push(st, int(single.apex[0]), q, 0.0, 3.0 * G.h, 60)
    assert out.status == "ok" and not out.jumps
    d, F = out.curve
    assert np.all(np.diff(d) > 0)
    i = int(np.argmax(F))
    assert 0 < i < len(F) - 1 and F[-2] < 0.0 <= F[-1]  # through (ii), back at (iii)
    assert out.F_cr >= F[i] and out.F_cr - F[i] < 0.01 * F[i]
    probe = DisplacementProbe(st, int(single.apex[0]), DOWN)
    pos, F_end, neg = probe.solve(out.full_states["iii"], float(d[-1]))
    assert neg == 0  # stable with the apex held, checked by a fresh probe's Newton
    assert F_end == pytest.approx(F[-1], abs=1e-6 * max(1.0, abs(F[-1])))
    assert np.max(np.abs(pos - st.positions_of(out.full_states["iii"]))) < 1e-8


def test_stretch_measures_the_largest_edge_strain(single):
    st = sheet_structure(single)
    q0 = np.array(st.initial_state(), dtype=float)
    assert stretch(st, q0) == 0.0
    q = q0.copy()
    n3 = 3 * st.n_nodes
    q[:n3] *= 1.015  # every edge 1.5 % longer (a uniform scaling of the positions)
    assert stretch(st, q) == pytest.approx(0.015, rel=1e-9)
    q = q0.copy()
    q[:n3:3] *= 0.99  # x shortened by 1 %: the edges along x by 1 %, the others less
    assert stretch(st, q) == pytest.approx(0.01, rel=1e-9)


def test_the_tangent_predictor_lands_near_the_next_held_state(single):
    """The guess of an increment from a held state part-way up the push: the held move with
    the others' linear response to it leaves a gradient far below that of the held move
    alone (whose neighbouring elements are stretched to second order in the move), and
    second order in the increment (the predictor is exact to first order)."""
    st = sheet_structure(single, "free", 0)
    apex = int(single.apex[0])
    start = rig_push(st, apex, np.array(st.initial_state(), dtype=float), 0.0, 0.01, 5)
    q = start.full_states["iii"]  # held at d = 10 mm, on the rising branch
    probe = DisplacementProbe(st, apex, DOWN)
    c, system = probe.control, probe.system
    held = c.member_dofs[:, c.axis]
    length, _ = st.scales()

    def residual(step, predict=True):
        system.reset_frames()
        if predict:
            guess, moved = sheet_rig._predict(system, st, q, held, step, 0.05 * length)
            assert np.allclose(guess[held], q[held] + step) and moved >= abs(step)
        else:
            guess = q.copy()
            guess[held] += step
        system.evaluate(guess)
        return float(np.max(np.abs(system.grad[:system.n])))

    assert residual(-2e-3) < 0.05 * residual(-2e-3, predict=False)  # one of 60 over 3 h
    order = np.log2(residual(-1e-3) / residual(-5e-4))
    assert 1.6 < order < 2.4


def test_a_push_ends_at_the_stretch_limit_as_monostable_within_it(single, monkeypatch):
    """With the limit lowered below what this cell's snap needs, the push ends where a rod
    first passes it, every recorded state within it, and says so (an answer with its
    reason: the elastic range, not a cut-short computation)."""
    st = sheet_structure(single, "free", 0)
    q = np.array(st.initial_state(), dtype=float)
    monkeypatch.setattr(sheet_rig, "STRETCH_LIMIT", 2e-5)
    out = rig_push(st, int(single.apex[0]), q, 0.0, 3.0 * G.h, 60)
    assert out.status.startswith("monostable:") and "stretch passes" in out.status
    assert np.all(out.stretch <= 2e-5) and len(out.curve[0]) < 61
    assert "iii" in out.full_states  # the release starts from the last state within it


def test_protocol_and_its_steps_are_checked(single):
    with pytest.raises(ValueError, match="protocol"):
        simulate_sheet(single, [0], protocol="force")
    for steps in (0, -3, 2.5, True, 10**6):
        with pytest.raises(ValueError, match=r"steps .* must be an integer in \[1, 100000\]"):
            simulate_sheet(single, [0], steps=steps, protocol="mgdc")
    # the rig's increments must resolve the peak and the negative force (5 answered
    # "monostable" for this cell, which snaps)
    for steps in (5, 19, 2.5):
        with pytest.raises(ValueError, match=r"steps \(the rig's increments .* \[20, 100000\]"):
            simulate_sheet(single, [0], steps=steps, protocol="rig")


class _DenseSystem:
    """A symmetric K as a system: lower band storage, factor with inertia, solve."""

    def __init__(self, K):
        self.K, self.n = np.asarray(K, dtype=float), len(K)
        self.band = np.zeros((self.n, self.n))

    def evaluate(self, q):
        for k in range(self.n):
            self.band[k, : self.n - k] = np.diag(self.K, -k)
        return 0.0

    def factor(self):
        A = np.zeros((self.n, self.n))
        for k in range(self.n):
            A += np.diag(self.band[k, : self.n - k], -k)
            if k:
                A += np.diag(self.band[k, : self.n - k], k)
        self._A = A
        self.negative_eigenvalues = int(np.sum(np.linalg.eigvalsh(A) < 0.0))
        return True

    def solve(self, b):
        return scipy.linalg.solve(self._A, b)


def test_negative_mode_where_the_eigenvalue_nearest_zero_is_positive():
    rng = np.random.default_rng(5)
    Q = np.linalg.qr(rng.standard_normal((6, 6)))[0]
    lam = np.array([-4.0, 0.05, 1.0, 2.0, 3.0, 5.0])  # inverse iteration finds 0.05 first
    K = (Q * lam) @ Q.T
    v = push3d._negative_mode(_DenseSystem(K), None)
    assert float(v @ K @ v) / float(v @ v) == pytest.approx(-4.0, rel=1e-6)
    assert abs(float(v @ Q[:, 0])) == pytest.approx(np.linalg.norm(v), rel=1e-6)


def test_cli_pushes_with_the_rig_and_records_the_protocol(tmp_path, capsys):
    import xarray as xr

    from snapmorph.cli import main

    nc = tmp_path / "states.nc"
    assert main(["sheet", "--L", "100", "--h", "40", "--t", "0.5", "--w", "5", "--cells", "1x1",
                 "--order", "0", "--protocol", "rig", "--out", str(nc)]) == 0
    out = capsys.readouterr().out
    assert "protocol rig" in out and "NOT A RESULT" not in out
    with xr.open_dataset(nc) as ds:
        assert ds.attrs["protocol"] == "rig"
        assert float(ds["F_cr"].values[-1]) == pytest.approx(1.2468, abs=5e-4)
    assert main(["sheet", "--L", "100", "--h", "40", "--t", "0.5", "--w", "5", "--cells", "1x1",
                 "--order", "0", "--protocol", "force"]) == 2
    assert "--protocol" in capsys.readouterr().err


def test_f_cr_is_the_first_maximum_not_the_force_of_a_cell_pushed_on():
    """A cell that does not snap and is pushed on until its arches stretch: F rises past its
    first peak again; F_cr is the first peak (the vertex of its parabola), and a wiggle of
    less than 5 % is no peak."""
    d = np.linspace(0.0, 0.02, 11)
    F = np.array([0.0, 1.0, 1.5, 1.6, 1.58, 1.62, 1.2, 0.6, 0.3, 2.0, 9.0])
    assert sheet_rig._first_peak(F) == 5  # 1.6 -> 1.58 is a wiggle
    F_cr, d_cr = sheet_rig._peak(d, F, [])
    assert 1.62 <= F_cr < 1.7 and d[4] < d_cr < d[6]
    assert np.isnan(sheet_rig._peak(d, np.linspace(0.0, 3.0, 11), [])[0])  # never peaks


def test_a_release_accepts_an_equilibrium_newton_cannot_check(single, monkeypatch):
    """Where Newton from a fresh system fails at the end of a release's descent (a sheet
    rolled so far that an edge has turned by nearly 180 degrees), the descent's state
    stands when the descent with the frames carried (`relax`) does not move it; a state
    that is no equilibrium still raises."""
    from snapmorph.solver.problem import ConvergenceError

    st = sheet_structure(single)
    q = np.array(st.initial_state(), dtype=float)  # an equilibrium

    def no_newton(*args, **kwargs):
        raise ConvergenceError("equilibrium not found (test)")

    monkeypatch.setattr(type(st), "solve_equilibrium", no_newton)
    assert np.array_equal(push3d._equilibrium_at(st, q), q)
    bent = q.copy()
    st.reduced_system().increment(bent, np.random.default_rng(2).standard_normal(
        st.reduced_system().n), 1e-3)
    with pytest.raises(ConvergenceError, match="test"):
        push3d._equilibrium_at(st, bent)
