"""CSV targets: x, y columns with their unit in the header, an optional tangent column.

The header names the columns and their unit: `x_mm,y_mm`, `x (in),y (in)`, `x_m`, `x_cm`,
`x [mm]`; `units=` ("mm", "cm", "m", "in") says it when the header does not (no header, or
`x,y`: mm). A third column is a tangent direction only when its header says so
(`tangent_deg`, `angle_deg`, `heading_deg`; `_rad` for radians); a `z` column is accepted when
z is constant (the curve is planar) and refused otherwise; any other third column is refused.
Lines starting with `#` and blank lines are skipped; a UTF-8 byte-order mark, CRLF line ends
and `;` or tab separators (with decimal commas) are accepted.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from snapmorph.design.targets_frame import DrawingFrame
from snapmorph.design.targets_pieces import JOIN_TOL_MM, PLANAR_TOL_MM, TargetError

#: mm per unit of a CSV column
MM_PER = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4}
_UNIT_WORDS = {"mm": "mm", "millimetre": "mm", "millimeter": "mm", "cm": "cm", "m": "m",
               "metre": "m", "meter": "m", "in": "in", "inch": "in", "inches": "in", '"': "in"}
_ANGLE = re.compile(r"^(tangent|angle|heading|direction|tangent_angle|phi|theta)$")
_HEADER = re.compile(r"^\s*([A-Za-z][A-Za-z_ ]*?)\s*(?:[_ ]\s*|\(\s*|\[\s*)?"
                     r"(mm|cm|m|in|inch|inches|millimetres?|millimeters?|metres?|meters?|deg|"
                     r"degrees?|rad|radians?|\")?\s*[\)\]]?\s*$", re.IGNORECASE)


def read_csv(path, units: str | None = None, where: str | None = None):
    """(points (N, 2) in mm, tangents (N,) in degrees or None, frame, notes) of a CSV target."""
    path = Path(path)
    where = where or str(path)
    if units is not None and units not in MM_PER:
        raise TargetError(f"units must be one of {', '.join(MM_PER)}, got {units!r}", "units")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise TargetError(f"{where}: not a readable text file ({exc})", "unreadable") from None
    header, rows, lines = None, [], []
    for n, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        cells = _split(line)
        values = [_number(c) for c in cells]
        if all(v is not None for v in values):
            rows.append(values)
            lines.append(n)
        elif header is None and not rows and all(v is None for v in values):
            header = (n, cells)
        else:
            bad = cells[[v is None for v in values].index(True)]
            raise TargetError(f"{where}, line {n}: not a number: {bad!r} in {raw.strip()!r}",
                              "unreadable")
    if not rows:
        raise TargetError(f"{where}: no points (expected lines 'x_mm, y_mm[, tangent_deg]')",
                          "no-curve")
    widths = {len(r) for r in rows}
    if len(widths) != 1:
        i = next(i for i, r in enumerate(rows) if len(r) != len(rows[0]))
        raise TargetError(f"{where}, line {lines[i]}: {len(rows[i])} values where the first "
                          f"point has {len(rows[0])}", "unreadable")
    ncol = widths.pop()
    names, col_units = _columns(header, ncol, where)
    unit = _unit(col_units[:2], units, header, where)
    data = np.array(rows, dtype=float)
    notes = []
    if header is None:
        notes.append(f"{where}: no header line: columns taken as x, y in {unit}"
                     + (" (add a header x_mm,y_mm or say --units)" if units is None else ""))
    tangents = None
    if ncol < 2 or ncol > 3:
        raise TargetError(f"{where}: every line needs 2 values (x, y) or 3 (x, y and a column "
                          f"its header names: tangent_deg or z_mm), got {ncol}", "unreadable")
    if ncol == 3:
        kind = names[2]
        if kind == "tangent":
            factor = 180.0 / math.pi if col_units[2] == "rad" else 1.0
            tangents = data[:, 2] * factor
        elif kind == "z":
            z_mm = data[:, 2] * MM_PER[col_units[2] or unit]
            if np.ptp(z_mm) > PLANAR_TOL_MM:
                raise TargetError(f"{where}: the curve is not planar (column 3, z, varies by "
                                  f"{np.ptp(z_mm):.2f} mm); draw the target flat in the XY plane",
                                  "non-planar")
            notes.append(f"{where}: column 3 is z, constant ({z_mm[0]:g} mm): not used")
        elif header is None:
            raise TargetError(f"{where}: 3 columns and no header: name them (x_mm,y_mm,"
                              "tangent_deg if the third is the tangent direction in degrees, "
                              "x_mm,y_mm,z_mm if it is z) or remove the third", "unreadable")
        else:
            raise TargetError(f"{where}: column 3 is headed {header[1][2]!r}: a third column is "
                              "read only as a tangent (tangent_deg, angle_deg) or as a constant "
                              "z (z_mm); rename or remove it", "unreadable")
    mm = data[:, :2] * MM_PER[unit]
    if len(mm) > 2 and np.hypot(*(mm[-1] - mm[0])) <= JOIN_TOL_MM < _length(mm):  # not a dot
        raise TargetError(f"{where}: the curve is closed (the last point is the first, "
                          f"{_length(mm):.2f} mm round); a closed curve is never a target: "
                          "remove the last point or leave the ends apart", "closed")
    frame = DrawingFrame("csv", mm_per_unit=MM_PER[unit], source=where)
    return mm, tangents, frame, notes


def _length(mm) -> float:
    return float(np.sum(np.hypot(*np.diff(mm, axis=0).T)))


def _split(line: str) -> list:
    """Cells of one line (quotes allowed): ';' separated with decimal commas (as a German
    locale writes), else ',' separated, else tabs or spaces."""
    import csv

    if ";" in line:
        return [c.strip().replace(",", ".") for c in next(csv.reader([line], delimiter=";"))]
    if "," in line:
        return [c.strip() for c in next(csv.reader([line]))]
    return line.split()


def _number(cell: str):
    try:
        v = float(cell)
    except ValueError:
        return None
    return v


def _columns(header, ncol, where):
    """(names, units): each column's role ("x", "y", "z", "tangent" or its own name) and its
    unit from the header (None when the header gives none)."""
    if header is None:
        return ["x", "y", "?"][:ncol] + ["?"] * max(0, ncol - 3), [None] * ncol
    n, cells = header
    if len(cells) != ncol:
        raise TargetError(f"{where}, line {n}: the header has {len(cells)} columns, the points "
                          f"{ncol}", "unreadable")
    names, units = [], []
    for cell in cells:
        m = _HEADER.match(cell)
        name = (m.group(1) if m else cell).strip().lower().replace(" ", "_").rstrip("_")
        unit = (m.group(2) or "").lower() if m else ""
        if _ANGLE.match(name) or unit.startswith("deg") or unit.startswith("rad"):
            names.append("tangent")
            units.append("rad" if unit.startswith("rad") else "deg")
            continue
        names.append(name if name in ("x", "y", "z") else name)
        units.append(_UNIT_WORDS.get(unit) if unit else None)
    if names[:2] != ["x", "y"]:
        raise TargetError(f"{where}, line {n}: the first two columns must be x and y (e.g. "
                          f"x_mm,y_mm), the header says {', '.join(cells[:2])}", "unreadable")
    return names, units


def _unit(xy_units, units, header, where) -> str:
    """The unit of x and y: the header's, else `units`, else mm; a clash is refused."""
    declared = {u for u in xy_units if u}
    if len(declared) > 1:
        raise TargetError(f"{where}: x and y have different units in the header "
                          f"({' and '.join(sorted(declared))})", "units")
    said = declared.pop() if declared else None
    if said and units and said != units:
        raise TargetError(f"{where}: the header says {said}, --units says {units}: fix one",
                          "units")
    return said or units or "mm"
