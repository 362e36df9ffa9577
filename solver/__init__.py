"""Planar discrete-elastic-rods solver with MGDC path following (paper, Appendix A).

Kernels (`energies`), assembly (`assembly`), banded linear algebra (`banded`), the
constrained system (`system`), the model builder (`structure`) and the path followers
(`continuation`) live apart; `unit` builds the paper's bistable unit on top.
"""

if __name__ != "snapmorph.solver":  # imported under its pre-0.2 top-level name `solver`
    from _snapmorph_legacy import alias_old_name  # warns, then hands out snapmorph.solver

    alias_old_name(__name__)

from snapmorph.solver.kernel_cache import discard_stale_kernels

discard_stale_kernels()  # before any cached kernel is loaded (see solver.kernel_cache)

from snapmorph.solver.continuation import ConvergenceError, Path  # noqa: E402
from snapmorph.solver.structure import Rod, Structure  # noqa: E402
from snapmorph.solver.structure3d import Rod3D, Structure3D  # noqa: E402

__all__ = ["Structure", "Rod", "Path", "ConvergenceError", "Structure3D", "Rod3D"]
