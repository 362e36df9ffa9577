"""MGDC's second-order predictor (`solver.mgdc`, ``predictor="second-order"``) and the second
difference of the stiff terms it is built on (`solver.assembly.stiff_second_difference`)."""

import numpy as np
import pytest

from snapmorph.solver.assembly import assemble_system
from snapmorph.solver.energies import spring_terms, stretch_terms
from snapmorph.solver.mgdc import _Mgdc, follow_mgdc
from snapmorph.solver.problem import make_control
from snapmorph.solver.steps import driver_options
from validation.arch import clamped_arch

H = 0.005  # m, the arch's rise (h / t = 10)


def _stiff_gradient(system, q):
    """The reduced gradient of the stretching and spring terms alone, element by element in
    Python (the reference the kernel is checked against)."""
    stretch_nodes, stretch_params, _, _, spring_nodes, spring_params = system.elements
    out = np.zeros(system.n)
    g, h = np.empty(4), np.empty((4, 4))
    for nodes, dofs, terms in (
            (stretch_nodes, system.dofs[0],
             lambda x, e: stretch_terms(x, stretch_params[e, 0], stretch_params[e, 1], g, h)),
            (spring_nodes, system.dofs[2],
             lambda x, e: spring_terms(x, *spring_params[e, :3], g, h))):
        for e in range(nodes.shape[0]):
            x = np.concatenate([q[2 * n: 2 * n + 2] for n in nodes[e]])
            terms(x, e)
            for a in range(4):
                if dofs[e, a] >= 0:
                    out[dofs[e, a]] += g[a]
    return out


@pytest.mark.parametrize("tie", ["rods", "springs"])
def test_stiff_second_difference_is_that_of_the_stretching_and_spring_gradients(tie):
    from snapmorph.units import UnitGeometry
    from snapmorph.units.geometry import build_unit

    if tie == "rods":
        st = clamped_arch(H)[0]
    else:  # a unit bonded by springs: spring elements in the system
        st = build_unit(UnitGeometry(L=1.0, h=0.2, t=0.005, w=0.05, b=0.05), nodes=41,
                        tie="spring").structure
    system = st.reduced_system()
    rng = np.random.default_rng(3)
    q = st.initial_state()
    system.increment(q, 1e-3 * rng.standard_normal(system.n))
    du = 1e-3 * rng.standard_normal(system.n)
    system.evaluate(q)
    assert system.factor()
    band, grad = system.band.copy(), system.grad.copy()
    plus, minus = q.copy(), q.copy()
    system.increment(plus, du)
    system.increment(minus, du, -1.0)
    expected = _stiff_gradient(system, plus) + _stiff_gradient(system, minus) \
        - 2.0 * _stiff_gradient(system, q)
    got = system.stiff_second_difference(q, du)
    scale = np.max(np.abs(expected))
    assert scale > 0.0
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * scale)
    # the factorisation and gradient of the system's own state are untouched
    np.testing.assert_array_equal(system.band, band)
    np.testing.assert_array_equal(system.grad, grad)


def test_stiff_second_difference_halves_as_the_square_of_the_increment():
    st = clamped_arch(H)[0]
    system = st.reduced_system()
    rng = np.random.default_rng(5)
    q = st.initial_state()
    du = rng.standard_normal(system.n)
    sizes = [np.linalg.norm(system.stiff_second_difference(q, a * du)) for a in (1e-5, 5e-6)]
    assert sizes[0] / sizes[1] == pytest.approx(4.0, rel=2e-3)


def _follower(predictor):
    """An MGDC push of the clamped arch (h / t = 10) moved six steps along its path."""
    st, mid, _ = clamped_arch(H)
    control = make_control(st, mid, (0.0, -1.0), 0.8 * H, "mgdc")
    o = driver_options(100, 1e-9, 12, 20000, 1e-7, None, 0.5, 8, None, "follow")
    o.update(max_accept_iter=8, target_iterations=4, tol_disp=1e-11, predictor=predictor)
    m = _Mgdc(st, control, o, None, "follow", False, 0.0)
    for _ in range(6):
        assert m._accept(*m._step())
    return m


def _residual(m, q, lam):
    system = m.system
    band, g, gf = np.empty_like(system.band), np.empty_like(system.grad), \
        np.empty_like(system.grad_full)
    assemble_system(q, system.elements, system.dofs, band, g, gf)
    return float(np.linalg.norm(g - lam * m.P))


def test_second_order_predictor_leaves_a_residual_of_higher_order_than_the_tangent():
    """From a converged state: the tangent step's residual falls as s^2; with the curvature
    term it is 50-400 x smaller at these steps and falls faster (the stretching part as s^3;
    the bending part, left out of the term, as s^2 below it)."""
    m = _follower("second-order")
    tangent, second = [], []
    for scale in (1.0, 0.5, 0.25):
        dlam = m.s0 * scale / np.linalg.norm(m.uP)
        q = m.q.copy()
        m.system.increment(q, m.uP, dlam)
        tangent.append(_residual(m, q, m.lam + dlam))
        bend = m._bend(m.uP, dlam)
        assert bend is not None
        m.system.increment(q, bend[0])
        second.append(_residual(m, q, m.lam + dlam + bend[1]))
    assert tangent[0] / tangent[1] == pytest.approx(4.0, rel=0.05)
    assert tangent[1] / tangent[2] == pytest.approx(4.0, rel=0.05)
    for t, s in zip(tangent, second):
        assert s < 0.02 * t, (t, s)
    assert second[0] / second[1] > 5.0, second


def test_the_predictors_follow_the_same_path_and_second_order_saves_iterations():
    st, mid, EI = clamped_arch(H)
    paths = {p: st.push(mid, (0.0, -1.0), 0.8 * H * 3, method="mgdc", predictor=p)
             for p in ("tangent", "second-order")}
    for p, path in paths.items():
        assert path.status == "ok", (p, path.status)
    a, b = paths["tangent"], paths["second-order"]
    # every sample of both paths on the curve of a dense displacement-controlled push (the
    # clamped arch's path is monotone in d: the rig follows it without a jump)
    rig = st.push(mid, (0.0, -1.0), 0.8 * H * 3, method="displacement", steps=600)
    assert rig.status == "ok" and rig.info["rig_jumps"] == []
    peak = float(np.max(rig.force))
    for path in (a, b):
        assert np.all(np.diff(path.displacement) > 0)
        d, F = path.displacement, path.force
        inside = d <= rig.displacement[-1]  # MGDC's last step lands past the distance
        assert inside.sum() >= len(d) - 1
        off = np.abs(F[inside] - np.interp(d[inside], rig.displacement, rig.force))
        assert np.max(off) < 2e-3 * peak, np.max(off) / peak
    assert b.info["total_iterations"] < 0.75 * a.info["total_iterations"]


def test_predictor_option_is_validated():
    st, mid, _ = clamped_arch(H)
    control = make_control(st, mid, (0.0, -1.0), H, "mgdc")
    with pytest.raises(ValueError, match="predictor"):
        follow_mgdc(st, control, predictor="cubic")


def test_systems_without_a_second_difference_keep_the_tangent():
    """3-D rods give no stiff second difference: the option leaves their path bit for bit."""
    from snapmorph.solver.structure3d import Structure3D

    x = np.linspace(0.0, 0.1, 31)
    z = 0.005 * 0.5 * (1 - np.cos(2 * np.pi * x / 0.1))
    st = Structure3D()
    st.add_rod(np.stack([x, np.zeros_like(x), z], 1), width=5e-3, thickness=0.5e-3, E=2.2e9)
    for k in (0, 1, 29, 30):
        st.fix(k, "xyz")
    paths = [st.push(15, (0.0, 0.0, -1.0), 0.004, method="mgdc", predictor=p)
             for p in ("tangent", "second-order")]
    np.testing.assert_array_equal(paths[0].force, paths[1].force)
