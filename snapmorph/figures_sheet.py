"""3-D views of a sheet's states (`units.sheet.SheetResult`): as made, then after every
step, the pushed cell named and the snapped cells' apexes marked."""

from __future__ import annotations

import math

import numpy as np


def plot_states(result, path):
    """One 3-D panel per state of ``result`` (mm), written to ``path``."""
    sheet = result.sheet
    states = [("as made", sheet.mesh.positions, np.zeros(sheet.n_cells, bool))]
    states += [(f"step {k + 1}: cell {s.cell} pushed" + ("" if s.stable else " (unstable)"),
                s.positions, s.snapped) for k, s in enumerate(result.steps)]
    return plot_shapes(sheet, states, path)


def plot_shapes(sheet, states, path):
    """One 3-D panel (mm) per (title, positions (n, 3) m, snapped (n_cells,)) of ``states``:
    e.g. two shapes reached with the same snapped cells in different orders."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    states = [(t, P, np.asarray(s, dtype=bool)) for t, P, s in states]
    cols = min(3, len(states))
    rows = math.ceil(len(states) / cols)
    fig = plt.figure(figsize=(4.2 * cols, 3.6 * rows))
    lo = min(float(np.min(p[:, 2])) for _, p, _ in states) * 1e3
    hi = max(float(np.max(p[:, 2])) for _, p, _ in states) * 1e3
    for i, (title, P, snapped) in enumerate(states):
        ax = fig.add_subplot(rows, cols, i + 1, projection="3d")
        Q = 1e3 * np.asarray(P)
        for rod in sheet.mesh.rods:
            ax.plot(*Q[rod.nodes].T, color="0.3", lw=0.7)
        apex = Q[sheet.apex]
        ax.scatter(*apex[snapped].T, color="tab:red", s=12, label="snapped")
        ax.scatter(*apex[~snapped].T, color="tab:blue", s=12, label="as made")
        ax.set_title(title, fontsize=9)
        ax.set_zlim(lo, hi)
        ax.set_xlabel("x (mm)", fontsize=7)
        ax.set_ylabel("y (mm)", fontsize=7)
        ax.set_zlabel("z (mm)", fontsize=7)
        ax.tick_params(labelsize=6)
        span = np.ptp(Q[:, :2], axis=0)
        # z drawn at least a fifth of the plan size (true scale flattens the snaps away)
        ax.set_box_aspect((span[0], span[1], max(hi - lo, 0.2 * float(np.max(span)))))
    fig.axes[0].legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
