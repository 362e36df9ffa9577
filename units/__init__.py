"""Unit models built on the generic rod solver: the planar unit, the 3-D unit with its frame
base, and the paper's 2-D unit (two crossing arches on a square frame).

`solver/` keeps the generic rod mechanics and path followers; the models of particular units
live here and are re-exported where their public names lived before (`solver.unit`,
`solver.unit_model`).
"""
