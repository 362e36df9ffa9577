"""Everything the workshop needs for one design, in one call.

    ws = write_workshop(units, "out/", bed="600x400", kerf_mm=0.15)
    ws.paths      # sheet-1.dxf/.svg ... (or base/tabs/arches), molds.dxf/.svg, mold-<i>.stl,
                  # assembly.txt/.svg/.png
    ws.warnings   # one line each: parts larger than a common bed when no bed was given
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class Workshop:
    """What `write_workshop` wrote (paths) and what the user should be told (warnings)."""

    paths: list = field(default_factory=list)
    warnings: list = field(default_factory=list)


def write_workshop(units, out_dir, *, bed=None, bed_length_mm: float | None = None,
                   kerf_mm: float = 0.0, colours: dict | None = None,
                   mold_block_mm: float = 5.0, mold_width_mm: float | None = None,
                   stl: bool = True, assembly: bool = True, shape_xy=None) -> Workshop:
    """Drawings (`drawings.write_drawings`: nested on sheets of `bed` when given, cuts offset
    by `kerf_mm` / 2, every sheet checked), the molds as STL solids (`molds_stl`, unless stl is
    False) and the assembly sheet (`assembly_sheet`, unless assembly is False; `shape_xy` the
    snapped base to draw on it, m). BedWarnings are collected into `warnings`, not raised."""
    from snapmorph.design.drawings import BedWarning, write_drawings

    units = list(units)
    out = Path(out_dir)
    ws = Workshop()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", BedWarning)
        ws.paths += write_drawings(units, out, bed_length_mm=bed_length_mm, colours=colours,
                                   mold_block_mm=mold_block_mm, bed=bed, kerf_mm=kerf_mm)
    ws.warnings += [str(w.message) for w in caught if issubclass(w.category, BedWarning)]
    for w in caught:
        if not issubclass(w.category, BedWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if stl and any(not u.is_spacer for u in units):
        from snapmorph.design.molds_stl import write_stl_molds

        ws.paths += write_stl_molds(units, out, width_mm=mold_width_mm, block_mm=mold_block_mm)
    if assembly:
        from snapmorph.design.assembly_sheet import assembly_sheet
        from snapmorph.design.nesting import MARGIN_MM, parse_bed

        length = bed_length_mm
        if bed is not None:
            size = parse_bed(bed)
            long_side = size[0] if size[1] is None else max(size) - 2 * MARGIN_MM
            length = long_side if length is None else min(length, long_side)
        ws.paths += assembly_sheet(units, out, bed_length_mm=length, shape_xy=shape_xy)
    return ws
