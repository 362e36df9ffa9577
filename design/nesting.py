"""Nesting the laser-cut parts on sheets of the bed's size.

A shelf packer of bounding boxes (texts, MARKS notes included), first fit by decreasing
height, each part turned by 90° when it only fits that way or lies better along the bed's long
side. Parts keep `gap` mm between them and `margin` mm from the sheet's edges. Good enough for
strips and blanks, which are long thin rectangles; not a true-shape nester.

    sheets = nest_parts(parts_of(base, tabs, arches), bed=(600, 400))
"""

from __future__ import annotations

import numpy as np

from snapmorph.design.drawing_checks import entity_box

#: a bed most laser cutters have, for the warning when no bed is given (mm)
COMMON_BED = (600.0, 400.0)
GAP_MM = 5.0
MARGIN_MM = 5.0


def parse_bed(text) -> tuple:
    """(width, height) mm from "600x400" (also "600 x 400", "600*400", a pair); a single
    number is a strip length only: (length, None)."""
    if isinstance(text, (tuple, list)):
        vals = [float(v) for v in text]
    else:
        parts = str(text).lower().replace("*", "x").replace("×", "x").split("x")
        try:
            vals = [float(v) for v in parts]
        except ValueError:
            raise ValueError(f"bed must be WIDTHxHEIGHT in mm (e.g. 600x400), got {text!r}") \
                from None
    if len(vals) not in (1, 2) or not all(np.isfinite(v) and v > 0 for v in vals):
        raise ValueError(f"bed must be WIDTHxHEIGHT in mm, both > 0 (e.g. 600x400), got {text!r}")
    return (vals[0], vals[1]) if len(vals) == 2 else (vals[0], None)


def parts_of(*sheets) -> list:
    """[(name, [entities])] of every part of the sheets, named "<sheet>: <part>"."""
    return [(f"{s.name}: {part}", [s.entities[i] for i in idx])
            for s in sheets for part, idx in s.parts.items()]


def _box(entities):
    b = np.array([entity_box(e) for e in entities])
    return (*b[:, :2].min(axis=0), *b[:, 2:].max(axis=0))


def _turned(entities):
    """The entities turned 90° counter-clockwise about the origin."""
    from dataclasses import replace

    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    return [replace(e, points=np.asarray(e.points, float) @ rot.T,
                    angle=(e.angle + 90.0) % 360.0 if e.text else e.angle) for e in entities]


def _moved(entities, dx, dy):
    from dataclasses import replace

    return [replace(e, points=np.asarray(e.points, float) + [dx, dy]) for e in entities]


def nest_parts(parts, bed=COMMON_BED, gap: float = GAP_MM, margin: float = MARGIN_MM,
               rotate: bool = True, name: str = "sheet") -> list:
    """Sheets ("sheet-1", ...; drawings.Sheet, origin at the sheet's lower left corner, mm)
    holding every part of `parts` ([(name, [Entity])]) inside bed = (width, height) mm, no two
    parts' boxes closer than gap. Raises ValueError naming a part that fits in no orientation."""
    from snapmorph.design.sheets import Sheet

    W, H = (float(v) for v in bed)
    room = (W - 2 * margin, H - 2 * margin)
    placed = []  # (name, entities, w, h), each oriented for the bed
    for pname, ents in parts:
        x0, y0, x1, y1 = _box(ents)
        w, h = x1 - x0, y1 - y0
        fits = w <= room[0] + 1e-9 and h <= room[1] + 1e-9
        fits_turned = rotate and h <= room[0] + 1e-9 and w <= room[1] + 1e-9
        if not fits and not fits_turned:
            raise ValueError(f"{pname} ({w:.1f} x {h:.1f} mm) does not fit the {W:g} x {H:g} mm "
                             f"bed (margin {margin:g} mm)" + ("" if rotate else " unturned"))
        if not fits or (fits_turned and (h - w) * (room[0] - room[1]) > 0):
            ents = _turned(ents)
            x0, y0, x1, y1 = _box(ents)
            w, h = x1 - x0, y1 - y0
        placed.append((pname, _moved(ents, -x0, -y0), w, h))
    placed.sort(key=lambda p: (-p[3], -p[2]))
    sheets, shelves = [], []  # shelves: [sheet index, y, height, x used]
    for pname, ents, w, h in placed:
        spot = next((s for s in shelves if h <= s[2] + 1e-9 and s[3] + w <= room[0] + 1e-9), None)
        if spot is None:
            k = next((k for k in range(len(sheets))
                      if _top(shelves, k, gap) + h <= room[1] + 1e-9), None)
            if k is None:
                sheets.append(Sheet(f"{name}-{len(sheets) + 1}"))
                k = len(sheets) - 1
            spot = [k, _top(shelves, k, gap), h, 0.0]
            shelves.append(spot)
        k, y, _, x = spot
        for e in _moved(ents, margin + x, margin + y):
            sheets[k].add(pname, e)
        spot[3] = x + w + gap
    return sheets


def _top(shelves, k, gap) -> float:
    """Height used on sheet k by its shelves, with the gap above the last one."""
    return max((y + h + gap for s, y, h, _ in shelves if s == k), default=0.0)


def oversize(parts, bed=COMMON_BED) -> list:
    """Warnings (one line each) for parts that exceed bed in either orientation."""
    W, H = bed
    out = []
    for pname, ents in parts:
        x0, y0, x1, y1 = _box(ents)
        w, h = x1 - x0, y1 - y0
        if not ((w <= W and h <= H) or (h <= W and w <= H)):
            out.append(f"{pname} is {w:.1f} x {h:.1f} mm: larger than a {W:g} x {H:g} mm laser "
                       f"bed (give the bed, e.g. --bed {W:g}x{H:g}, to split and nest the parts)")
    return out
