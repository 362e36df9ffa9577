"""Dead loads and self-weight, load-controlled paths, and pushes under dead loads.

- A dead load is a potential energy term, E = -f (x - X): the assembled gradient and tangent
  match finite differences of the assembled energy (planar and 3-D, with rigid groups and
  ties: a grouped node's load acts on its group's DOFs through W);
- self-weight: each edge's weight rho A |e_bar| g, half on each of its nodes;
- a cantilever under its own weight against the exact heavy elastica
  theta'' = -(q / EI)(L - s) cos(theta), theta(0) = 0, theta'(L) = 0 (validation.heavy_cantilever):
  <= 0.1 % at 101 nodes for q L^3 / EI = 0.1 .. 10, converging as O(N^-2);
- a tip-loaded cantilever followed by `follow_load` is the elastica psi'' = -alpha cos(psi);
- the clamped shallow arch under a central dead load reaches its limit load factor at the
  displacement-controlled force maximum;
- planar and 3-D agree on a planar heavy cantilever;
- a push under dead loads starts from their equilibrium, and its force is the extra force.
"""

import numpy as np
import pytest

from snapmorph.solver import ConvergenceError, Structure, Structure3D
from snapmorph.solver.materials import MATERIALS, PAPER_PETG, PETG, PLA, Material, material
from snapmorph.solver.states import DisplacementProbe, refine_maximum
from validation.arch import L_SPAN, T, clamped_arch, first_peak_index
from validation.cantilever import elastica_deflection
from validation.heavy_cantilever import EI, L, W
from validation.heavy_cantilever import T as T_CANT
from validation.heavy_cantilever import heavy_cantilever, heavy_elastica, tip_errors


def _loaded_frame(three_d=False):
    """Two rods, a rigid group, a tie, a support, gravity and a point load (curved, so that
    every term is non-trivial)."""
    n = 9
    s = np.linspace(0.0, 0.1, n)
    z = 0.01 * np.sin(np.pi * s / 0.1)
    if three_d:
        st = Structure3D()
        a = st.add_rod(np.stack([s, 0 * s, z], 1), width=5e-3, thickness=np.linspace(4e-4, 6e-4, n - 1),
                       E=2.2e9, normal=(0, 1.0, 0))
        b = st.add_rod(np.stack([s, 0 * s, z - 0.02], 1), width=8e-3, thickness=5e-4, E=1e9,
                       normal=(0, 1.0, 0))
        st.fix(a.nodes[0], "xyz")
    else:
        st = Structure()
        a = st.add_rod(np.stack([s, z], 1), width=5e-3, thickness=np.linspace(4e-4, 6e-4, n - 1),
                       E=2.2e9)
        b = st.add_rod(np.stack([s, z - 0.02], 1), width=8e-3, thickness=5e-4, E=1e9)
        st.fix(a.nodes[0], "xz")
    st.rigid([a.nodes[3], a.nodes[4], a.nodes[5]])
    st.tie(a.nodes[-1], b.nodes[-1])
    st.add_gravity(PETG, direction=(0.3, -1.0) if not three_d else (0.3, 0.2, -1.0))
    st.add_load(b.nodes[2], np.full(st.dim, 0.7))
    return st


def _central_differences(system, q, j, h):
    """d(energy)/dq_j and d(reduced gradient)/dq_j of ``system`` at ``q`` by central
    differences of step ``h``."""
    out = []
    for sign in (1.0, -1.0):
        shifted = q.copy()
        shifted[j] += sign * h
        out.append((system.evaluate(shifted), system.grad.copy()))
    (Ep, gp), (Em, gm) = out
    return (Ep - Em) / (2 * h), (gp - gm) / (2 * h)


@pytest.mark.parametrize("three_d", [False, True])
def test_dead_load_gradient_and_tangent_match_finite_differences(three_d, rng):
    """E = elastic - f (x - X): its assembled gradient and tangent against central
    differences of the assembled energy at a random deformed state."""
    st = _loaded_frame(three_d)
    sysm = st.unconstrained_system() if three_d else st._unconstrained()
    q = st.initial_state()
    n_pos = st.dim * st.n_nodes
    q[:n_pos] += 2e-4 * rng.standard_normal(n_pos)
    if three_d:
        q[n_pos:] += 0.05 * rng.standard_normal(q.shape[0] - n_pos)
    sysm.evaluate(q)
    g = sysm.grad_full.copy()
    K = sysm.dense_stiffness(q)
    for j in np.flatnonzero(sysm.dof_map >= 0)[: n_pos: 3]:
        dE, dgrad = _central_differences(sysm, q, j, 1e-7)
        assert abs(dE - g[j]) <= 1e-6 * np.max(np.abs(g)) + 1e-9
        assert np.max(np.abs(dgrad - K[:, sysm.dof_map[j]])) <= 1e-5 * np.max(np.abs(K))
    # the loads' own share: gradient minus the load-free system's is -f on every node
    bare = st.without_dead_loads()
    sys0 = bare.unconstrained_system() if three_d else bare._unconstrained()
    sys0.evaluate(q)
    f = st.dead_loads().reshape(-1)
    assert np.allclose(g[:n_pos] - sys0.grad_full[:n_pos], -f, rtol=0, atol=1e-12)


@pytest.mark.parametrize("three_d", [False, True])
def test_self_weight_is_each_edges_weight_split_to_its_nodes_and_acts_through_w(three_d):
    st = _loaded_frame(three_d)
    st.clear_loads()
    rho, g = 1.3e3, 9.81
    st.add_gravity(rho, g=g)
    f = st.dead_loads()
    weight = 0.0
    for k, rod in enumerate(st.rods):
        X = st.reference_positions[rod.nodes]
        lengths = np.linalg.norm(np.diff(X, axis=0), axis=1)
        area = (rod.width * rod.thickness if three_d
                else 0.5 * np.sum(rod.width * rod.thickness, axis=1))
        weight += rho * g * float(np.sum(area * lengths))
        # every interior node carries half of each adjacent edge
        i = 2
        expect = 0.5 * rho * g * (area[i - 1] * lengths[i - 1] + area[i] * lengths[i])
        assert f[rod.nodes[i], -1] == pytest.approx(-expect, rel=1e-12)
    assert st.total_dead_load() == pytest.approx(weight, rel=1e-12)
    assert np.allclose(f[:, :-1], 0.0)
    # at the stress-free state the reduced gradient is -W^T f: a group's DOF carries the
    # loads of all its members, a supported component none
    sysm = st.reduced_system()
    sysm.evaluate(st.initial_state())
    expect = np.zeros(sysm.n)
    for node in range(st.n_nodes):
        for c, j in enumerate(st.node_dofs(node)):
            if sysm.dof_map[j] >= 0:
                expect[sysm.dof_map[j]] -= f[node, c]
    assert np.allclose(sysm.grad, expect, rtol=0, atol=1e-8 * weight)


@pytest.mark.parametrize("alpha", [0.1, 0.3, 1.0, 3.0, 10.0])
def test_heavy_cantilever_matches_the_heavy_elastica_within_0p1_percent_at_101_nodes(alpha):
    """q L^3 / EI = alpha; the exact heavy elastica by shooting (validation.heavy_cantilever)."""
    d_err, r_err, path = tip_errors(101, alpha)
    assert path.status == "ok" and path.load_factor[-1] == 1.0
    assert path.negative_eigenvalues.max() == 0 and path.limit_load_factor is None
    assert d_err < 1e-3 and r_err < 1e-3, (d_err, r_err)


def test_heavy_elastica_reference_is_the_beam_for_small_loads():
    """Linear beam: delta = q L^4 / (8 EI), theta = q L^3 / (6 EI)."""
    delta, x, theta = heavy_elastica(1e-4)
    assert delta == pytest.approx(1e-4 / 8, rel=1e-4)
    assert theta == pytest.approx(1e-4 / 6, rel=1e-4)
    assert x == pytest.approx(1.0, abs=1e-8)


@pytest.mark.slow
def test_heavy_cantilever_error_falls_as_n_to_the_minus_two():
    """Log-log slope of the tip errors over 41..321 nodes: deflection and rotation at
    alpha = 1, rotation at alpha = 10 (whose deflection error changes sign near 41 nodes,
    so that its slope over this range says nothing)."""
    ns = np.array([41, 81, 161, 321])
    one = np.array([tip_errors(n, 1.0)[:2] for n in ns])
    ten = np.array([tip_errors(n, 10.0)[1] for n in ns])
    for errors in (one[:, 0], one[:, 1], ten):
        slope = -np.polyfit(np.log(ns), np.log(errors), 1)[0]
        assert 1.9 < slope < 2.1, (errors, slope)


def test_tip_loaded_cantilever_followed_by_load_is_the_elastica():
    """A dead tip load P (P L^2 / EI = 10 at load factor 1) on the clamped cantilever:
    every state of the load-controlled path is the elastica's (validation.cantilever)."""
    st = heavy_cantilever(101, 0.0)  # weightless
    tip = st.n_nodes - 1
    st.add_load(tip, (0.0, -10.0 * EI / L**2))
    path = st.follow_load(1.0)
    assert path.status == "ok" and path.load_factor[-1] == 1.0
    # displacement and force of a single point load: the tip's deflection, the load
    assert np.allclose(path.displacement, -path.positions[:, -1, 1], rtol=0, atol=1e-15)
    assert np.allclose(path.force, path.load_factor * 10.0 * EI / L**2, rtol=1e-14)
    keep = path.load_factor > 0.01
    for lam, d in zip(path.load_factor[keep][::5], path.displacement[keep][::5]):
        exact = elastica_deflection(10.0 * lam) * L
        assert abs(d - exact) <= 1e-3 * exact, (lam, d, exact)



@pytest.mark.parametrize("h_over_t", [6, 10, 20])
def test_arch_under_a_central_dead_load_reaches_its_limit_at_the_displacement_controlled_maximum(
        h_over_t):
    """The reference clamped arch (validation.arch): the limit load factor of a central dead
    load equals the force maximum of the displacement-controlled push (refined by Brent on
    displacement-controlled solves) within 0.5 %; past it the structure is unstable under
    the dead load, and the path ends when the factor falls back to 0 ("limit")."""
    h = h_over_t * T
    st, mid, EI_arch = clamped_arch(h)
    unit = EI_arch * h / L_SPAN**3
    rig = st.push(mid, (0.0, -1.0), 2.2 * h, method="displacement")
    i = first_peak_index(rig.force)
    F_max, _ = refine_maximum(DisplacementProbe(st, mid), rig.displacement, rig.force,
                              rig.positions, i)
    F0 = 1000.0 * unit
    st.add_load(mid, (0.0, -F0))
    path = st.follow_load(1.0)
    assert path.status.startswith("limit:"), path.status
    assert path.limit_load_factor * F0 == pytest.approx(F_max, rel=5e-3)
    k = int(np.argmax(path.load_factor))
    assert path.negative_eigenvalues[: k].max() == 0
    assert path.negative_eigenvalues[k + 2:].min() >= 1
    assert path.load_factor[-1] <= 0.0 < path.load_factor[-2]


def test_arch_under_a_dead_load_above_its_limit_snaps_to_the_inverted_state():
    """With no lower stop the path goes on past the limit and the second limit, and reaches
    the full load on the inverted branch: status "snapped", a stable state there."""
    h = 10 * T
    st, mid, EI_arch = clamped_arch(h)
    st.add_load(mid, (0.0, -1000.0 * EI_arch * h / L_SPAN**3))
    path = st.follow_load(1.0, min_factor=-np.inf)
    assert path.status.startswith("snapped:"), path.status
    assert path.load_factor[-1] == 1.0 and path.negative_eigenvalues[-1] == 0
    assert path.displacement[-1] > 1.5 * h
    forces = [c for c in path.critical_points if c.kind == "limit" and c.control == "force"]
    assert len(forces) == 2 and forces[1].F < 0.0 < forces[0].F


@pytest.mark.parametrize("alpha", [1.0, 10.0])
def test_planar_and_3d_agree_on_a_planar_heavy_cantilever(alpha):
    p2 = heavy_cantilever(101, alpha).follow_load(1.0)
    p3 = heavy_cantilever(101, alpha, three_d=True).follow_load(1.0)
    assert p2.status == p3.status == "ok"
    X3 = p3.positions[-1]
    assert np.max(np.abs(X3[:, 1])) == 0.0 and np.max(np.abs(p3.twist)) < 1e-12
    assert np.max(np.abs(p2.positions[-1] - X3[:, [0, 2]])) <= 1e-12 * L
    assert p3.energy[-1] == pytest.approx(p2.energy[-1], rel=1e-12)


@pytest.mark.parametrize("method", ["mgdc", "displacement"])
def test_push_under_a_dead_load_starts_from_its_equilibrium_and_reports_the_extra_force(method):
    """A tip load P0 on the cantilever, then a push of the tip: the push starts at the
    sag under P0 with zero force, and F_push(d) = F_free(d) - P0 (the load-free push)."""
    st = heavy_cantilever(51, 0.0)  # weightless
    tip = st.n_nodes - 1
    free = st.push(tip, (0.0, -1.0), 0.6 * L, method=method)
    P0 = 0.5 * EI / L**2
    st.add_load(tip, (0.0, -P0))
    path = st.push(tip, (0.0, -1.0), 0.6 * L, method=method)
    assert free.status == path.status == "ok"
    sag = elastica_deflection(0.5) * L
    assert path.displacement[0] == pytest.approx(sag, rel=2e-3)
    assert path.force[0] == 0.0
    d = np.linspace(path.displacement[1], 0.59 * L, 20)
    F_free = np.interp(d, free.displacement, free.force)
    F_push = np.interp(d, path.displacement, path.force)
    assert np.max(np.abs(F_push - (F_free - P0))) < 2e-3 * P0


def test_push_of_a_structure_that_cannot_carry_its_dead_loads_raises():
    h = 10 * T
    st, mid, EI_arch = clamped_arch(h)
    st.add_load(mid, (0.0, -1000.0 * EI_arch * h / L_SPAN**3))
    with pytest.raises(ConvergenceError, match="does not carry its dead loads"):
        st.push(mid, (0.0, -1.0), 2.0 * h)


def test_load_free_runs_keep_their_bits_and_a_push_restarts_from_a_path_state():
    """Loads added and removed change no bit of a push; a push under self-weight is the
    push from the end of `follow_load` to factor 1 (``start=path_state(...)``), bit for bit."""
    h = 10 * T
    st, mid, _ = clamped_arch(h)
    before = st.push(mid, (0.0, -1.0), 2.2 * h)
    st.add_gravity(PAPER_PETG)
    st.clear_loads()
    after = st.push(mid, (0.0, -1.0), 2.2 * h)
    for a, b in ((before.positions, after.positions), (before.force, after.force),
                 (before.energy, after.energy)):
        assert np.array_equal(a, b)
    st.add_gravity(PAPER_PETG, g=50 * 9.81)  # 50 g: a sag worth seeing
    loaded = st.follow_load(1.0)
    auto = st.push(mid, (0.0, -1.0), 2.2 * h)
    given = st.push(mid, (0.0, -1.0), 2.2 * h, start=st.path_state(loaded))
    assert auto.status == given.status == "ok"
    assert np.array_equal(auto.positions, given.positions)
    assert np.array_equal(auto.force, given.force)
    assert auto.displacement[0] == pytest.approx(-loaded.positions[-1][mid, 1]
                                                 + st.reference_positions[mid, 1], rel=1e-9)
    assert auto.force[0] == 0.0 and auto.displacement[0] > 0.0


def test_follow_load_validates_its_request():
    st = heavy_cantilever(11, 1.0)
    with pytest.raises(ValueError, match="method must be 'mgdc'"):
        st.follow_load(1.0, method="displacement")
    with pytest.raises(ValueError, match="max_factor"):
        st.follow_load(-1.0)
    with pytest.raises(ValueError, match="min_factor"):
        st.follow_load(1.0, min_factor=2.0)
    st.clear_loads()
    with pytest.raises(ValueError, match="no dead loads"):
        st.follow_load(1.0)
    with pytest.raises(ValueError, match="density"):
        st.add_gravity(-1.0)
    with pytest.raises(ValueError, match="force"):
        st.add_load(3, (1.0, 2.0, 3.0))


def test_follow_load_ends_short_on_the_distance_with_a_failure_status():
    st = heavy_cantilever(41, 10.0)
    path = st.follow_load(1.0, distance=0.05 * L)
    assert path.status.startswith("stopped:") and path.load_factor[-1] < 1.0


def test_materials_carry_their_datasheet_values():
    assert (PAPER_PETG.E, PAPER_PETG.density, PAPER_PETG.nu) == (2.2e9, 1.3e3, 0.38)
    assert (PETG.E, PETG.density) == (1.80e9, 1.23e3)
    assert (PLA.E, PLA.density) == (3.6e9, 1.24e3)
    assert PETG.allowable_strain == pytest.approx(48e6 / 1.8e9)
    assert PLA.allowable_strain == pytest.approx(60e6 / 3.6e9)
    assert material("PETG") is PETG and set(MATERIALS) == {"petg", "pla", "paper"}
    custom = Material(E=1e9, density=500.0, nu=0.3, allowable_strain=0.01)
    assert custom.G == pytest.approx(1e9 / 2.6)
    for bad in (dict(E=-1.0, density=1.0), dict(E=1.0, density=float("nan")),
                dict(E=1.0, density=1.0, nu=0.7)):
        with pytest.raises(ValueError):
            Material(**bad)
    st = heavy_cantilever(11, 1.0)
    st.clear_loads()
    st.add_gravity(PETG)
    weight = PETG.density * 9.81 * W * T_CANT * L
    assert st.total_dead_load() == pytest.approx(weight, rel=1e-12)


def test_every_driver_sees_the_dead_loads():
    """The loads live in the assembled energy, so Newton equilibrium, the displacement
    probes, the stability counts and the 3-D energy descent need no special case: a tip
    load P0 held by a prescribed tip displacement is a reaction (F = F_free - P0, same
    state); the equilibrium solve and the descent land where follow_load does."""
    from snapmorph.solver.stability import state_stability

    st = heavy_cantilever(41, 0.0)  # weightless
    tip = st.n_nodes - 1
    P0 = 0.5 * EI / L**2
    free_probe = DisplacementProbe(st, tip)
    guess = st.reference_positions.copy()
    pos_free, F_free, _ = free_probe.solve(guess, 0.3 * L)
    st.add_load(tip, (0.0, -P0))
    pos, F, neg = DisplacementProbe(st, tip).solve(guess, 0.3 * L)
    assert F == pytest.approx(F_free - P0, rel=1e-9)
    assert np.max(np.abs(pos - pos_free)) < 1e-9 * L
    st.add_gravity(PAPER_PETG, g=200.0)  # q L^3 / EI = 1.3
    loaded = st.follow_load(1.0)
    assert loaded.status == "ok"
    end = loaded.positions[-1]
    again, info = st.solve_equilibrium(end)
    assert info["iterations"] <= 1 and np.max(np.abs(again - end)) < 1e-12 * L
    stab = state_stability(st, end, tip)
    assert stab.negative_force == 0 == stab.negative_displacement
    # 3-D: the energy descent (Structure3D.relax) from the stress-free state
    st3 = heavy_cantilever(41, 0.5, three_d=True)
    q, _ = st3.relax()
    p3 = st3.follow_load(1.0)
    assert np.max(np.abs(st3.positions_of(q) - p3.positions[-1])) < 1e-9 * L
