"""Figures of arrays and designs (matplotlib, Agg backend; lengths plotted in mm)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from snapmorph.design.biarcs import sample_arcs
from snapmorph.design.drawings import arch_profile


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=150, bbox_inches="tight")
    _plt().close(fig)
    return path


def label_grid(axes, used: int, fontsize) -> None:
    """A grid of panels (axes: 2-D array) in mm: x labels on the bottom row, y labels on the
    left column, and the panels after the first `used` switched off."""
    for ax in axes[-1, :]:
        ax.set_xlabel("x (mm)", fontsize=fontsize)
    for ax in axes[:, 0]:
        ax.set_ylabel("y (mm)", fontsize=fontsize)
    for ax in list(axes.flat)[used:]:
        ax.axis("off")


def draw_array(ax, units, xy=None, joints=None, color="C0", label=None):
    """Draw a base polyline (m) with its unit joints on ax, in mm."""
    if xy is not None:
        ax.plot(xy[:, 0] * 1e3, xy[:, 1] * 1e3, "-", color=color, lw=2, label=label)
    if joints is not None:
        ax.plot(joints[:, 0] * 1e3, joints[:, 1] * 1e3, "|", color="k", ms=8, mew=1)


def draw_flat(ax, units, y0: float = 0.0, legend: bool = False):
    """The unsnapped array in side view: base line and each arch on its side (mm); the unit
    joints as short vertical ticks. legend: add a legend for base, arches and joints."""
    x = 0.0
    arch_label = "arches (unsnapped, stress free)"
    for i, u in enumerate(units, start=1):
        ax.plot([x * 1e3, (x + u.L) * 1e3], [y0, y0], "k-", lw=2,
                label="base strip" if i == 1 else None)
        if not u.is_spacer:
            a = arch_profile(u, 81)
            ax.plot((x + a[:, 0]) * 1e3, y0 + u.side * a[:, 1] * 1e3, "-", color="C1", lw=1,
                    label=arch_label)
            arch_label = None
        below = u.side >= 0  # the number on the side without the arch
        ax.text((x + u.L / 2) * 1e3, y0 + (-1 if below else 1) * 0.02 * u.L * 1e3, str(i),
                ha="center", va="top" if below else "bottom", fontsize=7)
        ax.plot([x * 1e3] * 2, [y0 - 2, y0 + 2], "k-", lw=0.8)
        x += u.L
    ax.plot([x * 1e3] * 2, [y0 - 2, y0 + 2], "k-", lw=0.8)
    if legend:
        from matplotlib.lines import Line2D

        handles, _ = ax.get_legend_handles_labels()
        handles.append(Line2D([], [], color="k", lw=0, marker="|", ms=9, mew=0.8,
                              label="unit joints (numbers: unit index)"))
        ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))


def plot_design(design, path, title: str | None = None) -> Path:
    """Target, control points, biarcs and the predicted all-snapped shape; the flat array."""
    plt = _plt()
    allp = np.vstack([design.target, design.predicted])
    aspect = np.ptp(allp[:, 1]) / max(np.ptp(allp[:, 0]), 1e-12)
    h1 = float(np.clip(6.5 * aspect * 1.15, 1.2, 9.0)) + 0.8
    total = sum(u.L for u in design.units)
    tall = max([u.h for u in design.units] + [0.0])
    h2 = float(np.clip(6.5 * (2 * tall + 0.08 * total) / total, 0.6, 3.0)) + 0.6
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(9, h1 + h2 + 0.6),
                                  gridspec_kw={"height_ratios": [h1, h2]}, constrained_layout=True)
    T = design.target * 1e3
    ax.plot(T[:, 0], T[:, 1], "-", color="0.6", lw=5, alpha=0.6, label="target")
    drawn = getattr(getattr(design, "source", None), "drawn", False)
    if design.points is not None and not drawn:  # a drawn curve's vertices are no data points
        ax.plot(design.points[:, 0] * 1e3, design.points[:, 1] * 1e3, "o", color="0.3", ms=4,
                label="target points" if len(design.points) != len(design.control_points) else None)
    for j, (piece, u) in enumerate(zip(design.pieces, design.units)):
        if not piece.arcs:
            continue
        arc_xy = sample_arcs(piece.arcs, 33) * 1e3
        ax.plot(arc_xy[:, 0], arc_xy[:, 1], "--", lw=1.2, color="C2" if not u.is_spacer else "C3",
                label=("biarcs (units)" if not u.is_spacer else "flat arcs (spacers)")
                if j == _first(design, u.is_spacer) else None)
        m = arc_xy[len(arc_xy) // 2]
        ax.annotate(str(j + 1), m, textcoords="offset points", xytext=(0, 6), fontsize=8,
                    ha="center", color="C2" if not u.is_spacer else "C3")
    C = design.control_points * 1e3
    if len(C):
        ax.plot(C[:, 0], C[:, 1], "s", color="k", ms=5, mfc="none", label="control points")
    for p, a in zip(C, design.control_angles):
        d = 0.04 * design.target_length * 1e3
        ax.plot([p[0] - d * math.cos(a), p[0] + d * math.cos(a)],
                [p[1] - d * math.sin(a), p[1] + d * math.sin(a)], "k-", lw=0.8)
    P = design.predicted * 1e3
    ax.plot(P[:, 0], P[:, 1], "-", color="C0", lw=1.5, label="predicted (map, all snapped)")
    J = design.joints * 1e3
    ax.plot(J[:, 0], J[:, 1], "|", color="C0", ms=9)
    for j, xy in enumerate(J[1:-1]):
        ax.annotate(str(j + 2), xy, textcoords="offset points", xytext=(4, -8), fontsize=6,
                    color="C0")
    v = getattr(design, "verification", None)
    if v is not None:
        Q = v["xy"] * 1e3
        ax.plot(Q[:, 0], Q[:, 1], ":", color="C3", lw=1.8,
                label=f"simulated array ({v['status']})")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(title or _design_title(design))
    draw_flat(ax2, design.units, legend=True)
    ax2.set_aspect("equal", adjustable="datalim")
    ax2.set_xlabel("x (mm), undeformed array (flat, as cut)")
    ax2.set_ylabel("y (mm)")
    return _save(fig, path)


def _design_title(design) -> str:
    n_arch = sum(not u.is_spacer for u in design.units)
    text = (f"{n_arch} units, {len(design.units) - n_arch} spacers; predicted deviation max "
            f"{100 * design.max_deviation:.2f} % of {design.target_length * 1e3:.0f} mm")
    if getattr(design, "placement_mode", None):
        text += f" ({design.placement_mode} placement)"
    v = getattr(design, "verification", None)
    if v is not None:
        status = "" if v["status"] == "ok" else f" ({v['status'].split(':')[0]})"
        text += f"\nsimulated array{status}: {100 * v['max_deviation']:.2f} %"
    if getattr(design, "met", None) is False:
        text += (f"   TOLERANCE {100 * design.tol:.2f} % MISSED"
                 if design.max_deviation > design.tol else "   VERIFICATION FAILED")
    return text


def _first(design, spacer: bool) -> int:
    for j, u in enumerate(design.units):
        if u.is_spacer == spacer:
            return j
    return -1


def plot_states(states: dict, path, title: str | None = None, ncols: int = 4) -> Path:
    """One panel per state {state string: (K, 2) m}, same scale, state string as the label."""
    plt = _plt()
    keys = list(states)
    ncols = min(ncols, len(keys))
    nrows = math.ceil(len(keys) / ncols)
    allp = np.vstack(list(states.values())) * 1e3
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.05 * (hi - lo).max()
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.2 * ncols, 2.4 * nrows), squeeze=False)
    for ax, key in zip(axes.flat, keys):
        xy = states[key] * 1e3
        ax.plot(xy[:, 0], xy[:, 1], "-", color="C0", lw=2)
        ax.plot(xy[0, 0], xy[0, 1], "ks", ms=4)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal")
        ax.set_title(f"state {key}", fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(keys):]:
        ax.axis("off")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, path)


def plot_state(xy, path, units=None, joints=None, title: str | None = None) -> Path:
    """One array shape (m)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4))
    draw_array(ax, units, xy, joints)
    ax.plot(xy[0, 0] * 1e3, xy[0, 1] * 1e3, "ks", ms=5)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    if title:
        ax.set_title(title)
    return _save(fig, path)
