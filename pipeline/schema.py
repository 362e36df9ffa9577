"""Design-map schema, version 2: names, dtypes, units and meanings (see docs/design-map-schema.md).

Version 2 adds the released state (iii) (actuator and rollers removed: the unit as used in an
array), theta_end (the angle between one end tangent and the chord), the status codes
"timeout" and "second_state_unstable", and the model options as global attributes.

One place that both the writer (`pipeline.dataset`) and the reader (`maps.DesignMap`) use, so
that the two cannot drift apart. Import cost: numpy only.
"""

from __future__ import annotations

import numpy as np

SCHEMA_VERSION = 2
#: schema versions `maps.DesignMap` can read (version 1 has no released state: it loads with
#: a warning and only `state="actuated"` lookups work)
READABLE_VERSIONS = (1, 2)
DEFAULT_SAMPLES = 65  # M, base-shape samples uniform in arc length

#: dimensions of every scalar variable, in storage order
GRID_DIMS = ("h_over_L", "t_over_L", "w_over_L")

#: float variables on the grid: name -> (units, long_name)
FLOAT_VARS = {
    "F_cr": ("1", "critical (maximum) force before snap through, F_cr L^2 / (E I_arch)"),
    "d_cr": ("1", "apex displacement at F_cr, d_cr / L"),
    "d_unstable": ("1", "apex displacement at the unstable equilibrium (ii), d / L"),
    "d_second": ("1", "apex displacement at the second stable state (iii), d / L"),
    "S": ("1", "horizontal distance of the base end points in the actuated state (iii) "
               "(actuator still glued, rollers on), S / L"),
    "theta": ("degree", "total turning angle: signed angle between the two end tangents of the base "
                        "in the actuated state (iii)"),
    "theta_end": ("degree", "end angle: signed angle between the base's start tangent and its chord "
                            "in the actuated state (iii), theta / 2 for a symmetric base"),
    "energy_barrier": ("1", "energy barrier, integral of F dd from 0 to d_unstable, U L / (E I_arch)"),
    "energy_stored": ("1", "stored energy, integral of F dd from 0 to d_second, U L / (E I_arch)"),
    "S_released": ("1", "chord (distance of the base end points) in the released state (iii) "
                        "(actuator and rollers removed: the unit as used in an array), S / L"),
    "theta_released": ("degree", "total turning angle: signed angle between the two end tangents "
                                 "of the base in the released state (iii)"),
    "theta_end_released": ("degree", "end angle: signed angle between the base's start tangent and "
                                     "its chord in the released state (iii), theta_released / 2 "
                                     "for a symmetric base"),
}

#: int8 flag variables on the grid: name -> (units, long_name); -1 means unknown
FLAG_VARS = {
    "bistable": ("1", "1 when the second stable state (iii) was found, else 0"),
    "self_standing": ("1", "1 when state (iii) stays stable with the actuator and rollers removed "
                           "(the released unit is still bistable), 0 when not, -1 unknown"),
    "bifurcation": ("1", "1 when the followed path met a bifurcation before snap through, 0 not, -1 unknown"),
}

#: variables that exist only at bistable points (status ok); F_cr and d_cr may exist at monostable ones
BISTABLE_ONLY = ("d_unstable", "d_second", "S", "theta", "theta_end", "energy_barrier",
                 "energy_stored")
#: variables of the released state: exist only at ok points with self_standing = 1
RELEASED_VARS = ("S_released", "theta_released", "theta_end_released")
#: variables added in schema 2: a point solver may leave them out (they are then NaN)
OPTIONAL_VARS = ("theta_end", *RELEASED_VARS)
#: base-shape variables (dims grid + (sample, xz)) and the state each describes
SHAPE_VARS = ("base_shape", "base_shape_released")
#: lookup states -> (S, theta, theta_end, base shape) variable names
STATES = {
    "released": ("S_released", "theta_released", "theta_end_released", "base_shape_released"),
    "actuated": ("S", "theta", "theta_end", "base_shape"),
}

STATUS_CODES = {-1: "pending", 0: "ok", 1: "monostable", 2: "not_converged", 3: "invalid_geometry",
                4: "timeout", 5: "second_state_unstable"}
PENDING, OK, MONOSTABLE, NOT_CONVERGED, INVALID_GEOMETRY = -1, 0, 1, 2, 3
TIMEOUT, SECOND_STATE_UNSTABLE = 4, 5
#: codes of points that were solved and found not bistable (F_cr and d_cr exist)
NOT_BISTABLE = (MONOSTABLE, SECOND_STATE_UNSTABLE)
#: codes of points whose solve failed (no value exists)
FAILED = (NOT_CONVERGED, INVALID_GEOMETRY, TIMEOUT)

STATUS_ATTRS = {
    "units": "1",
    "long_name": "status of the simulation of the point",
    "flag_values": np.array(sorted(STATUS_CODES), dtype=np.int8),
    "flag_meanings": " ".join(STATUS_CODES[k] for k in sorted(STATUS_CODES)),
}

BASE_SHAPE_ATTRS = {
    "units": "1",
    "long_name": "base centreline in the actuated state (iii) / L, uniform in arc length, starting "
    "at (0, 0) with the start tangent along +x, arch on the +z side",
}

SHAPE_ATTRS = {
    "base_shape": BASE_SHAPE_ATTRS,
    "base_shape_released": {
        "units": "1",
        "long_name": "base centreline in the released state (iii) (actuator and rollers removed) / L, "
        "uniform in arc length, starting at (0, 0) with the start tangent along +x, arch on the +z "
        "side",
    },
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

#: every data variable a schema-2 map must hold
REQUIRED_VARS = (*FLOAT_VARS, *FLAG_VARS, "status", *SHAPE_VARS, "solve_time")
#: the variables of schema 1 (a map of that version holds these)
REQUIRED_VARS_V1 = tuple(v for v in REQUIRED_VARS
                         if v not in (*OPTIONAL_VARS, "base_shape_released"))

#: global attributes a schema-1 or -2 map must hold
REQUIRED_ATTRS = (
    "schema_version", "b_over_L", "resolution", "package_version", "git_commit", "created",
    "normalisation", "E_reference", "title",
)
#: model options recorded as global attributes of a schema-2 map (lengths / L)
MODEL_ATTRS = ("joint_length_over_L", "bond_length_over_L")

#: variables compared by `maps check` and the resume test (solve_time is a wall-clock measurement)
COMPARED_VARS = (*FLOAT_VARS, *FLAG_VARS, "status", *SHAPE_VARS)
