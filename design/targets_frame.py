"""The coordinate frame of the drawing a target came from, and output in that frame.

A target is used in its own frame: mm (m inside the code), y up. `DrawingFrame` remembers how
that frame sits in the file it was read from, so that the target, the predicted and the
simulated shapes can be written back where they overlay the user's drawing:

- SVG: target (x, y) = (X, -Y) in mm, (X, Y) the page position after every transform
  (y down). Written back as an SVG of the same width, height and viewBox (coordinates in its
  user units), and as a DXF in mm with y up from the page's bottom edge, as Inkscape's own DXF
  export places it.
- DXF: target = WCS x, y times the drawing unit in mm. Written back as a DXF of the same
  `$INSUNITS` (coordinates in drawing units), and as an SVG in mm whose page is the curves'
  bounding box plus 5 mm (a view: positions in it are relative to that page).
- CSV: target = the columns in mm. Written back as a DXF in mm and the SVG view.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: layer / group names and colours (AutoCAD colour index) of the overlay curves
OVERLAY_COLOURS = {"target": 7, "predicted": 5, "simulated": 1}


def mm_per_px() -> float:
    """mm per SVG px: svgelements' own px per mm (96 px per inch), so that the user units of a
    mm document convert back exactly as svgelements converted them."""
    global _MM_PER_PX
    if _MM_PER_PX is None:
        from svgelements import Length

        _MM_PER_PX = 1.0 / float(Length("1mm").value(ppi=96))
    return _MM_PER_PX


_MM_PER_PX = None  # svgelements is imported on first use only


@dataclass
class DrawingFrame:
    """Where the target's frame sits in its source file.

    kind: "svg", "dxf" or "csv". mm_per_unit: the file's length unit in mm (DXF drawing unit,
    CSV column unit). insunits: the DXF `$INSUNITS` code read (0 = unitless). svg: the root's
    width, height and viewBox strings; svg_matrix: (a, b, c, d, e, f) from SVG user units to
    px (96/in) of the page; page_mm: page width and height (mm)."""

    kind: str
    mm_per_unit: float = 1.0
    insunits: int | None = None
    svg: dict = field(default_factory=dict)
    svg_matrix: tuple = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    page_mm: tuple | None = None
    source: str = ""

    # --- from the target's frame (m, y up) to the file's coordinates --------------------------
    def to_file(self, xy_m) -> np.ndarray:
        """Points (k, 2) in the source file's own coordinates (SVG user units, DXF drawing
        units, CSV column units)."""
        mm = np.asarray(xy_m, dtype=float) * 1e3
        if self.kind != "svg":
            return mm / self.mm_per_unit
        px = np.stack([mm[:, 0], -mm[:, 1]], axis=-1) / mm_per_px()
        a, b, c, d, e, f = self.svg_matrix
        inv = np.linalg.inv(np.array([[a, c], [b, d]]))
        return (px - [e, f]) @ inv.T

    def to_dxf_mm(self, xy_m) -> np.ndarray:
        """Points (k, 2) in mm, y up, where a DXF of the same drawing has them."""
        mm = np.asarray(xy_m, dtype=float) * 1e3
        if self.kind == "svg" and self.page_mm is not None:
            return mm + [0.0, self.page_mm[1]]  # Y_dxf = page height - Y_svg = page height + y
        return mm


def write_target_csv(points_m, path) -> Path:
    """The target as read, in its own frame: `x_mm,y_mm` (the file `fk --overlay` and
    `tolerance --target` read back)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, np.asarray(points_m, float) * 1e3, delimiter=",", fmt="%.6f",
               header="x_mm,y_mm", comments="")
    return path


def write_in_drawing_frame(frame: DrawingFrame, curves: dict, out_dir, stem: str = "overlay",
                           colours: dict | None = None) -> list:
    """Write `curves` ({name: (k, 2) points in m, in the target's frame}, e.g. target,
    predicted, simulated) as `<stem>.svg` and `<stem>.dxf` in out_dir, placed where they
    overlay the drawing the target came from (one group / layer per curve, named as in
    `curves`). Returns the two paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    colours = {**OVERLAY_COLOURS, **(colours or {})}
    curves = {k: np.asarray(v, dtype=float) for k, v in curves.items() if v is not None}
    return [_overlay_svg(frame, curves, out / f"{stem}.svg", colours),
            _overlay_dxf(frame, curves, out / f"{stem}.dxf", colours)]


def _overlay_svg(frame, curves, path, colours) -> Path:
    from ezdxf.colors import aci2rgb

    if frame.kind == "svg":
        attrs = " ".join(f'{k}="{v}"' for k, v in frame.svg.items() if v)
        pts = {k: frame.to_file(v) for k, v in curves.items()}
        a, b, c, d, _, _ = frame.svg_matrix
        stroke = 0.5 / max(abs(a * d - b * c), 1e-300) ** 0.5  # about 0.13 mm
    else:  # an SVG in mm, y down
        pts = {k: v * [1e3, -1e3] for k, v in curves.items()}
        allp = np.vstack(list(pts.values()))
        lo, hi = allp.min(axis=0) - 5.0, allp.max(axis=0) + 5.0
        size = hi - lo
        attrs = (f'width="{size[0]:.3f}mm" height="{size[1]:.3f}mm" '
                 f'viewBox="{lo[0]:.4f} {lo[1]:.4f} {size[0]:.4f} {size[1]:.4f}"')
        stroke = 0.2
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" {attrs}>']
    for name, p in pts.items():
        r, g, b_ = aci2rgb(int(colours.get(name, 7))) if colours.get(name, 7) != 7 else (0, 0, 0)
        d = " ".join(f"{x:.10g},{y:.10g}" for x, y in p)
        out.append(f'<g id="{name}"><polyline points="{d}" fill="none" '
                   f'stroke="rgb({r},{g},{b_})" stroke-width="{stroke:.4g}"/></g>')
    out.append("</svg>")
    path.write_text("\n".join(out) + "\n")
    return path


def _overlay_dxf(frame, curves, path, colours) -> Path:
    import ezdxf

    doc = ezdxf.new("R2000", setup=True)
    if frame.kind == "dxf":
        doc.header["$INSUNITS"] = int(frame.insunits or 0)
        pts = {k: frame.to_file(v) for k, v in curves.items()}
    else:
        doc.header["$INSUNITS"] = 4
        pts = {k: frame.to_dxf_mm(v) for k, v in curves.items()}
    msp = doc.modelspace()
    for name, p in pts.items():
        layer = name.upper()
        if layer not in doc.layers:
            doc.layers.add(layer, color=int(colours.get(name, 7)))
        msp.add_lwpolyline([tuple(map(float, q)) for q in p], dxfattribs={"layer": layer})
    doc.saveas(path)
    return path
