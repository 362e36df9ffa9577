"""Sheets tiled from 2-D units: the tilings and the mesh (no solver needed; `units.sheet`
simulates them).

A sheet is a tiling of regular polygons of side L (``tiling`` "square", "triangle" or
"hexagon") in ``rows x cols`` cells, every cell a 2-D unit of `units.polygon`: its sides
are strips of width w shared with the neighbouring cells (one rod per edge of the tiling,
rigidly bonded to the other edges at every vertex), and its arches rise from its sides'
midpoints to its apex. Cells are numbered row after row from the bottom left (row 0 at
y = 0): in a 3 x 3 square sheet cell 4 is the centre. Triangles alternate, apex up where
row + column is even; hexagons (flat top and bottom) stand in columns, every odd column
half a cell higher. SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from snapmorph.units.frame3d import PETG_NU, Mesh3D, UnitGeometry
from snapmorph.units.polygon import (add_cell_arches, check_geometry_polygon, check_sides,
                                     side_abscissae)

__all__ = ["TILINGS", "SheetModel", "check_cells", "cell_polygons", "build_sheet_mesh"]

#: tiling -> sides of its cells
TILINGS = {"triangle": 3, "square": 4, "hexagon": 6}
#: the largest number of cells a sheet may have (a 12 x 12 sheet at the default mesh is
#: ~10^5 DOFs, the sparse factorisation's measured range)
MAX_CELLS = 144


@dataclass
class SheetModel:
    """A meshed sheet: its mesh, tiling, shape (rows, cols), geometry and resolution, and
    per cell: ``apex`` node, ``feet`` (its sides' midpoint nodes), ``ring`` (the nodes its
    actuator moves as one), ``edges`` (its sides' edge indices), ``centre`` (x, y) m;
    ``edge_nodes``: node indices of every edge of the tiling (corner to corner);
    ``edge_cells``: the cells sharing each edge; ``holds``: a statically determinate set of
    (node, components) that holds only the sheet's rigid-body motion (`free_holds`)."""

    mesh: Mesh3D
    tiling: str
    shape: tuple
    geometry: UnitGeometry
    nodes: int
    apex: np.ndarray
    feet: list
    ring: list
    edges: list
    centre: np.ndarray
    edge_nodes: list
    edge_cells: list
    holds: list = field(default_factory=list)
    overlaps: str = "elastic"

    @property
    def n_cells(self) -> int:
        return len(self.apex)

    def boundary_edges(self) -> list:
        """Edges of the tiling on the sheet's boundary (one cell only)."""
        return [e for e, cells in enumerate(self.edge_cells) if len(cells) == 1]


def check_cells(cells) -> tuple:
    """``cells`` ((rows, cols) or a count n: the most nearly square rows x cols = n, rows <=
    cols) as (rows, cols), or a ValueError."""
    if isinstance(cells, (int, np.integer)) and not isinstance(cells, (bool, np.bool_)):
        n = int(cells)
        if not 1 <= n <= MAX_CELLS:
            raise ValueError(f"cells (number of cells) must be in [1, {MAX_CELLS}]; got {n}")
        rows = max(r for r in range(1, int(math.isqrt(n)) + 1) if n % r == 0)
        return rows, n // rows
    try:
        rows, cols = (int(c) for c in cells)
        ok = all(float(c) == int(c) and not isinstance(c, (bool, np.bool_)) for c in cells)
    except (TypeError, ValueError):
        ok = False
    if not ok or rows < 1 or cols < 1 or rows * cols > MAX_CELLS:
        raise ValueError(f"cells must be (rows, cols) of integers >= 1 with rows x cols <= "
                         f"{MAX_CELLS}, or a count; got {cells!r}")
    return rows, cols


def cell_polygons(tiling: str, rows: int, cols: int, L: float) -> list:
    """The cells' vertices (k, 2) m, counter-clockwise, row after row from the bottom left."""
    if tiling not in TILINGS:
        raise ValueError(f"tiling must be one of {tuple(TILINGS)}; got {tiling!r}")
    out = []
    H = 0.5 * math.sqrt(3.0) * L
    for i in range(rows):
        for j in range(cols):
            if tiling == "square":
                x, y = j * L, i * L
                out.append(np.array([[x, y], [x + L, y], [x + L, y + L], [x, y + L]]))
            elif tiling == "triangle":
                x, y = 0.5 * j * L, i * H
                if (i + j) % 2 == 0:
                    out.append(np.array([[x, y], [x + L, y], [x + 0.5 * L, y + H]]))
                else:
                    out.append(np.array([[x + 0.5 * L, y], [x + L, y + H], [x, y + H]]))
            else:
                cx, cy = 1.5 * j * L, 2 * i * H + (H if j % 2 else 0.0)
                a = np.radians([240.0, 300.0, 0.0, 60.0, 120.0, 180.0])
                out.append(np.stack([cx + L * np.cos(a), cy + H + L * np.sin(a)], 1))
    return out


def _vertex_ids(polygons, L):
    """Unique vertices of the tiling: (ids per polygon, (m, 2) positions)."""
    keys, points, ids = {}, [], []
    for P in polygons:
        row = []
        for p in P:
            key = (round(p[0] / L * 1e6), round(p[1] / L * 1e6))
            if key not in keys:
                keys[key] = len(points)
                points.append(np.array(p, dtype=float))
            row.append(keys[key])
        ids.append(row)
    return ids, np.array(points)


def build_sheet_mesh(g: UnitGeometry, tiling: str = "square", cells=(3, 3), nodes: int = 21,
                     nu: float = PETG_NU, overlaps: str = "elastic") -> SheetModel:
    """Mesh a sheet (module docstring): no actuator or supports (`units.sheet` adds them
    per push). ``nodes``: resolution, the spacing is L / (nodes - 1) as in the 2-D unit."""
    if tiling not in TILINGS:
        raise ValueError(f"tiling must be one of {tuple(TILINGS)}; got {tiling!r}")
    sides = check_sides(TILINGS[tiling])
    check_geometry_polygon(g, sides)
    rows, cols = check_cells(cells)
    if (isinstance(nodes, bool) or not isinstance(nodes, (int, np.integer))
            or not 11 <= nodes <= 201):
        raise ValueError(f"nodes (resolution: nodes along a side) must be an integer in "
                         f"[11, 201]; got {nodes!r}")
    spacing = g.L / (int(nodes) - 1)
    polygons = cell_polygons(tiling, rows, cols, g.L)
    vid, V = _vertex_ids(polygons, g.L)
    s, mid = side_abscissae(g.L, g.w, spacing)
    mesh = Mesh3D(E=g.E, nu=nu)
    edge_index, edge_nodes, edge_cells = {}, [], []
    at_vertex = {}  # vertex -> the edge-end nodes there
    cell_edges = []
    for c, ids in enumerate(vid):
        mine = []
        for k in range(sides):
            a, b = ids[k], ids[(k + 1) % sides]
            key = (min(a, b), max(a, b))
            if key not in edge_index:
                pa, pb = V[key[0]], V[key[1]]
                d = (pb - pa) / g.L
                xyz = np.stack([pa[0] + s * d[0], pa[1] + s * d[1], np.zeros_like(s)], 1)
                nodes_e = mesh.add_rod(f"edge{len(edge_nodes)}", xyz, g.w, g.t)
                edge_index[key] = len(edge_nodes)
                edge_nodes.append(nodes_e)
                edge_cells.append([])
                at_vertex.setdefault(key[0], []).append(int(nodes_e[0]))
                at_vertex.setdefault(key[1], []).append(int(nodes_e[-1]))
            e = edge_index[key]
            edge_cells[e].append(c)
            mine.append(e)
        cell_edges.append(mine)
    for ends in at_vertex.values():
        for other in ends[1:]:
            mesh.bond(ends[0], other)
    apex, feet, ring, centres = [], [], [], []
    names = [f"s{k}" for k in range(sides)]
    for c, P in enumerate(polygons):
        f = [int(edge_nodes[e][mid]) for e in cell_edges[c]]
        _, top, group = add_cell_arches(mesh, g, P, f, names, spacing, overlaps,
                                        prefix=f"cell{c}_")
        apex.append(top)
        feet.append(f)
        ring.append(group)
        centres.append(P.mean(axis=0))
    model = SheetModel(mesh, tiling, (rows, cols), g, int(nodes), np.array(apex), feet, ring,
                       cell_edges, np.array(centres), edge_nodes, edge_cells,
                       overlaps=overlaps)
    model.holds = free_holds(model)
    return model


def free_holds(model: SheetModel) -> list:
    """A statically determinate set of (node, components) holding only the rigid-body
    motion of a free sheet: the midpoint of cell 0's first side in x, y and z; the midpoint
    node of the sheet farthest from it in x and z when that node's offset is mostly along y
    (else in y and z), which stops turning about z and about the in-plane axis across the
    line between them; and the midpoint farthest from that line in z (no turning about the
    line). Six components, no redundancy: under no load their reactions vanish."""
    X = model.mesh.positions
    mids = sorted({n for f in model.feet for n in f})
    a = model.feet[0][0]
    dist = [float(np.linalg.norm(X[n, :2] - X[a, :2])) for n in mids]
    b = mids[int(np.argmax(dist))]
    d = X[b, :2] - X[a, :2]
    d = d / np.linalg.norm(d)
    across = "xz" if abs(d[1]) >= abs(d[0]) else "yz"
    off = [abs(float(d[0] * (X[n, 1] - X[a, 1]) - d[1] * (X[n, 0] - X[a, 0]))) for n in mids]
    c = mids[int(np.argmax(off))]
    if off[mids.index(c)] <= 1e-9 * model.geometry.L:  # one row of midpoints: any corner
        corner = model.edge_nodes[0][0]
        c = int(corner)
    return [(int(a), "xyz"), (int(b), across), (int(c), "z")]
