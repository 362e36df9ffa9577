"""Figures of multi-shape designs and morphing plans (matplotlib, Agg; lengths in mm).

- `plot_target_overlay(md, k, path)`: target k, the predicted and (if verified) simulated
  bases of its pattern, the snapped units drawn thick; the flat array below.
- `plot_patterns(md, path)`: every target with its pattern's shape, and the pattern matrix
  (a row per target, a cell per unit as wide as the unit: snapped, unsnapped or spacer).
- `plot_morph_plan(plan, path)`, `plot_morph_plans(md, path)`: the reconfiguration steps.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from snapmorph.design.plots import _plt, _save, draw_flat

SNAP_COLOURS = {1: "C0", -1: "C1"}


def _pieces(xy, units):
    """Split a base polyline built by `chain` (M - 1 segments per map-shaped unit, one per
    straight one) at its unit joints: list of (k_i, 2) arrays. Joints are found by arc
    length, which is the same in every state."""
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    edges = np.concatenate([[0.0], np.cumsum([u.L for u in units])]) * s[-1] / sum(
        u.L for u in units)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        inside = (s > a) & (s < b)
        pa = np.array([np.interp(a, s, xy[:, 0]), np.interp(a, s, xy[:, 1])])
        pb = np.array([np.interp(b, s, xy[:, 0]), np.interp(b, s, xy[:, 1])])
        out.append(np.vstack([pa, xy[inside], pb]))
    return out


def draw_pattern_shape(ax, xy, units, pattern, lw=1.6, label=None):
    """The base xy (m) in mm, snapped units thick and coloured by side, the others thin."""
    for i, (piece, u) in enumerate(zip(_pieces(xy, units), units)):
        P = piece * 1e3
        if pattern[i]:
            ax.plot(P[:, 0], P[:, 1], "-", color=SNAP_COLOURS[u.side], lw=lw * 2.2,
                    solid_capstyle="butt")
        else:
            ax.plot(P[:, 0], P[:, 1], "-", color="0.25", lw=lw, solid_capstyle="butt")
    J = np.array([p[0] for p in _pieces(xy, units)] + [xy[-1]]) * 1e3
    ax.plot(J[:, 0], J[:, 1], "|", color="k", ms=6, mew=0.8)
    ax.plot(xy[0, 0] * 1e3, xy[0, 1] * 1e3, "ks", ms=4, label=label)


def _legend_handles():
    from matplotlib.lines import Line2D

    return [Line2D([], [], color="0.6", lw=5, alpha=0.6, label="target"),
            Line2D([], [], color=SNAP_COLOURS[1], lw=3.5, label="snapped, arch side +1"),
            Line2D([], [], color=SNAP_COLOURS[-1], lw=3.5, label="snapped, arch side -1"),
            Line2D([], [], color="0.25", lw=1.6, label="unsnapped unit or spacer"),
            Line2D([], [], color="C3", lw=1.6, ls=":", label="simulated array")]


def plot_target_overlay(md, k: int, path, title: str | None = None) -> Path:
    """Target k of a `MultiDesign` with the predicted (and simulated) base of its pattern."""
    plt = _plt()
    T = md.targets[k].xy
    P = md.predicted[k]
    allp = np.vstack([T, P])
    aspect = np.ptp(allp[:, 1]) / max(np.ptp(allp[:, 0]), 1e-12)
    h1 = float(np.clip(6.5 * aspect * 1.15, 1.5, 9.0)) + 0.8
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(9, h1 + 2.4),
                                  gridspec_kw={"height_ratios": [h1, 1.6]},
                                  constrained_layout=True)
    ax.plot(T[:, 0] * 1e3, T[:, 1] * 1e3, "-", color="0.6", lw=5, alpha=0.6)
    draw_pattern_shape(ax, P, md.units, md.patterns[k])
    handles = _legend_handles()
    if md.verification is not None:
        v = md.verification[k]
        Q = v["xy"] * 1e3
        ax.plot(Q[:, 0], Q[:, 1], ":", color="C3", lw=1.6)
        handles[-1].set_label(f"simulated array ({v['status']})")
    else:
        handles = handles[:-1]
    ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    d = md.deviations[k][md.placement_mode]
    text = (f"T{k + 1} {md.names[k]}: pattern {md.states[k]}; predicted max "
            f"{100 * d[0]:.2f} % of {md.targets[k].length * 1e3:.0f} mm ({md.placement_mode})")
    if md.verification is not None:
        text += f", simulated {100 * md.verification[k]['max_deviation']:.2f} %"
    if not md.met[k]:
        text += f"\nTOLERANCE {100 * md.tol:.2f} % MISSED"
    ax.set_title(title or text, fontsize=10)
    draw_flat(ax2, md.units, legend=True)
    ax2.set_aspect("equal", adjustable="datalim")
    ax2.set_xlabel("x (mm), the array flat, as cut")
    return _save(fig, path)


def _draw_matrix(ax, md):
    """The pattern matrix: a row per target, a cell per unit (width = L)."""
    from matplotlib.patches import Rectangle

    K = len(md.patterns)
    x = 0.0
    for i, u in enumerate(md.units):
        for k, pat in enumerate(md.patterns):
            y = K - 1 - k
            if u.is_spacer:
                face, hatch = "0.85", "//"
            elif pat[i]:
                face, hatch = SNAP_COLOURS[u.side], None
            else:
                face, hatch = "white", None
            ax.add_patch(Rectangle((x * 1e3, y), u.L * 1e3, 0.9, facecolor=face, hatch=hatch,
                                   edgecolor="k", lw=0.6))
        ax.text((x + u.L / 2) * 1e3, K + 0.05, str(i + 1), ha="center", va="bottom", fontsize=6)
        x += u.L
    ax.set_xlim(0, x * 1e3)
    ax.set_ylim(-0.1, K + 0.6)
    ax.set_yticks([K - 1 - k + 0.45 for k in range(K)])
    ax.set_yticklabels([f"T{k + 1} {md.states[k]}" for k in range(K)], fontsize=7)
    ax.set_xlabel("position along the flat array (mm); filled: snapped (blue arch side +1, "
                  "orange -1), white: unsnapped, hatched: spacer", fontsize=8)


def plot_patterns(md, path, title: str | None = None) -> Path:
    """All targets of a `MultiDesign` with their patterns' shapes, and the pattern matrix."""
    plt = _plt()
    K = len(md.targets)
    fig = plt.figure(figsize=(4.2 * K, 5.6), constrained_layout=True)
    grid = fig.add_gridspec(2, K, height_ratios=[3.4, 0.5 + 0.35 * K])
    for k in range(K):
        ax = fig.add_subplot(grid[0, k])
        T = md.targets[k].xy * 1e3
        ax.plot(T[:, 0], T[:, 1], "-", color="0.6", lw=5, alpha=0.6)
        draw_pattern_shape(ax, md.predicted[k], md.units, md.patterns[k], lw=1.2)
        if md.verification is not None:
            Q = md.verification[k]["xy"] * 1e3
            ax.plot(Q[:, 0], Q[:, 1], ":", color="C3", lw=1.3)
        ax.set_aspect("equal", adjustable="datalim")
        d = md.deviations[k][md.placement_mode][0]
        sim = ("" if md.verification is None else
               f", sim {100 * md.verification[k]['max_deviation']:.2f} %")
        ax.set_title(f"T{k + 1} {md.names[k]}\n{md.states[k]}: pred {100 * d:.2f} %{sim}"
                     + ("" if md.met[k] else " MISSED"), fontsize=8)
        ax.tick_params(labelsize=7)
    _draw_matrix(fig.add_subplot(grid[1, :]), md)
    fig.suptitle(title or f"one array, {K} shapes: {sum(not u.is_spacer for u in md.units)} "
                 f"arched units, {md.array_length * 1e3:.0f} mm; tol {100 * md.tol:.2f} % "
                 f"({md.placement_mode} placement)", fontsize=10)
    return _save(fig, path)


def push_direction(xy_unit: np.ndarray, side: int, action: str) -> tuple:
    """(point, direction) of the press on a unit whose base is `xy_unit` (m): at the middle of
    its base, pointing towards the base from the arch's side (snap: side's normal; push back:
    the other side's)."""
    mid = len(xy_unit) // 2
    p = xy_unit[mid]
    tvec = xy_unit[min(mid + 1, len(xy_unit) - 1)] - xy_unit[max(mid - 1, 0)]
    tvec = tvec / max(math.hypot(*tvec), 1e-300)
    left = np.array([-tvec[1], tvec[0]])
    towards = -side * left if action == "snap" else side * left
    return p, towards


def _draw_plan_row(axes, plan, lo, hi, first: int = 0, prefix: str = ""):
    """Shapes first, first + 1, ... of a plan on the given axes (one per axis)."""
    shapes = plan.shapes
    flags = [plan.start] + [tuple(c == "1" for c in s.state) for s in plan.steps]
    pad = 0.06 * float(np.max(hi - lo))
    arrow = 0.12 * float(np.max(hi - lo))
    for ax, j in zip(axes, range(first, first + len(axes))):
        if j >= len(shapes):
            ax.axis("off")
            continue
        draw_pattern_shape(ax, shapes[j], plan.units, flags[j], lw=1.0)
        if j + 1 < len(shapes):  # the next step's press, drawn on this shape
            step = plan.steps[j]
            piece = _pieces(shapes[j], plan.units)[step.unit]
            p, d = push_direction(piece, plan.units[step.unit].side, step.action)
            tail = (p - d * arrow / 1e3) * 1e3
            ax.annotate("", xy=p * 1e3, xytext=tail,
                        arrowprops=dict(arrowstyle="-|>", color="C3", lw=1.4))
            ax.text(*tail, f"{step.unit + 1}", color="C3", fontsize=7, ha="center",
                    va="center")
        label = f"{prefix}start " if j == 0 else f"after step {j}: "
        crossing = j > 0 and plan.steps[j - 1].crossing
        ax.set_title(f"{label}{plan.states[j]}" + (" CROSSES" if crossing else ""), fontsize=7)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)


def plot_morph_plan(plan, path, title: str | None = None, ncols: int = 5) -> Path:
    """A `MorphPlan`: the start shape, then the shape after each step; a red arrow on each
    shape shows where the next press goes and from which side (towards the base)."""
    plt = _plt()
    shapes = plan.shapes
    n = len(shapes)
    ncols = min(ncols, n)
    nrows = math.ceil(n / ncols)
    allp = np.vstack(shapes) * 1e3
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    fig, axes = plt.subplots(nrows, ncols, figsize=(2.9 * ncols, 2.6 * nrows + 0.6),
                             squeeze=False, constrained_layout=True)
    _draw_plan_row(list(axes.flat), plan, lo, hi)
    fig.suptitle(title or f"reconfiguration {plan.states[0]} -> {plan.states[-1]}: "
                 f"{len(plan.steps)} steps (arrow: the next press, towards the base; "
                 "snap from the arch's face, push back from the other)", fontsize=9)
    return _save(fig, path)


def plot_morph_plans(md, path, ncols: int = 6) -> Path:
    """The plans T1 -> T2 -> ... of a `MultiDesign`, each in rows of at most `ncols` shapes,
    each in its first target's placement."""
    plt = _plt()
    plans = [md.morph_plan(k, k + 1) for k in range(len(md.targets) - 1)]
    rows = [(k, first) for k, p in enumerate(plans) for first in range(0, len(p.shapes), ncols)]
    ncols = min(ncols, max(len(p.shapes) for p in plans))
    allp = np.vstack([np.vstack(p.shapes) for p in plans]) * 1e3
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    fig, axes = plt.subplots(len(rows), ncols, figsize=(2.6 * ncols, 2.5 * len(rows) + 0.6),
                             squeeze=False, constrained_layout=True)
    for row, (k, first) in zip(axes, rows):
        _draw_plan_row(list(row), plans[k], lo, hi, first=first, prefix=f"T{k + 1} -> T{k + 2}: ")
    text = "; ".join(f"T{k + 1} -> T{k + 2}: {len(p.steps)} steps" for k, p in enumerate(plans))
    fig.suptitle(f"reconfiguration ({text}); arrow: the next press, towards the base (snap from "
                 "the arch's face, push back from the other)", fontsize=9)
    return _save(fig, path)


def plot_nearest(result, path, title: str | None = None) -> Path:
    """A `design.nearest.NearestState`: the target and the nearest state's base, placed."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.8), constrained_layout=True)
    T = result.target * 1e3
    ax.plot(T[:, 0], T[:, 1], "-", color="0.6", lw=5, alpha=0.6)
    draw_pattern_shape(ax, result.predicted, result.units, result.pattern)
    ax.legend(handles=_legend_handles()[:-1], fontsize=8, loc="upper left",
              bbox_to_anchor=(1.01, 1.0))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    mx = result.deviation[0]
    ax.set_title((title + "\n" if title else "") + f"state {result.state}: max deviation "
                 f"{100 * mx:.2f} % ({mx * result.target_length * 1e3:.1f} mm, "
                 f"{result.placement_mode} placement)", fontsize=9)
    return _save(fig, path)
