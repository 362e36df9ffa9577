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
stiffness of its half edge, g_i = K_i / (l_i / 2) for each of EI1, EI2 and GJ. N carries no
degrees of freedom: it is eliminated exactly (the star-mesh transform of a network of springs,
here the pair kernels' bending and twisting measures) into one pair between every two arms,

    k_ij = g_i g_j / sum_k g_k.

With two arms this is the rod's own node pair (1 / (l_a / 2 K_a + l_b / 2 K_b)); a stiff arm
(g_c -> inf) ties every other arm to itself over that arm's half edge only; a soft one
(g_c -> 0) hangs off the node frame with its half edge, and leaves the through rod alone.
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


def star_mesh_stiffness(g):
    """(n, n, 3) pair stiffnesses k_ij = g_i g_j / sum_k g_k of a star of n arms of
    stiffness ``g`` (n, 3) (per bending/twisting component) with its centre eliminated."""
    g = np.asarray(g, dtype=float)
    return g[:, None, :] * g[None, :, :] / np.sum(g, axis=0)


def rigid_junction(structure, nodes):  # noqa: C901 - one loop over the pairs of arms
    """Join the coincident ``nodes`` (of any rods, each an end or an interior node) rigidly at
    one node frame: positions shared, and every two edges touching the node coupled by the
    pair of the star-mesh transform (module docstring), which replaces the rods' own node
    pairs there. Returns the number of pairs added."""
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
    g = np.array([[rod.EI1[j], rod.EI2[j], rod.GJ[j]] / (0.5 * st._frame(rod, j)[2])
                  for rod, j, _ in arms])
    k = star_mesh_stiffness(g)
    for n in nodes:
        st._pairs.pop(("node", n), None)
    added = 0
    for p in range(len(arms)):
        for q in range(p + 1, len(arms)):
            (rod_a, ja, away_a), (rod_b, jb, away_b) = arms[p], arms[q]
            sa, sb = -away_a, away_b  # edge a oriented into the node, edge b out of it
            ta = sa * st._frame(rod_a, ja)[0]
            tb = sb * st._frame(rod_b, jb)[0]
            if ta @ tb < -0.9:  # a fold (both arms run the same way): frame to frame
                sb = -sb
            pair = st._make_pair(rod_a, ja, sa, rod_b, jb, sb)
            st._pairs[("junction", nodes[0], p, q)] = pair[:4] + tuple(k[p, q]) + pair[7:]
            added += 1
    for n in nodes[1:]:
        st._merges.append((nodes[0], n))
    st._cache = None
    return added
