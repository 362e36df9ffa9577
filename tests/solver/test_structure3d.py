"""`solver.Structure3D`: whole-structure derivatives, the problem interface, clamps, joints,
determinism and bad input."""

import subprocess
import sys

import numpy as np
import pytest

from snapmorph.solver import Structure3D
from snapmorph.solver.banded import band_to_dense
from snapmorph.solver.equilibrium import equilibrium
from validation.strip3d import cantilever

E, NU, W, T = 2.2e9, 0.38, 5e-3, 0.5e-3


def two_rods_with_joint_and_clamp(rng, n=7):
    """A curved strip clamped at node 0 and a second strip leaving it at a rigid joint."""
    s = np.linspace(0.0, 0.1, n)
    a = np.stack([s, 0.01 * np.sin(20 * s), 2.0 * s**2], 1)
    st = Structure3D()
    r1 = st.add_rod(a, width=W, thickness=np.linspace(T, 2 * T, n - 1), E=E, nu=NU,
                    normal=(0.0, 0.3, 1.0))
    b = a[-1] + np.stack([0.3 * s, 0.6 * s, -0.2 * s], 1)
    r2 = st.add_rod(b, width=2 * W, thickness=T, E=E, nu=0.3, normal=(1.0, 0.0, 0.0))
    st.clamp(r1.nodes[0], toward=r1.nodes[1])
    st.joint(r1.nodes[-1], r2.nodes[0])
    return st


def _fd_full(sysm, q, h=1e-7):
    E0 = sysm.evaluate(q)
    g = sysm.grad_full.copy()
    K = band_to_dense(sysm.band)
    g_fd = np.empty_like(g)
    K_fd = np.empty_like(K)
    for i in range(q.size):
        qp, qm = q.copy(), q.copy()
        qp[i] += h
        qm[i] -= h
        Ep = sysm.evaluate(qp)
        gp = sysm.grad_full.copy()
        Em = sysm.evaluate(qm)
        gm = sysm.grad_full.copy()
        g_fd[i] = (Ep - Em) / (2 * h)
        K_fd[:, i] = (gp - gm) / (2 * h)
    return E0, g, K, g_fd, K_fd


def test_whole_structure_gradient_and_stiffness_fd(rng):
    st = two_rods_with_joint_and_clamp(rng)
    sysm = st.unconstrained_system()
    q0 = st.initial_state()
    # reference frames carried to one state, derivatives checked at another one
    sysm.accept(q0 + rng.normal(size=q0.size) * 3e-3)
    q = q0 + rng.normal(size=q0.size) * 3e-3
    E0, g, K, g_fd, K_fd = _fd_full(sysm, q)
    assert E0 > 0
    assert np.max(np.abs(g - g_fd)) < 1e-7 * np.max(np.abs(g))
    assert np.max(np.abs(K - K_fd)) < 1e-7 * np.max(np.abs(K))
    # the stress-free state has zero energy and zero force
    assert st.energy() == pytest.approx(0.0, abs=1e-20)


def test_reduced_stiffness_is_derivative_of_reduced_gradient(rng):
    """The reduced K (twists scaled to lengths, merged nodes) against FD along reduced DOFs."""
    st = two_rods_with_joint_and_clamp(rng)
    sysm = st.reduced_system()
    q = st.initial_state() + rng.normal(size=3 * st.n_nodes + st.n_edges) * 2e-3
    q[sysm.dof_map < 0] = st.initial_state()[sysm.dof_map < 0]
    sysm.evaluate(q)
    K = band_to_dense(sysm.band)
    h = 1e-7
    K_fd = np.empty_like(K)
    for i in range(sysm.n):
        du = np.zeros(sysm.n)
        du[i] = h
        qp, qm = q.copy(), q.copy()
        sysm.increment(qp, du)
        sysm.increment(qm, du, -1.0)
        sysm.evaluate(qp)
        gp = sysm.grad.copy()
        sysm.evaluate(qm)
        K_fd[:, i] = (gp - sysm.grad) / (2 * h)
    assert np.max(np.abs(K - K_fd)) < 1e-7 * np.max(np.abs(K))
    # reduced() inverts increment()
    du = rng.normal(size=sysm.n) * 1e-3
    q2 = q.copy()
    sysm.increment(q2, du)
    np.testing.assert_allclose(sysm.reduced(q2) - sysm.reduced(q), du, atol=1e-15)


def test_problem_interface_members():
    n = 11
    x = np.linspace(0, 0.1, n)
    st = Structure3D()
    rod = st.add_rod(np.stack([x, 0 * x, 0 * x], 1), width=W, thickness=T, E=E, nu=NU)
    assert st.dim == 3 and st.component_names == "xyz" and st.n_nodes == n
    q0 = st.initial_state()
    assert q0.shape == (3 * n + n - 1,)
    q0[0] = 99.0
    assert st.initial_state()[0] == 0.0  # a fresh copy every call
    np.testing.assert_array_equal(st.node_dofs(4), [12, 13, 14])
    q = st.initial_state()
    assert st.positions_of(q).shape == (n, 3)
    assert st.state_fields(q)["twist"].shape == (n - 1,)
    length, force = st.scales()
    assert length == pytest.approx(0.1)
    assert force == pytest.approx(E * W * T**3 / 12 / 0.1**2)
    st.clamp(rod.nodes[0], toward=rod.nodes[1])
    st.rigid([rod.nodes[4], rod.nodes[5]])
    st.fix(rod.nodes[-1], "yz")
    rep = st.supernodes()
    assert rep[5] == rep[4]
    fixed = st.fixed_components()
    assert fixed[0].all() and list(fixed[-1]) == [False, True, True]
    sysm = st.reduced_system(extra_fixed=[(rod.nodes[-1], 0)])
    assert sysm.n == 3 * (n - 2) - 3 + (n - 1)  # node 0 and the last node held, 4-5 merged
    assert sysm.bandwidth <= 13  # positions and twists interleaved along the rod
    assert np.all(sysm.dof_map[st.node_dofs(5)] == sysm.dof_map[st.node_dofs(4)])


@pytest.mark.parametrize("direction,EI_name", [((0.0, 0.0, -1.0), "EI1"), ((0.0, 1.0, 0.0), "EI2")])
def test_clamp_at_the_node_converges_second_order(direction, EI_name):
    """Small tip load on a cantilever clamped exactly at node 0: tip deflection P L^3 / (3 EI)
    about either axis, with errors falling as N^-2."""
    L = 0.1
    errors = []
    for n in (11, 21, 41):
        st, rod = cantilever(n, L)
        EI = float(getattr(st.rods[0], EI_name)[0])
        P = 1e-4 * 3 * EI / L**2  # deflection 1e-4 L: linear to about 1e-8
        pos, info = equilibrium(st, None, rod.nodes[-1], direction, P)
        d = float(np.dot(pos[-1] - st.reference_positions[-1], direction))
        errors.append(abs(d / (P * L**3 / (3 * EI)) - 1))
    assert errors[-1] < 4e-4  # 0.5 / (N - 1)^2
    assert 3.8 < errors[0] / errors[1] < 4.2 and 3.8 < errors[1] / errors[2] < 4.2


def _corner(reverse_second=False, n=9):
    s = np.linspace(0.0, 0.05, n)
    a = np.stack([s, 0 * s, 0 * s], 1)
    b = np.stack([0 * s + 0.05, s, 0 * s], 1)
    return a, b if not reverse_second else b[::-1]


def test_joint_equals_one_kinked_rod():
    """Two rods rigidly jointed at a corner behave exactly as one rod with the same kink,
    whichever way the second rod is numbered."""
    a, b = _corner()
    one = Structure3D()
    r = one.add_rod(np.concatenate([a, b[1:]]), width=W, thickness=T, E=E, nu=NU)
    one.clamp(r.nodes[0], toward=r.nodes[1])
    p_one = one.push(r.nodes[-1], direction=(0.0, 0.0, -1.0), distance=0.01, method="mgdc")
    for reverse in (False, True):
        a, b = _corner(reverse)
        two = Structure3D()
        r1 = two.add_rod(a, width=W, thickness=T, E=E, nu=NU)
        r2 = two.add_rod(b, width=W, thickness=T, E=E, nu=NU)
        corner_b = r2.nodes[-1] if reverse else r2.nodes[0]
        tip = r2.nodes[0] if reverse else r2.nodes[-1]
        two.clamp(r1.nodes[0], toward=r1.nodes[1])
        two.joint(r1.nodes[-1], corner_b)
        p_two = two.push(tip, direction=(0.0, 0.0, -1.0), distance=0.01, method="mgdc")
        assert p_two.status == "ok" and p_one.status == "ok"
        F1 = np.interp(0.008, p_one.displacement, p_one.force)
        F2 = np.interp(0.008, p_two.displacement, p_two.force)
        assert F2 == pytest.approx(F1, rel=1e-9)
        # the corner twists the first rod: orientation is carried through the joint
        assert np.max(np.abs(p_two.twist[-1, : len(a) - 1])) > 1e-2
    # without the joint's orientation coupling (a tie), the second rod hangs free
    a, b = _corner()
    tied = Structure3D()
    r1 = tied.add_rod(a, width=W, thickness=T, E=E, nu=NU)
    r2 = tied.add_rod(b, width=W, thickness=T, E=E, nu=NU)
    tied.clamp(r1.nodes[0], toward=r1.nodes[1])
    tied.tie(r1.nodes[-1], r2.nodes[0])
    with pytest.raises(ValueError, match="singular|rigid"):
        tied.push(r2.nodes[-1], direction=(0.0, 0.0, -1.0), distance=0.01, method="mgdc")


def test_fused_iterations_match_the_general_path(rng):
    """`RodSystem3D.fused_newton` / `fused_mgdc` (one compiled call per iteration) make the
    same step as evaluate + factor + solve + increment, to round-off, and report the same
    inertia; status 0 when converged, 1 on a failed LDL^T."""
    st = two_rods_with_joint_and_clamp(rng)
    sysm = st.reduced_system()
    q0 = st.initial_state() + rng.normal(size=st.initial_state().size) * 2e-4
    P = rng.normal(size=sysm.n)
    lam = 0.3
    # general path
    sysm.evaluate(q0)
    R = sysm.grad - lam * P
    assert sysm.factor()
    neg = sysm.negative_eigenvalues
    du = sysm.solve(-R)
    q_ref = q0.copy()
    sysm.increment(q_ref, du)
    both = sysm.solve(np.stack([P, -R], axis=1))
    uP1 = rng.normal(size=sysm.n)
    dl_ref = -float(uP1 @ both[:, 1]) / float(uP1 @ both[:, 0])
    q_mgdc_ref = q0.copy()
    sysm.increment(q_mgdc_ref, dl_ref * both[:, 0] + both[:, 1])
    scale = np.max(np.abs(q_ref - q0))
    # fused Newton
    q = q0.copy()
    status, r_max, du_max = sysm.fused_newton(q, lam, P, 0.0)
    assert status == 2 and sysm.negative_eigenvalues == neg
    assert r_max == pytest.approx(np.max(np.abs(R)), rel=1e-12)
    assert du_max == pytest.approx(np.max(np.abs(du)), rel=1e-9)
    np.testing.assert_allclose(q, q_ref, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(sysm.last_correction[: sysm.n], du, rtol=0,
                               atol=1e-9 * np.max(np.abs(du)))
    # fused MGDC corrector
    q = q0.copy()
    status, r_max, du_max, dl = sysm.fused_mgdc(q, lam, P, uP1, 0.0)
    assert status == 2 and dl == pytest.approx(dl_ref, rel=1e-9)
    np.testing.assert_allclose(q, q_mgdc_ref, rtol=0, atol=1e-9 * np.max(np.abs(q_mgdc_ref - q0)))
    # converged: nothing moves, K stays factorised
    q = q0.copy()
    assert sysm.fused_newton(q, lam, P, np.inf)[0] == 0
    np.testing.assert_array_equal(q, q0)
    # NaN state: status 1, nothing moves
    q = q0.copy()
    q[0] = np.nan
    assert sysm.fused_newton(q, lam, P, 0.0)[0] == 1


def test_identical_inputs_give_bit_identical_paths():
    st, rod = cantilever(21)
    p1 = st.push(rod.nodes[-1], direction=(0.0, 0.3, -1.0), distance=0.03)
    p2 = st.push(rod.nodes[-1], direction=(0.0, 0.3, -1.0), distance=0.03)
    assert p1.status == "ok"
    np.testing.assert_array_equal(p1.positions, p2.positions)
    np.testing.assert_array_equal(p1.twist, p2.twist)
    np.testing.assert_array_equal(p1.force, p2.force)
    assert p1.positions.shape == (len(p1), 21, 3) and p1.twist.shape == (len(p1), 20)


@pytest.mark.parametrize("call,match", [
    (lambda st: st.add_rod(np.zeros((5, 2)), W, T, E), "xyz"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, np.nan], [2, 0, 0]], W, T, E), "xyz"),
    (lambda st: st.add_rod([[0, 0, 0], [0, 0, 0], [2, 0, 0]], W, T, E), "coincident"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, 0], [2, 0, 0]], -W, T, E), "width"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, 0], [2, 0, 0]], W, [T, T, T], E), "thickness"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, 0], [2, 0, 0]], W, T, -1.0), "E"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, 0], [2, 0, 0]], W, T, "steel"), "E"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, 0], [2, 0, 0]], W, T, E, nu=0.7), "nu"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, 0], [2, 0, 0]], W, T, E, normal=(2, 0, 0)), "normal"),
    (lambda st: st.add_rod([[0, 0, 0], [1, 0, 0], [2, 0, 0]], W, T, E, normal=(0, 0)), "normal"),
])
def test_bad_rods_raise_clear_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call(Structure3D())


def test_bad_constraints_and_pushes_raise_clear_errors():
    st, rod = cantilever(11)
    with pytest.raises(ValueError, match="components"):
        st.fix(3, "xw")
    with pytest.raises(ValueError, match="node"):
        st.fix(11, "x")
    with pytest.raises(ValueError, match="node"):
        st.fix(2.0, "x")
    with pytest.raises(ValueError, match="toward"):
        st.clamp(3, toward=7)
    with pytest.raises(ValueError, match="already clamped"):
        st.clamp(0, toward=1)
    with pytest.raises(ValueError, match="coincident"):
        st.joint(2, 5)
    with pytest.raises(ValueError, match="rigid"):
        st.rigid([3])
    with pytest.raises(ValueError, match="direction"):
        st.push(10, direction=(0.0, -1.0), distance=0.01)
    with pytest.raises(ValueError, match="distance"):
        st.push(10, direction=(0.0, 0.0, -1.0), distance=-0.01)
    with pytest.raises(ValueError, match="fixed in"):
        st.push(0, direction=(0.0, 0.0, -1.0), distance=0.01)
    with pytest.raises(ValueError, match="method"):
        st.push(10, direction=(0.0, 0.0, -1.0), distance=0.01, method="arclength")
    with pytest.raises(ValueError, match="no rods"):
        Structure3D().push(0, distance=0.01)
    free = Structure3D()
    free.add_rod([[0, 0, 0], [0.05, 0, 0], [0.1, 0, 0]], W, T, E)
    with pytest.raises(ValueError, match="singular|rigid"):
        free.push(2, direction=(0.0, 0.0, -1.0), distance=0.01)


def test_bad_input_never_shows_a_numba_traceback():
    """From a clean process, as a user would: the error is one ValueError line."""
    code = ("import numpy as np\nfrom solver import Structure3D\nst = Structure3D()\n"
            "st.add_rod(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]), width=5e-3, "
            "thickness=0.5e-3, E=2.2e9, normal=(1.0, 0.0, 0.0))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert r.returncode != 0
    assert "ValueError: normal must be" in r.stderr
    assert "numba" not in r.stderr.lower()


def test_joint_of_rods_side_by_side_couples_their_frames():
    """Two rods both starting at the joint along the same line (edges that would fold by
    180 degrees in a kink pair) are coupled frame to frame: no singularity (exact
    derivatives at a bent state), and the joint carries moments: with the first rod clamped
    at the joint, the second is a cantilever (tip deflection within the joint's extra
    compliance, 3 l / L of PL^3/3EI), where a tie alone would leave it free to swing."""
    L, n = 0.05, 21
    s = np.linspace(0.0, L, n)
    st = Structure3D()
    r1 = st.add_rod(np.stack([s, 0 * s, 0 * s], 1), W, T, E)
    r2 = st.add_rod(np.stack([s, 0 * s, 0 * s], 1), W, T, E)
    st.joint(r1.nodes[0], r2.nodes[0])
    sysm = st.unconstrained_system()
    rng = np.random.default_rng(3)
    q = st.initial_state()
    q[: 3 * st.n_nodes] += 1e-3 * rng.standard_normal(3 * st.n_nodes)
    q[3 * st.n_nodes:] += 0.05 * rng.standard_normal(st.n_edges)
    sysm.evaluate(q)
    g = sysm.grad_full.copy()
    assert np.all(np.isfinite(g))
    h = 1e-7
    for k in rng.choice(q.size, 12, replace=False):
        qp, qm = q.copy(), q.copy()
        qp[k] += h
        qm[k] -= h
        fd = (sysm.evaluate(qp) - sysm.evaluate(qm)) / (2 * h)
        assert abs(fd - g[k]) <= 1e-5 * (abs(g[k]) + np.max(np.abs(g)) * 1e-3)
    st.clamp(r1.nodes[0], r1.nodes[1])
    st.fix(r1.nodes[-1], "xyz")
    P = 1e-4  # N: small deflection
    pos, _ = equilibrium(st, None, int(r2.nodes[-1]), (0.0, 0.0, -1.0), P)
    delta = -pos[r2.nodes[-1], 2]
    EI = E * W * T**3 / 12
    ratio = delta / (P * L**3 / (3 * EI))
    # the joint is a kink pair of stiffness EI / l (two half edges in series): the root
    # turns by P L l / EI more, the tip drops by 3 l / L of PL^3/3EI more
    assert abs(ratio - (1.0 + 3.0 / (n - 1))) < 0.01, ratio
    # two rods continuing one another through the joint are fine too
    r3 = st.add_rod(np.stack([-s, 0 * s, 0 * s], 1), W, T, E)
    st.joint(r3.nodes[0], r1.nodes[0])


def test_path_states_restart_in_any_system():
    """A path records its twists in the canonical convention (frames carried straight from
    the stress-free ones), so a state taken off a path that turns in 3-D restarts a fresh
    system at the same equilibrium. On this path (a strip with a tilted face normal pushed
    obliquely) the time-parallel frames pick up a holonomy of up to 0.64 rad: the raw
    twists restarted this way do not even converge (measured)."""
    L, n = 0.1, 21
    s = np.linspace(0.0, L, n)
    st = Structure3D()
    rod = st.add_rod(np.stack([s, 0 * s, 0 * s], 1), W, T, E, normal=(0.0, 0.5, 0.866))
    st.clamp(rod.nodes[0], rod.nodes[1])
    tip = int(rod.nodes[-1])
    direction = (0.0, 0.6, -0.8)
    path = st.push(tip, direction, 0.8 * L, method="mgdc")
    assert path.status == "ok"
    K = len(path.force)
    for j in (K // 3, 2 * K // 3, K - 1):
        q = st.state(path.positions[j], path.twist[j])
        pos, info = st.solve_equilibrium(q, node=tip, direction=direction, force=path.force[j])
        assert np.max(np.abs(pos - path.positions[j])) < 1e-9 * L
        assert np.max(np.abs(st.twist_of(info["state"]) - path.twist[j])) < 1e-7
