"""The paper's Table 1 specimens: force–deformation curves and shapes (paper Fig. "forcedef")."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from snapmorph.plotting.unit import draw_curve, draw_shapes  # noqa: E402

MM = 1e-3
# nominal h (mm), t (mm) -> (measured average h, measured average L) in mm; w = b = 5 mm
TABLE1 = {
    (10, 0.50): (9.11, 99.2),
    (10, 0.75): (9.10, 99.0),
    (20, 0.50): (19.24, 99.5),
    (20, 0.75): (19.96, 99.7),
    (40, 0.50): (40.68, 99.4),
    (40, 0.75): (39.85, 99.5),
}


def simulate_specimens(which="average"):
    """{(h_nominal, t): UnitResult} for the six specimens, nominal or measured-average sizes."""
    from snapmorph.units import UnitGeometry, simulate_unit

    out = {}
    for (hn, t), (h_avg, L_avg) in TABLE1.items():
        h, L = (h_avg, L_avg) if which == "average" else (hn, 100.0)
        out[hn, t] = simulate_unit(UnitGeometry(L=L * MM, h=h * MM, t=t * MM, w=5 * MM, b=5 * MM))
    return out


def specimen_table(results) -> str:
    """Markdown table of the metrics of the six specimens."""
    head = "| h nom (mm) | t (mm) | h, L used (mm) | status | F_cr (N) | d_cr (mm) | d_unstable (mm) | d_second (mm) | S/L | theta (deg) | bistable | self-standing |"
    lines = [head, "|" + "---|" * 12]
    for (hn, t), r in results.items():
        g = r.geometry

        def f(v, s=1e3, d=3):
            return "n/a" if v != v else f"{v * s:.{d}f}"

        lines.append(
            f"| {hn} | {t:.2f} | {g.h*1e3:.2f}, {g.L*1e3:.1f} | {r.status} | {f(r.F_cr, 1, 3)} | "
            f"{f(r.d_cr)} | {f(r.d_unstable)} | {f(r.d_second)} | {f(r.S / g.L, 1, 4)} | "
            f"{f(r.theta_deg, 1, 2)} | {r.bistable} | {r.self_standing} |"
        )
    return "\n".join(lines)


THICKNESS_COLOUR = {0.50: "#000000", 0.75: "#0072B2"}  # Okabe-Ito black and blue


def plot_specimens(nominal, average, path):
    """Curves (top) by arch height, both thicknesses, nominal dashed; shapes (bottom), true
    aspect ratio, axes in mm."""
    from snapmorph.plotting.unit import shape_legend_handles, state_legend_handles

    fig, axes = plt.subplots(2, 3, figsize=(15, 8.6), gridspec_kw={"height_ratios": [1.2, 1]},
                             constrained_layout=True)
    for col, hn in enumerate((10, 20, 40)):
        ax = axes[0, col]
        for t, color in THICKNESS_COLOUR.items():
            draw_curve(ax, average[hn, t], label=f"t = {t} mm, measured average", color=color)
            draw_curve(ax, nominal[hn, t], label=f"t = {t} mm, nominal", color=color,
                       mark=False, ls="--", lw=0.9)
        ax.set_title(f"h = {hn} mm: force against apex displacement", fontsize=10)
        handles, _ = ax.get_legend_handles_labels()
        ax.legend(handles=handles + state_legend_handles(), fontsize=7, loc="upper right")
        sh = axes[1, col]
        offset = -2.2 * hn
        draw_shapes(sh, average[hn, 0.50])
        draw_shapes(sh, average[hn, 0.75], offset=offset)
        for t, y in ((0.50, 0.0), (0.75, offset)):
            sh.annotate(f"t = {t} mm", (0.0, y), xytext=(-4, 0), textcoords="offset points",
                        ha="right", va="center", fontsize=8)
        sh.set_title(f"h = {hn} mm: shapes at (i)-(iii), measured average", fontsize=10)
    for a in axes[1]:
        a.set_aspect("equal", adjustable="datalim")  # true shapes; the axes are the mm scale
    axes[1, 2].legend(handles=shape_legend_handles(), fontsize=7, loc="upper left",
                      bbox_to_anchor=(1.01, 1.0))
    fig.suptitle("Table 1 specimens (w = b = 5 mm): solid measured-average sizes, dashed nominal",
                 fontsize=11)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
