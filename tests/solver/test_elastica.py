"""Cantilever with a vertical tip displacement against the exact large-deflection elastica.

Elastica (inextensible, clamped at s = 0, vertical dead load P at s = L, psi = slope angle):
    psi'' = -alpha cos(psi),  psi(0) = 0,  psi'(1) = 0,  alpha = P L^2 / EI,
    tip deflection delta / L = integral_0^1 sin(psi) ds.
Solved here by shooting on psi'(0) with a tight-tolerance ODE integrator.
"""

import numpy as np
import pytest

from validation.cantilever import EI, L, cantilever_path, max_relative_errors


def test_cantilever_matches_elastica_within_half_percent_at_100_nodes():
    path = cantilever_path(101)
    assert path.status == "ok"
    assert path.force[-1] * L**2 / EI > 9.9
    d_err, f_err = max_relative_errors(path)
    assert d_err < 5e-3
    assert f_err < 5e-3


def test_displacement_control_matches_elastica_too():
    path = cantilever_path(101, method="displacement", steps=60)
    assert path.status == "ok"
    d_err, f_err = max_relative_errors(path)
    assert f_err < 5e-3


@pytest.mark.slow
def test_cantilever_error_falls_as_n_to_the_minus_two():
    ns = np.array([26, 51, 101, 201])
    errors = np.array([max_relative_errors(cantilever_path(n, steps=20))[0] for n in ns])
    slope = np.polyfit(np.log(ns), np.log(errors), 1)[0]
    assert slope < -1.8, (errors, slope)
