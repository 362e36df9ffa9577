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


def write_units_csv(units, path) -> Path:
    """Write `units.csv` (columns unit, L_mm, h_mm, t_mm, w_mm, side; unit numbered from 1)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(CSV_COLUMNS)
        for i, u in enumerate(units, start=1):
            writer.writerow([i, _mm(u.L), _mm(u.h), _mm(u.t), _mm(u.w), u.side])
    return path


def read_units_csv(path, b_over_L: float = 0.0) -> list[Unit]:
    """Read `units.csv`; b (not a column) is set to b_over_L * L for arched units."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"units file not found: {path}")
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise ValueError(f"{path}: no units (expected a header {','.join(CSV_COLUMNS)} and rows)")
    missing = [c for c in CSV_COLUMNS if c not in rows[0]]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}; "
                         f"expected {','.join(CSV_COLUMNS)}")
    units = []
    for n, row in enumerate(rows, start=2):
        try:
            L, h, t, w = (float(row[c]) * 1e-3 for c in ("L_mm", "h_mm", "t_mm", "w_mm"))
            side = int(float(row["side"]))
        except (TypeError, ValueError):
            raise ValueError(f"{path}, line {n}: not a number in {dict(row)}") from None
        try:
            units.append(Unit(L=L, h=h, t=t, w=w, side=side, b=b_over_L * L if h > 0 else 0.0))
        except ValueError as exc:
            raise ValueError(f"{path}, line {n}: {exc}") from None
    return units


def _mm(x: float) -> str:
    """A length in m as mm text, exact enough to round-trip (1 nm)."""
    return f"{x * 1e3:.6f}".rstrip("0").rstrip(".")
