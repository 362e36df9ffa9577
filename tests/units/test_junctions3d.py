"""`units.junctions3d`: rods joined at one node frame (the star-mesh transform of their half
edges), against a single rod, a dangling branch and the pair-of-edges joints of
`Structure3D.joint` (issue 25)."""

from __future__ import annotations

import numpy as np
import pytest

from snapmorph.solver import Structure3D
from snapmorph.solver.equilibrium import equilibrium
from snapmorph.units.junctions3d import (junction_arms, pair_constants, pair_rotation_rows,
                                         rigid_junction, star_mesh_stiffness)

E, NU, W, T, L = 2.2e9, 0.38, 5e-3, 0.5e-3, 0.1


def _line(x0, x1, n, axis=0, at=(0.0, 0.0, 0.0)):
    p = np.tile(np.asarray(at, dtype=float), (n, 1))
    p[:, axis] = np.linspace(x0, x1, n)
    return p


def _tip_deflection(st, tip, direction, P):
    pos, _ = equilibrium(st, None, int(tip), direction, P)
    return float(np.dot(pos[tip] - st.reference_positions[tip], direction))


def test_star_mesh_stiffness_of_two_arms_is_the_series_pair():
    g = np.array([[1.0, 2.0, 3.0], [4.0, 6.0, 0.5]])
    k = star_mesh_stiffness([np.diag(v) for v in g])
    assert np.diagonal(k[0, 1]) == pytest.approx(1.0 / (1.0 / g[0] + 1.0 / g[1]), rel=1e-15)
    g3 = np.vstack([g, [[1e12, 1e-12, 2.0]]])
    k3 = star_mesh_stiffness([np.diag(v) for v in g3])
    # a rigid third arm ties each arm to itself over that arm's half edge only; a
    # vanishing one leaves the other two in series
    assert k3[0, 2, 0, 0] == pytest.approx(g[0, 0], rel=1e-9)
    assert k3[0, 1, 1, 1] == pytest.approx(k[0, 1, 1, 1], rel=1e-9)


def test_pair_constants_fit_a_kinked_pair():
    """The pair's rows at a right angle, as the kernel measures them: kappa1 and psi measure
    rotations across and about the bisector of the two tangents, kappa2 about the normal
    (twice the angle, 2 tan(phi / 2)); a stiffness with equal in-plane axes is fitted
    exactly."""
    x, y, z = np.eye(3)
    rows = pair_rotation_rows((x, z, 1.0), 1.0, (y, z, 1.0), 1.0)
    assert rows == pytest.approx(np.array([[1, -1, 0], [0, 0, -2], [1, 1, 0]]), abs=1e-12)
    K = np.diag([3.0, 3.0, 5.0])
    k1, k2, kt = pair_constants(rows, K)
    M = k1 * np.outer(rows[0], rows[0]) + k2 * np.outer(rows[1], rows[1]) + kt * np.outer(
        rows[2], rows[2])
    assert M == pytest.approx(K, rel=1e-12)
    # unequal axes: the mean is kept, the difference (an off-diagonal term) is not
    k1, _, kt = pair_constants(rows, np.diag([2.0, 4.0, 5.0]))
    assert (k1, kt) == pytest.approx((1.5, 1.5), rel=1e-12)


@pytest.mark.parametrize("direction", [(0.0, 0.0, -1.0), (0.0, 1.0, 0.0)])
def test_two_collinear_rods_at_a_junction_are_one_rod(direction):
    """A cantilever split in two rods joined at a junction has the single rod's pairs and tip
    deflection (bending through the thickness and in the strip's plane)."""
    one = Structure3D()
    r = one.add_rod(_line(0, L, 21), width=W, thickness=T, E=E, nu=NU)
    one.clamp(r.nodes[0], toward=r.nodes[1])
    two = Structure3D()
    a = two.add_rod(_line(0, L / 2, 11), width=W, thickness=T, E=E, nu=NU)
    b = two.add_rod(_line(L / 2, L, 11), width=W, thickness=T, E=E, nu=NU)
    two.clamp(a.nodes[0], toward=a.nodes[1])
    assert rigid_junction(two, [a.nodes[-1], b.nodes[0]]) == 1
    pair = two._pairs[("junction", int(a.nodes[-1]), 0, 1)]
    assert pair[4:] == pytest.approx(one._pairs[("node", 10)][4:], rel=1e-14, abs=1e-14)
    P = 1e-6
    d1 = _tip_deflection(one, int(r.nodes[-1]), direction, P)
    d2 = _tip_deflection(two, int(b.nodes[-1]), direction, P)
    assert d2 == pytest.approx(d1, rel=1e-9)


def _cantilever_with_branch(join):
    """A cantilever along x with a free branch along y leaving its middle node."""
    st = Structure3D()
    r = st.add_rod(_line(0, L, 21), width=W, thickness=T, E=E, nu=NU)
    st.clamp(r.nodes[0], toward=r.nodes[1])
    br = st.add_rod(_line(0, 0.02, 5, axis=1, at=(L / 2, 0, 0)), width=W, thickness=T, E=E, nu=NU)
    join(st, int(r.nodes[10]), int(br.nodes[0]))
    return st, int(r.nodes[-1])


def test_a_free_branch_leaves_the_rod_it_leaves_alone():
    """A branch that carries no load should change nothing. The pair-of-edges joints in both
    orders (`Mesh3D.bond`) tie the through rod's two edges to each other through the branch
    and stiffen it: the tip deflection of a 20-edge cantilever falls 2.0 % (bending through
    the thickness) and 2.5 % (in plane). At one node frame it is unchanged in plane (to the
    solve's tolerance) and grows 0.074 % in bending, where the right-angle pair keeps only
    the mean of the through rod's twist and the branch's bending stiffness (measured)."""
    plain = Structure3D()
    r = plain.add_rod(_line(0, L, 21), width=W, thickness=T, E=E, nu=NU)
    plain.clamp(r.nodes[0], toward=r.nodes[1])
    P = 1e-6

    def both_orders(s, a, b):
        s.joint(a, b)
        s.joint(b, a)

    for direction, tol in (((0.0, 0.0, -1.0), 1e-3), ((0.0, 1.0, 0.0), 1e-8)):
        d_plain = _tip_deflection(plain, int(r.nodes[-1]), direction, P)
        errors = []
        for join in (lambda s, a, b: rigid_junction(s, [a, b]), both_orders):
            st, tip = _cantilever_with_branch(join)
            errors.append(_tip_deflection(st, tip, direction, P) / d_plain - 1)
        junction, bond = errors
        assert abs(junction) < tol
        assert bond < -0.015


def test_arms_and_bad_junctions():
    st = Structure3D()
    r = st.add_rod(_line(0, L, 5), width=W, thickness=T, E=E, nu=NU)
    s = st.add_rod(_line(0, 0.02, 3, axis=1, at=(L / 2, 0, 0)), width=W, thickness=T, E=E, nu=NU)
    arms = junction_arms(st, [int(r.nodes[2]), int(s.nodes[0])])
    assert [(j, side) for _, j, side in arms] == [(1, -1.0), (2, 1.0), (0, 1.0)]
    with pytest.raises(ValueError, match="coincident"):
        rigid_junction(st, [int(r.nodes[1]), int(s.nodes[0])])
    with pytest.raises(ValueError, match="distinct"):
        rigid_junction(st, [int(r.nodes[2]), int(r.nodes[2])])
    assert rigid_junction(st, [int(r.nodes[2]), int(s.nodes[0])]) == 3
    assert ("node", int(r.nodes[2])) not in st._pairs
