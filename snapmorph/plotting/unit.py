"""Plots of one unit: force–displacement curve with states (i)–(iii), and the shapes."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# Okabe-Ito colours (colour-blind safe); states also differ by marker shape.
STATE_STYLE = {"i": ("#D55E00", "(i) F_cr"), "ii": ("#E69F00", "(ii) unstable"),
               "iii": ("#009E73", "(iii) second stable")}
STATE_MARKER = {"i": "^", "ii": "o", "iii": "s"}


def state_legend_handles():
    """Legend handles for the state markers (i)-(iii) of `draw_curve`."""
    from matplotlib.lines import Line2D

    return [Line2D([], [], ls="none", marker=STATE_MARKER[k], color=c, mec="k", mew=0.5, ms=6,
                   label=name) for k, (c, name) in STATE_STYLE.items()]


def shape_legend_handles():
    """Legend handles for `draw_shapes`: one colour per state, base solid, arch dashed."""
    from matplotlib.lines import Line2D

    hs = [Line2D([], [], color=c, lw=1.5, label=name) for c, name in STATE_STYLE.values()]
    hs += [Line2D([], [], color="0.3", ls="-", lw=1.2, label="base"),
           Line2D([], [], color="0.3", ls="--", lw=1.2, label="arch")]
    return hs


def state_points(r):
    """(d, F) of the states (i)-(iii) that exist, in mm and N."""
    pts = {}
    if r.F_cr == r.F_cr:
        pts["i"] = (r.d_cr * 1e3, r.F_cr)
    if r.d_unstable == r.d_unstable:
        pts["ii"] = (r.d_unstable * 1e3, 0.0)
    if r.d_second == r.d_second:
        pts["iii"] = (r.d_second * 1e3, 0.0)
    return pts


def draw_curve(ax, r, label=None, color="k", mark=True, **kw):
    d, F = r.curve
    ax.plot(d * 1e3, F, color=color, label=label, **kw)
    if mark:
        for key, (x, y) in state_points(r).items():
            c, name = STATE_STYLE[key]
            ax.plot(x, y, STATE_MARKER[key], color=c, mec="k", mew=0.5, ms=6, zorder=5)
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_xlabel("apex displacement d (mm)")
    ax.set_ylabel("force F (N)")


def draw_shapes(ax, r, offset=0.0):
    for key in ("i", "ii", "iii"):
        if key not in r.shapes:
            continue
        c, name = STATE_STYLE[key]
        s = r.shapes[key]
        for part, ls in (("base", "-"), ("arch", "--")):
            if part in s:
                xy = s[part] * 1e3
                ax.plot(xy[:, 0], xy[:, 1] + offset, ls, color=c, lw=1.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")


def plot_unit(r, path):
    """One figure: the curve with (i)-(iii) marked, and the three deformed shapes."""
    g = r.geometry
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.4), constrained_layout=True)
    draw_curve(a1, r, color="#0072B2", label="push test: force against apex displacement")
    handles, _ = a1.get_legend_handles_labels()
    a1.legend(handles=handles + state_legend_handles(), fontsize=7, loc="upper right")
    a1.set_title(f"L {g.L*1e3:g}, h {g.h*1e3:g}, t {g.t*1e3:g}, w {g.w*1e3:g}, b {g.b*1e3:g} mm: "
                 f"{r.status}", fontsize=10)
    draw_shapes(a2, r)
    a2.legend(handles=shape_legend_handles(), fontsize=7, loc="upper left",
              bbox_to_anchor=(1.01, 1.0))
    a2.set_title(f"shapes; S/L = {r.S / g.L:.3f}, theta = {r.theta_deg:.1f} deg" if r.bistable
                 else "shapes", fontsize=10)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path
