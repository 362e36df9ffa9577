"""Deprecated module (snapmorph 0.1): the reference structures with known answers are shared
validation cases now, outside the installed package, in the repository's ``validation/``
folder (`validation.arch.clamped_arch`, imported by the tests and the benchmarks).

Importing this module warns; in a checkout of the repository (its root on ``sys.path``) it
hands out `validation.arch.clamped_arch` for one release.
"""

from __future__ import annotations

import warnings

warnings.warn("snapmorph.solver.reference_models is deprecated: the reference structures are "
              "the repository's validation cases (validation.arch.clamped_arch)",
              DeprecationWarning, stacklevel=2)

try:
    from validation.arch import clamped_arch  # noqa: E402, F401
except ImportError as exc:  # an installed snapmorph without the repository
    raise ImportError("the reference structures moved to the repository's validation/ "
                      "folder (validation.arch.clamped_arch); run from a checkout") from exc
