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


def _old_make_control_parts(st, node, direction):
    """The direction, members and their DOFs as `make_control` computed them before its
    direction memo and `nodes_dofs`."""
    n = np.asarray(direction, dtype=float).reshape(-1)
    n = n / np.max(np.abs(n))
    n = n / np.linalg.norm(n)
    rep = st.supernodes()
    members = np.flatnonzero(rep == rep[node])
    return n, members, np.array([st.node_dofs(m) for m in members], dtype=np.int64)


def test_make_control_remembers_directions_not_their_arrays():
    """`make_control`'s direction memo gives the bits the normalisation gives (-0.0 kept
    apart from 0.0), a fresh array every call, and remembers no invalid direction; the
    members' DOFs at once (`nodes_dofs`) are those of `node_dofs`."""
    from snapmorph.solver.problem import make_control

    st, rod = rod_structure()
    st.fix(0, "xz")
    st.fix(1, "xz")
    st.rigid([8, 9, 10])
    for direction in ((0.0, -1.0), (-0.0, -1.0), (0.3, -1.7), [1e300, 3e299], (0.0, -1.0)):
        c = make_control(st, 9, direction, 0.01, "mgdc")
        n, members, member_dofs = _old_make_control_parts(st, 9, direction)
        assert c.direction.tobytes() == n.tobytes()
        assert np.array_equal(c.members, members) and c.member_dofs.dtype == np.int64
        assert np.array_equal(c.member_dofs, member_dofs)
        c.direction[:] = 7.0  # a caller's change reaches no later control
    assert make_control(st, 9, (0.0, -1.0), 0.01, "mgdc").direction.tolist() == [0.0, -1.0]
    assert np.signbit(make_control(st, 9, (-0.0, -1.0), 0.01, "mgdc").direction[0])
    for _ in range(2):  # asked twice: still refused
        with pytest.raises(ValueError, match="direction must be a finite non-zero"):
            make_control(st, 9, (np.inf, 1.0), 0.01, "mgdc")
        with pytest.raises(ValueError, match="direction must be a finite non-zero"):
            make_control(st, 9, (0.0, 0.0, -1.0), 0.01, "mgdc")


def test_state_from_copies_and_checks_what_it_is_given():
    """`state_from` (no copy of a float input of its own): the state is a new array, the
    input untouched; non-finite values and wrong shapes are still refused, ints accepted."""
    from snapmorph.solver.problem import real_scalar, state_from

    st, rod = rod_structure()
    X = st.reference_positions.copy()
    for given in (X, X.reshape(-1), np.asfortranarray(X), X.astype(np.float32), X.tolist()):
        q = state_from(st, given)
        assert q.flags.writeable and q.flags.c_contiguous and q.shape == (22,)
        assert np.array_equal(q, np.asarray(given, dtype=float).reshape(-1))
        q[:] = 1.0
        assert np.array_equal(X, st.reference_positions)
    assert np.array_equal(state_from(st, np.ones((11, 2), dtype=int)), np.ones(22))
    bad = X.copy()
    bad[3, 1] = np.nan
    for given in (bad, bad.reshape(-1)):
        with pytest.raises(ValueError, match="NaN or infinite"):
            state_from(st, given)
    with pytest.raises(ValueError, match="shape"):
        state_from(st, np.zeros((3, 2)))
    assert real_scalar(0.25, "d", "m") == 0.25 and np.isnan(real_scalar(np.nan, "d", "m"))
    with pytest.raises(ValueError, match="single real number"):
        real_scalar([0.1, 0.2], "d", "m")
    q0 = st.initial_state()
    q0[:] = 0.0
    assert np.array_equal(st.initial_state(), X.reshape(-1))  # a fresh copy every call


def test_tie_all_bonds_as_tie_does_and_refuses_what_tie_refuses():
    """`Structure.tie_all`: the same ties (Python int pairs, in order) as `tie` pair by pair,
    and bad pairs refused with `tie`'s errors (a node out of range, a node tied to itself,
    a float or bool index, an unknown method)."""
    st_all, _ = rod_structure()
    st_one, _ = rod_structure()
    pairs = [(np.int64(0), np.int64(5)), (3, 7), (10, 2)]
    st_all.tie_all(pairs)
    for a, b in pairs:
        st_one.tie(a, b)
    assert st_all._merges == st_one._merges and all(type(v) is int for p in st_all._merges for v in p)
    assert np.array_equal(st_all.supernodes(), st_one.supernodes())
    st_all.tie_all(np.array([[1, 4]]))
    assert st_all._merges[-1] == (1, 4)
    for bad, match in (([(0, 11)], "does not exist"), ([(2, 2)], "itself"),
                       ([(1.0, 2)], "integer node index"), ([(True, 2)], "integer node index"),
                       ([(-1, 2)], "does not exist"), (np.array([[0, 11]]), "does not exist"),
                       (np.array([[3, 3]]), "itself"), (np.array([[-1, 3]]), "does not exist"),
                       (np.array([[True, False]]), "integer node index")):
        with pytest.raises(ValueError, match=match):
            rod_structure()[0].tie_all(bad)
    with pytest.raises(ValueError, match="tie method"):
        rod_structure()[0].tie_all([(1, 2)], method="glue")
    springs, _ = rod_structure()
    springs.tie_all([(0, 5), (3, 7)], method="spring", stiffness=1e5)
    assert springs._spring_nodes == [(0, 5), (3, 7)] and springs._merges == []


@pytest.mark.filterwarnings("ignore:All-NaN slice")  # (the message's np.nanmin of a NaN width)
def test_scalar_sections_are_the_arrays_they_stand_for():
    """A scalar width or thickness (its checks done once) gives the bits of the same value
    per half edge; an invalid scalar is refused as before."""
    a, b = Structure(), Structure()
    a.add_rod(XZ, width=5e-3, thickness=5e-4, E=2.2e9)
    b.add_rod(XZ, width=np.full((10, 2), 5e-3), thickness=np.full(10, 5e-4), E=2.2e9)
    for x, y in zip(a.elements(), b.elements()):
        assert x.tobytes() == y.tobytes()
    assert a.rods[0].width.shape == (10, 2) and a.rods[0].width.flags.writeable
    for value in (np.inf, np.nan, -5e-3, 0.0):
        with pytest.raises(ValueError, match="width must be finite and > 0"):
            Structure().add_rod(XZ, width=value, thickness=5e-4, E=2.2e9)
