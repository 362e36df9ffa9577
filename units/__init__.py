"""Unit models built on the generic rod solver: the planar unit, the 3-D unit with its frame
base, and the paper's 2-D unit (two crossing arches on a square frame).

`solver/` keeps the generic rod mechanics and path followers; the models of particular units
live here and are re-exported where their public names lived before (`solver.unit`,
`solver.unit_model`). The planar unit: `units.geometry` (`UnitGeometry`, meshing) and
`units.planar` (`simulate_unit`, `UnitResult`), also importable from `units` itself.
"""

if __name__ != "snapmorph.units":  # imported under its pre-0.2 top-level name `units`
    from _snapmorph_legacy import alias_old_name  # warns, then hands out snapmorph.units

    alias_old_name(__name__)

_LAZY = {"UnitGeometry": "snapmorph.units.geometry", "build_unit": "snapmorph.units.geometry",
         "simulate_unit": "snapmorph.units.planar", "UnitResult": "snapmorph.units.planar"}


def __getattr__(name):  # lazy, so that importing units.<model> stays light
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'units' has no attribute {name!r}")
