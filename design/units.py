"""The unit of an array, and the `units.csv` file that lists a design.

A unit is a base of length L carrying (or not) a bistable arch of apex height h on one side:

- ``side = +1``: the arch sits on the +z (left, counter-clockwise) side of the base, walking the
  array from its start; snapping curls the base towards that side (θ > 0, a left turn).
- ``side = -1``: the mirror image (a right turn when snapped).
- ``h = 0, side = 0``: an arch-less straight spacer, straight in every state.

``b`` is the extra flat length of each arch end (m). The design maps are built at one b/L (the
default map at b/L = 0, as in the paper's parametric study), so ``b`` defaults to 0; a unit looked
up in a map must have the map's b/L (checked in `design.shapes`).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

CSV_COLUMNS = ("unit", "L_mm", "h_mm", "t_mm", "w_mm", "side")
#: optional columns: b_mm, the extra flat length of an arch's ends (written by
#: `write_units_csv`; a file without it gets b = b_over_L L)
OPTIONAL_COLUMNS = ("b_mm",)


@dataclass(frozen=True)
class Unit:
    """One unit, SI units (m): base length L, arch height h, sheet thickness t, strip width w,
    side ±1 (0 for a spacer, h = 0; default +1 / 0), flat-end extra length b."""

    L: float
    h: float
    t: float
    w: float
    side: int | None = None
    b: float = 0.0

    def __post_init__(self):
        if self.side is None:  # default: +1 for an arch, 0 for a spacer
            object.__setattr__(self, "side", 1 if _positive(self.h) else 0)
        for name in ("L", "h", "t", "w", "b"):
            value = getattr(self, name)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"Unit.{name} must be a number (m), got {value!r}") from None
            if not math.isfinite(value):
                raise ValueError(f"Unit.{name} must be finite, got {value}")
            object.__setattr__(self, name, value)
        if self.L <= 0:
            raise ValueError(f"Unit.L must be > 0 m, got {self.L}")
        if self.t <= 0:
            raise ValueError(f"Unit.t must be > 0 m, got {self.t}")
        if self.w <= 0:
            raise ValueError(f"Unit.w must be > 0 m, got {self.w}")
        if self.h < 0:
            raise ValueError(f"Unit.h must be >= 0 m (0 for a straight spacer), got {self.h}")
        if self.b < 0:
            raise ValueError(f"Unit.b must be >= 0 m, got {self.b}")
        side = self.side
        if isinstance(side, bool) or not isinstance(side, (int, float)) or side not in (-1, 0, 1):
            raise ValueError(f"Unit.side must be +1, -1 (arch) or 0 (spacer), got {side!r}")
        object.__setattr__(self, "side", int(side))
        if self.h > 0:
            if self.side == 0:
                raise ValueError("Unit.side must be +1 or -1 for a unit with an arch (h > 0)")
            if 2 * (self.b + self.w) >= self.L:
                raise ValueError(
                    f"Unit.L = {self.L * 1e3:.3g} mm leaves no room for the arch: the flat ends "
                    f"take 2(b + w) = {2 * (self.b + self.w) * 1e3:.3g} mm"
                )
            if self.h >= self.L:
                raise ValueError(f"Unit.h must be < L, got h = {self.h}, L = {self.L}")
        elif self.side != 0:
            raise ValueError("Unit.side must be 0 for a straight spacer (h = 0)")

    @property
    def is_spacer(self) -> bool:
        """True for an arch-less straight unit."""
        return self.h == 0.0

    @property
    def arch_length(self) -> float:
        """Length la of the sinusoidal part of the arch (m): L - 2(b + w)."""
        return self.L - 2.0 * (self.b + self.w)

    def mirrored(self) -> "Unit":
        """The same unit with its arch on the other side."""
        return Unit(L=self.L, h=self.h, t=self.t, w=self.w, side=-self.side, b=self.b)


def _positive(x) -> bool:
    try:
        return float(x) > 0
    except (TypeError, ValueError):
        return False


def spacer(L: float, t: float, w: float) -> Unit:
    """A straight arch-less unit of length L (m)."""
    return Unit(L=L, h=0.0, t=t, w=w, side=0)


PLACEMENT_PREFIX = "# placement"


def write_units_csv(units, path, placement=None) -> Path:
    """Write `units.csv` (columns unit, L_mm, h_mm, t_mm, w_mm, side, and b_mm when an arched
    unit has flat ends b > 0 (0 for a spacer); unit numbered from 1).

    `placement`: optional ``(x0_m, y0_m, angle_rad)``, the start point and start tangent of
    unit 1 in the target's frame (a design's frame). It is written as a first comment line
    ``# placement x0_mm=<g> y0_mm=<g> angle_deg=<g>`` that `read_placement` reads back, so that
    `snapmorph fk` / `array` draw the units where the design put them.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    header = None
    if placement is not None:
        x0, y0, angle = _check_placement(placement)
        header = (f"{PLACEMENT_PREFIX} x0_mm={x0 * 1e3:.12g} y0_mm={y0 * 1e3:.12g} "
                  f"angle_deg={math.degrees(angle):.12g}")
    with path.open("w", newline="") as fh:
        if header:
            fh.write(header + "\n")
        writer = csv.writer(fh)
        # b_mm only when it says something: a file without it reads as b = 0 (or b/L of the
        # reader's map), which is what the files of b = 0 designs always said
        with_b = any(u.b > 0 and not u.is_spacer for u in units)
        writer.writerow((*CSV_COLUMNS, *(OPTIONAL_COLUMNS if with_b else ())))
        for i, u in enumerate(units, start=1):
            row = [i, _mm(u.L), _mm(u.h), _mm(u.t), _mm(u.w), u.side]
            writer.writerow(row + ([_mm(0.0 if u.is_spacer else u.b)] if with_b else []))
    return path


def _check_placement(placement):
    try:
        x0, y0, angle = (float(v) for v in placement)
    except (TypeError, ValueError):
        raise ValueError("placement must be (x0_m, y0_m, angle_rad), three numbers; "
                         f"got {placement!r}") from None
    if not all(math.isfinite(v) for v in (x0, y0, angle)):
        raise ValueError(f"placement (x0_m, y0_m, angle_rad) must be finite; got {placement!r}")
    return x0, y0, angle


def read_placement(path):
    """The placement line of a `units.csv`: ``(x0_m, y0_m, angle_rad)``, or None if absent."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"units file not found: {path}")
    with path.open() as fh:
        for n, line in enumerate(fh, start=1):
            text = line.strip()
            if not text:
                continue
            if not text.startswith("#"):
                return None  # the placement line comes before the header
            if not text.startswith(PLACEMENT_PREFIX):
                continue
            fields = {}
            for item in text[len(PLACEMENT_PREFIX):].split():
                key, sep, value = item.partition("=")
                if sep:
                    fields[key] = value
            try:
                x0 = float(fields["x0_mm"]) * 1e-3
                y0 = float(fields["y0_mm"]) * 1e-3
                angle = math.radians(float(fields["angle_deg"]))
            except (KeyError, ValueError):
                raise ValueError(f"{path}, line {n}: expected '{PLACEMENT_PREFIX} x0_mm=<number> "
                                 f"y0_mm=<number> angle_deg=<number>', got {text!r}") from None
            if not all(math.isfinite(v) for v in (x0, y0, angle)):
                raise ValueError(f"{path}, line {n}: placement values must be finite; "
                                 f"got {text!r}")
            return x0, y0, angle
    return None


def has_b_column(path) -> bool:
    """Whether a units.csv's header (its first line not starting with #) has the b_mm column."""
    with Path(path).open(newline="") as fh:
        for line in fh:
            if line.strip() and not line.lstrip().startswith("#"):
                return "b_mm" in (c.strip() for c in next(csv.reader([line])))
    return False


def read_units_csv(path, b_over_L: float = 0.0) -> list[Unit]:
    """Read `units.csv`. An arched unit's b is its row's b_mm when the file has that column
    (`write_units_csv` writes it), else b_over_L * L; a spacer's b is 0.

    Lines starting with ``#`` (e.g. the placement line) are skipped. A spacer is a row with
    ``h_mm = 0`` and ``side = 0``; an arched unit has ``h_mm > 0`` and ``side`` +1 or -1.
    Errors name the file, the line, the column and its unit (mm).
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"units file not found: {path}")
    try:
        b_over_L = float(b_over_L)
    except (TypeError, ValueError):
        raise ValueError(f"b_over_L must be a number in [0, 0.5); got {b_over_L!r}") from None
    if not (0.0 <= b_over_L < 0.5):
        raise ValueError(f"b_over_L must be in [0, 0.5); got {b_over_L}")
    try:
        with path.open(newline="") as fh:
            numbered = [(n, line) for n, line in enumerate(fh, start=1)
                        if line.strip() and not line.lstrip().startswith("#")]
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text CSV file") from None
    if not numbered:
        raise ValueError(f"{path}: no units (expected a header {','.join(CSV_COLUMNS)} and rows)")
    reader = csv.reader(line for _, line in numbered)
    rows = list(reader)
    header = [c.strip() for c in rows[0]]
    missing = [c for c in CSV_COLUMNS if c not in header]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}; "
                         f"expected {','.join(CSV_COLUMNS)}")
    if len(rows) < 2:
        raise ValueError(f"{path}: no units (only a header)")
    units = []
    for (n, _), row in zip(numbered[1:], rows[1:]):
        if len(row) != len(header):
            raise ValueError(f"{path}, line {n}: {len(row)} fields, expected {len(header)} "
                             f"({','.join(header)})")
        rec = dict(zip(header, (v.strip() for v in row)))
        mm = {}
        for c in ("L_mm", "h_mm", "t_mm", "w_mm"):
            try:
                v = float(rec[c])
            except ValueError:
                raise ValueError(f"{path}, line {n}: not a number in {c} (a length in mm, "
                                 f"> 0): {rec[c]!r}") from None
            if not math.isfinite(v):
                raise ValueError(f"{path}, line {n}: {c} must be finite (mm); got {rec[c]!r}")
            mm[c] = v
        for c in ("L_mm", "t_mm", "w_mm"):
            if mm[c] <= 0:
                raise ValueError(f"{path}, line {n}: {c} must be > 0 mm; got {rec[c]}")
        if mm["h_mm"] < 0:
            raise ValueError(f"{path}, line {n}: h_mm must be >= 0 mm (0 for a spacer); "
                             f"got {rec['h_mm']}")
        side_text = rec["side"]
        try:
            side_value = float(side_text)
        except ValueError:
            side_value = math.nan
        if side_value not in (1.0, -1.0, 0.0):
            raise ValueError(f"{path}, line {n}: side must be 1, -1 (arch on the left / right) "
                             f"or 0 (spacer); got {side_text!r}")
        side = int(side_value)
        if mm["h_mm"] == 0 and side != 0:
            raise ValueError(f"{path}, line {n}: h_mm = 0 is a spacer, whose side must be 0; "
                             f"got side = {side_text} (give h_mm > 0 for an arched unit)")
        if mm["h_mm"] > 0 and side == 0:
            raise ValueError(f"{path}, line {n}: side = 0 marks a spacer, whose h_mm must be 0; "
                             f"got h_mm = {rec['h_mm']} (give side 1 or -1 for an arched unit)")
        L, h, t, w = (mm[c] * 1e-3 for c in ("L_mm", "h_mm", "t_mm", "w_mm"))
        b = b_over_L * L
        if "b_mm" in rec:
            b = _b_mm(rec["b_mm"], path, n)
        try:
            units.append(Unit(L=L, h=h, t=t, w=w, side=side, b=b if h > 0 else 0.0))
        except ValueError as exc:
            raise ValueError(f"{path}, line {n}: {exc}") from None
    return units


def _b_mm(text: str, path, n: int) -> float:
    """A row's b_mm (extra flat length of the arch ends, mm >= 0) in m."""
    try:
        v = float(text)
    except ValueError:
        raise ValueError(f"{path}, line {n}: not a number in b_mm (the extra flat length of the "
                         f"arch ends, mm, >= 0): {text!r}") from None
    if not (math.isfinite(v) and v >= 0):
        raise ValueError(f"{path}, line {n}: b_mm (the extra flat length of the arch ends) must "
                         f"be finite and >= 0 mm; got {text!r}")
    return v * 1e-3


def _mm(x: float) -> str:
    """A length in m as mm text, exact enough to round-trip (1 nm)."""
    return f"{x * 1e3:.6f}".rstrip("0").rstrip(".")
