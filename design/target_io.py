"""Reading targets from the files people draw them in: SVG, DXF and CSV.

    points, tangents = read_target("hook.svg", select="curveA")      # (N, 2) m, deg or None
    tf = read_target_file("hook.dxf", units="in")                  # also the notes and frame
    tf.points, tf.tangents, tf.length_mm, tf.notes, tf.source, tf.frame

- SVG (`targets_svg`, svgelements): every transform, the document's units, all path syntax;
  `<defs>`, markers, symbols, clip paths and hidden elements are not drawn, so not read.
- DXF (`targets_dxf`, ezdxf's path tools): LINE, ARC, CIRCLE, ELLIPSE, LWPOLYLINE, POLYLINE,
  SPLINE and INSERT (block transforms), OCS applied, model space only, `$INSUNITS` honoured.
- CSV (`targets_csv`): units from the header or `units`; a tangent column only when named.

Pieces whose ends meet within `JOIN_TOL_MM` (0.05 mm) are one curve; closed curves are never
targets; of several open curves, `select` (id, layer or group, DXF handle) chooses one, else
the file is refused with the list. Points come back in the target's frame: mm of the drawing
(SVG: y flipped so the curve looks as drawn), in m. Refusals are `TargetError` (a ValueError)
with a one-line message in mm and a `reason`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from snapmorph.design.targets_frame import DrawingFrame
from snapmorph.design.targets_pieces import (JOIN_TOL_MM, TargetError, chain_pieces,  # noqa: F401
                                             choose)
from snapmorph.design.targets_svg import svg_path_points  # noqa: F401  (kept importable here)

#: file kinds by extension
KINDS = {".svg": "svg", ".dxf": "dxf", ".csv": "csv", ".txt": "csv"}
UNITS = ("mm", "cm", "m", "in")


@dataclass
class TargetFile:
    """A target as read: points (N, 2) m and tangents (N,) deg or None, in the target's frame;
    `source` names what was read (element, entities, layer), `notes` what the caller should
    print (units assumed, elements skipped), `frame` where the target sits in the file."""

    points: np.ndarray
    tangents: np.ndarray | None
    frame: DrawingFrame
    source: str = ""
    notes: list = field(default_factory=list)

    @property
    def length_mm(self) -> float:
        return float(np.sum(np.hypot(*np.diff(self.points, axis=0).T))) * 1e3

    @property
    def drawn(self) -> bool:
        """A curve from a drawing (SVG, DXF): taken as drawn, not splined through its points."""
        return self.frame.kind in ("svg", "dxf")

    def target(self, what: str = "target"):
        """This curve as a `design.Target`: a drawn curve as drawn, CSV points with tangents as
        the biarcs through them, other CSV points by the spline through them."""
        from snapmorph.design.biarcs import biarcs, sample_arcs
        from snapmorph.design.targets import Target

        if self.tangents is not None:
            angles = np.unwrap(np.radians(np.asarray(self.tangents, dtype=float)))
            return Target.from_polyline(sample_arcs(biarcs(self.points, angles), ARC_SAMPLES),
                                        what=what)
        if self.drawn:
            return Target.from_polyline(self.points, what=what)
        return Target.from_points(self.points, what=what)


#: samples per biarc arc when a CSV target gives tangents (as `inverse_design` samples them)
ARC_SAMPLES = 65


def target_file_of(obj, select=None, units=None) -> TargetFile | None:
    """`obj` as a `TargetFile` when it is one or names a file (read with `select`, `units`);
    None for points (then `select` and `units` must be None)."""
    if isinstance(obj, TargetFile):
        if select is not None or units is not None:
            raise ValueError("select and units apply to a target file's path, not to a "
                             "TargetFile already read")
        return obj
    if isinstance(obj, (str, bytes)) or hasattr(obj, "__fspath__"):
        return read_target_file(obj.decode() if isinstance(obj, bytes) else obj, select=select,
                                units=units)
    if select is not None or units is not None:
        raise ValueError("select and units apply to a target file (.svg, .dxf, .csv); the "
                         "target given is points")
    return None


def read_target(path, select=None, units=None):
    """(points (N, 2) in m, tangents (N,) in degrees or None) of the one open curve of a .svg,
    .dxf or .csv file (see `read_target_file`)."""
    tf = read_target_file(path, select=select, units=units)
    return tf.points, tf.tangents


def read_target_file(path, select=None, units=None, join_tol_mm: float = JOIN_TOL_MM
                     ) -> TargetFile:
    """The target of a drawing or CSV file, with the notes to print and its frame.

    select: the id, layer / group name or DXF handle of the curve, when the file holds more
        than one open curve (SVG, DXF). units: "mm", "cm", "m" or "in" for a CSV without a unit
        in its header or a DXF without (or with a wrong) `$INSUNITS`; an SVG carries its own.
    """
    path = Path(path)
    if not path.is_file():
        raise TargetError(f"target file not found: {path}", "unreadable")
    if units is not None and units not in UNITS:
        raise TargetError(f"units must be one of {', '.join(UNITS)}, got {units!r}", "units")
    kind = KINDS.get(path.suffix.lower(), "csv")
    if kind == "csv":
        from snapmorph.design.targets_csv import read_csv

        if select is not None:
            raise TargetError(f"{path}: a CSV holds one curve; select is for SVG and DXF files",
                              "not-selected")
        mm, tangents, frame, notes = read_csv(path, units=units)
        return TargetFile(mm * 1e-3, tangents, frame, source=f"{path.name} ({len(mm)} points)",
                          notes=notes)
    if kind == "svg":
        from snapmorph.design.targets_svg import read_svg

        if units is not None:
            raise TargetError(f"{path}: an SVG carries its own units (width, height, viewBox); "
                              "units is for CSV and DXF files", "units")
        pieces, frame, notes = read_svg(path)
    else:
        from snapmorph.design.targets_dxf import read_dxf

        pieces, frame, notes = read_dxf(path, units=units)
    curves = chain_pieces(pieces, join_tol_mm)
    curve = choose(curves, select, where=str(path))
    skipped = [c for c in curves if c is not curve and c.closed]
    if skipped:
        notes.append(f"{path}: closed curves are not targets, not read: "
                     + "; ".join(c.describe() for c in skipped[:6])
                     + (f"; and {len(skipped) - 6} more" if len(skipped) > 6 else ""))
    if len(curve.pieces) > 1:
        notes.append(f"{path}: {len(curve.pieces)} pieces joined into one curve (ends within "
                     f"{join_tol_mm:g} mm)")
    return TargetFile(curve.points[:, :2] * 1e-3, None, frame, source=curve.label, notes=notes)
