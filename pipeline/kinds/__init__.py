"""The built-in kinds of map, plug-ins like any other: each module holds a `SolverSpec` named
`SPEC` (its point solver, schema section, grids and hooks), found by `pipeline.solvers.get_spec`
through `pipeline.solvers.KNOWN`.

- `unit`: the planar arch-on-base unit over (h/L, t/L, w/L), the map of docs/design-map-schema.md;
- `unit2d`: the 2-D unit (square frame, two crossing arches) over (h/L, t/L); in the same
  module `unit2d_triangle` (`TRIANGLE`) and `unit2d_hexagon` (`HEXAGON`), the 2-D unit on a
  triangle and on a hexagon.
"""
