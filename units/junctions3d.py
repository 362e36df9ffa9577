"""Rigid junctions of several rods at one node frame (issue 25), on a `solver.Structure3D`.

Built from the structure's own pairs (`Structure3D._make_pair`) and position merges; it sits
in units/ so that the solver's sources (every committed map's fingerprint) stay unchanged:
it belongs next to `Structure3D.joint` when the maps are next rebuilt.

`Structure3D.joint` couples one edge of each of two rods with a pair as compliant as their two
half edges in series. Where rods cross (a bar jointed to a strip running through the node),
the bar's edge is coupled to the strip's edge on each side of the node: the bar's half edge is
then counted twice (both pairs stiffen it, in parallel), and the two pairs also tie the strip's
two edges to each other through the bar, which stiffens the strip's own bending at the node.

A rigid junction is instead one node frame N that every edge touching the node (an arm: both
edges of a rod through the node, the one edge of a rod ending there) hangs off with the
rotational stiffness of its half edge, G_i (3 x 3: GJ about its tangent, EI1 and EI2 about
its two other axes, over l_i / 2). N carries no degrees of freedom: it is eliminated exactly
(the star-mesh transform of a network of springs) into a stiffness between every two arms,

    K_ij = G_i S^-1 G_j,   S = sum_k G_k.

With two collinear arms this is the rod's own node pair (1 / (l_a / 2 K_a + l_b / 2 K_b) per
axis); a stiff arm ties every other arm to itself over that arm's half edge only; a soft one
hangs off the node frame with its half edge and leaves the rod running through alone.

Each K_ij is carried by one pair of `solver.energies3d` between the two edges, whose three
constants (k1, k2, kt) are fitted to it (`pair_constants`): exactly for collinear edges; at a
kink the pair measures rotations about the bisector of the two tangents and across it with
one constant each only, so the fit keeps the mean of the two in-plane axes' stiffnesses
where K differs between them (a right-angle junction of a bar and a strip).
"""

from __future__ import annotations

import numpy as np


def junction_arms(structure, nodes):
    """The edges touching the coincident ``nodes``: (rod, edge index in the rod, +1 when the
    edge runs away from the node / -1 when it runs into it), in order."""
    arms = []
    for n in nodes:
        rod, i = structure._rod_of(n)
        if i > 0:
            arms.append((rod, i - 1, -1.0))
        if i < len(rod.nodes) - 1:
            arms.append((rod, i, 1.0))
    return arms


def star_mesh_stiffness(G):
    """(n, n, 3, 3) stiffnesses K_ij = G_i S^-1 G_j, S = sum_k G_k, between every two arms of
    a star of n arms of rotational stiffness ``G`` (n, 3, 3) (N m / rad) whose centre, the node
    frame, is eliminated: the exact stiffness network of the arms' frames."""
    G = np.asarray(G, dtype=float)
    S_inv = np.linalg.inv(np.sum(G, axis=0))
    return np.einsum("iab,bc,jcd->ijad", G, S_inv, G)


def arm_stiffness(rod, j, frame):
    """(3, 3) rotational stiffness (N m / rad, global axes) of edge ``j`` of ``rod`` over its
    half length: GJ about its tangent, EI1 about m2 = t x m1 (bending through the
    thickness), EI2 about the face normal m1 (in plane); ``frame`` = (t, m1, length)."""
    t, m1, length = frame
    m2 = np.array([t[1] * m1[2] - t[2] * m1[1], t[2] * m1[0] - t[0] * m1[2],
                   t[0] * m1[1] - t[1] * m1[0]])  # t x m1 (np.cross costs 10x a junction's arm)
    return (rod.GJ[j] * (t[:, None] * t) + rod.EI1[j] * (m2[:, None] * m2)
            + rod.EI2[j] * (m1[:, None] * m1)) / (0.5 * length)


def pair_rotation_rows(frame_a, sa, frame_b, sb):
    """(3, 3) rows r_c: the change of the pair's (kappa1, kappa2, psi) per rotation of frame b
    against frame a about each global axis, at the stress-free frames (the kernel's exact
    gradients carried by dv = omega x v). The pair's energy is then 1/2 omega^T (sum_c k_c
    r_c r_c^T) omega: rotations about t, m2 and m1 for collinear edges; at a kink in the
    strips' plane, about the bisector of the two tangents and across it, with energies
    scaled by sec^2 of half the angle (the kernel's 2 tan(angle / 2))."""
    from snapmorph.solver.energies3d import material_curvature, twist_angle
    from snapmorph.solver.structure3d import _frame_pair

    z = _frame_pair(frame_a[0], frame_a[1], frame_b[0], frame_b[1], sa, sb)
    g = np.empty((3, 18))  # the gradients of kappa1, kappa2, psi
    h = np.empty((18, 18))
    material_curvature(z, 1, g[0], h)
    material_curvature(z, 2, g[1], h)
    twist_angle(z, g[2], h)
    # d/d omega of g . v(omega) = g . (omega x v) = omega . (v x g), summed over frame b's
    # three vectors v (whole arrays at once: numpy calls per entry cost more than the fit)
    v, gv = z[9:].reshape(1, 3, 3), g[:, 9:].reshape(3, 3, 3)
    cross = np.empty((3, 3, 3))
    cross[..., 0] = v[..., 1] * gv[..., 2] - v[..., 2] * gv[..., 1]
    cross[..., 1] = v[..., 2] * gv[..., 0] - v[..., 0] * gv[..., 2]
    cross[..., 2] = v[..., 0] * gv[..., 1] - v[..., 1] * gv[..., 0]
    return cross[:, 0] + cross[:, 1] + cross[:, 2]


def pair_constants(rows, K):
    """(k1, k2, kt) whose pair energy sum_c k_c r_c r_c^T is nearest to the target stiffness
    ``K`` (3, 3) (least squares over the matrix entries; exact for collinear edges, where
    the rows are the frame's axes): the normal equations sum_d (r_c . r_d)^2 k_d =
    r_c^T K r_c."""
    A = (rows @ rows.T) ** 2
    b = np.einsum("ca,ab,cb->c", rows, K, rows)
    return tuple(float(v) for v in np.maximum(np.linalg.solve(A, b), 0.0))


def rigid_junction(structure, nodes, pairs=None):
    """Join the coincident ``nodes`` (of any rods, each an end or an interior node) rigidly at
    one node frame: positions shared, and every two edges touching the node coupled by the
    pair of the star-mesh transform (module docstring), which replaces the rods' own node
    pairs there. ``pairs``: the junction's pairs as `junction_pairs` returned them for a
    structure with the same rods at these nodes (the fit is then not repeated). Returns the
    number of pairs added."""
    st = structure
    nodes = [st.check_node(n, "junction node") for n in nodes]
    if pairs is None:
        pairs = junction_pairs(st, nodes)
    for n in nodes:
        st._pairs.pop(("node", n), None)
    st._pairs.update(pairs)
    for n in nodes[1:]:
        st._merges.append((nodes[0], n))
    st._cache = None
    return len(pairs)


def junction_pairs(structure, nodes):
    """{key: pair} of the rigid junction of the coincident ``nodes`` (`rigid_junction`), in
    `Structure3D`'s pair layout, without adding them: they depend only on the rods' stress-free
    frames and stiffnesses at the node, so one fit serves every structure of the same mesh."""
    st = structure
    nodes = [st.check_node(n, "junction node") for n in nodes]
    if len(set(nodes)) != len(nodes) or len(nodes) < 1:
        raise ValueError(f"a junction needs distinct nodes; got {nodes}")
    x0 = st._node_position(nodes[0])
    for n in nodes[1:]:
        gap = float(np.linalg.norm(st._node_position(n) - x0))
        if gap > 1e-9 * st._size():
            raise ValueError(f"a junction needs coincident nodes; nodes {nodes[0]} and {n} are "
                             f"{gap:.3g} m apart")
    arms = junction_arms(st, nodes)
    frames = [st._frame(rod, j) for rod, j, _ in arms]
    K = star_mesh_stiffness([arm_stiffness(rod, j, f) for (rod, j, _), f in zip(arms, frames)])
    pairs = {}
    for p in range(len(arms)):
        for q in range(p + 1, len(arms)):
            (rod_a, ja, away_a), (rod_b, jb, away_b) = arms[p], arms[q]
            sa, sb = -away_a, away_b  # edge a oriented into the node, edge b out of it
            if (sa * frames[p][0]) @ (sb * frames[q][0]) < -0.9:
                sb = -sb  # a fold (both arms run the same way): frame to frame
            pair = st._make_pair(rod_a, ja, sa, rod_b, jb, sb)
            ks = pair_constants(pair_rotation_rows(frames[p], sa, frames[q], sb), K[p, q])
            pairs[("junction", nodes[0], p, q)] = pair[:4] + ks + pair[7:]
    return pairs
