"""Re-export shim: the planar unit's simulation lives in `units.planar`.

Kept so that every existing ``from solver.unit import ...`` keeps working.
"""

from units.geometry import DEFAULT_NODES, UnitGeometry, build_unit  # noqa: F401
from units.planar import (  # noqa: F401
    E_INTERNAL, L_INTERNAL, STATUS_CODES, UnitResult, _chord_angle, _end_tangent_angle,
    _first_peak, _refine_peak, _self_standing, _simulate, _solve_zero_force, _state_stability,
    _zero_crossings, simulate_unit,
)

__all__ = ["UnitGeometry", "UnitResult", "simulate_unit", "STATUS_CODES", "DEFAULT_NODES"]
