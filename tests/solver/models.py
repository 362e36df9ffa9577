"""Model builders shared by the solver tests."""

import numpy as np

from snapmorph.solver import Structure, reference_models


def clamped_rod_nodes(n_nodes, length):
    """Node abscissae of a rod whose clamp sits at the midpoint of its first edge.

    The clamped first edge straddles s = 0 (nodes at -ds/2 and +ds/2) and the last node is
    at s = length: the clamp then acts at s = 0 to second order in ds.
    """
    ds = length / (n_nodes - 1.5)
    return -0.5 * ds + ds * np.arange(n_nodes)


def first_peak_index(force):
    """Index of the first local maximum of a force history (the snap-through force)."""
    i = 1
    while i < len(force) - 1 and force[i + 1] >= force[i]:
        i += 1
    return i


def clamped_arch(h, n_nodes=101, t=0.5e-3, l=0.1, w=5e-3, E=2.2e9):
    """Clamped–clamped cosine arch, midpoint held in rotation and x (see
    `solver.reference_models`). Returns (structure, mid, EI)."""
    return reference_models.clamped_arch(h, n_nodes=n_nodes, t=t, l=l, w=w, E=E)
