"""Deprecated (snapmorph 0.2): the planar unit's point solver is `snapmorph.pipeline.kinds.unit`
(`solve_point` also from `snapmorph.pipeline`). This alias stays for one release."""

import warnings

from snapmorph.pipeline.kinds.unit import (  # noqa: F401
    BOND_LENGTH, E_REF, JOINT_LENGTH_OVER_L, L_REF, default_resolution, empty_record,
    finalise_record, model_options, normalise_result, resample_shape, solve_point, unit_model,
    warm_up,
)

warnings.warn("snapmorph.pipeline.point is deprecated (snapmorph 0.2): import from "
              "snapmorph.pipeline.kinds.unit", DeprecationWarning, stacklevel=2)
