"""snapmorph: design of shape-retaining morphing structures from bistable arch-on-base units."""

__version__ = "0.1.0"
