"""DXF targets, read with ezdxf: every curve entity of the model space.

LINE, ARC, CIRCLE, ELLIPSE, LWPOLYLINE (bulges), 2-D and 3-D POLYLINE and SPLINE are
flattened by ezdxf in world coordinates (the OCS of an entity with extrusion (0, 0, -1), as CAD
mirroring leaves it, applied): arcs, ellipses and splines by their own exact flattening,
polylines through their LINE / ARC segments, anything else through `ezdxf.path.make_path`
(which would turn arcs into Bézier approximations, 2.7e-5 of the radius off). INSERTs are
expanded with their block transforms (`virtual_entities`, nested blocks too). Each entity becomes one `Piece` in mm:
`$INSUNITS` gives the drawing unit (0, unitless, and files without it are taken as mm with a
note). Paper space, entities on layers that are off or frozen, and texts, points, hatches and
dimensions are not read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from snapmorph.design.targets_frame import DrawingFrame
from snapmorph.design.targets_pieces import Piece, TargetError

#: the curve entities read
CURVES = ("LINE", "ARC", "CIRCLE", "ELLIPSE", "LWPOLYLINE", "POLYLINE", "SPLINE", "HELIX")
#: flattening: largest distance (mm) between a curve and the polyline that samples it
SAGITTA_MM = 1e-4
#: mm per drawing unit, by $INSUNITS code (0, unitless, is taken as mm)
MM_PER_INSUNIT = {0: 1.0, 1: 25.4, 2: 304.8, 3: 1609344.0, 4: 1.0, 5: 10.0, 6: 1000.0,
                  7: 1e6, 8: 25.4e-6, 9: 0.0254, 10: 914.4, 11: 1e-7, 12: 1e-6, 13: 1e-3,
                  14: 100.0, 15: 1e4, 16: 1e5}
UNIT_NAMES = {0: "unitless", 1: "in", 2: "ft", 3: "mi", 4: "mm", 5: "cm", 6: "m", 7: "km",
              8: "µin", 9: "mil", 10: "yd", 11: "Å", 12: "nm", 13: "µm", 14: "dm", 15: "dam",
              16: "hm"}
#: --units names and their $INSUNITS codes
UNIT_CODES = {"mm": 4, "cm": 5, "m": 6, "in": 1}


def read_dxf(path, units: str | None = None, where: str | None = None):
    """(pieces, frame, notes) of a DXF file's model space, in mm. `units` ("mm", "cm", "m",
    "in") overrides the file's `$INSUNITS` (said in a note when they differ)."""
    import ezdxf
    from ezdxf import recover

    path = Path(path)
    where = where or str(path)
    try:
        doc = ezdxf.readfile(str(path))
    except ezdxf.DXFStructureError:
        try:
            doc, _ = recover.readfile(str(path))
        except (OSError, ezdxf.DXFError) as exc:
            raise TargetError(f"{where}: not a readable DXF file ({exc})", "unreadable") from None
    except (OSError, ezdxf.DXFError, UnicodeDecodeError) as exc:
        raise TargetError(f"{where}: not a readable DXF file ({exc})", "unreadable") from None
    notes = []
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    if units is not None:
        want = UNIT_CODES[units]
        if code not in (0, want):
            notes.append(f"{where}: $INSUNITS says {UNIT_NAMES.get(code, code)}, read as "
                         f"{units} as asked")
        code = want
    elif code == 0:
        notes.append(f"{where}: no drawing unit ($INSUNITS unitless or absent): taken as mm "
                     "(say --units in|cm|m if it is not)")
    if code not in MM_PER_INSUNIT:
        raise TargetError(f"{where}: unknown drawing unit $INSUNITS = {code}; say --units "
                          "mm|cm|m|in", "units")
    scale = MM_PER_INSUNIT[code]
    if _repair_inserts(doc):
        notes.append(f"{where}: INSERTs with a z scale of 0 (as LibreCAD writes them) read with "
                     "z scale 1")
    hidden = {layer.dxf.name.lower() for layer in doc.layers
              if not layer.is_on() or layer.is_frozen()}
    pieces, skipped = [], {}
    for entity, owner in _entities(doc.modelspace()):
        kind = entity.dxftype()
        layer = entity.dxf.get("layer", "0")
        if layer.lower() in hidden or entity.dxf.get("invisible", 0):
            skipped[f"on hidden layer {layer}"] = skipped.get(f"on hidden layer {layer}", 0) + 1
            continue
        if kind not in CURVES or (kind == "POLYLINE" and not _is_curve_polyline(entity)):
            skipped[kind] = skipped.get(kind, 0) + 1
            continue
        pts, closed = _points(entity, SAGITTA_MM / scale)
        if len(pts) < 2:
            continue
        handle = entity.dxf.get("handle")
        names = {h for h in (handle, owner and owner.dxf.get("handle")) if h}
        groups = {layer, f"layer {layer}"}
        label = f"{kind} {handle}" if handle else f"{kind} in INSERT {owner.dxf.handle}"
        if owner is not None:
            groups.add(owner.dxf.name)
            label += f" (block {owner.dxf.name})"
        pieces.append(Piece(pts * scale, f"{label} on layer {layer}", closed=closed,
                            names=frozenset(names), groups=frozenset(groups), order=len(pieces)))
    if skipped:
        notes.append(f"{where}: not read: " + ", ".join(f"{n} {k}" for k, n in skipped.items()))
    frame = DrawingFrame("dxf", mm_per_unit=scale, insunits=code, source=where)
    return pieces, frame, notes


def _entities(space, owner=None, depth=0):
    """(entity, top-level INSERT or None) for every entity, blocks expanded in place."""
    for e in space:
        if e.dxftype() == "INSERT":
            if depth > 16:
                raise TargetError("blocks nested more than 16 deep (a block inserting itself?)",
                                  "unreadable")
            yield from _entities(e.virtual_entities(), owner or e, depth + 1)
        else:
            yield e, owner


def _repair_inserts(doc) -> int:
    """Give INSERTs with a zero scale factor in z a z scale of 1 (ezdxf cannot transform a
    block by a singular matrix; z does not matter to a planar drawing). Returns how many."""
    fixed = 0
    for layout in (doc.modelspace(), *doc.blocks):
        for e in layout.query("INSERT"):
            if e.dxf.get("zscale", 1.0) == 0.0:
                e.dxf.zscale = 1.0
                fixed += 1
    return fixed


def _is_curve_polyline(e) -> bool:
    """A 2-D or 3-D POLYLINE (not a polyface or polygon mesh)."""
    return not (e.is_poly_face_mesh or e.is_polygon_mesh)


def _points(entity, sagitta: float):
    """(points (k, 3) in drawing units, closed) of one curve entity, in world coordinates:
    lines by their ends, arcs, ellipses and splines by their own exact flattening (points on
    the curve, at most `sagitta` from it between them), polylines segment by segment (their
    bulges as arcs); other curves through `ezdxf.path.make_path`."""
    kind = entity.dxftype()
    closed = kind == "CIRCLE" or (kind == "ELLIPSE" and _full_ellipse(entity))
    if kind == "LINE":
        pts = [entity.dxf.start, entity.dxf.end]
    elif kind in ("ARC", "CIRCLE"):
        pts = list(entity.flattening(sagitta))
    elif kind in ("ELLIPSE", "SPLINE", "HELIX"):
        pts = list(entity.flattening(sagitta, segments=16))
        closed = closed or (kind != "ELLIPSE" and bool(entity.closed))
    elif kind in ("LWPOLYLINE", "POLYLINE"):
        closed = bool(entity.closed if kind == "LWPOLYLINE" else entity.is_closed)
        corners = np.array([tuple(v) for v in (entity.vertices_in_wcs() if kind == "LWPOLYLINE"
                                                else entity.points_in_wcs())], float)
        pts = [corners[0]] if len(corners) else []
        for seg in entity.virtual_entities():  # LINEs and ARCs in world coordinates
            p = _points(seg, sagitta)[0]
            if len(p) and np.linalg.norm(p[-1] - pts[-1]) < np.linalg.norm(p[0] - pts[-1]):
                p = p[::-1]  # an ARC always runs counter-clockwise: a negative bulge reversed
            pts.extend(p[1:])
    else:
        from ezdxf import path as ezpath

        pts = list(ezpath.make_path(entity).flattening(distance=sagitta, segments=16))
    pts = np.array([tuple(v) for v in pts], dtype=float).reshape(-1, 3)
    if len(pts):
        keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-12])
        pts = pts[keep]
    return pts, closed


def _full_ellipse(e) -> bool:
    span = (e.dxf.end_param - e.dxf.start_param) % (2 * np.pi)
    return span < 1e-9 or abs(span - 2 * np.pi) < 1e-9
