"""Fabrication drawings of an array (paper, Fig. "inverse_experiment" d), in millimetres.

Three sheets, each written as DXF (R2000, $INSUNITS = mm) and SVG:

- ``base``: the base strip of the whole array, laid flat. Each arched unit is a hollow frame,
  outer width 4w, two rails of width w around a 2w-wide hole, solid over its end regions of
  length b + w; spacers are solid. Unit boundaries engraved across the strip, units numbered
  with the side their arch goes on ("3+": on the engraved face, "3-": on the other face). The
  strip is cut at unit boundaries into pieces no longer than the bed (at a boundary where both
  neighbours leave one face free, when there is one); joints engraved "J1"..., each joined by
  an overlap tab "T1"... (a separate part, 4w wide, over both neighbours' solid end regions)
  glued across it on the free face, not by a butt joint alone.
- ``tabs``: one overlap tab per joint of the base pieces (when the strip is split).
- ``arches``: one flat blank per arched unit, width w, developed length 2(b + w) plus the arc
  length of the sinusoid z = (h/2)(1 - cos(2π(x - x0)/la)), the flat-end limits engraved.
- ``molds``: one closed profile per arched unit to extrude (by at least w) and 3D print: the
  arch with its flat ends, offset by t/2 so that the strip's centreline follows the sinusoid
  when it lies on the mold, over a base block.

Layers: CUT (through cuts), ENGRAVE (on the part), MARKS (notes beside the parts, not
fabricated); their colours (AutoCAD colour indices) are configurable. Before a sheet is
written it is checked (`drawing_checks.check_paths`: closed cuts, no duplicate lines); with a
bed (`write_drawings(..., bed=(600, 400))`) the laser-cut parts are nested on sheets of that
size (`nesting`), with `kerf_mm` the cuts are offset by half the kerf (`kerf`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from snapmorph.design.sheets import Entity, Sheet
from snapmorph.design.units import Unit
from snapmorph.units.shapes import sinusoid_length

LAYERS = ("CUT", "ENGRAVE", "MARKS")
DEFAULT_COLOURS = {"CUT": 1, "ENGRAVE": 5, "MARKS": 3}  # red, blue, green (ACI)
GAP = 10.0  # mm between parts on a sheet
SIDE_NOTE = ("unit n+: arch on the engraved face of the base, n-: on the other face; "
             "J<k>: glue joint k")


# --- geometry of one unit (mm) ---------------------------------------------------------------
def developed_length(u: Unit) -> float:
    """Flat blank length of the arch strip (m): flat ends plus the sinusoid's arc length."""
    return 2.0 * (u.b + u.w) + sinusoid_length(u.h, u.arch_length)


def arch_profile(u: Unit, n: int = 241) -> np.ndarray:
    """Centreline of the formed arch (m), (k, 2): flat ends then the sinusoid, apex at L/2."""
    x0, la = u.b + u.w, u.arch_length
    xs = x0 + la * (1 - np.cos(np.linspace(0, math.pi, n))) / 2  # denser near the ends
    zs = 0.5 * u.h * (1 - np.cos(2 * math.pi * (xs - x0) / la))
    return np.vstack([[0.0, 0.0], np.stack([xs, zs], axis=-1), [u.L, 0.0]])


def _rect(x0, y0, x1, y1) -> np.ndarray:
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def _line(x0, y0, x1, y1) -> np.ndarray:
    return np.array([[x0, y0], [x1, y1]], dtype=float)


def _label(u: Unit, i: int) -> str:
    return f"{i}" if u.is_spacer else f"{i}{'+' if u.side > 0 else '-'}"


# --- sheets --------------------------------------------------------------------------------------
def split_pieces(units, bed_length_mm: float | None):
    """Unit index ranges [(first, last + 1)] of base pieces no longer than the bed (mm).

    Each piece is as long as the bed allows, cut at the last unit boundary where both
    neighbours leave a face free for the overlap tab (`tab_face`), or at the last boundary
    when no such one fits."""
    lengths = [u.L * 1e3 for u in units]
    if bed_length_mm is None or sum(lengths) <= bed_length_mm:
        return [(0, len(units))]
    if bed_length_mm <= 0:
        raise ValueError(f"bed length must be > 0 mm, got {bed_length_mm}")
    for i, L in enumerate(lengths):
        if L > bed_length_mm:
            raise ValueError(f"unit {i + 1} ({L:.1f} mm) is longer than the bed "
                             f"({bed_length_mm:.1f} mm)")
    pieces, start = [], 0
    while sum(lengths[start:]) > bed_length_mm + 1e-9:
        run, fits = 0.0, []
        for i in range(start, len(units)):
            run += lengths[i]
            if run > bed_length_mm + 1e-9:
                break
            fits.append(i + 1)  # a cut after unit i keeps the piece within the bed
        free = [j for j in fits if j < len(units) and
                tab_face(units[j - 1], units[j]) is not None]
        end = free[-1] if free else fits[-1]
        pieces.append((start, end))
        start = end
    pieces.append((start, len(units)))
    return pieces


def tab_face(a: Unit, b: Unit):
    """The face (-1, +1) where neither unit a nor the next one b has its arch, for the overlap
    tab over their joint: -1 (the face not engraved) when free, else +1, else None."""
    for face in (-1, 1):
        if a.side != face and b.side != face:
            return face
    return None


def tab_ends(a: Unit, b: Unit) -> tuple:
    """How far (m) the overlap tab over the joint of unit a and the next unit b reaches into
    each: their solid end regions, b + w (a spacer's side as far as the other's)."""
    ea = None if a.is_spacer else a.b + a.w
    eb = None if b.is_spacer else b.b + b.w
    ea = ea if ea is not None else (eb if eb is not None else a.w)
    return ea, eb if eb is not None else ea


def base_sheet(units, bed_length_mm: float | None = None) -> Sheet:
    """The base strip, split into pieces laid one above the other."""
    sheet = Sheet("base")
    pieces = split_pieces(units, bed_length_mm)
    width = max(4 * u.w for u in units) * 1e3
    y_off = 0.0
    for p, (a, b) in enumerate(pieces, start=1):
        part = f"piece {p}"
        X = np.concatenate([[0.0], np.cumsum([u.L * 1e3 for u in units[a:b]])])
        yc = y_off
        sheet.add(part, Entity("CUT", _rect(0, yc - width / 2, X[-1], yc + width / 2), True))
        for k, u in enumerate(units[a:b]):
            i = a + k + 1
            w, end = u.w * 1e3, (u.b + u.w) * 1e3
            x0, x1 = X[k], X[k + 1]
            if not u.is_spacer:
                sheet.add(part, Entity("CUT", _rect(x0 + end, yc - w, x1 - end, yc + w), True))
                sheet.add(part, Entity("ENGRAVE", np.array([[0.5 * (x0 + x1), yc + 1.5 * w]]),
                                       text=_label(u, i), height=0.6 * w))
            else:
                sheet.add(part, Entity("ENGRAVE", np.array([[0.5 * (x0 + x1), yc]]),
                                       text=_label(u, i), height=0.6 * w))
            if k > 0:  # boundary with the previous unit, inset from the cut edge
                inset = 0.05 * width
                sheet.add(part, Entity("ENGRAVE", _line(x0, yc - width / 2 + inset,
                                                        x0, yc + width / 2 - inset)))
        if p > 1:
            _joint(sheet, part, p - 1, 0.0, yc, units[a], +1)
        if p < len(pieces):
            _joint(sheet, part, p, X[-1], yc, units[b - 1], -1)
        sheet.add(part, Entity("MARKS", np.array([[0.0, yc + width / 2 + 0.6 * GAP]]),
                               text=f"base piece {p}/{len(pieces)}: units {a + 1}-{b}, "
                                    f"{X[-1]:.1f} mm", height=3.0))
        y_off -= width + 2 * GAP
    for k, note in enumerate(SIDE_NOTE.split("; ")):
        sheet.add("notes", Entity("MARKS", np.array([[0.0, width / 2 + 0.6 * GAP + 8.0 - 5 * k]]),
                                  text=note + (";" if k == 0 else ""), height=3.0))
    return sheet


def tab_sheet(units, bed_length_mm: float | None = None) -> Sheet:
    """The overlap tabs T1... of the base pieces' joints, one under the other (empty when the
    strip is one piece)."""
    sheet = Sheet("tabs")
    pieces = split_pieces(units, bed_length_mm)
    width = max(4 * u.w for u in units) * 1e3
    for j, (_, b) in enumerate(pieces[:-1], start=1):
        _tab(sheet, j, units[b - 1], units[b], width, -(j - 1) * (width + GAP))
    return sheet


def _tab(sheet, j, a: Unit, b: Unit, width, yc):
    """Overlap tab T<j> over joint J<j>: a rectangle 4w wide over both end regions, the joint
    line engraved across its middle."""
    ea, eb = (v * 1e3 for v in tab_ends(a, b))
    length, x = ea + eb, ea  # the joint is ea from the tab's left end
    face = tab_face(a, b)
    part = f"tab {j}"
    sheet.add(part, Entity("CUT", _rect(0, yc - width / 2, length, yc + width / 2), True))
    inset = 0.1 * width
    sheet.add(part, Entity("ENGRAVE", _line(x, yc - width / 2 + inset, x, yc + width / 2 - inset)))
    sheet.add(part, Entity("ENGRAVE", np.array([[x / 2, yc]]), text=f"T{j}", height=0.3 * width))
    where = {-1: "- face", 1: "+ face", None: "- face, under the arch end"}[face]
    sheet.add(part, Entity("MARKS", np.array([[0.0, yc + width / 2 + 2.5]]),
                           text=f"tab T{j}: {length:.1f} x {width:.1f} mm, across J{j}, {where}",
                           height=3.0))


def _joint(sheet, part, j, x, yc, u: Unit, direction):
    """Engrave 'J<j>' on the lower rail next to a joint end at x (direction +1: to the right)."""
    w = u.w * 1e3
    h = 0.6 * w
    offset = (u.b + u.w) * 1e3 + 0.5 * 0.75 * 2 * h + 1.0
    sheet.add(part, Entity("ENGRAVE", np.array([[x + direction * offset, yc - 1.5 * w]]),
                           text=f"J{j}", height=h))


def arch_sheet(units) -> Sheet:
    """Flat arch blanks, one under the other."""
    sheet = Sheet("arches")
    y = 0.0
    for i, u in enumerate(units, start=1):
        if u.is_spacer:
            continue
        part = f"arch {i}"
        length, w, end = developed_length(u) * 1e3, u.w * 1e3, (u.b + u.w) * 1e3
        sheet.add(part, Entity("CUT", _rect(0, y, length, y + w), True))
        inset = 0.1 * w
        for x in (end, length - end):
            sheet.add(part, Entity("ENGRAVE", _line(x, y + inset, x, y + w - inset)))
        label = _label(u, i)
        hgt = min(0.6 * w, 0.8 * end / max(1, 0.75 * len(label)))
        sheet.add(part, Entity("ENGRAVE", np.array([[0.5 * end, y + 0.5 * w]]), text=label,
                               height=hgt))
        sheet.add(part, Entity("MARKS", np.array([[0.0, y + w + 2.5]]),  # above: parts nest
                               text=f"arch {i}, side {'+' if u.side > 0 else '-'}: "
                                    f"{length:.1f} x {w:.1f} mm (h {u.h * 1e3:.1f}, "
                                    f"L {u.L * 1e3:.1f})", height=min(3.0, 0.8 * w)))
        y -= w + GAP
    return sheet


def mold_profile(u: Unit, block: float = 0.005, n: int = 241) -> np.ndarray:
    """Closed mold outline (m), (k, 2): the arch's lower face (centreline offset by t/2) on top
    of a block of thickness `block` below the flat ends."""
    c = arch_profile(u, n)
    d = np.gradient(c, axis=0)
    nrm = np.stack([-d[:, 1], d[:, 0]], axis=-1)
    nrm /= np.hypot(*nrm.T)[:, None]
    top = c - 0.5 * u.t * nrm
    top[0, 0], top[-1, 0] = 0.0, u.L  # the flat ends stay flat
    bottom = -0.5 * u.t - block
    return _dedupe(np.vstack([[[u.L, bottom], [0.0, bottom]], top]))


def mold_sheet(units, block_mm: float = 5.0) -> Sheet:
    """Mold profiles, one under the other."""
    sheet = Sheet("molds")
    bottom = GAP
    for i, u in enumerate(units, start=1):
        if u.is_spacer:
            continue
        part = f"mold {i}"
        y = bottom - GAP - u.h * 1e3  # the flat ends' level, the apex one GAP below the last
        prof = mold_profile(u, block_mm * 1e-3) * 1e3
        prof[:, 1] += y
        sheet.add(part, Entity("CUT", prof, True))
        bottom = y - 0.5 * u.t * 1e3 - block_mm
        sheet.add(part, Entity("ENGRAVE", np.array([[0.5 * u.L * 1e3, bottom + 0.5 * block_mm]]),
                               text=f"{i}", height=0.6 * block_mm))
        sheet.add(part, Entity("MARKS", np.array([[u.L * 1e3 + GAP, y]]),
                               text=f"mold {i}: L {u.L * 1e3:.1f}, h {u.h * 1e3:.1f} mm; "
                                    f"extrude >= {u.w * 1e3 + 2:.0f} mm", height=3.0))
    return sheet


def _dedupe(p: np.ndarray, tol: float = 1e-12) -> np.ndarray:
    """Drop consecutive duplicates (and a closing duplicate of the first point)."""
    keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > tol])
    p = p[keep]
    if len(p) > 1 and np.hypot(*(p[-1] - p[0])) <= tol:
        p = p[:-1]
    return p


# --- writers -------------------------------------------------------------------------------------
def write_dxf(sheet: Sheet, path, colours: dict | None = None) -> Path:
    """DXF R2000 in mm; closed outlines as closed LWPOLYLINEs."""
    import ezdxf
    from ezdxf.enums import TextEntityAlignment

    colours = {**DEFAULT_COLOURS, **(colours or {})}
    doc = ezdxf.new("R2000", setup=True)
    doc.units = ezdxf.units.MM
    doc.header["$INSUNITS"] = 4
    doc.header["$MEASUREMENT"] = 1
    for name in LAYERS:
        doc.layers.add(name, color=int(colours[name]))
    msp = doc.modelspace()
    for e in sheet.entities:
        if e.text:
            msp.add_text(e.text, height=e.height,
                         dxfattribs={"layer": e.layer, "rotation": float(e.angle)}).set_placement(
                tuple(map(float, e.points[0])),
                align=TextEntityAlignment.MIDDLE_LEFT if e.left_aligned
                else TextEntityAlignment.MIDDLE_CENTER)
        else:
            pts = _dedupe(e.points) if e.closed else e.points
            msp.add_lwpolyline([tuple(map(float, q)) for q in pts], close=e.closed,
                               dxfattribs={"layer": e.layer})
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    doc.saveas(path)
    return path


def write_svg(sheet: Sheet, path, colours: dict | None = None, margin: float = 5.0,
              page=None) -> Path:
    """SVG in true millimetres (one group per layer); page = (width, height) mm: the page is
    that sheet, origin at its lower left corner (else the drawing's extent plus margin)."""
    from ezdxf.colors import aci2rgb

    colours = {**DEFAULT_COLOURS, **(colours or {})}
    if page is not None:
        x0, y0, x1, y1 = 0.0, 0.0, float(page[0]), float(page[1])
    else:
        allp = np.vstack([e.points for e in sheet.entities])
        widths = [0.6 * len(e.text) * e.height for e in sheet.entities if e.text]
        x0, y0 = allp.min(axis=0) - margin
        x1, y1 = allp.max(axis=0) + margin
        x1 += max(widths, default=0.0)
    W, H = x1 - x0, y1 - y0

    def xy(p):
        return f"{p[0] - x0:.4f},{y1 - p[1]:.4f}"

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W:.3f}mm" height="{H:.3f}mm" '
           f'viewBox="0 0 {W:.4f} {H:.4f}">', f"<title>snapmorph {sheet.name}</title>"]
    for layer in LAYERS:
        r, g, b = aci2rgb(int(colours[layer]))
        out.append(f'<g id="{layer}" stroke="rgb({r},{g},{b})" fill="none" stroke-width="0.1">')
        for e in sheet.entities:
            if e.layer != layer:
                continue
            if e.text:
                p = e.points[0]
                turn = (f' transform="rotate({-e.angle:g} {p[0] - x0:.4f} {y1 - p[1]:.4f})"'
                        if e.angle else "")
                out.append(f'<text x="{p[0] - x0:.4f}" y="{y1 - p[1]:.4f}"{turn} '
                           f'font-size="{e.height:.3f}" '
                           f'text-anchor="{"start" if e.left_aligned else "middle"}" '
                           f'dominant-baseline="middle" fill="rgb({r},{g},{b})" stroke="none" '
                           f'font-family="sans-serif">{_xml(e.text)}</text>')
            else:
                tag = "polygon" if e.closed else "polyline"
                pts = " ".join(xy(q) for q in (_dedupe(e.points) if e.closed else e.points))
                out.append(f'<{tag} points="{pts}"/>')
        out.append("</g>")
    out.append("</svg>")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(out) + "\n")
    return path


def _xml(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


class BedWarning(UserWarning):
    """A part larger than a common laser bed, drawings written without a bed."""


def write_drawings(units, out_dir, bed_length_mm: float | None = None,
                   colours: dict | None = None, mold_block_mm: float = 5.0, *,
                   bed=None, kerf_mm: float = 0.0, check: bool = True) -> list[Path]:
    """The drawings as .dxf and .svg in out_dir; returns the paths written.

    Without `bed`: base, tabs (when the strip is split: `bed_length_mm`), arches and molds,
    one file pair each; a `BedWarning` for a part larger than `nesting.COMMON_BED`. With
    bed = (width, height) mm (or "600x400"): the strip is split to fit the bed's long side,
    and base pieces, tabs and arch blanks are nested on sheet-1, sheet-2, ... of that size;
    the molds (3-D printed, not cut) stay on their own sheet. `kerf_mm`: closed cut paths
    offset by kerf/2 (`kerf.compensate`). Every sheet is checked before it is written
    (`drawing_checks`: closed cuts, no line twice; nested sheets: parts inside, no overlap);
    a failed check raises ValueError (unless check is False)."""
    import warnings

    from snapmorph.design import nesting
    from snapmorph.design.drawing_checks import assert_clean
    from snapmorph.design.kerf import compensate

    units = list(units)
    out_dir = Path(out_dir)
    size = None if bed is None else nesting.parse_bed(bed)
    if size is not None and size[1] is None:  # a single number: a strip length, as before
        bed_length_mm, size = (size[0] if bed_length_mm is None else
                               min(bed_length_mm, size[0])), None
    if size is not None:
        longest = max(size) - 2 * nesting.MARGIN_MM
        bed_length_mm = longest if bed_length_mm is None else min(bed_length_mm, longest)
    cut = [base_sheet(units, bed_length_mm), tab_sheet(units, bed_length_mm)]
    arched = any(not u.is_spacer for u in units)
    if arched:
        cut.append(arch_sheet(units))
    cut = [compensate(s, kerf_mm) for s in cut if s.entities]
    molds = [mold_sheet(units, mold_block_mm)] if arched else []
    if size is None:
        sheets, layout = cut + molds, None
        for msg in nesting.oversize(nesting.parts_of(*cut), nesting.COMMON_BED):
            warnings.warn(msg, BedWarning, stacklevel=2)
    else:
        sheets = nesting.nest_parts(nesting.parts_of(*cut), size) + molds
        layout = {s.name: size for s in sheets[:len(sheets) - len(molds)]}
    paths = []
    for sheet in sheets:
        if check:
            assert_clean(sheet, None if layout is None else layout.get(sheet.name))
        paths.append(write_dxf(sheet, out_dir / f"{sheet.name}.dxf", colours))
        paths.append(write_svg(sheet, out_dir / f"{sheet.name}.svg", colours,
                               page=None if layout is None else layout.get(sheet.name)))
    return paths
