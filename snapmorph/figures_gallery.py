"""The gallery page `index.md` of a figures folder: every PNG with a caption and every Markdown
table linked, so a reader can review them all in one place (`make figures`)."""

from __future__ import annotations

from pathlib import Path

#: One line each: what the figure shows and how to read it (file stem -> caption).
CAPTIONS = {
    "specimens_forcedef": "Table 1 specimens: force against apex displacement with states (i) "
                          "F_cr, (ii) unstable and (iii) second stable marked; shapes in mm.",
    "design_maps": "Design maps for b = 0: F_cr, S/L and θ over h/L against t/L and w/L; grey "
                   "cells are monostable, triangles the Table 1 specimens (their b = w).",
    "fk_states": "Forward kinematics of the paper's three identical units from the design map "
                 "(b = 0): the 8 states, one panel each, same scale in mm.",
    "inverse_M": "Inverse design of the M from five points with the paper's control points: "
                 "target, biarcs, predicted all-snapped shape (top) and the flat array (bottom).",
    "inverse_S": "Inverse design of the S from control points with tangents (circular arms and a "
                 "straight): target, biarcs and prediction (top), flat array (bottom).",
    "arrays_three_units": "The paper's three units, every state: whole-array simulation against "
                          "forward kinematics (dev = largest distance, % of the array length).",
    "arrays_M": "The paper's Table 3 M array, every state: simulation against forward kinematics.",
    "unit3d_states": "The unit in 3-D (frame base, elastic end plates; h = 20 mm): states (i)-(iii) "
                     "in perspective, the side view with the planar model (dotted) and the released "
                     "state (dashed), both force-displacement curves.",
    "unit3d_knockdown": "F_cr of the 3-D unit against the tilt of its arch, relative to the "
                        "untilted unit, at h = 20 and 40 mm.",
    "unit2d_states": "The paper's 2-D unit (square frame, crossing arches; h = 40 mm): as made, "
                     "second stable state actuated and released (one pair of sides curls, the "
                     "frame warps), and the force-displacement curve.",
}


def write_gallery(folder) -> Path:
    """Write `folder/index.md` listing every figure (PNG, embedded) and table (Markdown, linked)
    in `folder`: the paper's figures in the paper's order, then any other in name order;
    returns its path."""
    folder = Path(folder)
    lines = ["# snapmorph figures", "",
             "Written by `make figures` (`snapmorph figures --out figures`). Lengths in mm unless "
             "a label says otherwise; the design maps are for b = 0.", ""]
    tables = sorted(folder.glob("*.md"))
    tables = [t for t in tables if t.name != "index.md"]
    if tables:
        lines += ["## Tables", ""] + [f"- [{t.stem}]({t.name})" for t in tables] + [""]
    lines += ["## Figures", ""]
    pngs = {p.stem: p for p in folder.glob("*.png")}
    order = [s for s in CAPTIONS if s in pngs] + sorted(set(pngs) - set(CAPTIONS))
    for png in (pngs[s] for s in order):
        caption = CAPTIONS.get(png.stem, "")
        lines += [f"### {png.stem}", ""]
        if caption:
            lines += [caption, ""]
        lines += [f"![{png.stem}]({png.name})", ""]
    path = folder / "index.md"
    path.write_text("\n".join(lines))
    return path
