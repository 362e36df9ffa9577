"""SVG targets, read with svgelements: every transform, the document's units, all path syntax.

svgelements applies each ancestor's transform (layers, groups, `<use>` clones) and the root's
viewBox / width / height (px at 96 per inch, mm, cm, in, pt), parses every path command
(compact arc flags included) and leaves out what is not drawn: `<defs>`, markers, symbols,
clip paths, `display:none`. Each drawn shape becomes one `Piece` per subpath, in mm in the
target's frame: page position (X, Y) (y down) → (X, -Y), so the target looks as drawn. Closed
shapes (rect, circle, ellipse, polygon, a path ending in Z) are pieces marked closed.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from snapmorph.design.targets_frame import DrawingFrame, mm_per_px
from snapmorph.design.targets_pieces import Piece, TargetError

#: sampling of curved segments: one point per this many mm of curve, 16 to 4000 per segment
SAMPLE_MM = 0.25

_CLOSED_SHAPES = ("Rect", "Circle", "Ellipse", "Polygon")


def read_svg(path, where: str | None = None):
    """(pieces, frame, notes) of an SVG file: every drawn shape's subpaths, in mm."""
    import io
    import xml.etree.ElementTree as ET

    import svgelements as se

    path = Path(path)
    where = where or str(path)
    try:
        root = ET.parse(path).getroot()
        context = _mark(root)
        svg = se.SVG.parse(io.BytesIO(ET.tostring(root)), ppi=96)
    except (ET.ParseError, ValueError, TypeError, AttributeError, IndexError) as exc:
        raise TargetError(f"{where}: not a readable SVG file ({exc})", "unreadable") from None
    mmpx = mm_per_px()
    frame = _frame(svg, where)
    pieces, notes, last_use = [], [], None
    for el in svg.elements():
        if isinstance(el, se.Use):
            last_use = el
            continue
        if not isinstance(el, se.Shape) or el.values.get("visibility") in ("hidden", "collapse"):
            continue
        info = context.get(el.values.get(_INDEX), {})
        via_use = last_use if _from_use(el) else None
        if info.get("hidden") and via_use is None:
            continue  # inside <defs>, <symbol>, <marker>, <clipPath>, ...: drawn only if used
        shape = se.Path(el)
        if not len(shape):
            continue
        kind = type(el).__name__
        own = {el.id} if el.id else set()
        groups = set(info.get("above", ()))
        name = el.id
        if via_use is not None:
            use = context.get(via_use.values.get(_INDEX), {})
            own.add(via_use.id)
            groups |= set(use.get("above", ()))
            name = via_use.id or name
        label = f"{kind.lower()}#{name}" if name else f"{kind.lower()} {len(pieces) + 1} (no id)"
        subpaths = list(shape.as_subpaths())
        for k, sub in enumerate(subpaths):
            xy, closed = sample_subpath(se.Path(sub))
            if len(xy) < 2:
                continue
            mm = np.column_stack([xy[:, 0] * mmpx, -xy[:, 1] * mmpx, np.zeros(len(xy))])
            pieces.append(Piece(mm, label + (f" subpath {k + 1}" if len(subpaths) > 1 else ""),
                                closed=closed or kind in _CLOSED_SHAPES,
                                names=frozenset(own - {None}), groups=frozenset(groups),
                                order=len(pieces)))
    return pieces, frame, notes


#: the attribute that numbers every element, so that a shape svgelements yields is found in
#: the XML tree (svgelements keeps no parent links)
_INDEX = "data-snapmorph-index"
#: containers whose content is drawn only through a <use>, or not at all
_NOT_DRAWN = {"defs", "symbol", "marker", "clipPath", "mask", "pattern", "metadata",
              "namedview", "title", "desc"}


def _mark(root) -> dict:
    """Number every element (attribute _INDEX); {index: {"above": the ids and Inkscape labels
    of its ancestor groups, "hidden": inside a container that is not drawn}}. A root width or
    height in m or Q (Inkscape writes m for a metre document), which svgelements does not
    know, is rewritten in mm."""
    for key in ("width", "height"):
        m = re.fullmatch(r"\s*([-+.\deE]+)\s*(m|Q)\s*", root.get(key) or "")
        if m:
            root.set(key, f"{float(m.group(1)) * (1000.0 if m.group(2) == 'm' else 0.25):.10g}mm")
    out = {}

    def walk(node, above, hidden):
        tag = node.tag.split("}")[-1] if isinstance(node.tag, str) else ""
        index = str(len(out))
        node.set(_INDEX, index)
        out[index] = {"above": tuple(above), "hidden": hidden}
        if tag in ("g", "svg", "a", "switch", "symbol"):
            above = above + [v for v in (node.get("id"), _label(node)) if v]
        for child in node:
            walk(child, above, hidden or tag in _NOT_DRAWN)

    walk(root, [], False)
    return out


def _from_use(el) -> bool:
    """True for a shape svgelements produced from a <use> (it inherits the use's href)."""
    return any(k.endswith("href") for k in el.values)


def _label(node):
    for k, v in node.attrib.items():
        if k.endswith("}label") or k == "inkscape:label":
            return f"layer {v}" if node.get(_INK + "groupmode") == "layer" else v
    return None


_INK = "{http://www.inkscape.org/namespaces/inkscape}"


def _frame(svg, where) -> DrawingFrame:
    m = svg.viewbox_transform if svg.viewbox is not None else None
    matrix = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    if m:
        import svgelements as se

        mm = se.Matrix(m)
        matrix = (mm.a, mm.b, mm.c, mm.d, mm.e, mm.f)
    attrs = {k: svg.values.get(k) for k in ("width", "height", "viewBox")}
    page = (float(svg.width) * mm_per_px(), float(svg.height) * mm_per_px()) \
        if (attrs["width"] and attrs["height"]) or attrs["viewBox"] else None
    return DrawingFrame("svg", svg=attrs, svg_matrix=matrix, page_mm=page, source=where)


def sample_subpath(sub):
    """(points (k, 2) in the path's units, closed) of one svgelements subpath: lines by their
    ends, curves every SAMPLE_MM (an even count of intervals, so a Bézier's midpoint is kept)."""
    import svgelements as se

    px_step = SAMPLE_MM / mm_per_px()
    pts, closed, start = [], False, None
    for seg in sub:
        if isinstance(seg, se.Move):
            start = np.array([seg.end.x, seg.end.y], float)
            pts.append(start)
            continue
        if start is None:  # a path that does not start with a move
            start = np.array([seg.start.x, seg.start.y], float)
            pts.append(start)
        if isinstance(seg, se.Close):
            closed = True
            end = start
            if np.hypot(*(pts[-1] - end)) > 0:
                pts.append(end.copy())
            continue
        if isinstance(seg, se.Line):
            pts.append(np.array([seg.end.x, seg.end.y], float))
            continue
        n = int(min(4000, max(16, math.ceil(seg.length(error=1e-6) / px_step))))
        n += n % 2
        pts.extend(np.asarray(seg.npoint(np.linspace(0.0, 1.0, n + 1)[1:]), float))
    if not pts:
        return np.zeros((0, 2)), closed
    p = np.array(pts, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > 1e-12])
    return p[keep], closed


def svg_path_points(d: str, where: str = "SVG path") -> np.ndarray:
    """Points (N, 2) in SVG user units along one open path `d` (no transform, y down).
    A closed path (Z) or a second subpath (a second M) is refused: this is one curve."""
    import svgelements as se

    if not d.strip() or d.strip()[0] not in "Mm":
        raise ValueError(f"{where}: path data must start with M (moveto), got {d[:30]!r}")
    try:
        path = se.Path(d)
    except ValueError:
        raise ValueError(f"{where}: malformed path data {d[:40]!r} (every command needs its "
                         "numbers: L needs 2 numbers, C 6, A 7)") from None
    if any(isinstance(s, se.Close) for s in path):
        raise ValueError(f"{where}: the path is closed (Z); the target must be an open curve")
    if sum(isinstance(s, se.Move) for s in path) > 1:
        raise ValueError(f"{where}: more than one subpath (a second M); the target must be one "
                         "open curve")
    return sample_subpath(path)[0]
