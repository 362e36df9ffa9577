"""The arch molds as STL solids, ready to 3D print, beside their DXF profiles.

A mold is the closed profile of `drawings.mold_profile` (the arch's lower face, the centreline
offset by t/2, over a block) extruded across the strip: `width` mm (default w + 2 mm, so that
the strip lies fully on it). The solid is built as a watertight triangle mesh: the profile's
top is a function of x, so each cap is a strip of trapezoids between the top and the bottom
edge, and the sides close it. trimesh checks it (watertight, consistent winding, volume > 0)
and writes binary STL in mm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from snapmorph.design.units import Unit


def mold_mesh(u: Unit, width_mm: float | None = None, block_mm: float = 5.0):
    """The mold of unit u as a `trimesh.Trimesh` in mm: x along the unit, y across (0 to
    width), z up (the flat ends' lower face at z = -t/2, the block's bottom at -t/2 - block)."""
    import trimesh

    from snapmorph.design.drawings import arch_profile

    if u.is_spacer:
        raise ValueError("a spacer has no arch, so no mold")
    width = (u.w * 1e3 + 2.0) if width_mm is None else float(width_mm)
    if not width > 0:
        raise ValueError(f"mold width must be > 0 mm, got {width_mm}")
    top = _lower_face(arch_profile(u), u.t) * 1e3
    if np.any(np.diff(top[:, 0]) <= 0):
        raise ValueError(f"the mold's top is not a function of x (t = {u.t * 1e3:g} mm is "
                         "large against the arch's curvature)")
    bottom = -0.5 * u.t * 1e3 - block_mm
    n = len(top)
    # vertices: top front, bottom front, top back, bottom back (each n, x increasing)
    x, z = top[:, 0], top[:, 1]
    v = np.concatenate([np.column_stack([x, np.zeros(n), z]),
                        np.column_stack([x, np.zeros(n), np.full(n, bottom)]),
                        np.column_stack([x, np.full(n, width), z]),
                        np.column_stack([x, np.full(n, width), np.full(n, bottom)])])
    tf, bf, tb, bb = (np.arange(n) + k * n for k in range(4))
    i, j = np.arange(n - 1), np.arange(1, n)
    quads = [np.column_stack([bf[i], bf[j], tf[j], tf[i]]),   # front cap (y = 0), normal -y
             np.column_stack([bb[i], tb[i], tb[j], bb[j]]),   # back cap (y = width)
             np.column_stack([tf[i], tf[j], tb[j], tb[i]]),   # the top the strip lies on
             np.column_stack([bf[i], bb[i], bb[j], bf[j]]),   # the bottom
             np.array([[bf[0], tf[0], tb[0], bb[0]],          # the two ends
                       [bf[-1], bb[-1], tb[-1], tf[-1]]])]
    q = np.vstack(quads)
    faces = np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    mesh = trimesh.Trimesh(vertices=v, faces=faces, process=True)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _lower_face(centre: np.ndarray, t: float) -> np.ndarray:
    """The arch's lower face: the centreline (m) offset by t/2 to the side of its normal's
    -z, ends kept at x = 0 and L (as `drawings.mold_profile` does)."""
    d = np.gradient(centre, axis=0)
    nrm = np.stack([-d[:, 1], d[:, 0]], axis=-1)
    nrm /= np.hypot(*nrm.T)[:, None]
    low = centre - 0.5 * t * nrm
    low[0, 0], low[-1, 0] = centre[0, 0], centre[-1, 0]
    keep = np.concatenate([[True], np.diff(low[:, 0]) > 1e-12])
    return low[keep]


def write_stl_molds(units, out_dir, width_mm: float | None = None, block_mm: float = 5.0,
                    check: bool = True) -> list:
    """mold-<i>.stl (binary, mm) for every arched unit i (numbered from 1 as in units.csv);
    each checked watertight with a positive volume unless check is False. Returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, u in enumerate(units, start=1):
        if u.is_spacer:
            continue
        mesh = mold_mesh(u, width_mm, block_mm)
        if check and not (mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0):
            raise ValueError(f"mold {i}: the mesh is not a closed solid (watertight "
                             f"{mesh.is_watertight}, volume {mesh.volume:.1f} mm³)")
        path = out / f"mold-{i}.stl"
        mesh.export(path, file_type="stl")
        paths.append(path)
    return paths
