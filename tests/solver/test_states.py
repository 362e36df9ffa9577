"""The state searches of `solver.states` and their users' guards."""

import numpy as np
import pytest


def test_refine_peak_at_the_last_sample_falls_back_without_an_index_error():
    from snapmorph.units.push_through import refine_peak

    d = np.array([0.0, 1.0, 2.0])
    F = np.array([0.0, 1.0, 2.0])  # the largest force is the last sample

    class Probe:
        def solve(self, guess, x):  # never called: there is no bracket
            raise AssertionError("solved without a bracket")

    F_max, d_max, exact = refine_peak(Probe(), d, F, np.zeros((3, 2, 2)), 2, ())
    assert (F_max, d_max, exact) == (2.0, 2.0, False)


def test_refine_peak_keeps_the_sample_when_no_solve_rises_above_it():
    """The sample at the maximum (closer than the search's tolerance) is the answer, not
    the vertex of the parabola through the samples (which overshoots between coarse
    samples): found on a map point where F_cr moved by 1e-4 with the path's sampling."""
    from snapmorph.units.push_through import parabola_peak, refine_peak

    d = np.array([0.0, 1.0, 2.0])
    F = np.array([0.0, 1.0, 0.5])

    class Probe:  # equilibria whose force peaks at the sample, a hair below it
        last_state = None

        def solve(self, guess, x):
            self.last_state = np.asarray(guess).copy()
            return guess, 1.0 - (x - 1.0) ** 2 - 1e-12, 0

    Q = np.zeros((3, 2, 2))
    assert parabola_peak(d, F, 1)[0] > 1.0  # what the old fallback answered
    assert refine_peak(Probe(), d, F, Q, 1, ()) == (1.0, 1.0, False)


class _Peaked:
    """A probe whose force is a known function of d (positions ignored)."""

    def __init__(self, F):
        self.F, self.last_state, self.calls = F, None, 0

    def solve(self, guess, x):
        self.calls += 1
        self.last_state = np.asarray(guess).copy()
        return guess, self.F(x), 0


def _peak_search(F, d):
    from snapmorph.solver.states import refine_maximum

    probe = _Peaked(F)
    Fs = np.array([F(x) for x in d])
    tol = 1e-6 * (d[2] - d[0])
    return (*refine_maximum(probe, d, Fs, np.zeros((3, 2, 2)), 1, tol_d=tol), probe.calls, tol)


def test_refine_maximum_on_a_smooth_lopsided_peak_solves_three_times():
    """A cubic's maximum from the samples and one solve: 3 solves, where Brent took 8-10."""
    F = lambda x: 1.0 - (x - 0.3) ** 2 + 0.8 * (x - 0.3) ** 3  # noqa: E731
    x_max = 0.3  # F'(0.3) = 0, F'' < 0
    F_max, d_max, calls, tol = _peak_search(F, np.array([0.0, 0.4, 1.0]))
    assert abs(d_max - x_max) <= tol
    assert F_max == pytest.approx(1.0, abs=1e-12)
    assert calls <= 4


def test_refine_maximum_finds_a_sharp_peak_that_far_samples_misplace():
    """A narrow peak (width 0.02) between samples 0.25 and 0.15 away is located to ten times
    the search's tolerance (the units' sharp extrema: tests/units/test_path_resolution.py)."""
    F = lambda x: 1.0 / (1.0 + ((x - 0.47) / 0.02) ** 2)  # noqa: E731
    F_max, d_max, calls, tol = _peak_search(F, np.array([0.2, 0.45, 0.6]))
    assert abs(d_max - 0.47) <= 10 * tol
    assert F_max == pytest.approx(1.0, abs=1e-9)


def test_hermite_guess_is_fourth_order_and_falls_back_on_unknown_slopes():
    """The cubic Hermite guess between two samples of a smooth q(d) is off by O(h^4) (the
    parabola through three samples by O(h^3)); a NaN slope (a critical point's row) falls
    back on the parabola."""
    from snapmorph.solver.states import _on_parabola, between

    q = lambda x: np.array([np.sin(3 * x), np.exp(x)])  # noqa: E731
    dq = lambda x: np.array([3 * np.cos(3 * x), np.exp(x)])  # noqa: E731
    errors = []
    for h in (0.2, 0.1, 0.05):
        ds = np.array([0.3, 0.3 + h, 0.3 + 2 * h])
        x = 0.3 + 0.6 * h
        guess = between(ds, [q(v) for v in ds], [dq(v) for v in ds], x)
        errors.append(np.max(np.abs(guess - q(x))))
        nan = [dq(ds[0]), np.full(2, np.nan), dq(ds[2])]
        assert np.array_equal(between(ds, [q(v) for v in ds], nan, x),
                              _on_parabola(ds, [q(v) for v in ds], x))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 3.6), orders


def _clamped_arch_snap_path():
    """(structure, apex, MGDC path) of a clamped shallow arch (L 100 mm, h 10 mm, 41 nodes)
    pushed down 15 mm at its apex in 40 steps: through its force peak and its snap."""
    from snapmorph.solver import Structure

    x = np.linspace(0.0, 0.1, 41)
    st = Structure()
    rod = st.add_rod(np.stack([x, 0.01 * np.sin(np.pi * x / 0.1)], 1), 5e-3, 0.5e-3, 2.2e9)
    for node in (0, 1, 39, 40):
        st.fix(int(rod.nodes[node]), "xz")
    apex = int(rod.nodes[20])
    st.fix(apex, "x")
    path = st.push(apex, (0.0, -1.0), 0.015, steps=40)
    return st, apex, path


def test_mgdc_path_rates_are_the_derivative_of_the_positions_along_d():
    """`Path.rates` (dq/dd from the tangent K^-1 P) against central differences of two
    displacement-controlled solves at d +- delta, on a clamped arch's snap path: before and
    after the force peak and past the snap (where F < 0)."""
    from snapmorph.solver.states import DisplacementProbe

    st, apex, path = _clamped_arch_snap_path()
    assert path.rates is not None and path.rates.shape == path.positions.shape
    probe = DisplacementProbe(st, apex)
    delta = 1e-6
    k_peak = int(np.argmax(path.force))
    checked = 0
    for k in (k_peak // 2, k_peak + 3, int(np.argmin(path.force))):
        if not np.all(np.isfinite(path.rates[k])):
            continue
        d = path.displacement[k]
        plus = probe.solve(path.positions[k], d + delta)[0].copy()
        minus = probe.solve(path.positions[k], d - delta)[0].copy()
        fd = (plus - minus) / (2 * delta)
        assert np.max(np.abs(path.rates[k] - fd)) <= 1e-5 * np.max(np.abs(fd))
        checked += 1
    assert checked == 3


def test_probe_settles_on_the_last_iterate_and_reads_the_same_force():
    """A displacement-controlled solve (`newton` with ``settle``) ends on a gradient-only
    evaluation once the corrections are below the tolerance, its K left factorised at the
    iterate before: the same state and force as the full last iteration, one assembly and
    factorisation fewer (counted on the Python loop over the fused iterations); the
    compiled loop (`System.newton_loop`) gives the Python loop's bits."""
    from snapmorph.solver import newton as newton_module
    from snapmorph.solver.problem import state_from
    from snapmorph.solver.states import DisplacementProbe
    from snapmorph.solver.system import BandedSystem
    from snapmorph.units import UnitGeometry
    from snapmorph.units.geometry import build_unit

    m = build_unit(UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3), nodes=41)
    probe = DisplacementProbe(m.structure, m.apex)
    system = probe.system

    def solve(settle, compiled):
        calls = []
        full, light = system.fused_newton, system.settle
        system.fused_newton = lambda *a, **k: calls.append("full") or full(*a, **k)
        system.settle = lambda *a, **k: calls.append("settle") or light(*a, **k)
        if not compiled:
            system.newton_loop = lambda *a, **k: BandedSystem.newton_loop(system, *a, **k)
        q = state_from(m.structure, m.structure.reference_positions)
        q[probe.control.member_dofs[:, 1]] -= 0.004  # the actuator's nodes pushed 4 mm
        try:
            it = newton_module.newton(system, q, 0.0, None, 1e-9 * probe.fscale,
                                      1e-11 * probe.length, 30, 0.025, settle=settle)
        finally:
            del system.fused_newton, system.settle
            if not compiled:
                del system.newton_loop
        return q.copy(), probe.control.force(system), calls, it

    (q1, F1, calls1, it1), (q0, F0, calls0, it0) = solve(True, False), solve(False, False)
    assert it1 == it0 >= 2
    assert calls1.count("full") == calls0.count("full") - 1 and calls1[-1] == "settle"
    assert np.array_equal(q1, q0)
    assert F1 == pytest.approx(F0, rel=1e-12)
    for settle, (q, F, _, it) in ((True, (q1, F1, None, it1)), (False, (q0, F0, None, it0))):
        qc, Fc, calls, itc = solve(settle, True)
        assert calls == [] and itc == it and np.array_equal(qc, q) and Fc == F


def test_mgdc_path_stiffness_is_the_apex_stiffness_of_its_states():
    """`Path.stiffness` (dF/dd from the tangent, N/m) against the tangent stiffness of the
    same states computed apart (1 / (e^T K^-1 e) for a force on the pushed node,
    `units.metrics.apex_stiffness`), before the force peak and after it (negative)."""
    from snapmorph.units.metrics import apex_stiffness

    st, apex, path = _clamped_arch_snap_path()
    assert path.stiffness is not None and path.stiffness.shape == path.force.shape
    k_peak = int(np.argmax(path.force))
    for k in (0, k_peak // 2, k_peak + 3):
        want = apex_stiffness(st, path.positions[k], apex, (0.0, -1.0))
        assert path.stiffness[k] == pytest.approx(want, rel=1e-9)
    assert path.stiffness[k_peak + 3] < 0.0 < path.stiffness[0]
