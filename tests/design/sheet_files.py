"""Written sheets checked as a laser shop sees them (shared by the workshop and CLI tests): the
DXF read back with ezdxf, every cut outline and text inside the sheet, the parts' outer
outlines apart, the SVG page the sheet's size."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import ezdxf
import numpy as np


def sheet_problems(dxf_path, bed) -> tuple[list, int]:
    """(problems, holes) of a written sheet-<k>.dxf (and its .svg) of bed = (width, height)
    mm: audit errors, cut outlines or texts outside the sheet, outer outlines whose boxes
    meet, an SVG page of another size; holes: cut outlines inside another one."""
    W, H = bed
    dxf_path = Path(dxf_path)
    doc = ezdxf.readfile(dxf_path)
    problems = [f"audit: {e}" for e in doc.audit().errors]
    cuts = [np.array([p[:2] for p in pl.get_points()]) for pl in
            doc.modelspace().query("LWPOLYLINE") if pl.dxf.layer == "CUT"]
    for c in cuts:
        if not (c.min() >= 0 and c[:, 0].max() <= W and c[:, 1].max() <= H):
            problems.append(f"cut outline outside the sheet: {c.min(axis=0)}..{c.max(axis=0)}")
    for t in doc.modelspace().query("TEXT"):
        p = t.dxf.align_point if t.dxf.hasattr("align_point") else t.dxf.insert
        if not (0 <= p.x <= W and 0 <= p.y <= H):
            problems.append(f"text {t.dxf.text!r} outside the sheet at ({p.x}, {p.y})")
    boxes = [(c.min(axis=0), c.max(axis=0)) for c in cuts]
    inside = [any(np.all(lo >= lo2) and np.all(hi <= hi2) and k != m
                  for m, (lo2, hi2) in enumerate(boxes)) for k, (lo, hi) in enumerate(boxes)]
    outer = [b for b, hole in zip(boxes, inside) if not hole]
    for i, (lo, hi) in enumerate(outer):
        for lo2, hi2 in outer[i + 1:]:
            if not (np.any(hi < lo2) or np.any(hi2 < lo)):
                problems.append(f"outlines {lo}..{hi} and {lo2}..{hi2} overlap")
    root = ET.parse(dxf_path.with_suffix(".svg")).getroot()
    if (root.get("width"), root.get("height")) != (f"{W:.3f}mm", f"{H:.3f}mm"):
        problems.append(f"SVG page {root.get('width')} x {root.get('height')}, not the sheet")
    return problems, sum(inside)
