"""The pre-0.2 top-level import names, kept for one release as aliases that warn.

Outside the library packages on purpose: it imports none of them until an old name is used.

snapmorph 0.1 installed its packages as top-level ``solver``, ``units``, ``pipeline``, ``maps``
and ``design``, names that collide with other distributions on the package index. They are
now ``snapmorph.solver``, ``snapmorph.units``, ...; importing an old name warns with a
`DeprecationWarning` and hands out the very same module objects (``solver.Structure is
snapmorph.solver.Structure``), submodules included. ``solver.unit`` and
``solver.unit_model`` were shims already: they are the planar unit's modules.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

#: old top-level package -> its module now
OLD_PACKAGES = {name: f"snapmorph.{name}" for name in ("solver", "units", "pipeline", "maps", "design")}

#: old modules that moved elsewhere than snapmorph.<old name>
MOVED = {"solver.unit": "snapmorph.units.planar", "solver.unit_model": "snapmorph.units.geometry",
         "design.tolerance": "snapmorph.design.fabrication_tolerance",
         # research scripts, no longer installed: from a checkout only (studies/)
         "units.studies3d": "studies.studies3d", "units.diagnostics3d": "studies.diagnostics3d"}


def new_name(old: str) -> str | None:
    """The module an old import name stands for now (None: not an old name)."""
    if old in MOVED:
        return MOVED[old]
    top = old.partition(".")[0]
    return f"snapmorph.{old}" if top in OLD_PACKAGES else None


def alias_old_name(name: str) -> None:
    """Called first thing by each package's ``__init__`` with its ``__name__``. Imported as
    snapmorph.<name>: nothing to do. Imported under its old top-level name (a checkout's folder
    found on ``sys.path``, or the installed alias package): warn, and make that name and every
    submodule under it the snapmorph modules."""
    if name not in OLD_PACKAGES:
        return
    _warn(name)
    _install_finder()
    sys.modules[name] = importlib.import_module(OLD_PACKAGES[name])


def _warn(old, stacklevel=4):
    # stacklevel: past the callers in this file and the package __init__ (the import
    # machinery's own frames are skipped), to the module that wrote the import
    warnings.warn(f"'{old}' is a deprecated import name (snapmorph 0.1); import "
                  f"'{new_name(old)}' instead", DeprecationWarning, stacklevel=stacklevel)


class _AliasLoader(importlib.abc.Loader):
    """Loads an old submodule name as the module it stands for now (the same object)."""

    def __init__(self, target):
        self.target = target

    def create_module(self, spec):
        module = importlib.import_module(self.target)
        self._own_spec = module.__spec__
        return module

    def exec_module(self, module):
        # the import machinery has set the alias's spec on the module: give it back its own
        # (find_spec of the new name, and the map fingerprints, read it)
        module.__spec__ = self._own_spec


class _AliasFinder(importlib.abc.MetaPathFinder):
    """``solver.structure`` -> ``snapmorph.solver.structure``: placed before the path finders,
    so that an old name never loads a second copy of a module."""

    def find_spec(self, fullname, path=None, target=None):
        if "." not in fullname:
            return None  # the top-level names are the packages' own (alias_old_name)
        new = new_name(fullname)
        if new is None:
            return None
        if fullname in MOVED:
            _warn(fullname, stacklevel=3)
        return importlib.util.spec_from_loader(fullname, _AliasLoader(new))


_FINDER = _AliasFinder()


def _install_finder():
    if _FINDER not in sys.meta_path:
        sys.meta_path.insert(0, _FINDER)
