"""Re-export shim: the planar unit's geometry and mesh live in `units.geometry`.

Kept so that every existing ``from solver.unit_model import ...`` keeps working.
"""

from units.geometry import (  # noqa: F401
    DEFAULT_NODES, JOINT_LENGTH, JOINT_LENGTH_DEFAULT, MAX_NODES, MIN_FLAT_FRACTION,
    MIN_SECTION_FRACTION, MIN_WIDTH_FRACTION,
    MIN_SPAN_FRACTION, PETG_E, SUPPORT_OFFSET, UnitGeometry, UnitModel, _half_sinusoid_x,
    _segment_points, build_unit, check_nodes, check_real,
)

__all__ = ["UnitGeometry", "UnitModel", "build_unit", "DEFAULT_NODES", "PETG_E",
           "SUPPORT_OFFSET", "JOINT_LENGTH", "JOINT_LENGTH_DEFAULT"]
