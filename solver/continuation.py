"""Deprecated module name (snapmorph 0.1): the path followers live in their own modules now.

`solver.mgdc.follow_mgdc`, `solver.displacement.follow_displacement`,
`solver.equilibrium.equilibrium`, `solver.path.Path` and, in `solver.problem`, `Control`,
`make_control`, `state_from` and `ConvergenceError`. Importing this module warns; it hands
out those same objects for one release.
"""

from __future__ import annotations

import warnings

from snapmorph.solver.displacement import WORK_TOL, follow_displacement
from snapmorph.solver.equilibrium import equilibrium
from snapmorph.solver.mgdc import WANDER, follow_mgdc
from snapmorph.solver.newton import SETTLE_FACTOR, TOL_DISP
from snapmorph.solver.path import Path
from snapmorph.solver.problem import MAX_DISTANCE, Control, ConvergenceError, make_control, state_from
from snapmorph.solver.steps import CROSSING_REFINE

warnings.warn("snapmorph.solver.continuation is deprecated: import the path followers from "
              "snapmorph.solver.mgdc, .displacement, .equilibrium, .path and .problem",
              DeprecationWarning, stacklevel=2)

__all__ = ["follow_mgdc", "follow_displacement", "equilibrium", "Path", "Control",
           "make_control", "state_from", "ConvergenceError", "TOL_DISP", "SETTLE_FACTOR",
           "CROSSING_REFINE", "WANDER", "WORK_TOL", "MAX_DISTANCE"]
