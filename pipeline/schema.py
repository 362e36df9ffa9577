"""Deprecated (snapmorph 0.2): the map schema is `snapmorph.maps.schema`, the status codes are
`snapmorph.units.status`. This alias stays for one release."""

import warnings

from snapmorph.maps.schema import (  # noqa: F401
    BASE_SHAPE_ATTRS, BISTABLE_ONLY, COMPARED_VARS, COORD_ATTRS, DEFAULT_SAMPLES, FLAG_VARS,
    FLOAT_VARS, GRID_DIMS, MODEL_ATTRS, NORMALISATION, OPTIONAL_VARS, READABLE_VERSIONS,
    RELEASED_VARS, REQUIRED_ATTRS, REQUIRED_VARS, REQUIRED_VARS_V1, SCHEMA_VERSION, SHAPE_ATTRS,
    SHAPE_VARS, SOLVE_TIME_ATTRS, STATES, status_attrs,
)
from snapmorph.units.status import (  # noqa: F401
    FAILED, INVALID_GEOMETRY, MONOSTABLE, NOT_BISTABLE, NOT_CONVERGED, OK, PENDING,
    SECOND_STATE_UNSTABLE, TIMEOUT,
)
from snapmorph.units.status import NAME as _NAME

warnings.warn("snapmorph.pipeline.schema is deprecated (snapmorph 0.2): import the map schema "
              "from snapmorph.maps.schema and the status codes from snapmorph.units.status",
              DeprecationWarning, stacklevel=2)

#: code -> name of every status (the table of `snapmorph.units.status`)
STATUS_CODES = dict(sorted(_NAME.items()))
STATUS_ATTRS = status_attrs(STATUS_CODES)
