"""Forward kinematics, inverse design and fabrication drawings of arrays of bistable units.

    from snapmorph.design import Unit, forward_kinematics, inverse_design
    u = Unit(L=0.1, h=0.02, t=0.5e-3, w=5e-3, side=+1)          # SI units
    xy = forward_kinematics([u, u, u], snapped=[False, True, False])
    d = inverse_design(points_xy, t=0.5e-3, w=5e-3, tol=0.01, verify=True)   # any planar curve
    d.units, d.predicted, d.deviations, d.placement, d.met, d.verification
    md = inverse_design_multi([C_xy, S_xy], t=0.5e-3, w=5e-3, tol=0.02)   # one array, two shapes
    md.patterns, md.met; nearest_state(md.units, new_xy).state; md.morph_plan(0, 1)
    tf = read_target_file("hook.svg", select="curveA")   # the curve as drawn, its notes, frame
    d = inverse_design(tf, t=0.5e-3, w=5e-3, tol_abs=1e-3, verify=True)
    d.write("out/", bed="600x400", kerf_mm=0.15)   # overlay in the drawing's frame, workshop

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
from snapmorph.design.target_io import TargetFile, read_target, read_target_file
from snapmorph.design.targets_frame import DrawingFrame, write_in_drawing_frame, write_target_csv
from snapmorph.design.targets_pieces import TargetError
from snapmorph.design.targets_scale import check_scale
from snapmorph.design.workshop import Workshop, write_workshop
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
    "DrawingFrame",
    "MapLookup",
    "MorphPlan",
    "MultiDesign",
    "NearestState",
    "Target",
    "TargetError",
    "TargetFile",
    "Unit",
    "Workshop",
    "all_snap_patterns",
    "all_states",
    "biarc",
    "biarcs",
    "chain",
    "check_scale",
    "forward_kinematics",
    "inverse_design",
    "parse_snapped",
    "inverse_design_multi",
    "morph_plan",
    "nearest_state",
    "parse_state",
    "read_target",
    "read_target_file",
    "read_units_csv",
    "spacer",
    "tolerance",
    "verify_design",
    "verify_multi",
    "write_in_drawing_frame",
    "write_target_csv",
    "write_units_csv",
    "write_workshop",
]
