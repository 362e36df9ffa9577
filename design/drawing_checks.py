"""Checks of a sheet before it is written: what a laser cutter or its operator would trip on.

- `check_paths`: every CUT outline is closed, no segment has zero length, no line is drawn
  twice (the same segment in two entities, either way round: the laser would cut it twice).
- `check_layout`: on a sheet of a bed size, every part (its outlines and its texts, MARKS
  included) lies inside the sheet and no two parts' boxes overlap.

Texts are measured as boxes `TEXT_WIDTH` × height per character (the SVG writer's estimate).
"""

from __future__ import annotations

import math

import numpy as np

#: width of one character over the text height (a sans-serif estimate, generous)
TEXT_WIDTH = 0.6
#: segments whose ends agree to this many mm are the same line
SAME_MM = 1e-6


def entity_box(e) -> tuple:
    """(x0, y0, x1, y1) mm of an entity: its points, or the box of its text (MARKS start at
    their point, engraved labels are centred on it; both centred vertically; turned by angle)."""
    if not e.text:
        p = np.asarray(e.points, float)
        return (*p.min(axis=0), *p.max(axis=0))
    w, h = TEXT_WIDTH * len(e.text) * e.height, e.height
    x0 = 0.0 if e.left_aligned else -w / 2
    corners = np.array([[x0, -h / 2], [x0 + w, -h / 2], [x0 + w, h / 2], [x0, h / 2]])
    a = math.radians(e.angle)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    c = corners @ rot.T + np.asarray(e.points[0], float)
    return (*c.min(axis=0), *c.max(axis=0))


def part_boxes(sheet) -> dict:
    """{part name: (x0, y0, x1, y1) mm} over all of a part's entities."""
    out = {}
    for part, idx in sheet.parts.items():
        boxes = np.array([entity_box(sheet.entities[i]) for i in idx])
        out[part] = (*boxes[:, :2].min(axis=0), *boxes[:, 2:].max(axis=0))
    return out


def _part_of(sheet) -> dict:
    return {i: part for part, idx in sheet.parts.items() for i in idx}


def check_paths(sheet) -> list:
    """Problems of the sheet's paths, one string each (empty: clean): open CUT paths,
    zero-length segments, lines drawn twice."""
    problems, seen = [], {}
    owner = _part_of(sheet)
    for i, e in enumerate(sheet.entities):
        if e.text:
            continue
        p = np.asarray(e.points, float)
        where = f"{owner.get(i, 'sheet')} ({e.layer})"
        closed = e.closed or (len(p) > 2 and np.hypot(*(p[-1] - p[0])) <= SAME_MM)
        if e.layer == "CUT" and not closed:
            problems.append(f"{where}: open cut path from ({p[0][0]:.2f}, {p[0][1]:.2f}) to "
                            f"({p[-1][0]:.2f}, {p[-1][1]:.2f}) mm")
        ring = np.vstack([p, p[:1]]) if e.closed else p
        for a, b in zip(ring[:-1], ring[1:]):
            if np.hypot(*(b - a)) <= SAME_MM:
                problems.append(f"{where}: zero-length segment at ({a[0]:.2f}, {a[1]:.2f}) mm")
                continue
            key = tuple(sorted((tuple(np.round(a / SAME_MM).astype(int)),
                                tuple(np.round(b / SAME_MM).astype(int)))))
            if key in seen and e.layer in ("CUT", "ENGRAVE"):
                problems.append(f"{where}: line ({a[0]:.2f}, {a[1]:.2f})-({b[0]:.2f}, "
                                f"{b[1]:.2f}) mm drawn twice (also in {seen[key]})")
            seen.setdefault(key, where)
    return problems


def check_layout(sheet, bed) -> list:
    """Problems of a nested sheet of size bed = (width, height) mm: parts outside it, parts
    whose boxes overlap."""
    W, H = bed
    boxes = part_boxes(sheet)
    problems = []
    for part, (x0, y0, x1, y1) in boxes.items():
        if x0 < -SAME_MM or y0 < -SAME_MM or x1 > W + SAME_MM or y1 > H + SAME_MM:
            problems.append(f"{part} ({x0:.1f}..{x1:.1f} x {y0:.1f}..{y1:.1f} mm) is not inside "
                            f"the {W:g} x {H:g} mm sheet")
    names = list(boxes)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            A, B = boxes[a], boxes[b]
            if min(A[2], B[2]) - max(A[0], B[0]) > SAME_MM and \
                    min(A[3], B[3]) - max(A[1], B[1]) > SAME_MM:
                problems.append(f"{a} and {b} overlap")
    return problems


def assert_clean(sheet, bed=None) -> None:
    """Raise ValueError naming the sheet and its problems (paths; layout when bed is given)."""
    problems = check_paths(sheet) + (check_layout(sheet, bed) if bed is not None else [])
    if problems:
        more = f"; and {len(problems) - 8} more" if len(problems) > 8 else ""
        raise ValueError(f"sheet {sheet.name}: " + "; ".join(problems[:8]) + more)
