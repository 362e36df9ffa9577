"""Deprecated import name: `pipeline` is `snapmorph.pipeline` (see _snapmorph_legacy)."""

from _snapmorph_legacy import alias_old_name

alias_old_name(__name__)
