"""Deprecated (snapmorph 0.2): the planar unit's grid is `snapmorph.pipeline.kinds.unit`
(`Grid`, `PRESETS`, `preset` also from `snapmorph.pipeline`). This alias stays for one
release."""

import warnings

from snapmorph.pipeline.kinds.unit import (  # noqa: F401
    DEFAULT_MAP_RESOLUTION, MIN_RESOLUTION, PRESET_RESOLUTION, PRESETS, Grid, preset,
)

warnings.warn("snapmorph.pipeline.grid is deprecated (snapmorph 0.2): import Grid, PRESETS and "
              "preset from snapmorph.pipeline", DeprecationWarning, stacklevel=2)
