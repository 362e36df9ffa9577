"""Discrete-elastic-rods solver with MGDC path following (paper, Appendix A): planar and 3-D.

Layers, each importing only those below it:

- kernels: `energies` / `energies3d` (+ `frames3d`), assembled by `assembly` / `assembly3d`;
  banded LDL^T with its inertia count (`banded`, orderings in `ordering`); fused compiled
  iterations (`iteration`);
- systems (`system`): a constrained, assembled problem in reduced DOFs (`ReducedSystem`
  planar, `RodSystem3D` 3-D, one `BandedSystem` base);
- structures: `Structure` (`structure`) and `Structure3D` (`structure3d`) on one
  bookkeeping base (`constraints`: supports, ties, rigid groups, supernodes, node checks);
- the problem layer (`problem`): the problem interface as protocols (`PushProblem`,
  `System`), the push `Control`, states, load vector and load unit, `ConvergenceError`;
  the one Newton (`newton`), energy descent (`descent`) and root finder (`roots`);
- drivers: Newton equilibrium (`equilibrium`), displacement control (`displacement`) and
  MGDC (`mgdc`), sharing path recording (`path`) and step control (`steps`); critical
  points and branch switching (`branching`), stability (`stability`), single states at a
  prescribed displacement (`states`); dead loads followed by a load factor (`loading`).

Dead loads and self-weight (`Structure.add_load`, `add_gravity`) are energy terms of every
system (docs/loads.md); materials with datasheet presets are in `materials`.

The paper's bistable unit is built on top, in `snapmorph.units`.
"""

if __name__ != "snapmorph.solver":  # imported under its pre-0.2 top-level name `solver`
    from _snapmorph_legacy import alias_old_name  # warns, then hands out snapmorph.solver

    alias_old_name(__name__)

from snapmorph.solver.kernel_cache import discard_stale_kernels

discard_stale_kernels()  # before any cached kernel is loaded (see solver.kernel_cache)

from snapmorph.solver.materials import Material  # noqa: E402
from snapmorph.solver.path import Path  # noqa: E402
from snapmorph.solver.problem import ConvergenceError  # noqa: E402
from snapmorph.solver.structure import Rod, Structure  # noqa: E402
from snapmorph.solver.structure3d import Rod3D, Structure3D  # noqa: E402

__all__ = ["Structure", "Rod", "Path", "ConvergenceError", "Structure3D", "Rod3D", "Material"]
