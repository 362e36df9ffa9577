"""Checks shared by the unit models' tests (planar, 3-D, 2-D)."""

from __future__ import annotations

import numpy as np
import pytest


def require_solver_3d():
    """Skip the test when the 3-D rod solver (`solver.Structure3D`) is not available."""
    try:
        from snapmorph.solver import Structure3D  # noqa: F401
    except ImportError:  # pragma: no cover - before issue 13 landed
        pytest.skip("solver.Structure3D is not available")


def assert_supports_hold_only_rigid_motion(X, supports):
    """The held components ``supports`` [(node, "xyz" subset)] at positions ``X`` (n, 3) are
    six and independent on the rigid-body motions: the unit is held statically determinately
    (e_k . (omega x p) = omega . (p x e_k) is a rotation's component along a held axis)."""
    rows = []
    for node, comps in supports:
        for c in comps:
            k = "xyz".index(c)
            row = np.zeros(6)
            row[k] = 1.0
            row[3:] = np.cross(X[node], np.eye(3)[k])
            rows.append(row)
    assert len(rows) == 6 and np.linalg.matrix_rank(np.array(rows)) == 6


def make_second_state_unstable(monkeypatch, module):
    """Let ``module._state_stability`` report two negative eigenvalues at its second call,
    state (iii) (the first, state (ii), stays real): no geometry found keeps an unstable
    state (iii), so this is how its reporting is tested."""
    from snapmorph.solver.stability import StateStability

    real = module._state_stability
    calls = []

    def second_unstable(*args):
        calls.append(1)
        s = real(*args)
        return StateStability(2, 2) if len(calls) == 2 else s

    monkeypatch.setattr(module, "_state_stability", second_unstable)
