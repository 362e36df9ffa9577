"""Figures of simulated arrays against forward kinematics (matplotlib, Agg; plotted in mm)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from design.plots import _plt, _save


def _draw(ax, result, fk=None, arches=True, joints=True):
    """The simulated base (thick), its arches (thin) and the FK prediction (dashed), in mm."""
    if arches:
        for a in result.arches:
            if a is not None:
                ax.plot(a[:, 0] * 1e3, a[:, 1] * 1e3, "-", color="C1", lw=0.7)
    b = result.base * 1e3
    ax.plot(b[:, 0], b[:, 1], "-", color="C0", lw=2.2, label="array simulation")
    if fk is not None:
        ax.plot(fk[:, 0] * 1e3, fk[:, 1] * 1e3, "--", color="k", lw=1.0,
                label="forward kinematics")
    if joints:
        j = result.joints * 1e3
        ax.plot(j[:, 0], j[:, 1], "o", color="k", ms=2.5)
    ax.plot([0.0, 0.0], [-6.0, 6.0], "-", color="0.3", lw=3)  # the clamp


def plot_study(study, path, title: str | None = None, ncols: int = 4) -> Path:
    """One panel per state of an `ArrayStudy`: simulation, arches and FK overlaid, same scale,
    with the deviation from FK (fraction of the array length)."""
    plt = _plt()
    keys = list(study.states)
    ncols = min(ncols, len(keys))
    nrows = math.ceil(len(keys) / ncols)
    pts = [r.positions for r in study.states.values()] + list(study.fk.values())
    allp = np.vstack(pts) * 1e3
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.05 * (hi - lo).max()
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.3 * ncols, 3.0 * nrows), squeeze=False)
    rows = {r.state: r for r in study.rows}
    for ax, key in zip(axes.flat, keys):
        _draw(ax, study.states[key], study.fk.get(key))
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal")
        r = rows[key]
        dev = "" if math.isnan(r.dev_fk) else f"  dev {100 * r.dev_fk:.2f} %"
        ax.set_title(f"{key}{dev}" + ("" if r.status == "ok" else f" ({r.status})"), fontsize=8)
        ax.tick_params(labelsize=6)
    for ax in list(axes.flat)[len(keys):]:
        ax.axis("off")
    h, lab = axes.flat[0].get_legend_handles_labels()
    fig.legend(h, lab, loc="lower center", ncol=2, fontsize=8, frameon=False)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return _save(fig, path)


def plot_result(result, path, fk=None, title: str | None = None) -> Path:
    """One simulated state (`ArrayResult`) with its arches, and the FK polyline if given (m)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 5))
    _draw(ax, result, fk)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")
    ax.legend(fontsize=8, loc="best")
    if title:
        ax.set_title(title, fontsize=10)
    return _save(fig, path)


def plot_snaps(result, path, title: str | None = None) -> Path:
    """Actuator force against apex displacement of each snap of an `ArrayResult`."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 4))
    for k, s in enumerate(result.snaps, start=1):
        ax.plot(s.d * 1e3, s.F, "-", lw=1.2, label=f"snap {k}: unit {s.unit + 1}")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_xlabel("apex displacement towards the base (mm)")
    ax.set_ylabel("actuator force (N)")
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    return _save(fig, path)
