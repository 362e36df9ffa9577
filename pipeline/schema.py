"""Design-map schema, version 1: names, dtypes, units and meanings (see docs/design-map-schema.md).

One place that both the writer (`pipeline.dataset`) and the reader (`maps.DesignMap`) use, so
that the two cannot drift apart. Import cost: numpy only.
"""

from __future__ import annotations

import numpy as np

SCHEMA_VERSION = 1
DEFAULT_SAMPLES = 65  # M, base-shape samples uniform in arc length

#: dimensions of every scalar variable, in storage order
GRID_DIMS = ("h_over_L", "t_over_L", "w_over_L")

#: float variables on the grid: name -> (units, long_name)
FLOAT_VARS = {
    "F_cr": ("1", "critical (maximum) force before snap through, F_cr L^2 / (E I_arch)"),
    "d_cr": ("1", "apex displacement at F_cr, d_cr / L"),
    "d_unstable": ("1", "apex displacement at the unstable equilibrium (ii), d / L"),
    "d_second": ("1", "apex displacement at the second stable state (iii), d / L"),
    "S": ("1", "horizontal distance of the base end points in state (iii), S / L"),
    "theta": ("degree", "signed angle between the base end tangents in state (iii)"),
    "energy_barrier": ("1", "energy barrier, integral of F dd from 0 to d_unstable, U L / (E I_arch)"),
    "energy_stored": ("1", "stored energy, integral of F dd from 0 to d_second, U L / (E I_arch)"),
}

#: int8 flag variables on the grid: name -> (units, long_name); -1 means unknown
FLAG_VARS = {
    "bistable": ("1", "1 when the second stable state (iii) was found, else 0"),
    "self_standing": ("1", "1 when state (iii) stays stable with the actuator removed, 0 when not, -1 unknown"),
    "bifurcation": ("1", "1 when the followed path met a bifurcation before snap through, 0 not, -1 unknown"),
}

#: variables that exist only at bistable points (status ok); F_cr and d_cr may exist at monostable ones
BISTABLE_ONLY = ("d_unstable", "d_second", "S", "theta", "energy_barrier", "energy_stored")

STATUS_CODES = {-1: "pending", 0: "ok", 1: "monostable", 2: "not_converged", 3: "invalid_geometry"}
PENDING, OK, MONOSTABLE, NOT_CONVERGED, INVALID_GEOMETRY = -1, 0, 1, 2, 3

STATUS_ATTRS = {
    "units": "1",
    "long_name": "status of the simulation of the point",
    "flag_values": np.array(sorted(STATUS_CODES), dtype=np.int8),
    "flag_meanings": " ".join(STATUS_CODES[k] for k in sorted(STATUS_CODES)),
}

BASE_SHAPE_ATTRS = {
    "units": "1",
    "long_name": "base centreline in state (iii) / L, uniform in arc length, starting at (0, 0) "
    "with the start tangent along +x, arch on the +z side",
}

SOLVE_TIME_ATTRS = {"units": "s", "long_name": "wall time of the simulation of the point"}

COORD_ATTRS = {
    "h_over_L": {"units": "1", "long_name": "arch apex height over base length, h / L"},
    "t_over_L": {"units": "1", "long_name": "sheet thickness over base length, t / L"},
    "w_over_L": {"units": "1", "long_name": "strip width over base length, w / L"},
    "sample": {"units": "1", "long_name": "base-shape sample index, uniform in arc length"},
    "xz": {"units": "1", "long_name": "component of a base-shape point"},
}

NORMALISATION = (
    "I_arch = w t^3 / 12; F_norm = F L^2 / (E I_arch); energy_norm = U L / (E I_arch); "
    "lengths / L; theta in degrees"
)

#: every data variable a schema-1 map must hold
REQUIRED_VARS = (*FLOAT_VARS, *FLAG_VARS, "status", "base_shape", "solve_time")

#: global attributes a schema-1 map must hold
REQUIRED_ATTRS = (
    "schema_version", "b_over_L", "resolution", "package_version", "git_commit", "created",
    "normalisation", "E_reference", "title",
)

#: variables compared by `maps check` and the resume test (solve_time is a wall-clock measurement)
COMPARED_VARS = (*FLOAT_VARS, *FLAG_VARS, "status", "base_shape")
