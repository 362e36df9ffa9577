"""Figures of array shapes for `snapmorph fk` and `snapmorph array`: lengths in mm, equal axes,
one colour-blind-safe palette (Okabe & Ito), a legend entry for every mark."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

# one Agg set-up and one way of saving for every figure of the project
from snapmorph.design.plots import _plt, _save, label_grid

#: Okabe-Ito colours (safe for the common colour-vision deficiencies).
OKABE_ITO = {"blue": "#0072B2", "orange": "#E69F00", "green": "#009E73", "vermillion": "#D55E00",
             "sky": "#56B4E9", "purple": "#CC79A7", "yellow": "#F0E442", "black": "#000000",
             "grey": "#999999"}


def transform(xy, placement):
    """Points (..., 2) in m from the array's own frame (start at the origin, heading +x) into
    the frame given by `placement` = (x0_m, y0_m, angle_rad); unchanged when it is None."""
    xy = np.asarray(xy, dtype=float)
    if placement is None:
        return xy
    x0, y0, a = placement
    c, s = math.cos(a), math.sin(a)
    return xy @ np.array([[c, s], [-s, c]]) + np.array([x0, y0])


def _frame_label(placement) -> str:
    return "target's frame (units.csv placement)" if placement is not None else \
        "array frame: start at (0, 0), heading +x"


def draw_target(ax, target_xy, label="target (--overlay)"):
    """The overlay target (m) as a wide light band with its points."""
    t = np.asarray(target_xy) * 1e3
    ax.plot(t[:, 0], t[:, 1], "-", color=OKABE_ITO["grey"], lw=5, alpha=0.5, label=label,
            solid_capstyle="round")
    ax.plot(t[:, 0], t[:, 1], "o", color=OKABE_ITO["grey"], ms=3, label="target points")


def plot_fk_state(xy, joints, path, *, title=None, target=None, placement=None,
                  start_angle=0.0) -> Path:
    """One forward-kinematics shape: base polyline and unit joints (m, already placed)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 4.5), constrained_layout=True)
    if target is not None:
        draw_target(ax, target)
    b = np.asarray(xy) * 1e3
    ax.plot(b[:, 0], b[:, 1], "-", color=OKABE_ITO["blue"], lw=2, label="base (forward kinematics)")
    j = np.asarray(joints) * 1e3
    ax.plot(j[:, 0], j[:, 1], "o", color=OKABE_ITO["black"], ms=3.5, label="unit joints")
    ax.plot(b[0, 0], b[0, 1], "s", color=OKABE_ITO["vermillion"], ms=6, label="start (unit 1)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.grid(True, color="0.9", lw=0.6)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title((title + "\n" if title else "") + _frame_label(placement), fontsize=9)
    return _save(fig, path)


def plot_fk_states(states: dict, path, *, title=None, target=None, placement=None,
                   ncols: int = 4) -> Path:
    """One panel per state {state string: (K, 2) m, already placed}, same scale and axes in mm."""
    plt = _plt()
    keys = list(states)
    ncols = max(1, min(ncols, len(keys)))
    nrows = math.ceil(len(keys) / ncols)
    pts = [np.asarray(v) for v in states.values()]
    if target is not None:
        pts.append(np.asarray(target))
    allp = np.vstack(pts) * 1e3
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.06 * max((hi - lo).max(), 1e-9)
    span = hi - lo + 2 * pad
    row_h = float(np.clip(3.0 * span[1] / max(span[0], 1e-12), 1.0, 4.0)) + 0.7  # equal aspect
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.3 * ncols, row_h * nrows + 1.2),
                             squeeze=False, sharex=True, sharey=True)
    for ax, key in zip(axes.flat, keys):
        if target is not None:
            t = np.asarray(target) * 1e3
            ax.plot(t[:, 0], t[:, 1], "-", color=OKABE_ITO["grey"], lw=4, alpha=0.5,
                    label="target (--overlay)")
        xy = np.asarray(states[key]) * 1e3
        ax.plot(xy[:, 0], xy[:, 1], "-", color=OKABE_ITO["blue"], lw=2,
                label="base (forward kinematics)")
        ax.plot(xy[0, 0], xy[0, 1], "s", color=OKABE_ITO["vermillion"], ms=4,
                label="start (unit 1)")
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal", adjustable="box")
        ax.set_title(f"state {key}", fontsize=9)
        ax.tick_params(labelsize=7)
        ax.grid(True, color="0.9", lw=0.5)
    label_grid(axes, len(keys), 8)
    h, lab = axes.flat[0].get_legend_handles_labels()
    fig.legend(h, lab, loc="lower center", ncol=len(h), fontsize=8, frameon=False,
               bbox_to_anchor=(0.5, 0.0))
    head = (title + " — " if title else "") + "state: one character per unit, 1 = snapped"
    fig.suptitle(head + "\n" + _frame_label(placement), fontsize=9)
    fig.tight_layout(rect=(0, 0.6 / fig.get_figheight(), 1, 1))
    return _save(fig, path)
