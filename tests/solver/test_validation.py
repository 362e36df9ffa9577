"""Bad input raises ValueError naming the problem; hopeless paths stop with a status."""

import numpy as np
import pytest

from snapmorph.solver import ConvergenceError, Structure

XZ = np.stack([np.linspace(0, 0.1, 11), np.zeros(11)], 1)


def rod_structure():
    st = Structure()
    rod = st.add_rod(XZ, width=5e-3, thickness=5e-4, E=2.2e9)
    return st, rod


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(xz=np.where(np.arange(22).reshape(11, 2) == 5, np.nan, XZ)), "NaN"),
        (dict(width=-1.0), "width"),
        (dict(width=0.0), "width"),
        (dict(thickness=np.zeros(10)), "thickness"),
        (dict(thickness=np.ones(4)), "thickness"),
        (dict(E=0.0), "E"),
        (dict(E=np.nan), "E"),
        (dict(xz=XZ[:2]), "at least 3 nodes"),
        (dict(xz=np.zeros((5, 3))), "xz"),
        (dict(xz=np.repeat(XZ, 2, axis=0)), "coincident"),
    ],
)
def test_add_rod_rejects_bad_input(kwargs, match):
    args = dict(xz=XZ, width=5e-3, thickness=5e-4, E=2.2e9) | kwargs
    with pytest.raises(ValueError, match=match):
        Structure().add_rod(**args)


def test_unknown_or_conflicting_constraints():
    st, rod = rod_structure()
    with pytest.raises(ValueError, match="components"):
        st.fix(0, "y")
    with pytest.raises(ValueError, match="does not exist"):
        st.fix(99, "x")
    with pytest.raises(ValueError, match="itself"):
        st.tie(3, 3)
    with pytest.raises(ValueError, match="distinct"):
        st.rigid([2, 2])
    with pytest.raises(ValueError, match="tie method"):
        st.tie(1, 2, method="glue")


def test_pushing_a_node_fixed_in_that_direction():
    st, rod = rod_structure()
    st.fix(0, "xz")
    st.fix(1, "xz")
    st.fix(10, "z")
    with pytest.raises(ValueError, match="fixed in z"):
        st.push(10, (0.0, -1.0), 0.01)
    with pytest.raises(ValueError, match=r"fixed in x: it cannot be pushed along \(1, 0\)"):
        st.push(0, (1.0, 0.0), 0.01)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(direction=(0.0, 0.0)), "direction"),
        (dict(direction=(np.nan, 1.0)), "direction"),
        (dict(distance=-0.01), "distance"),
        (dict(distance=np.inf), "distance"),
        (dict(method="arc"), "method"),
        (dict(method="displacement", direction=(1.0, -1.0)), "axis-aligned"),
    ],
)
def test_push_rejects_bad_requests(kwargs, match):
    st, rod = rod_structure()
    st.fix(0, "xz")
    st.fix(1, "xz")
    args = dict(direction=(0.0, -1.0), distance=0.01, method="mgdc") | kwargs
    with pytest.raises(ValueError, match=match):
        st.push(10, **args)


def test_unsupported_structure_under_load_control_is_an_error_not_a_hang():
    st, rod = rod_structure()  # no supports at all: rigid-body motion is free
    with pytest.raises(ValueError, match="rigid-body"):
        st.push(10, (0.0, -1.0), 0.01, method="mgdc")


def test_path_that_cannot_converge_stops_with_a_status():
    # a tie spring of absurd stiffness ruins the conditioning; the path must end, with a
    # status string, after a bounded number of attempts
    st, rod = rod_structure()
    st.fix(0, "xz")
    st.fix(1, "xz")
    path = st.push(10, (0.0, -1.0), 0.05, method="displacement", max_iter=1, steps=2)
    assert path.status.startswith("not converged")
    assert len(path) >= 1


def test_equilibrium_failure_raises_convergence_error():
    st, rod = rod_structure()
    st.fix(0, "xz")
    st.fix(1, "xz")
    with pytest.raises(ConvergenceError):
        st.solve_equilibrium(st.reference_positions, node=10, force=1e3, max_iter=2)
