"""The design-map schema, version 3: what a map file of the planar unit holds (names, dimensions,
units, meanings), the normalisation, and the two states (iii). See docs/design-map-schema.md.

The writer (`snapmorph.pipeline`) builds files from these names and the reader
(`maps.DesignMap`) checks files against them, so the two cannot drift apart. The status codes
are not here: a file carries them in its ``status`` variable as CF ``flag_values`` /
``flag_meanings`` (`status_attrs`, `status_names`), and the schema knows only the names of the
statuses that matter to a reader. Import cost: numpy only.

Version 2 adds the released state (iii) (actuator and rollers removed: the unit as used in an
array), theta_end (the angle between one end tangent and the chord), the statuses "timeout"
and "second_state_unstable", and the model options as global attributes.

Version 3 adds b/L (the extra flat length of the arch ends) as a fourth grid axis and the unit
metrics of the snap path and of the released state (`METRIC_VARS`, `TEXT_VARS`). A map built at
one fixed b/L keeps the three-axis layout, b/L a global attribute as in version 2.
"""

from __future__ import annotations

import numpy as np

SCHEMA_VERSION = 3
#: schema versions `maps.DesignMap` can read (version 1 has no released state: it loads with
#: a warning and only `state="actuated"` lookups work)
READABLE_VERSIONS = (1, 2, 3)
DEFAULT_SAMPLES = 65  # M, base-shape samples uniform in arc length

#: dimensions of every scalar variable of a version-1 or -2 map (b/L fixed), in storage order
GRID_DIMS = ("h_over_L", "t_over_L", "w_over_L")
#: the grid dimensions of a version-3 map: b/L the fourth axis
B_DIM = "b_over_L"
GRID_DIMS_B = (*GRID_DIMS, B_DIM)
#: the extra dimensions of a base shape: (sample, xz)
SHAPE_DIMS = ("sample", "xz")
XZ = ("x", "z")

_ACTUATED = "in the actuated state (iii)"
_RELEASED = "in the released state (iii)"


def _state_vars(suffix: str, state: str, chord: str) -> dict:
    """S, theta and theta_end of one state (iii) (names with `suffix`): name -> (units,
    long_name); `chord` says what S is there."""
    theta = "theta" + suffix
    return {
        "S" + suffix: ("1", chord.format(state)),
        theta: ("degree", f"total turning angle: signed angle between the two end tangents of "
                          f"the base {state}"),
        "theta_end" + suffix: ("degree", f"end angle: signed angle between the base's start "
                                         f"tangent and its chord {state}, {theta} / 2 for a "
                                         f"symmetric base"),
    }


#: float variables of a schema-2 map: name -> (units, long_name)
FLOAT_VARS_V2 = {
    "F_cr": ("1", "critical (maximum) force before snap through, F_cr L^2 / (E I_arch)"),
    "d_cr": ("1", "apex displacement at F_cr, d_cr / L"),
    "d_unstable": ("1", "apex displacement at the unstable equilibrium (ii), d / L"),
    "d_second": ("1", "apex displacement at the second stable state (iii), d / L"),
    **_state_vars("", _ACTUATED, "horizontal distance of the base end points {} (actuator still "
                                 "glued, rollers on), S / L"),
    "energy_barrier": ("1", "energy barrier, integral of F dd from 0 to d_unstable, U L / (E I_arch)"),
    "energy_stored": ("1", "stored energy, integral of F dd from 0 to d_second, U L / (E I_arch)"),
    **_state_vars("_released", _RELEASED, "chord (distance of the base end points) {} (actuator "
                                          "and rollers removed: the unit as used in an array), S / L"),
}

#: the unit metrics (schema 3): name -> (units, long_name); forces normalised like F_cr,
#: lengths like d_cr, the stiffness as k L^3 / (E I_arch) (the force scale over the length
#: scale), strains as they are (dimensionless)
PATH_METRICS = {
    "F_min": ("1", "most negative force on the snap path, F_min L^2 / (E I_arch)"),
    "d_Fmin": ("1", "apex displacement at F_min, d / L"),
    "strain_max": ("1", "largest surface strain (bending kappa t / 2 plus axial) along the whole "
                        "snap path, dimensionless"),
}
RELEASED_METRICS = {
    "F_back": ("1", "snap-back load of the released unit: the apex force that returns state (iii) "
                    "to (i), F_back L^2 / (E I_arch)"),
    "stiffness_released": ("1", "tangent stiffness of the released state (iii) at the apex, "
                                "k L^3 / (E I_arch)"),
    "strain_max_released": ("1", "largest surface strain (bending kappa t / 2 plus axial) in the "
                                 "released state (iii), dimensionless"),
}
METRIC_VARS = {**PATH_METRICS, **RELEASED_METRICS}
#: float variables on the grid: name -> (units, long_name)
FLOAT_VARS = {**FLOAT_VARS_V2, **METRIC_VARS}
#: text variables on the grid (schema 3): name -> (units, long_name); "" where absent
TEXT_VARS = {
    "strain_where": ("1", "where strain_max sits on the unit (arch or base, which end), as the "
                          "unit result states it"),
}
#: how each metric is read from a unit result (SI) and normalised: map name -> (result field,
#: scale) with scale "force" (x L^2 / (E I_arch)), "length" (/ L), "stiffness"
#: (x L^3 / (E I_arch)), "1" (as it is) or "text"
METRIC_SOURCES = {
    "F_min": ("F_min", "force"), "d_Fmin": ("d_Fmin", "length"),
    "strain_max": ("strain_max", "1"), "F_back": ("F_back", "force"),
    "stiffness_released": ("stiffness_released", "stiffness"),
    "strain_max_released": ("strain_max_released", "1"), "strain_where": ("strain_where", "text"),
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
#: variables added in schema 2 and 3: a point solver may leave them out (they are then NaN)
OPTIONAL_VARS = ("theta_end", *RELEASED_VARS, *METRIC_VARS)
#: base-shape variables (dims grid + (sample, xz)) and the state each describes
SHAPE_VARS = ("base_shape", "base_shape_released")
#: lookup states -> (S, theta, theta_end, base shape) variable names
STATES = {
    "released": ("S_released", "theta_released", "theta_end_released", "base_shape_released"),
    "actuated": ("S", "theta", "theta_end", "base_shape"),
}

_SHAPE_FRAME = "/ L, uniform in arc length, starting at (0, 0) with the start tangent along +x, arch on the +z side"
#: base-shape variables: name -> (units, long_name)
SHAPE_ATTRS = {
    "base_shape": {"units": "1", "long_name": f"base centreline {_ACTUATED} {_SHAPE_FRAME}"},
    "base_shape_released": {"units": "1", "long_name": f"base centreline {_RELEASED} (actuator and "
                                                       f"rollers removed) {_SHAPE_FRAME}"},
}
BASE_SHAPE_ATTRS = SHAPE_ATTRS["base_shape"]

SOLVE_TIME_ATTRS = {"units": "s", "long_name": "wall time of the simulation of the point"}

COORD_ATTRS = {
    "h_over_L": {"units": "1", "long_name": "arch apex height over base length, h / L"},
    "t_over_L": {"units": "1", "long_name": "sheet thickness over base length, t / L"},
    "w_over_L": {"units": "1", "long_name": "strip width over base length, w / L"},
    "b_over_L": {"units": "1", "long_name": "extra flat length of the arch ends over base length, b / L"},
    "sample": {"units": "1", "long_name": "base-shape sample index, uniform in arc length"},
    "xz": {"units": "1", "long_name": "component of a base-shape point"},
}

NORMALISATION = (
    "I_arch = w t^3 / 12; F_norm = F L^2 / (E I_arch); energy_norm = U L / (E I_arch); "
    "lengths / L; theta in degrees"
)
#: the normalisation of a schema-3 map (adds the stiffness and the strains)
NORMALISATION_3 = (NORMALISATION + "; stiffness_norm = k L^3 / (E I_arch); strains dimensionless")

#: every data variable a schema-2 map must hold
REQUIRED_VARS = (*(v for v in FLOAT_VARS if v not in METRIC_VARS), *FLAG_VARS, "status",
                 *SHAPE_VARS, "solve_time")
#: every data variable a schema-3 map must hold
REQUIRED_VARS_V3 = (*REQUIRED_VARS, *METRIC_VARS, *TEXT_VARS)
#: the variables of schema 1 (a map of that version holds these)
REQUIRED_VARS_V1 = tuple(v for v in REQUIRED_VARS
                         if v not in (*OPTIONAL_VARS, "base_shape_released"))

#: global attributes a schema-1 or -2 map must hold
REQUIRED_ATTRS = (
    "schema_version", "b_over_L", "resolution", "package_version", "git_commit", "created",
    "normalisation", "E_reference", "title",
)
#: global attributes a schema-3 map with a b/L axis must hold (one without holds REQUIRED_ATTRS)
REQUIRED_ATTRS_V3 = tuple(a for a in REQUIRED_ATTRS if a != "b_over_L")
#: model options recorded as global attributes of a schema-2 map (lengths / L)
MODEL_ATTRS = ("joint_length_over_L", "bond_length_over_L")

#: variables compared by `maps check` and the resume test (solve_time is a wall-clock measurement)
COMPARED_VARS = (*FLOAT_VARS, *FLAG_VARS, "status", *SHAPE_VARS)
#: the same of a schema-3 map (and of a fixed-b map with the unit metrics)
COMPARED_VARS_V3 = (*COMPARED_VARS, *TEXT_VARS)

# -- the status variable ---------------------------------------------------------------------
#: what a reader needs to know of the statuses a file names: the status of a finished,
#: bistable point; of the points where the force peak (F_cr, d_cr) exists; of a point not
#: computed yet (a partial build)
OK_STATUS = "ok"
FORCE_STATUSES = ("ok", "monostable", "second_state_unstable")
PENDING_STATUS = "pending"
STATUS_LONG_NAME = "status of the simulation of the point"


def status_attrs(names: dict) -> dict:
    """The attributes of a map's int8 ``status`` variable for the statuses ``names``
    ({code: name}): CF ``flag_values`` (sorted codes) and ``flag_meanings``."""
    codes = sorted(names)
    return {"units": "1", "long_name": STATUS_LONG_NAME,
            "flag_values": np.array(codes, dtype=np.int8),
            "flag_meanings": " ".join(names[c] for c in codes)}


def status_names(attrs) -> dict:
    """{code: name} of the statuses a ``status`` variable's attributes declare (CF
    ``flag_values`` / ``flag_meanings``); ValueError when they are missing or do not match."""
    values, meanings = attrs.get("flag_values"), attrs.get("flag_meanings")
    if values is None or meanings is None:
        raise ValueError("status has no flag_values / flag_meanings attributes")
    codes = [int(v) for v in np.atleast_1d(np.asarray(values))]
    words = str(meanings).split()
    if len(codes) != len(words):
        raise ValueError(f"status has {len(codes)} flag_values but {len(words)} flag_meanings")
    return dict(zip(codes, words))
