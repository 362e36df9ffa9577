"""Figures of simulated arrays against forward kinematics (matplotlib, Agg; plotted in mm)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from snapmorph.design.plots import _plt, _save, label_grid

# Okabe-Ito colours, safe for colour-vision deficiencies (as snapmorph.plotting.arrays).
_BLUE, _ORANGE, _GREY = "#0072B2", "#E69F00", "#999999"


def _placed(xy, placement):
    """(K, 2) m from the clamp frame into `placement` = (x0_m, y0_m, angle_rad) (or as is)."""
    if placement is None:
        return np.asarray(xy)
    x0, y0, a = placement
    c, s = math.cos(a), math.sin(a)
    return np.asarray(xy) @ np.array([[c, s], [-s, c]]) + np.array([x0, y0])


def _draw(ax, result, fk=None, arches=True, joints=True, placement=None, target=None,
          labels=True):
    """The simulated base (thick), its arches (thin) and the FK prediction (dashed), in mm, in
    the frame of `placement` (default: clamp at the origin, heading +x); `target` (m) as a grey
    band. Every mark has a legend label."""
    if target is not None:
        t = np.asarray(target) * 1e3
        ax.plot(t[:, 0], t[:, 1], "-", color=_GREY, lw=5, alpha=0.5,
                label="target (--overlay)" if labels else None)
    if arches:
        first = True
        for a in result.arches:
            if a is not None:
                a = _placed(a, placement) * 1e3
                ax.plot(a[:, 0], a[:, 1], "-", color=_ORANGE, lw=0.8,
                        label="arches" if (labels and first) else None)
                first = False
    b = _placed(result.base, placement) * 1e3
    ax.plot(b[:, 0], b[:, 1], "-", color=_BLUE, lw=2.2,
            label="base, array simulation" if labels else None)
    if fk is not None:
        f = _placed(fk, placement) * 1e3
        ax.plot(f[:, 0], f[:, 1], "--", color="k", lw=1.0,
                label="base, forward kinematics" if labels else None)
    if joints:
        j = _placed(result.joints, placement) * 1e3
        ax.plot(j[:, 0], j[:, 1], "o", color="k", ms=2.5, label="unit joints" if labels else None)
    clamp = _placed(np.array([[0.0, -6e-3], [0.0, 6e-3]]), placement) * 1e3
    ax.plot(clamp[:, 0], clamp[:, 1], "-", color="0.3", lw=3,
            label="clamp (first base edge)" if labels else None)


def plot_study(study, path, title: str | None = None, ncols: int = 4, placement=None,
               target=None) -> Path:
    """One panel per state of an `ArrayStudy`: simulation, arches and FK overlaid, same scale,
    with the deviation from FK ("dev": largest distance between the simulated and the FK base,
    % of the array length), in the frame of `placement` (x0_m, y0_m, angle_rad) if given."""
    plt = _plt()
    keys = list(study.states)
    ncols = min(ncols, len(keys))
    nrows = math.ceil(len(keys) / ncols)
    pts = [_placed(r.positions, placement) for r in study.states.values()] + \
        [_placed(v, placement) for v in study.fk.values()]
    if target is not None:
        pts.append(np.asarray(target))
    allp = np.vstack(pts) * 1e3
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.05 * (hi - lo).max()
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.3 * ncols, 3.0 * nrows + 1.0),
                             squeeze=False)
    rows = {r.state: r for r in study.rows}
    for ax, key in zip(axes.flat, keys):
        _draw(ax, study.states[key], study.fk.get(key), placement=placement, target=target)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal")
        r = rows[key]
        if r.status == "ok":
            dev = "" if math.isnan(r.dev_fk) else f"  dev {100 * r.dev_fk:.2f} %"
            ax.set_title(f"{key}{dev}", fontsize=8)
        else:  # the reason is in the table; a short word here keeps the titles apart
            short = r.status.split(":")[0].split("(")[0].strip()[:28]
            ax.set_title(f"{key}: {short} (see table)", fontsize=8, color="#D55E00")
        ax.tick_params(labelsize=6)
    label_grid(axes, len(keys), 7)
    h, lab = axes.flat[0].get_legend_handles_labels()
    fig.legend(h, lab, loc="lower center", ncol=min(len(h), 6), fontsize=8, frameon=False)
    note = ("state: one character per unit, 1 = snapped; dev: largest distance between the "
            "simulated and the forward-kinematics base, % of the array length")
    if placement is not None:
        note += "\nin the target's frame (units.csv placement line)"
    fig.suptitle((title + "\n" if title else "") + note, fontsize=9)
    fig.tight_layout(rect=(0, 0.5 / fig.get_figheight(), 1, 1))
    return _save(fig, path)


def plot_result(result, path, fk=None, title: str | None = None, placement=None,
                target=None) -> Path:
    """One simulated state (`ArrayResult`) with its arches, and the FK polyline if given (m),
    in the frame of `placement` (x0_m, y0_m, angle_rad) if given, with `target` (m) if given."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 5), constrained_layout=True)
    _draw(ax, result, fk, placement=placement, target=target)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.grid(True, color="0.9", lw=0.6)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
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
