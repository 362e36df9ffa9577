"""Stability along a path: inertia, critical points, branch switching, imperfections.

Reference cases:
- the perfect clamped-clamped column under end shortening: Euler bifurcation at
  P_cr = 4 pi^2 EI / L^2; the buckled branch is a plateau at P_cr, the primary branch stays
  straight;
- the clamped cosine arch pushed at its midpoint with the midpoint rotation free (x held):
  the symmetric path meets an asymmetric bifurcation well below its force peak, and a
  structure with a tiny imperfection in the asymmetric mode follows the bifurcated branch;
- the same arch with its midpoint clamped (three rigid nodes, Qiu et al.'s configuration):
  no eigenvalue of the displacement-held stiffness crosses zero — only the two limit points
  of the force.
"""

import numpy as np
import pytest

from snapmorph.solver import Structure
from snapmorph.solver.stability import (
    StateStability,
    eigenmodes,
    held_count,
    seed_imperfection,
    state_stability,
)
from validation.arch import clamped_arch, first_peak_index
from validation.column import P_CR, column

L_SPAN, T, W, E = 0.1, 0.5e-3, 5e-3, 2.2e9
EI = E * W * T**3 / 12


def free_centre_arch(h_over_t, n_nodes=101):
    """The clamped cosine arch with only the midpoint's x held (its rotation free)."""
    h = h_over_t * T
    st, mid, _ = clamped_arch(h, n_nodes=n_nodes, t=T, l=L_SPAN, w=W, E=E,
                                               centre_clamped=False)
    return st, mid, h


def first_peak(force):
    """The first force maximum (N)."""
    return float(force[first_peak_index(force)])


def asymmetry(positions):
    """Largest difference (m) between a node's height and its mirror node's."""
    z = positions[..., 1]
    return float(np.max(np.abs(z - z[..., ::-1])))


# ---------------------------------------------------------------------- inertia
@pytest.mark.parametrize("rigid_centre", [True, False])
def test_inertia_matches_dense_eigenvalues_on_random_states(rng, rigid_centre):
    """LDL^T pivot signs (force control) and the bordered count (displacement held) against
    numpy's eigvalsh of the dense reduced stiffness, on random deformed states."""
    if rigid_centre:
        st, mid, _ = clamped_arch(10 * T, n_nodes=41)
    else:
        st, mid, _ = free_centre_arch(10, n_nodes=41)
    X = st.reference_positions
    held = st.reduced_system(extra_fixed=[(mid, 1)])
    counts = []
    for k in range(12):
        # smooth random bends from none to 3 h, and node jitter, make K indefinite
        amp = 0.25 * k * 10 * T
        modes = np.sin(np.outer(np.arange(len(X)) / len(X), np.pi * np.arange(1, 6)))
        pos = X.copy()
        pos[:, 1] += amp * modes @ rng.normal(size=5) / 3
        pos[:, 0] += 1e-3 * amp * rng.normal(size=len(X))
        s = state_stability(st, pos, mid)
        K = st.reduced_system().dense_stiffness(pos.reshape(-1))
        Kd = held.dense_stiffness(pos.reshape(-1))
        assert s.negative_force == int(np.sum(np.linalg.eigvalsh(K) < 0))
        assert s.negative_displacement == int(np.sum(np.linalg.eigvalsh(Kd) < 0))
        counts.append(s.negative_force)
    assert max(counts) >= 2 and min(counts) == 0  # the states span stable and unstable


def test_held_count_rule():
    assert held_count(1, -2.0) == 0 and held_count(1, 2.0) == 1 and held_count(0, -1.0) == 0
    s = StateStability(1, 0)
    assert not s.stable_force and s.stable_displacement


def test_path_counts_match_dense_eigenvalues_along_the_arch():
    """Every 8th MGDC step: the recorded counts equal those of the dense matrices."""
    st, mid, _ = clamped_arch(10 * T, n_nodes=41)
    path = st.push(mid, (0.0, -1.0), 2.2 * 10 * T, method="mgdc")
    full, held = st.reduced_system(), st.reduced_system(extra_fixed=[(mid, 1)])
    for k in range(0, len(path), 8):
        q = path.positions[k].reshape(-1)
        K, Kd = full.dense_stiffness(q), held.dense_stiffness(q)
        assert path.negative_eigenvalues[k] == np.sum(np.linalg.eigvalsh(K) < 0)
        assert path.negative_eigenvalues_displacement[k] == np.sum(np.linalg.eigvalsh(Kd) < 0)
    assert path.negative_eigenvalues.max() == 1  # the stretch between the limit points
    np.testing.assert_array_equal(path.stable, path.negative_eigenvalues == 0)


# ---------------------------------------------------------------------- the column
@pytest.mark.parametrize("method", ["mgdc", "displacement"])
def test_perfect_column_finds_euler_and_follows_the_buckled_branch(method):
    """Bifurcation at 4 pi^2 EI / L^2 (within 1 %), then the plateau of the buckled branch."""
    L = 0.1
    path = column(imperfection=0.0).push(100, (-1.0, 0.0), 0.03 * L, method=method)
    assert path.status == "ok"
    first = path.bifurcations[0]
    assert first.located and first.switched and first.multiplicity == 1
    assert abs(first.F / P_CR - 1) < 0.01
    # the critical mode is the first Euler mode: lateral, one sign, symmetric about midspan
    z = first.mode[:, 1]
    assert np.abs(first.mode[:, 0]).max() < 0.05 * np.abs(z).max()
    assert np.all(z >= -1e-9 * np.abs(z).max())
    np.testing.assert_allclose(z[1:-1], z[1:-1][::-1], atol=1e-6 * np.abs(z).max())
    # the rerouted path runs through the located point
    np.testing.assert_allclose(path.positions[first.index + 1], first.positions)
    window = (path.displacement > 0.005 * L) & (path.displacement < 0.02 * L)
    assert abs(path.force[window].mean() / P_CR - 1) < 0.01
    assert np.abs(path.positions[-1, :, 1]).max() > 0.05 * L  # buckled
    assert not any(c.kind == "limit" and c.control == "displacement" for c in path.critical_points)


def test_perfect_column_primary_branch_stays_straight():
    L = 0.1
    path = column(imperfection=0.0).push(100, (-1.0, 0.0), 0.01 * L, method="displacement",
                                         branch="primary")
    assert path.status == "ok"
    assert np.abs(path.positions[:, :, 1]).max() < 1e-12 * L
    assert path.force[-1] > 5 * P_CR  # compressed far beyond the Euler load
    crossings = path.bifurcations
    assert abs(crossings[0].F / P_CR - 1) < 0.01
    assert not any(c.switched for c in crossings)
    # higher Euler modes follow (the second, antisymmetric one near 2.05 P_cr)
    assert len(crossings) >= 3 and 1.9 < crossings[1].F / P_CR < 2.2
    assert path.negative_eigenvalues[-1] >= 3


# ---------------------------------------------------------------------- arches
@pytest.fixture(scope="module")
def free_arch_paths():
    st, mid, h = free_centre_arch(10)
    out = {"h": h, "mid": mid, "structure": st}
    out["follow"] = st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")
    out["primary"] = st.push(mid, (0.0, -1.0), 2.2 * h, method="displacement", branch="primary",
                             steps=200)
    _, modes = eigenmodes(st, 1, hold=[(mid, 1)])
    imperfect = seed_imperfection(st, modes[0], thickness_fraction=1e-4)
    out["imperfect"] = imperfect.push(mid, (0.0, -1.0), 2.2 * h, method="displacement", steps=400)
    return out


def test_free_arch_bifurcated_branch_matches_a_tiny_imperfection(free_arch_paths):
    p = free_arch_paths
    unit = EI * p["h"] / L_SPAN**3
    follow, primary, imperfect = p["follow"], p["primary"], p["imperfect"]
    for path in (follow, primary, imperfect):
        assert path.status == "ok"
    f_follow = first_peak(follow.force) / unit
    f_primary = first_peak(primary.force) / unit
    f_imperfect = first_peak(imperfect.force) / unit
    # the bifurcated branch's peak is the bifurcation itself, where the arch leaves symmetry
    bif = follow.bifurcations[0]
    assert bif.switched and abs(bif.F / unit - f_follow) < 1e-6 * f_follow
    assert asymmetry(follow.positions) > 0.1 * p["h"]  # (it rejoins the symmetric path near 1.95 h)
    assert asymmetry(primary.positions) < 1e-9 * p["h"]
    assert abs(f_follow / f_imperfect - 1) < 0.02
    assert f_follow < 0.85 * f_primary
    # the mode that breaks symmetry is antisymmetric about the midpoint
    z = bif.mode[:, 1]
    np.testing.assert_allclose(z, -z[::-1], atol=1e-4 * np.abs(z).max())
    # the asymmetric branch rejoins the symmetric path at the last bifurcation on it, where
    # the followed path runs through a bifurcation point as it turns and goes on symmetric
    rejoin, last = follow.bifurcations[1], primary.bifurcations[-1]
    assert rejoin.switched and abs(rejoin.d / last.d - 1) < 1e-3
    assert abs(rejoin.F - last.F) < 1e-3 * abs(last.F)
    assert asymmetry(follow.positions[-1]) < 1e-6 * p["h"]


def test_free_arch_primary_records_the_bifurcations_it_passes(free_arch_paths):
    primary = free_arch_paths["primary"]
    h = free_arch_paths["h"]
    d_bif = [c.d / h for c in primary.bifurcations]
    # the symmetric path is unstable (under displacement control) between pairs of them
    assert len(d_bif) >= 2 and d_bif[0] < 0.15
    k = np.searchsorted(primary.displacement / h, d_bif[0])
    assert primary.negative_eigenvalues_displacement[k + 1] == 1
    assert primary.negative_eigenvalues_displacement[k - 1] == 0
    # a displacement-controlled path never turns in d: its limit points are all of F
    assert all(c.control == "force" for c in primary.limit_points)


def test_limit_points_and_bifurcations_are_told_apart(free_arch_paths):
    # centrally clamped arch: two limit points of F (snap-through, snap-back), no bifurcation
    st, mid, _ = clamped_arch(10 * T)
    path = st.push(mid, (0.0, -1.0), 2.2 * 10 * T, method="mgdc")
    assert path.bifurcations == []
    kinds = [(c.kind, c.control) for c in path.critical_points]
    assert kinds == [("limit", "force"), ("limit", "force")]
    assert path.critical_points[0].F == pytest.approx(first_peak(path.force), rel=0.01)
    assert path.critical_points[1].F == pytest.approx(path.force.min(), rel=0.01)
    # free-centre arch: a bifurcation, and then the asymmetric branch snaps back in d
    follow = free_arch_paths["follow"]
    first, second = follow.critical_points[:2]
    assert (first.kind, second.kind, second.control) == ("bifurcation", "limit", "displacement")
    assert second.d < first.d


def test_branch_option_is_validated():
    st, mid, _ = clamped_arch(10 * T, n_nodes=31)
    with pytest.raises(ValueError, match="branch"):
        st.push(mid, (0.0, -1.0), 1e-3, branch="sideways")


# ---------------------------------------------------------------------- imperfections
def test_seeded_imperfection_is_stress_free_and_keeps_the_constraints():
    st, mid, _ = clamped_arch(10 * T, n_nodes=41)
    values, modes = eigenmodes(st, 3, hold=[(mid, 1)])
    assert np.all(np.diff(values) >= 0) and values[0] > 0
    imperfect = seed_imperfection(st, modes[0], thickness_fraction=0.01)
    shift = imperfect.reference_positions - st.reference_positions
    assert np.hypot(shift[:, 0], shift[:, 1]).max() == pytest.approx(0.01 * T)
    # zero up to round-off (the bending energy of the arch at 1 % of h is ~1e-7 J)
    assert imperfect.energy() < 1e-25
    assert np.abs(imperfect.gradient()).max() < 1e-9 * EI / L_SPAN**2
    assert imperfect.reduced_system().n == st.reduced_system().n
    # supports and the rigid centre carry over (zero mode there)
    assert np.all(shift[[0, 1, 39, 40]] == 0.0)
    np.testing.assert_allclose(shift[mid - 1: mid + 2], shift[[mid] * 3], atol=1e-18)
    with pytest.raises(ValueError, match="exactly one"):
        seed_imperfection(st, modes[0])
    with pytest.raises(ValueError, match="shape"):
        seed_imperfection(st, modes[0][:-1], amplitude=1e-6)


class _ParabolaProbe:
    """A stand-in for `DisplacementProbe`: F(d) = 1 - (d - 0.3)^2, except that solves in
    ``jump`` land on another equilibrium with 50 % more force."""

    def __init__(self, jump=None):
        self.jump = jump

    def solve(self, guess, d):
        F = 1.0 - (d - 0.3) ** 2
        if self.jump is not None and self.jump[0] <= d <= self.jump[1]:
            F *= 1.5
        return guess, F, 0


def test_refine_maximum_finds_the_vertex_and_refuses_a_branch_jump():
    """The default map once held F_cr 52 % above its neighbours: a displacement-controlled
    solve of the search had converged on another equilibrium and its force was taken as
    the maximum. A solve far off the samples' line now abandons the search (the callers fall
    back to the samples' parabola)."""
    from snapmorph.solver.problem import ConvergenceError
    from snapmorph.solver.states import refine_maximum

    d = np.array([0.0, 0.2, 0.4, 0.6])
    F = 1.0 - (d - 0.3) ** 2
    pos = [None] * 4
    F_max, d_max = refine_maximum(_ParabolaProbe(), d, F, pos, 1, tol_d=1e-6)
    assert abs(d_max - 0.3) < 1e-5 and abs(F_max - 1.0) < 1e-9
    with pytest.raises(ConvergenceError, match="left the path's branch"):
        refine_maximum(_ParabolaProbe(jump=(0.25, 0.35)), d, F, pos, 1, tol_d=1e-6)


def test_displacement_probe_marches_in_substeps_when_newton_fails():
    """Near the force maximum of a shallow 3-D unit (h = 9.1 mm) the held structure is close
    to a bifurcation, and a Newton started a whole path step away failed: the maximum fell
    back to the samples' parabola, so F_cr depended on the path's sampling (0.48507 and
    0.48540 N for two Newton tolerances of the push). Marching the held displacement in
    substeps converges, and the search then gives one F_cr for both samplings."""
    from snapmorph.solver.states import refine_maximum
    from snapmorph.units.frame3d import UnitGeometry
    from snapmorph.units.push3d import _probe, path_states, snap_crossings
    from snapmorph.units.unit3d import build_unit_3d

    g = UnitGeometry(L=0.1, h=0.0091, t=0.5e-3, w=5e-3, b=5e-3)
    m = build_unit_3d(g)
    st = m.structure
    found = []
    for tol in (1e-9, 1e-8):
        p = st.push(m.push_node, (0.0, 0.0, -1.0), 3 * g.h, method="mgdc", target_iterations=6,
                    tol=tol, stop=lambda rows: snap_crossings(rows["d"], rows["F"])[2] is not None)
        d, F = np.asarray(p.displacement), np.asarray(p.force)
        i = snap_crossings(d, F)[0]
        probe = _probe(st, m.push_node)
        F_max, _ = refine_maximum(probe, d, F, path_states(st, p), i,
                                  tol_d=2e-3 * (d[i + 1] - d[i - 1]))
        found.append(F_max)
    assert abs(found[0] / found[1] - 1) < 1e-6, found


def test_state_stability_read_off_the_newton_that_converged_there():
    """`state_stability(..., factorised=True)` on the system an equilibrium's Newton converged
    with (info["system"]) gives the counts of a fresh assembly at the state."""
    from snapmorph.solver.stability import state_stability
    from snapmorph.units import UnitGeometry, simulate_unit
    from snapmorph.units.geometry import build_unit

    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    r = simulate_unit(g, nodes=61)
    m = build_unit(g, nodes=61)
    st = m.structure
    for k in ("ii", "iii"):
        pos = np.zeros((st.n_nodes, 2))
        pos[m.arch_nodes], pos[m.base_nodes] = r.shapes[k]["arch"], r.shapes[k]["base"]
        solved, info = st.solve_equilibrium(pos, node=None)
        read = state_stability(st, solved, m.apex, system=info["system"], factorised=True)
        fresh = state_stability(st, solved, m.apex)
        assert read == fresh
        assert (read.negative_force, read.negative_displacement) == \
            ((1, 0) if k == "ii" else (0, 0))
