"""One target argument, as the multi-target functions take it, made into a `Target`.

`inverse_design_multi` and `nearest_state` accept each target in any of the forms
`inverse_design` accepts: (N, 2) points in m (a smooth curve through them), a file in mm
(CSV ``x, y[, tangent_deg]``, SVG, DXF; drawn curves taken as drawn, CSV points with tangents
as the biarcs through them), or a `design.Target`. This module only dispatches to the public
readers (`design.read_target`, `design.Target`, `design.biarcs`); it reads nothing itself.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from snapmorph.design.targets import Target


def as_target(obj, what: str = "target") -> Target:
    """`obj` as a `Target` (SI). ValueError naming `what` when it is none of the accepted
    forms: a Target, (N, 2) points in m, a .csv/.svg/.dxf file in mm or a
    `target_io.TargetFile` (read with `read_target_file`, e.g. with a `select`)."""
    from snapmorph.design.target_io import TargetFile, read_target_file

    if isinstance(obj, Target):
        return obj
    if isinstance(obj, TargetFile):
        return obj.target(what=what)
    if isinstance(obj, (str, bytes)) or hasattr(obj, "__fspath__"):
        path = Path(obj.decode() if isinstance(obj, bytes) else obj)
        if not path.is_file():
            raise ValueError(f"{what}: target file not found: {path}")
        return read_target_file(path).target(what=f"{what} ({path.name})")
    try:
        arr = np.asarray(obj, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be (N, 2) points in m, a .csv/.svg/.dxf file (mm) or a "
                         f"design.Target; got {type(obj).__name__}") from None
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"{what} must be (N, 2) points in m, a .csv/.svg/.dxf file (mm) or a "
                         f"design.Target; got an array of shape {arr.shape}")
    return Target.from_points(arr, what=what)
