"""Shared validation cases of the solver: structures with known answers and their closed forms.

Not installed with snapmorph: the tests (``tests/solver``) and the benchmarks (``bench/``) of a
checkout import these, so that a benchmark never imports a test module.

- `validation.cantilever`: the elastica cantilever pushed at its tip (exact large deflection);
- `validation.column`: the clamped–clamped column under end shortening (Euler, elastica);
- `validation.arch`: the clamped cosine arch pushed at its midpoint (Qiu, Lang & Slocum), as
  the project's reference model and as a user builds it, with its set-ups;
- `validation.strip3d`: 3-D strips (cantilevers, lateral–torsional buckling).
"""
