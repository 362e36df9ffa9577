"""Figure: the paper's parametric maps (Fig. "maps") from the committed design map.

Rows: h/L vs t/L at w/L = 0.05, and h/L vs w/L at t/L = 0.005 (nearest grid slices).
Columns: F_cr (in newtons for L = 100 mm, E = 2.2 GPa, as the paper plots it), S/L, theta.
Monostable points are shaded grey and failed points hatched (the legend says when a slice has
none); the Table 1 specimens are marked (their b = w while the map has the parametric study's
b = 0).
"""

import os

import numpy as np

SPECIMENS = [(9.11, 99.2, 0.5), (9.10, 99.0, 0.75), (19.24, 99.5, 0.5), (19.96, 99.7, 0.75),
             (40.68, 99.4, 0.5), (39.85, 99.5, 0.75)]  # h, L, t in mm; w = 5 mm


def _panel(ax, x, y, z, status, title, cmap, fmt):
    import matplotlib.colors as mcolors

    X, Y = np.meshgrid(x, y, indexing="ij")
    zz = np.where(status == 0, z, np.nan)
    pc = ax.pcolormesh(X, Y, zz, shading="nearest", cmap=cmap)
    grey = np.where(status == 1, 1.0, np.nan)
    ax.pcolormesh(X, Y, grey, shading="nearest", cmap=mcolors.ListedColormap(["0.8"]))
    bad = np.where(status >= 2, 1.0, np.nan)
    if np.isfinite(bad).any():
        ax.pcolor(X, Y, bad, hatch="xx", alpha=0.0, shading="nearest")
    ok = np.isfinite(zz)
    if ok.sum() > 4 and np.nanmax(zz) > np.nanmin(zz):
        cs = ax.contour(X, Y, zz, levels=8, colors="k", linewidths=0.5)
        ax.clabel(cs, fontsize=6, fmt=fmt)
    ax.set_title(title, fontsize=9)
    return pc


def make(out, args=None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from snapmorph.maps import DesignMap

    dm = DesignMap.load(getattr(args, "map", None) if args is not None else None)
    ds = dm.dataset
    E, L = 2.2e9, 0.1
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    fig, axes = plt.subplots(2, 3, figsize=(15, 9.2), constrained_layout=True)
    n_mono = n_fail = 0
    rows = [("t_over_L", "w_over_L", 0.05), ("w_over_L", "t_over_L", 0.005)]
    for row, (xname, fixed, value) in enumerate(rows):
        sl = ds.sel({fixed: value}, method="nearest")
        actual = float(sl[fixed])
        sl = sl.transpose(xname, "h_over_L", ...)
        x = sl[xname].values
        y = sl["h_over_L"].values
        status = sl["status"].values
        n_mono += int(np.sum(status == 1))
        n_fail += int(np.sum(status >= 2))
        t = sl["t_over_L"].values * L
        w = sl["w_over_L"].values * L
        if xname == "t_over_L":
            I = (w * t[:, None] ** 3 / 12.0) * np.ones((len(x), len(y)))
        else:
            I = (w[:, None] * t**3 / 12.0) * np.ones((len(x), len(y)))
        F = sl["F_cr"].values * E * I / L**2
        panels = [(F, "F_cr (N) for L = 100 mm, E = 2.2 GPa", "viridis", "%.2g"),
                  (sl["S"].values, "S / L (end-to-end length / L)", "viridis_r", "%.3f"),
                  (sl["theta"].values, "θ, base turning (deg)", "magma", "%.0f")]
        for col, (z, label, cmap, fmt) in enumerate(panels):
            ax = axes[row, col]
            pc = _panel(ax, x, y, z, status,
                        f"{label.split(' (')[0].split(' for')[0].split(',')[0]} at "
                        f"{fixed.replace('_over_', '/')} = {actual:.3g}", cmap, fmt)
            fig.colorbar(pc, ax=ax, label=label)
            ax.set_xlabel(xname.replace("_over_", "/") + " (thickness / L)" if xname == "t_over_L"
                          else "w/L (width / L)")
            ax.set_ylabel("h/L (arch height / L)")
            for h, Ls, ts in SPECIMENS:
                xv = ts / Ls if xname == "t_over_L" else 5.0 / Ls
                ax.plot(xv, h / Ls, "^", color="white", ms=7, mec="k")
    handles = [Line2D([], [], ls="none", marker="^", color="white", mec="k", ms=7,
                      label="Table 1 specimens (their b = w)")]
    handles.append(Patch(facecolor="0.8", edgecolor="0.5",
                         label="monostable" if n_mono else "monostable: none in these slices"))
    handles.append(Patch(facecolor="white", edgecolor="0.3", hatch="xx",
                         label="failed points" if n_fail else "failed points: none"))
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=9, frameon=False,
               bbox_to_anchor=(0.5, -0.04))
    fig.suptitle("Design maps for b = 0 (the parametric study's flat ends), contours labelled "
                 "in the colour bar's unit", fontsize=11)
    path = os.path.join(out, "design_maps.png")
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return [path]
