"""A drawing sheet: its entities (polylines and texts, mm) grouped by part.

What the drawings write (`drawings`), the nesting places (`nesting`), the kerf offsets
(`kerf`) and the checks read (`drawing_checks`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Entity:
    """A polyline (points (k, 2) mm, closed or open) or a text (at points[0], height mm,
    turned `angle` degrees counter-clockwise)."""

    layer: str
    points: np.ndarray
    closed: bool = False
    text: str = ""
    height: float = 0.0
    angle: float = 0.0

    @property
    def left_aligned(self) -> bool:
        """Notes (MARKS) start at their point; engraved labels are centred on it."""
        return self.layer == "MARKS"


@dataclass
class Sheet:
    """The drawing of one sheet; `parts` maps a part name to the indices of its entities."""

    name: str
    entities: list = field(default_factory=list)
    parts: dict = field(default_factory=dict)

    def add(self, part: str, entity: Entity) -> None:
        self.parts.setdefault(part, []).append(len(self.entities))
        self.entities.append(entity)

    def outlines(self, layer: str = "CUT") -> list:
        return [e for e in self.entities if e.layer == layer and not e.text and e.closed]
