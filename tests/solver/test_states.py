"""The state searches of `solver.states` and their users' guards."""

import numpy as np


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
