"""Kerf compensation: the laser burns away about a kerf's width centred on its path, so a part
cut on its drawn outline comes out kerf/2 too small all round and its holes kerf/2 too large.
Offsetting each closed CUT path by kerf/2 away from the material (outward for a part's outline,
into the hole for a hole) gives parts of the drawn size.
"""

from __future__ import annotations

import numpy as np

#: a corner's miter is cut off (bevelled) when it would reach further than this times |d|
MITER_LIMIT = 4.0


def signed_area(p: np.ndarray) -> float:
    """Shoelace area (mm²) of a closed polygon, > 0 counter-clockwise."""
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def offset_polygon(points, d: float) -> np.ndarray:
    """The closed polygon moved outward by d mm (inward for d < 0): every edge shifted along
    its outward normal, corners mitred (bevelled past MITER_LIMIT · |d|). For offsets small
    against the edges, as a kerf is."""
    p = np.asarray(points, dtype=float)
    if len(p) > 2 and np.hypot(*(p[-1] - p[0])) < 1e-12:
        p = p[:-1]
    if signed_area(p) < 0:
        return offset_polygon(p[::-1], d)[::-1]
    e = np.roll(p, -1, axis=0) - p  # edge i from p[i] to p[i + 1]
    n = np.stack([e[:, 1], -e[:, 0]], axis=-1) / np.hypot(*e.T)[:, None]  # outward (CCW)
    out = []
    for i in range(len(p)):
        n0, n1 = n[i - 1], n[i]  # the edges before and after vertex i
        m = n0 + n1
        cos_half = np.sqrt(max((1.0 + float(n0 @ n1)) / 2.0, 0.0))
        if cos_half < 1.0 / MITER_LIMIT:  # too sharp: bevel
            out += [p[i] + d * n0, p[i] + d * n1]
        else:
            out.append(p[i] + d * m / np.hypot(*m) / cos_half)
    return np.array(out)


def point_in_polygon(q, p) -> bool:
    """Ray casting: is point q inside the closed polygon p?"""
    x, y = q
    inside = False
    for (x0, y0), (x1, y1) in zip(p, np.roll(p, -1, axis=0)):
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def compensate(sheet, kerf_mm: float):
    """A copy of the sheet whose closed CUT paths are offset by kerf_mm / 2: outward for a
    part's outlines, inward for holes (CUT outlines inside another one of the same part)."""
    from dataclasses import replace

    from snapmorph.design.sheets import Sheet

    if not kerf_mm:
        return sheet
    if kerf_mm < 0 or not np.isfinite(kerf_mm):
        raise ValueError(f"kerf must be a width >= 0 mm, got {kerf_mm}")
    out = Sheet(sheet.name, list(sheet.entities), {k: list(v) for k, v in sheet.parts.items()})
    for part, idx in sheet.parts.items():
        cuts = [i for i in idx if sheet.entities[i].layer == "CUT" and sheet.entities[i].closed
                and not sheet.entities[i].text]
        for i in cuts:
            p = np.asarray(sheet.entities[i].points, float)
            hole = any(point_in_polygon(p[0], np.asarray(sheet.entities[j].points, float))
                       for j in cuts if j != i)
            out.entities[i] = replace(sheet.entities[i],
                                      points=offset_polygon(p, -kerf_mm / 2 if hole else kerf_mm / 2))
    return out
