"""Forward kinematics, inverse design and fabrication drawings of arrays of bistable units.

    from snapmorph.design import Unit, forward_kinematics, inverse_design
    u = Unit(L=0.1, h=0.02, t=0.5e-3, w=5e-3, side=+1)          # SI units
    xy = forward_kinematics([u, u, u], snapped=[False, True, False])
    d = inverse_design(points_xy, t=0.5e-3, w=5e-3, tol=0.01, verify=True)   # any planar curve
    d.units, d.predicted, d.deviations, d.placement, d.met, d.verification
    md = inverse_design_multi([C_xy, S_xy], t=0.5e-3, w=5e-3, tol=0.02)   # one array, two shapes
    md.patterns, md.met; nearest_state(md.units, new_xy).state; md.morph_plan(0, 1)

Unit shapes come from the design maps (`maps.DesignMap`) unless `source="simulate"`.
"""

import sys
import types

if __name__ != "snapmorph.design":  # imported under its pre-0.2 top-level name `design`
    from _snapmorph_legacy import alias_old_name  # warns, then hands out snapmorph.design

    alias_old_name(__name__)

from snapmorph.design.biarcs import Arc, biarc, biarcs
from snapmorph.design.inverse import inverse_design
from snapmorph.design.inverse_result import Design
from snapmorph.design.verification import verify_design
from snapmorph.design.kinematics import (all_snap_patterns, all_states, chain, forward_kinematics,
                                         parse_snapped, parse_state)
from snapmorph.design.lookup import MapLookup
from snapmorph.design.multishape import MultiDesign, inverse_design_multi, verify_multi
from snapmorph.design.nearest import NearestState, nearest_state
from snapmorph.design.reconfigure import MorphPlan, morph_plan
from snapmorph.design.target_io import read_target
from snapmorph.design.targets import Target
from snapmorph.design.units import Unit, read_units_csv, spacer, write_units_csv
from snapmorph.design.fabrication_tolerance import tolerance  # design.tolerance(units, ...)


class _Package(types.ModuleType):
    """`snapmorph.design.tolerance` is the function. The 0.1 module path ``design.tolerance``
    (now `design.fabrication_tolerance`, aliased by _snapmorph_legacy) would otherwise replace
    it: importing a submodule binds it on its package, and ``design`` is this package."""

    def __setattr__(self, name, value):
        if name == "tolerance" and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package

__all__ = [
    "Arc",
    "Design",
    "MapLookup",
    "MorphPlan",
    "MultiDesign",
    "NearestState",
    "Target",
    "Unit",
    "all_snap_patterns",
    "all_states",
    "biarc",
    "biarcs",
    "chain",
    "forward_kinematics",
    "inverse_design",
    "parse_snapped",
    "inverse_design_multi",
    "morph_plan",
    "nearest_state",
    "parse_state",
    "read_target",
    "read_units_csv",
    "spacer",
    "tolerance",
    "verify_design",
    "verify_multi",
    "write_units_csv",
]
