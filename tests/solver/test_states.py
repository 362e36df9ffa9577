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
