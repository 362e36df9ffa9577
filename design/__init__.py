"""Forward kinematics, inverse design and fabrication drawings of arrays of bistable units.

    from design import Unit, forward_kinematics, inverse_design
    u = Unit(L=0.1, h=0.02, t=0.5e-3, w=5e-3, side=+1)          # SI units
    xy = forward_kinematics([u, u, u], snapped=[False, True, False])
    d = inverse_design(points_xy, t=0.5e-3, w=5e-3)   # d.units, d.predicted, d.max_deviation

Unit shapes come from the design maps (`maps.DesignMap`) unless `source="simulate"`.
"""

from design.biarcs import Arc, biarc, biarcs
from design.inverse import Design, inverse_design
from design.kinematics import all_states, chain, forward_kinematics, parse_state
from design.lookup import MapLookup
from design.units import Unit, read_units_csv, spacer, write_units_csv

__all__ = [
    "Arc",
    "Design",
    "MapLookup",
    "Unit",
    "all_states",
    "biarc",
    "biarcs",
    "chain",
    "forward_kinematics",
    "inverse_design",
    "parse_state",
    "read_units_csv",
    "spacer",
    "write_units_csv",
]
