"""Planar discrete-elastic-rods solver with MGDC path following (paper, Appendix A).

Kernels (`energies`), assembly (`assembly`), banded linear algebra (`banded`), the
constrained system (`system`), the model builder (`structure`) and the path followers
(`continuation`) live apart; `unit` builds the paper's bistable unit on top.
"""

from solver.continuation import ConvergenceError, Path
from solver.structure import Rod, Structure
from solver.structure3d import Rod3D, Structure3D

__all__ = ["Structure", "Rod", "Path", "ConvergenceError", "Structure3D", "Rod3D"]
