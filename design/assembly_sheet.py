"""The assembly sheet: which arch goes on which unit, on which face, in which order to snap.

Written as text (`assembly.txt`) and as a picture (`assembly.svg`, `assembly.png`): the flat
strip seen from its side, each arch drawn on the face it goes on, numbered, with the order of
snapping; the joints and their overlap tabs; below, the shape the snapped array takes when
one is given.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def assembly_steps(units, bed_length_mm: float | None = None) -> list:
    """The assembly as numbered lines of text (no trailing newlines)."""
    from snapmorph.design.drawings import developed_length, split_pieces, tab_face

    units = list(units)
    pieces = split_pieces(units, bed_length_mm)
    arched = [(i, u) for i, u in enumerate(units, start=1) if not u.is_spacer]
    face = {1: "the engraved face (+)", -1: "the plain face (-)"}
    lines = ["Assembly of the array (units numbered from the strip's start, as in units.csv;",
             "the engraved face of the base is its + face).", ""]
    step = 1
    if len(pieces) > 1:
        lines.append(f"{step}. Join the base pieces, engraved face up, joint marks J<k> together:")
        for j, (_, b) in enumerate(pieces[:-1], start=1):
            f = tab_face(units[b - 1], units[b])
            where = face[f] if f is not None else "the plain face (-), under the arch's flat end"
            lines.append(f"   J{j}: between units {b} and {b + 1}; glue tab T{j} across it on "
                         f"{where}, its engraved line on the joint.")
        lines.append("")
        step += 1
    lines.append(f"{step}. Form each arch blank on its mold (mold-<i>.stl / molds.dxf) and let it "
                 "set:")
    for i, u in arched:
        lines.append(f"   arch {i}: blank {developed_length(u) * 1e3:.1f} x {u.w * 1e3:.1f} mm, "
                     f"height {u.h * 1e3:.1f} mm, on mold {i}.")
    lines.append("")
    step += 1
    lines.append(f"{step}. Bond each arch's two flat ends on its unit's solid end regions "
                 "(b + w from each end), the arch passing through the hole:")
    for i, u in arched:
        lines.append(f"   arch {i} on unit {i} ({u.L * 1e3:.1f} mm), on {face[u.side]}; flat ends "
                     f"{(u.b + u.w) * 1e3:.1f} mm long.")
    lines.append("")
    step += 1
    order = ", ".join(str(i) for i, _ in arched)
    lines.append(f"{step}. Snap the arches in this order, from the strip's start: {order}. Hold "
                 "the part already snapped, push each arch's apex through the base until it "
                 "clicks into its second state.")
    return lines


def assembly_sheet(units, out_dir, bed_length_mm: float | None = None, shape_xy=None,
                   name: str = "assembly") -> list:
    """Write <name>.txt, <name>.svg and <name>.png into out_dir; returns the paths.
    shape_xy: (k, 2) m, the snapped array's base (predicted or simulated), drawn below."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from snapmorph.design.drawings import arch_profile, split_pieces

    units = list(units)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    steps = assembly_steps(units, bed_length_mm)
    txt = out / f"{name}.txt"
    txt.write_text("\n".join(steps) + "\n")
    X = np.concatenate([[0.0], np.cumsum([u.L * 1e3 for u in units])])
    rows = 2 if shape_xy is not None else 1
    fig, axes = plt.subplots(rows, 1, figsize=(max(8.0, min(24.0, X[-1] / 40)), 3.2 * rows + 1),
                             squeeze=False)
    ax = axes[0, 0]
    ax.plot([0, X[-1]], [0, 0], color="k", lw=2)
    order = 0
    for i, u in enumerate(units, start=1):
        x0 = X[i - 1]
        ax.plot([x0, x0], [-2, 2], color="0.5", lw=0.8)
        if u.is_spacer:
            ax.text(x0 + u.L * 5e2, -4, f"{i}", ha="center", va="top", fontsize=8, color="0.4")
            continue
        order += 1
        prof = arch_profile(u) * 1e3
        ax.plot(x0 + prof[:, 0], u.side * prof[:, 1], color="tab:blue" if u.side > 0 else
                "tab:red", lw=1.5)
        apex = u.side * u.h * 1e3
        ax.text(x0 + u.L * 5e2, apex + u.side * 3, f"arch {i}{'+' if u.side > 0 else '-'}",
                ha="center", va="bottom" if u.side > 0 else "top", fontsize=8)
        ax.annotate(f"{order}", (x0 + u.L * 5e2, apex / 2), ha="center", va="center",
                    fontsize=8, bbox=dict(boxstyle="circle", fc="w", ec="k", lw=0.6))
    for j, (_, b) in enumerate(split_pieces(units, bed_length_mm)[:-1], start=1):
        ax.plot([X[b], X[b]], [-6, 6], color="tab:green", lw=1.5)
        ax.text(X[b], 7, f"J{j}/T{j}", ha="center", fontsize=8, color="tab:green")
    ax.set_aspect("equal")
    ax.set_xlabel("along the flat strip (mm); + face up; circled: order of snapping")
    ax.set_title("assembly: arch i on unit i, on the face drawn")
    if shape_xy is not None:
        s = np.asarray(shape_xy, float) * 1e3
        ax2 = axes[1, 0]
        ax2.plot(s[:, 0], s[:, 1], color="k")
        ax2.set_aspect("equal")
        ax2.set_title("the snapped array (mm)")
    fig.tight_layout()
    paths = [txt]
    for ext in ("svg", "png"):
        path = out / f"{name}.{ext}"
        fig.savefig(path, dpi=150)
        paths.append(path)
    plt.close(fig)
    return paths

