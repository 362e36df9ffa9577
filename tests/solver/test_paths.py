"""Path following that can be trusted (issue 12): the benchmark family, MGDC against
displacement control against references, set up through the public API the obvious way.

Centre-clamped cosine arch (l = 0.1 m, t = 0.5 mm, w = 5 mm, E = 2.2 GPa), x from 0 to l,
pushed at its midpoint to 2.2 h, in two set-ups:
- "fix": each end clamped by fixing its first two nodes, the centre by
  ``rigid([mid-1, mid, mid+1])`` and ``fix(mid, "x")`` (clamps half an edge inside: O(1/N));
- "clamp": ``clamp(0)``, ``clamp(n-1)`` and a sliding ``clamp(mid, hold_position=False)``
  with ``fix(mid, "x")`` (clamps exactly at the nodes: O(1/N^2)).
References (EI h / l^3): the converged beam values F_max = 711, 732, 710 and F_min = -338,
-363, -356 for h/t = 6, 10, 20 (issue 12). See docs/path-following.md for why both set-ups
meet a bifurcation at the force maximum (each half of the arch is point-symmetric).
"""

import subprocess
import sys

import numpy as np
import pytest

from snapmorph.solver import Structure
from validation.arch import E, L_SPAN, T, W, arch, first_peak_index
BEAM = {6: (711.0, -338.0), 10: (732.0, -363.0), 20: (710.0, -356.0)}


def push_both(h_over_t, n_nodes, setup, centre=True):
    """MGDC and displacement-control paths, each with (first peak, minimum) in EI h / l^3."""
    out = {}
    for method in ("mgdc", "displacement"):
        st, mid, h, EI = arch(h_over_t, n_nodes, setup, centre)
        path = st.push(mid, (0.0, -1.0), 2.2 * h, method=method)
        assert path.status == "ok", (method, path.status)
        assert path.displacement[-1] >= 2.2 * h * (1 - 1e-9)
        f = path.force / (EI * h / L_SPAN**3)
        out[method] = (path, f[first_peak_index(f)], f.min())
    return out


def assert_agree(out, rel=0.01):
    (_, pk_m, mn_m), (_, pk_d, mn_d) = out["mgdc"], out["displacement"]
    assert abs(pk_m / pk_d - 1) <= rel, (pk_m, pk_d)
    assert abs(mn_m / mn_d - 1) <= rel, (mn_m, mn_d)


def never_retraces(path, h):
    """After its last critical point the path only advances; it never comes back to a
    critical point it passed (no oscillation between two of them)."""
    d = path.displacement / h
    pts = [(round(c.d / h, 6), round(c.F, 9)) for c in path.critical_points if c.kind == "bifurcation"]
    return len(pts) == len(set(pts)) and d[-1] >= 2.2 * (1 - 1e-9)


@pytest.mark.parametrize("setup", ["fix", "clamp"])
@pytest.mark.parametrize("h_over_t", [6, 10, 20])
def test_centre_clamped_arch_mgdc_and_displacement_control_agree(h_over_t, setup):
    out = push_both(h_over_t, 101, setup)
    assert_agree(out)
    for path, _, _ in out.values():
        assert never_retraces(path, h_over_t * T)
        # continuous paths: no jump of a displacement-controlled rig was needed
        assert path.info["rig_jumps"] == []
        # a critical point at the force maximum, a bifurcation in the fix set-up (the
        # halves leave their point symmetry) or, when a limit point comes first, a limit
        first = path.critical_points[0]
        assert abs(first.F / path.force[first_peak_index(path.force)] - 1) < 1e-3
        if setup == "fix":
            assert first.kind == "bifurcation"
    if setup == "clamp":  # already converged to 0.3 % at 101 nodes
        peak, fmin = BEAM[h_over_t]
        assert abs(out["mgdc"][1] / peak - 1) < 0.003
        assert abs(out["mgdc"][2] / fmin - 1) < 0.01


@pytest.mark.slow
@pytest.mark.parametrize("n_nodes", [201, 401])
@pytest.mark.parametrize("setup", ["fix", "clamp"])
@pytest.mark.parametrize("h_over_t", [6, 10, 20])
def test_centre_clamped_arch_refined_meets_the_beam_values(h_over_t, setup, n_nodes):
    out = push_both(h_over_t, n_nodes, setup)
    assert_agree(out)
    if n_nodes == 401:
        peak, fmin = BEAM[h_over_t]
        for _, pk, mn in out.values():
            assert abs(pk / peak - 1) <= 0.03, pk
            assert abs(mn / fmin - 1) <= 0.05, mn


@pytest.mark.slow
def test_clamp_setup_converges_as_n_to_the_minus_two_and_fix_as_one_over_n():
    peaks = {s: [push_both(10, n, s)["displacement"][1] for n in (101, 201, 401)]
             for s in ("fix", "clamp")}
    for s, expected in (("fix", 1.0), ("clamp", 2.0)):
        p = np.array(peaks[s])
        ratio = (p[0] - p[1]) / (p[1] - p[2])  # 2^order for halved edges
        assert abs(np.log2(abs(ratio)) - expected) < 0.35, (s, p)


def test_same_push_is_bit_identical_whatever_ran_before():
    def push():
        st, mid, h, _ = arch(20, 101, "fix")
        return st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")

    first = push()
    # other work in between: another structure, the other driver, a bifurcating column
    st, mid, h, _ = arch(10, 51, "clamp", centre=False)
    st.push(mid, (0.0, -1.0), 2.2 * h, method="displacement")
    st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")
    second = push()
    assert first.status == "ok" and len(first) == len(second)
    assert np.array_equal(first.force, second.force)
    assert np.array_equal(first.positions, second.positions)
    # and in a fresh process
    code = (
        "import hashlib, sys; sys.path.insert(0, '.');"
        "from validation.arch import arch;"
        "st, mid, h, _ = arch(20, 101, 'fix');"
        "p = st.push(mid, (0.0, -1.0), 2.2 * h, method='mgdc');"
        "print(hashlib.sha256(p.force.tobytes() + p.positions.tobytes()).hexdigest())"
    )
    import hashlib

    fresh = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           check=True, timeout=600).stdout.strip()
    here = hashlib.sha256(first.force.tobytes() + first.positions.tobytes()).hexdigest()
    assert fresh == here


def test_centre_rotation_free_asymmetric_snap_with_snap_back():
    # only the midpoint's x held: the arch leaves symmetry at a bifurcation and its
    # asymmetric branch turns back in d (snap-back). MGDC follows the snap-back; a
    # displacement-controlled rig cannot and jumps (recorded in info["rig_jumps"]).
    h_over_t = 10
    st, mid, h, EI = arch(h_over_t, 101, "clamp", centre=False)
    mg = st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")
    st, mid, h, EI = arch(h_over_t, 101, "clamp", centre=False)
    dc = st.push(mid, (0.0, -1.0), 2.2 * h, method="displacement")
    unit = EI * h / L_SPAN**3
    for p in (mg, dc):
        assert p.status == "ok" and p.displacement[-1] >= 2.2 * h * (1 - 1e-9)
        assert p.critical_points[0].kind == "bifurcation" and p.critical_points[0].switched
    # the first peak is the bifurcation, the same for both
    pk_m = mg.force[first_peak_index(mg.force)] / unit
    pk_d = dc.force[first_peak_index(dc.force)] / unit
    assert abs(pk_m / pk_d - 1) < 0.01
    # MGDC met a true limit point of d (snap-back) and followed it back...
    assert any(c.kind == "limit" and c.control == "displacement" for c in mg.critical_points)
    assert np.any(np.diff(mg.displacement) < 0)
    # ...and the rig jumped where MGDC turned back; displacement control only advances
    assert len(dc.info["rig_jumps"]) >= 1
    assert np.all(np.diff(dc.displacement) > 0)
    # both end on the same (symmetric, inverted) branch
    k = int(np.flatnonzero(np.diff(mg.displacement) < 0)[-1]) + 1  # after the last turn
    f_m = np.interp(2.1 * h, mg.displacement[k:], mg.force[k:])
    f_d = np.interp(2.1 * h, dc.displacement, dc.force)
    assert abs(f_m / f_d - 1) < 0.01


def mgdc_and_rig(h_over_t, n_nodes, setup):
    """The arch with its centre free in rotation (x held) pushed to 2.2 h by MGDC and by
    displacement control: (MGDC path, rig path, structure, h, EI)."""
    st, mid, h, EI = arch(h_over_t, n_nodes, setup, centre=False)
    mg = st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")
    st, mid, h, EI = arch(h_over_t, n_nodes, setup, centre=False)
    dc = st.push(mid, (0.0, -1.0), 2.2 * h, method="displacement")
    return mg, dc, st, h, EI


def travelled(path):
    """Sum of |dd| along a path, m: the push distance for a path that only advances."""
    return float(np.sum(np.abs(np.diff(path.displacement))))


@pytest.mark.parametrize("h_over_t", [10, 20])
def test_centre_rotation_free_fix_setup_goes_forward_to_the_target(h_over_t):
    # The obvious set-up (ends fixed on two nodes, centre held in x only): the symmetric
    # path stays stable with the displacement held through its force maximum and meets a
    # subcritical bifurcation at d = 1.39 h, whose branch turns back in d and, unlike
    # the clamp set-up's, never restabilises: followed back it turned at d = 0.09 h onto
    # ever less stable branches, 748-20000 steps and F_min down to -13767 EI h / l^3
    # (issue 12). MGDC now leaves that branch and jumps on from the point as a
    # displacement-controlled rig does.
    mg, dc, st, h, EI = mgdc_and_rig(h_over_t, 101, "fix")
    unit = EI * h / L_SPAN**3
    for p in (mg, dc):
        assert p.status == "ok", p.status
        assert p.displacement[-1] >= 2.2 * h * (1 - 1e-9)
        assert never_retraces(p, h)
        assert len(p) < 400
    # the path goes forward: only short snap-backs near the rejoining point (< 5 % of h)
    assert travelled(mg) < 2.2 * h * 1.05
    assert mg.info["abandoned_branches"] and mg.info["rig_jumps"]
    bif = mg.bifurcations[0]
    assert bif.switched and abs(bif.d / h - 1.39) < 0.03
    assert mg.info["abandoned_branches"][0] == bif.d
    # MGDC and the rig agree on the peak and on the branch they end on; F_min is the
    # rejoining bifurcation's (a kink), a sane fraction of the peak
    pk_m = mg.force[first_peak_index(mg.force)]
    pk_d = dc.force[first_peak_index(dc.force)]
    assert abs(pk_m / pk_d - 1) < 0.01
    assert abs(mg.force.min() / pk_m) < 0.3
    assert abs(mg.force.min() / mg.bifurcations[-1].F - 1) < 1e-3
    f_m = np.interp(2.1 * h, mg.displacement, mg.force)
    f_d = np.interp(2.1 * h, dc.displacement, dc.force)
    assert abs(f_m / f_d - 1) < 0.01
    # on the stable asymmetric branch right after the jump (as the rig lands)
    k = int(np.flatnonzero(mg.displacement > bif.d * (1 + 1e-6))[0])
    assert mg.negative_eigenvalues_displacement[k] == 0 and mg.force[k] / unit > 100.0


@pytest.mark.parametrize("n_nodes", [101, pytest.param(201, marks=pytest.mark.slow)])
@pytest.mark.parametrize("setup", ["fix", "clamp"])
@pytest.mark.parametrize("h_over_t", [6, 10, 20])
def test_centre_rotation_free_mgdc_goes_forward_and_agrees_with_the_rig(h_over_t, setup,
                                                                        n_nodes):
    # The asymmetric-snap family: MGDC may follow short snap-backs (< 5 % of the push
    # again) but never wanders, never runs on a branch with more than one unstable mode
    # with d held, and meets the same first peak as the rig. (Before: fix set-up, 101
    # nodes, 748-20000 steps; clamp set-up, h/t = 6, 201 nodes: a tangent-plane "switch"
    # that fell back onto the unstable symmetric path, peak 710.5 where the rig sees 534.4.)
    mg, dc, st, h, EI = mgdc_and_rig(h_over_t, n_nodes, setup)
    for p in (mg, dc):
        assert p.status == "ok", p.status
        assert p.displacement[-1] >= 2.2 * h * (1 - 1e-9)
        assert never_retraces(p, h) and len(p) < 600
        assert p.negative_eigenvalues_displacement.max() <= 1
    assert travelled(mg) < 1.05 * mg.displacement[-1]
    pk_m = mg.force[first_peak_index(mg.force)]
    pk_d = dc.force[first_peak_index(dc.force)]
    assert abs(pk_m / pk_d - 1) < 0.01, (pk_m, pk_d)


def test_a_wandering_path_ends_with_a_status_that_says_so(monkeypatch):
    # Without the check that a backward branch restabilises, MGDC wanders as in issue 12
    # (d back and forth between 0.1 h and 1.9 h with the force growing without bound);
    # the wandering guard stops it with a status that says so instead of "ok".
    from snapmorph.solver.branching import BranchMonitor

    monkeypatch.setattr(BranchMonitor, "excursion_verdict", lambda self, new: None)
    st, mid, h, EI = arch(20, 101, "fix", centre=False)
    path = st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")
    assert path.status.startswith("stopped: the path wanders"), path.status
    assert "turning back" in path.status
    assert travelled(path) <= 6.0 * 2.2 * h + np.max(np.abs(np.diff(path.displacement)))
    assert len(path) < 2000


@pytest.mark.slow
@pytest.mark.parametrize("method", ["mgdc", "displacement"])
def test_lateral_torsional_buckling_at_201_nodes_is_detected_and_located(method):
    # 3-D: measured before the driver rework, the 201-node strip ended "ok" on the buckled
    # branch with no critical point. The bifurcation must be found, located and switched
    # at the finite-EI2 corrected Prandtl load (0.1 % at 201 nodes).
    from validation.strip3d import ltb_cantilever

    L = 0.1
    st, rod, EI1, EI2, GJ = ltb_cantilever(201, L)
    ref = 4.013 / np.sqrt((1 - EI1 / EI2) * (1 - GJ / EI2))
    d_cr = ref * np.sqrt(EI1 * GJ) / L**2 * L**3 / (3 * EI2)
    path = st.push(rod.nodes[-1], direction=(0.0, 0.0, -1.0), distance=2.0 * d_cr,
                   method=method)
    assert path.status == "ok", path.status
    bif = path.bifurcations
    assert len(bif) == 1 and bif[0].located and bif[0].switched
    assert abs(bif[0].F * L**2 / np.sqrt(EI1 * GJ) / ref - 1) < 1e-3
    assert path.info["rig_jumps"] == []
    # planar up to the point, sideways after it, and no state beyond P_cr on the primary
    y_tip = np.abs(path.positions[:, -1, 1])
    k = bif[0].index
    assert np.max(y_tip[: k + 1]) < 1e-9 and y_tip[-1] > 1e-3
    assert np.max(path.force[: k + 1]) <= bif[0].F * (1 + 1e-6)


@pytest.mark.parametrize("method", ["mgdc", "displacement"])
def test_euler_column_with_clamps(method):
    # clamped-clamped column, one end a sliding clamp: bifurcation at 4 pi^2 EI / L^2
    n, L = 101, 0.1
    x = np.linspace(0.0, L, n)
    st = Structure()
    st.add_rod(np.stack([x, np.zeros(n)], 1), width=W, thickness=T, E=E)
    st.clamp(0, toward=1)
    st.clamp(n - 1, toward=n - 2, hold_position=False)
    st.fix(n - 1, "z")
    p_cr = 4 * np.pi**2 * (E * W * T**3 / 12) / L**2
    path = st.push(n - 1, (-1.0, 0.0), 0.01 * L, method=method)
    assert path.status == "ok"
    bif = path.bifurcations[0]
    assert abs(bif.F / p_cr - 1) < 2e-3  # O(N^-2): 101 nodes
    assert bif.switched
    # buckled: the post-buckling force stays near P_cr (elastica: +0.25 % at 1 % shortening)
    assert 1.0 < path.force[-1] / p_cr < 1.01
    assert np.abs(path.positions[-1, :, 1]).max() > 0.05 * L


# ---------------------------------------------------------------------- cantilever, clamp API
def cantilever(n_nodes, method="mgdc"):
    from validation.cantilever import EI, L, T as TC, W as WC, E as EC

    s = np.linspace(0.0, L, n_nodes)
    st = Structure()
    rod = st.add_rod(np.stack([s, np.zeros_like(s)], 1), width=WC, thickness=TC, E=EC)
    st.clamp(0, toward=1)  # the obvious set-up, clamped exactly at node 0
    return st.push(rod.nodes[-1], (0.0, -1.0), 0.8106 * L, method=method, steps=20)


def test_cantilever_with_clamp_is_within_0_2_percent_at_101_nodes():
    from validation.cantilever import max_relative_errors

    for method in ("mgdc", "displacement"):
        path = cantilever(101, method)
        assert path.status == "ok"
        d_err, f_err = max_relative_errors(path)
        assert d_err < 2e-3 and f_err < 2e-3, (method, d_err, f_err)


@pytest.mark.slow
def test_cantilever_with_clamp_converges_as_n_to_the_minus_two():
    from validation.cantilever import max_relative_errors

    ns = np.array([26, 51, 101, 201])
    errors = np.array([max_relative_errors(cantilever(n))[0] for n in ns])
    slope = np.polyfit(np.log(ns), np.log(errors), 1)[0]
    assert slope <= -1.9, (errors, slope)


def test_clamp_is_validated_and_documented():
    st = Structure()
    st.add_rod(np.stack([np.linspace(0, 0.1, 11), np.zeros(11)], 1), width=W, thickness=T, E=E)
    with pytest.raises(ValueError, match="toward"):
        st.clamp(0, toward=5)
    st.clamp(0, toward=1)
    with pytest.raises(ValueError, match="clamped already"):
        st.clamp(0, toward=1)
    assert "midpoint" in Structure.fix.__doc__ and "clamp" in Structure.fix.__doc__
    # ghosts are internal: positions and paths show the real nodes only
    path = st.push(10, (0.0, -1.0), 0.01)
    assert path.positions.shape[1:] == (11, 2)


# ---------------------------------------------------------------------- issue 16: driver half
@pytest.mark.parametrize("method", ["mgdc", "displacement"])
def test_modulus_changes_no_step_and_no_bit_of_the_path(method):
    # the drivers solve every structure as made of the reference material: E = 1, 2.2e9, 1e200, 1e-200 give
    # the same steps, iterations and positions bit for bit, and forces proportional to E
    paths = {}
    for E_ in (1.0, 2.2e9, 1e200, 1e-200):
        st, mid, h, EI = arch(10, 101, "clamp", E=E_)
        paths[E_] = st.push(mid, (0.0, -1.0), 2.2 * h, method=method, time_limit=60)
    ref = paths[2.2e9]
    assert ref.status == "ok"
    for E_, p in paths.items():
        assert p.status == "ok", (E_, p.status)
        assert len(p) == len(ref) and np.array_equal(p.iterations, ref.iterations)
        assert np.array_equal(p.positions, ref.positions)
        np.testing.assert_allclose(p.force / E_, ref.force / 2.2e9, rtol=1e-14, atol=0)
        assert [c.kind for c in p.critical_points] == [c.kind for c in ref.critical_points]


@pytest.mark.parametrize("method", ["mgdc", "displacement"])
def test_lengths_in_millimetres_give_the_same_path(method):
    # lengths in mm and E in N/mm^2: the same path in F l^2 / EI (to the path's
    # interpolation error); the step sequence is not bit-identical (see
    # docs/path-following.md), the step count stays within 25 %
    st, mid, h, EI = arch(10, 101, "clamp")
    ref = st.push(mid, (0.0, -1.0), 2.2 * h, method=method)
    st, mid, h_mm, EI_mm = arch(10, 101, "clamp", E=2.2e3, t=0.5, l=100.0, w=5.0)
    mm = st.push(mid, (0.0, -1.0), 2.2 * h_mm, method=method)
    assert mm.status == "ok"
    d = np.linspace(0.05, 2.15, 40)
    f_ref = np.interp(d, ref.displacement / h, ref.force * L_SPAN**2 / EI)
    f_mm = np.interp(d, mm.displacement / h_mm, mm.force * 100.0**2 / EI_mm)
    assert np.max(np.abs(f_mm - f_ref)) < 0.01 * np.ptp(f_ref)
    assert abs(len(mm) / len(ref) - 1) < 0.25


def test_time_limit_ends_the_path_with_a_timeout_status():
    import time

    st, mid, h, _ = arch(10, 401, "fix")
    for method in ("mgdc", "displacement"):
        t0 = time.perf_counter()
        path = st.push(mid, (0.0, -1.0), 2.2 * h, method=method, time_limit=0.05)
        assert path.status.startswith("timeout"), path.status
        assert time.perf_counter() - t0 < 5.0
        assert len(path) >= 1


@pytest.mark.parametrize(
    "options,match",
    [
        (dict(steps=0), "steps"),
        (dict(steps=2.5), "steps"),
        (dict(tol=-1.0), "tol"),
        (dict(tol=float("nan")), "tol"),
        (dict(tol="1e-9"), "tol"),
        (dict(max_iter=0), "max_iter"),
        (dict(min_step_ratio=2.0), "min_step_ratio"),
        (dict(max_steps=0), "max_steps"),
        (dict(time_limit=-1.0), "time_limit"),
        (dict(time_limit=1j), "time_limit"),
        (dict(switch_size=0.0), "switch_size"),
        (dict(max_step=float("inf")), "max_step"),
        (dict(distance=1000.0), "distance"),
        (dict(distance="0.01"), "distance"),
        (dict(distance=[0.01]), "distance"),
        (dict(direction="down"), "direction"),
        (dict(direction=None), "direction"),
        (dict(direction=(0.0, -1.0, 0.0)), "direction"),
        (dict(direction=(1j, 0.0)), "direction"),
    ],
)
@pytest.mark.parametrize("method", ["mgdc", "displacement"])
def test_push_options_are_validated(method, options, match):
    st, mid, h, _ = arch(10, 21, "clamp")
    args = dict(direction=(0.0, -1.0), distance=0.01) | options
    with pytest.raises(ValueError, match=match):
        st.push(mid, method=method, **args)


XZ = np.stack([np.linspace(0, 0.1, 11), np.zeros(11)], 1)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(xz=None), "xz"),
        (dict(xz="rod"), "xz"),
        (dict(xz=XZ.astype(complex)), "xz"),
        (dict(xz=[[0, 0], [1, 0, 2], [2, 0]]), "xz"),
        (dict(width="5mm"), "width"),
        (dict(width=None), "width"),
        (dict(width=5e-3 + 1j), "width"),
        (dict(thickness=[1e-3, 2e-3]), "thickness"),
        (dict(E="2.2e9"), "E"),
        (dict(E=None), "E"),
        (dict(E=2.2e9 + 0j), "E"),
        (dict(E=[2.2e9, 1e9]), "E"),
        (dict(xz=np.array([[0, 0], [0.05, 0], [0.0, 0], [0.05, 0.01]])), "turns back"),
        (dict(thickness=1e-8), "thickness too small"),
    ],
)
def test_add_rod_names_the_bad_parameter(kwargs, match):
    args = dict(xz=XZ, width=5e-3, thickness=5e-4, E=2.2e9) | kwargs
    with pytest.raises(ValueError, match=match):
        Structure().add_rod(**args)


def test_tiny_width_and_the_thinnest_accepted_section_work():
    # width only scales the stiffness (scale-free); the thinnest accepted thickness
    # (length / 3e4) still solves
    x = np.linspace(0, 0.1, 21)
    xz = np.stack([x, 0.01 * np.sin(np.pi * x / 0.1)], 1)
    arc = float(np.sum(np.hypot(*np.diff(xz, axis=0).T)))
    for w, t in ((1e-9, 5e-4), (5e-3, arc / 3e4 * 1.0001)):
        st = Structure()
        st.add_rod(xz, width=w, thickness=t, E=2.2e9)
        st.clamp(0, toward=1)
        st.clamp(20, toward=19)
        path = st.push(10, (0.0, -1.0), 0.005, time_limit=60)
        assert path.status == "ok", (w, t, path.status)
        assert np.all(np.isfinite(path.force))


def test_path_repr_is_short():
    st, mid, h, _ = arch(10, 21, "clamp")
    text = repr(st.push(mid, (0.0, -1.0), 2.2 * h))
    assert len(text.splitlines()) <= 4 and len(text) < 400
    assert "status='ok'" in text and "array" not in text


def _work_gaps(path, structure):
    """Energy balance of each step of a displacement-controlled path (see
    `solver.displacement._work_mismatch`): |dE - 0.5 (F_k + F_k+1) dd| / (|dE| + fscale dd)."""
    fscale = structure.scales()[1]
    dd, dE = np.diff(path.displacement), np.diff(path.energy)
    work = 0.5 * (path.force[1:] + path.force[:-1]) * dd
    return np.abs(dE - work) / (np.abs(dE) + fscale * np.abs(dd))


def test_work_mismatch_is_zero_on_a_quadratic_energy_and_flags_a_jump():
    from snapmorph.solver.displacement import _work_mismatch

    # E = k d^2 / 2, F = k d: the trapezoid is exact
    k, d0, d1 = 3.0e3, 1e-3, 1.5e-3
    gap, allowed = _work_mismatch(0.5 * k * d0**2, 0.5 * k * d1**2, k * d0, k * d1, d1 - d0, 1.0)
    assert gap < 1e-12 and allowed
    # a step that gains energy the push did not supply is no snap; one that releases it is
    gap, allowed = _work_mismatch(0.0, 1.0, 0.0, 0.0, 1e-6, 1.0)
    assert gap > 0.99 and not allowed
    gap, allowed = _work_mismatch(0.0, -1.0, 0.0, 0.0, 1e-6, 1.0)
    assert gap > 0.99 and allowed


def test_a_step_that_gains_energy_however_small_ends_with_a_status_that_says_so(monkeypatch):
    # Were every step to gain energy beyond the work of the push (as the jump to a far
    # equilibrium did on the 401-node arch), the path must stop with a status saying so.
    import snapmorph.solver.displacement as cont

    monkeypatch.setattr(cont, "_work_mismatch", lambda *a: (1.0, False))
    st, mid, h, EI = arch(10, 101, "fix", centre=False)
    path = st.push(mid, (0.0, -1.0), 2.2 * h, method="displacement")
    assert path.status.startswith("stopped: energy jump"), path.status
    assert len(path) == 1


@pytest.mark.slow
@pytest.mark.parametrize("h_over_t", [10, 20])
def test_displacement_control_keeps_no_step_that_breaks_the_energy_balance(h_over_t):
    # 401 nodes, fix set-up, centre free: two steps after its rig jump, displacement control
    # kept a step to a far equilibrium (h/t = 10: F_min = -33049 EI h / l^3, energy up by
    # 0.8 J where the push did ~0 work, 12 Newton iterations, status "ok"; h/t = 20: -59969
    # with 20 iterations before the turn-candidate fix, then -181.3, a smaller jump across
    # the fold). Along the path dE/dd = F: every Newton step of an "ok" path must balance,
    # and the lowest force is where the rig leaves the stable branch: the fold in d that
    # MGDC passes before it runs back (unstable with d held, which no rig can hold) to the
    # rejoining point, MGDC's own F_min.
    mg, dc, st, h, EI = mgdc_and_rig(h_over_t, 401, "fix")
    assert dc.status == "ok" and mg.status == "ok", (dc.status, mg.status)
    assert dc.displacement[-1] >= 2.2 * h * (1 - 1e-9)
    newton = dc.iterations[1:] > 0  # not a rig move (iterations 0)
    assert np.all(_work_gaps(dc, st)[newton] <= 0.1)  # smooth steps: <= 0.05
    unit = EI * h / L_SPAN**3
    pk = dc.force[first_peak_index(dc.force)]
    assert abs(dc.force.min() / pk) < 0.5 and dc.iterations.max() <= 12
    folds = [c for c in mg.critical_points
             if c.kind == "limit" and c.control == "displacement" and c.d > 1.5 * h]
    fold = max(folds, key=lambda c: c.d)  # where the stable branch ends in d
    assert abs(dc.force.min() / fold.F - 1) < 0.01, (dc.force.min() / unit, fold.F / unit)


def test_compiled_corrector_loops_give_the_python_loops_bits():
    """`System.newton_loop`, `System.mgdc_loop` and `System.mgdc_step` (the fused
    iterations, and a whole MGDC step, in one compiled call, planar rods) against the
    drivers' own Python loops over `fused_newton` and `fused_mgdc` (the compiled calls
    switched off): the same path, force and states, bit for bit, through a limit point and
    a snap, and the same displacement-controlled solves."""
    from snapmorph.solver.states import DisplacementProbe
    from snapmorph.solver.system import BandedSystem, ReducedSystem

    def run():
        st, mid, h, _ = arch(20, 101, "fix")
        path = st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")
        probe = DisplacementProbe(st, mid)
        k = int(np.argmax(path.force))
        solved = probe.solve(path.positions[k], path.displacement[k] + 1e-4 * h)
        return path, solved

    compiled = run()
    names = ("newton_loop", "mgdc_loop", "mgdc_step")
    saved = [getattr(ReducedSystem, name) for name in names]
    for name in names:
        setattr(ReducedSystem, name, getattr(BandedSystem, name))
    try:
        python = run()
    finally:
        for name, fn in zip(names, saved):
            setattr(ReducedSystem, name, fn)
    (a, sa), (b, sb) = compiled, python
    assert a.status == b.status == "ok" and len(a) == len(b)
    assert np.array_equal(a.force, b.force) and np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.iterations, b.iterations)
    assert np.array_equal(sa[0], sb[0]) and sa[1] == sb[1]
