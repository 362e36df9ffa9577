"""Reading targets from the files people draw them in: CSV, SVG paths, DXF polylines.

Every reader returns (points (N, 2) in m, tangents (N,) in degrees or None). Files are in mm
(SVG user units are taken as mm). SVG's y axis points down; it is flipped so that the target is
the shape as seen on screen. Curves (SVG arcs and Béziers, DXF bulges) are sampled densely, so
the points describe the drawn curve itself.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from snapmorph.design.targets import read_target_csv

#: samples per SVG curve segment / DXF bulge arc
CURVE_SAMPLES = 48


def read_target(path):
    """(points m, tangents deg or None) from a .csv, .svg or .dxf file (mm)."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"target file not found: {path}")
    ext = path.suffix.lower()
    if ext == ".svg":
        return read_svg_path(path), None
    if ext == ".dxf":
        return read_dxf_polyline(path), None
    return read_target_csv(path)


# ------------------------------------------------------------------------------------- SVG
def read_svg_path(path) -> np.ndarray:
    """The first <path> of an SVG file, sampled: (N, 2) m (SVG units taken as mm, y flipped)."""
    import xml.etree.ElementTree as ET

    path = Path(path)
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ValueError(f"{path}: not a readable SVG file ({exc})") from None
    for el in root.iter():
        if el.tag.split("}")[-1] == "path" and el.get("d"):
            xy = svg_path_points(el.get("d"), where=str(path))
            return xy * np.array([1e-3, -1e-3])
    raise ValueError(f"{path}: no <path d=...> element (draw the target as one open path)")


_TOKEN = re.compile(r"[MmLlHhVvCcSsQqTtAaZz]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def svg_path_points(d: str, where: str = "SVG path") -> np.ndarray:
    """Points (N, 2) in SVG user units along a path `d` (M, L, H, V, C, S, Q, T, A, Z and their
    relative forms). One subpath only: a second M (a separate curve) is refused."""
    tokens = _TOKEN.findall(d)
    if not tokens or tokens[0] not in "Mm":
        raise ValueError(f"{where}: path data must start with M (moveto), got {d[:30]!r}")
    pts = []
    pos = np.zeros(2)
    start = np.zeros(2)
    last_ctrl = None  # reflected control point for S/T
    last_cmd = ""
    i = 0
    cmd = None

    def nums(k):
        nonlocal i
        out = []
        for _ in range(k):
            if i >= len(tokens) or tokens[i].isalpha():
                raise ValueError(f"{where}: command {cmd} needs {k} numbers")
            out.append(float(tokens[i]))
            i += 1
        return out

    moves = 0
    while i < len(tokens):
        if tokens[i].isalpha():
            cmd = tokens[i]
            i += 1
        elif cmd is None:
            raise ValueError(f"{where}: number without a command")
        elif cmd in "Mm":
            cmd = "L" if cmd == "M" else "l"  # implicit lineto after moveto
        rel = cmd.islower()
        C = cmd.upper()
        base = pos.copy() if rel else np.zeros(2)
        if C == "M":
            moves += 1
            if moves > 1:
                raise ValueError(f"{where}: more than one subpath (a second M); the target must be "
                                 "one open curve")
            pos = base + nums(2)
            start = pos.copy()
            pts.append(pos.copy())
        elif C == "L":
            pos = base + nums(2)
            pts.append(pos.copy())
        elif C == "H":
            x = nums(1)[0]
            pos = np.array([pos[0] * rel + x, pos[1]])
            pts.append(pos.copy())
        elif C == "V":
            y = nums(1)[0]
            pos = np.array([pos[0], pos[1] * rel + y])
            pts.append(pos.copy())
        elif C in "CS":
            if C == "C":
                c1 = base + nums(2)
            else:
                c1 = 2 * pos - last_ctrl if last_cmd in "CS" and last_ctrl is not None else pos.copy()
            c2 = base + nums(2)
            end = base + nums(2)
            u = np.linspace(0, 1, CURVE_SAMPLES + 1)[1:, None]
            pts.extend((1 - u) ** 3 * pos + 3 * (1 - u) ** 2 * u * c1 + 3 * (1 - u) * u ** 2 * c2
                       + u ** 3 * end)
            last_ctrl, pos = c2, end
        elif C in "QT":
            if C == "Q":
                c1 = base + nums(2)
            else:
                c1 = 2 * pos - last_ctrl if last_cmd in "QT" and last_ctrl is not None else pos.copy()
            end = base + nums(2)
            u = np.linspace(0, 1, CURVE_SAMPLES + 1)[1:, None]
            pts.extend((1 - u) ** 2 * pos + 2 * (1 - u) * u * c1 + u ** 2 * end)
            last_ctrl, pos = c1, end
        elif C == "A":
            rx, ry, phi, large, sweep = nums(5)
            end = base + nums(2)
            pts.extend(_svg_arc(pos, end, rx, ry, phi, large, sweep))
            pos = end
        elif C == "Z":
            raise ValueError(f"{where}: the path is closed (Z); the target must be an open curve")
        else:  # pragma: no cover - the tokenizer only yields the commands above
            raise ValueError(f"{where}: unknown path command {cmd!r}")
        last_cmd = C
        if C not in "CSQT":
            last_ctrl = None
    p = np.array(pts, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > 1e-9])
    return p[keep]


def _svg_arc(p0, p1, rx, ry, phi_deg, large, sweep):
    """Points (excluding p0) of an SVG elliptical arc (endpoint parametrisation, SVG 1.1 F.6)."""
    if rx == 0 or ry == 0 or np.allclose(p0, p1):
        return [np.array(p1, float)]
    rx, ry = abs(rx), abs(ry)
    phi = math.radians(phi_deg)
    c, s = math.cos(phi), math.sin(phi)
    dx, dy = (p0 - p1) / 2
    x1, y1 = c * dx + s * dy, -s * dx + c * dy
    lam = x1 ** 2 / rx ** 2 + y1 ** 2 / ry ** 2
    if lam > 1:
        rx, ry = rx * math.sqrt(lam), ry * math.sqrt(lam)
    num = rx ** 2 * ry ** 2 - rx ** 2 * y1 ** 2 - ry ** 2 * x1 ** 2
    den = rx ** 2 * y1 ** 2 + ry ** 2 * x1 ** 2
    coef = math.sqrt(max(0.0, num / den)) * (-1 if bool(large) == bool(sweep) else 1)
    cx1, cy1 = coef * rx * y1 / ry, -coef * ry * x1 / rx
    cx = c * cx1 - s * cy1 + (p0[0] + p1[0]) / 2
    cy = s * cx1 + c * cy1 + (p0[1] + p1[1]) / 2
    a0 = math.atan2((y1 - cy1) / ry, (x1 - cx1) / rx)
    a1 = math.atan2((-y1 - cy1) / ry, (-x1 - cx1) / rx)
    da = a1 - a0
    if sweep and da < 0:
        da += 2 * math.pi
    elif not sweep and da > 0:
        da -= 2 * math.pi
    n = max(2, int(math.ceil(CURVE_SAMPLES * abs(da) / (math.pi / 2))))
    a = a0 + da * np.linspace(0, 1, n + 1)[1:]
    x = cx + rx * np.cos(a) * c - ry * np.sin(a) * s
    y = cy + rx * np.cos(a) * s + ry * np.sin(a) * c
    out = np.stack([x, y], axis=-1)
    out[-1] = p1
    return list(out)


# ------------------------------------------------------------------------------------- DXF
def read_dxf_polyline(path) -> np.ndarray:
    """The first LWPOLYLINE or POLYLINE in a DXF's modelspace, bulges sampled as arcs:
    (N, 2) m (drawing units taken as mm)."""
    path = Path(path)
    try:
        import ezdxf
    except ImportError as exc:  # pragma: no cover - ezdxf is a dependency
        raise ValueError(f"reading DXF targets needs ezdxf ({exc})") from None
    try:
        doc = ezdxf.readfile(str(path))
    except (OSError, ezdxf.DXFError) as exc:
        raise ValueError(f"{path}: not a readable DXF file ({exc})") from None
    msp = doc.modelspace()
    for e in msp:
        kind = e.dxftype()
        if kind == "LWPOLYLINE":
            verts = [(x, y, b) for x, y, _, _, b in e.get_points("xyseb")]
            closed = e.closed
        elif kind == "POLYLINE":
            verts = [(v.dxf.location[0], v.dxf.location[1], v.dxf.get("bulge", 0.0))
                     for v in e.vertices]
            closed = e.is_closed
        else:
            continue
        if closed:
            raise ValueError(f"{path}: the polyline is closed; the target must be an open curve")
        pts = [np.array(verts[0][:2], float)]
        for (x0, y0, bulge), (x1, y1, _) in zip(verts[:-1], verts[1:]):
            pts.extend(_bulge_points(np.array([x0, y0]), np.array([x1, y1]), bulge))
        p = np.array(pts)
        keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > 1e-9])
        return p[keep] * 1e-3
    raise ValueError(f"{path}: no LWPOLYLINE or POLYLINE in the modelspace (draw the target as "
                     "one open polyline)")


def _bulge_points(p0, p1, bulge):
    """Points (excluding p0) of a DXF segment with bulge tan(included angle / 4)."""
    if abs(bulge) < 1e-12:
        return [p1]
    ang = 4 * math.atan(bulge)  # included angle, > 0 counter-clockwise
    chord = p1 - p0
    L = float(np.hypot(*chord))
    r = L / (2 * math.sin(abs(ang) / 2))
    mid = (p0 + p1) / 2
    normal = np.array([-chord[1], chord[0]]) / L
    h = r * math.cos(ang / 2)  # centre offset from the chord midpoint
    centre = mid + normal * h * np.sign(bulge)
    a0 = math.atan2(*(p0 - centre)[::-1])
    n = max(2, int(math.ceil(CURVE_SAMPLES * abs(ang) / (math.pi / 2))))
    a = a0 + ang * np.linspace(0, 1, n + 1)[1:]
    out = centre + r * np.stack([np.cos(a), np.sin(a)], axis=-1)
    out[-1] = p1
    return list(out)
