"""The state searches of `solver.states`: the maximum search from a bracket of samples."""

import math

import numpy as np
import pytest

from snapmorph.solver.states import bracketed_maximum


def _counted(f):
    calls = []

    def g(x):
        calls.append(x)
        return f(x)
    return g, calls


@pytest.mark.parametrize("f, x_max, x3", [
    (lambda x: 1.0 - (x - 0.37) ** 2, 0.37, (0.05, 0.3, 0.6)),      # a parabola
    (lambda x: math.sin(3.0 * x), math.pi / 6.0, (0.2, 0.5, 0.9)),  # smooth, not a parabola
    (lambda x: -abs(x - 0.41) ** 1.5, 0.41, (0.05, 0.3, 0.6)),      # not smooth at the top
    (lambda x: x * math.exp(-8.0 * x), 0.125, (0.02, 0.15, 0.6)),   # skewed
])
def test_bracketed_maximum_finds_the_maximum_to_its_tolerance(f, x_max, x3):
    x3 = np.array(x3)
    assert f(x3[1]) > f(x3[0]) and f(x3[1]) > f(x3[2])
    g, calls = _counted(f)
    tol = 1e-6
    x, F = bracketed_maximum(g, x3, [f(v) for v in x3], tol)
    assert abs(x - x_max) <= 2 * tol + 1e-9
    assert F == f(x)
    assert not set(calls) & set(x3.tolist())  # the known samples are not solved again
    assert len(calls) <= 40


def test_bracketed_maximum_needs_few_solves_on_a_smooth_peak():
    # what the unit's F_cr search sees: a smooth maximum between close samples
    f = lambda x: math.cos(x - 0.31)  # noqa: E731
    x3 = np.array([0.2, 0.3, 0.4])
    g, calls = _counted(f)
    x, _ = bracketed_maximum(g, x3, [f(v) for v in x3], 1e-6)
    assert abs(x - 0.31) < 2e-6
    assert len(calls) <= 6  # a bounded golden-section search from [0.2, 0.4] takes ~15


def test_bracketed_maximum_with_a_flat_side_still_searches():
    f = lambda x: -(x - 0.25) ** 2  # noqa: E731
    x3 = np.array([0.0, 0.5, 1.0])  # F(0) == F(0.5): not a strict bracket
    x, _ = bracketed_maximum(f, x3, [f(v) for v in x3], 1e-7)
    assert abs(x - 0.25) < 1e-6


def test_refine_peak_at_the_last_sample_falls_back_without_an_index_error():
    from snapmorph.units.push_through import refine_peak

    d = np.array([0.0, 1.0, 2.0])
    F = np.array([0.0, 1.0, 2.0])  # the largest force is the last sample

    class Probe:
        def solve(self, guess, x):  # never called: there is no bracket
            raise AssertionError("solved without a bracket")

    F_max, d_max, exact = refine_peak(Probe(), d, F, np.zeros((3, 2, 2)), 2, ())
    assert (F_max, d_max, exact) == (2.0, 2.0, False)
