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
