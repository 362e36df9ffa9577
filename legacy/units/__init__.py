"""Deprecated import name: `units` is `snapmorph.units` (see _snapmorph_legacy)."""

from _snapmorph_legacy import alias_old_name

alias_old_name(__name__)
