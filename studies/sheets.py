"""The studies of docs/sheets.md: polygon units' bistable ranges and mesh convergence, the
mesh convergence of a snapped 3 x 3 sheet's final shape, and the memory of sheets (many
orders of one set of cells).

    .venv/bin/python -m studies.sheets polygons [sides,...]      # h/L scans, F_cr at 21/41/81
    .venv/bin/python -m studies.sheets convergence [nodes,...]   # 3 x 3, order 4,0,8
    .venv/bin/python -m studies.sheets memory [square|hexagon] [orders] [nodes] [cells]
    .venv/bin/python -m studies.sheets coupling [order] [nodes]  # fast prediction vs sheet
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from snapmorph.units.frame3d import UnitGeometry  # noqa: E402


def polygons(sides=(3, 4, 6)):
    """Bistability over h/L (L the side, 100 mm; t 0.5, w 5 mm) and F_cr's mesh convergence
    at one bistable h/L."""
    from snapmorph.units.unit2d import simulate_unit_2d

    scan = {3: (0.05, 0.1, 0.15, 0.2, 0.3, 0.4), 4: (0.1, 0.15, 0.2, 0.3, 0.4),
            6: (0.1, 0.2, 0.25, 0.3, 0.4, 0.6, 0.8)}
    for n in sides:
        for hl in scan[n]:
            g = UnitGeometry(L=0.1, h=hl * 0.1, t=0.5e-3, w=5e-3)
            r = simulate_unit_2d(g, sides=n, nodes=21)
            print(f"sides {n} h/L {hl:.2f}: {r.status:12s} F_cr {r.F_cr:.4f} N bistable "
                  f"{r.bistable} self-standing {r.self_standing}", flush=True)
        hl = {3: 0.2, 4: 0.4, 6: 0.4}[n]
        F = []
        for nodes in (21, 41, 81):
            g = UnitGeometry(L=0.1, h=hl * 0.1, t=0.5e-3, w=5e-3)
            F.append(simulate_unit_2d(g, sides=n, nodes=nodes, check_self_standing=False).F_cr)
        print(f"sides {n} h/L {hl}: F_cr at 21/41/81 nodes {F[0]:.5f} / {F[1]:.5f} / "
              f"{F[2]:.5f} N: 41 vs 81 {100 * (F[1] / F[2] - 1):+.2f} %", flush=True)


def final_shape(nodes, order, shape=(3, 3), tiling="square"):
    """(apex heights (n_cells,) m, mean edge curvatures (n_edges,) 1/m, result) of a sheet
    snapped in ``order`` at ``nodes`` per side."""
    from snapmorph.units.sheet import build_sheet, simulate_sheet
    from snapmorph.units.unit2d import edge_metrics

    g = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)
    sheet = build_sheet(g, tiling, shape, nodes=nodes)
    r = simulate_sheet(sheet, order)
    f = r.final
    curv = np.array([edge_metrics(f.positions[e])["curvature"] for e in sheet.edge_nodes])
    return f.apex_heights, curv, r


def convergence(meshes=(21, 31, 41), order=(4, 0, 8)):
    """The final shape of a 3 x 3 square sheet snapped in ``order`` at several meshes:
    apex heights and edge curvatures against the finest."""
    rows = []
    for nodes in meshes:
        t0 = time.perf_counter()
        a, k, r = final_shape(nodes, list(order))
        rows.append((nodes, a, k))
        print(f"nodes {nodes}: {time.perf_counter() - t0:.0f} s, snapped "
              f"{np.flatnonzero(r.final.snapped).tolist()}, stable {r.final.stable}, "
              f"apex heights (mm) {np.round(1e3 * a, 2).tolist()}", flush=True)
    _, a_ref, k_ref = rows[-1]
    for nodes, a, k in rows[:-1]:
        da = float(np.max(np.abs(a - a_ref)) / np.max(np.abs(a_ref)))
        dk = float(np.max(np.abs(k - k_ref)) / np.max(np.abs(k_ref)))
        print(f"nodes {nodes} vs {rows[-1][0]}: apex heights {100 * da:.2f} % of the largest, "
              f"edge curvatures {100 * dk:.2f} % of the largest", flush=True)


def memory(tiling="square", n_orders=20, nodes=21, cells=(0, 2, 4, 6, 8)):
    """`explore_orders` on one set of cells of a 3 x 3 sheet (default the 5-cell set 0, 2,
    4, 6, 8; square or hexagonal)."""
    from snapmorph.units.sheet import build_sheet, explore_orders

    g = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)
    sheet = build_sheet(g, tiling, (3, 3), nodes=nodes)
    cells = list(cells)
    t0 = time.perf_counter()
    out = explore_orders(sheet, cells, orders=n_orders)
    print(f"{tiling} 3x3, cells {cells}, {len(out['orders'])} orders, {nodes} nodes: "
          f"{time.perf_counter() - t0:.0f} s; {len(out['groups'])} final shapes, "
          f"{out['distinct']} distinct stable", flush=True)
    for grp in out["groups"]:
        orders = [out["orders"][i] for i in grp["orders"]]
        print(f"  shape: snapped {grp['snapped']} stable {grp['stable']} spread "
              f"{1e3 * grp['spread']:.2f} mm, {len(orders)} orders, e.g. {orders[:3]}")
    d = out["distances"]
    print(f"  largest distance between finals {1e3 * d.max():.2f} mm")
    same = {}
    for grp in out["groups"]:
        same.setdefault(tuple(grp["snapped"]), []).append(grp)
    pairs = [g for g in same.values() if len(g) > 1 and all(x["stable"] for x in g)]
    if pairs:  # two stable shapes with the same snapped cells: the memory figure
        from snapmorph.figures_sheet import plot_shapes

        a, b = pairs[0][:2]
        path = f"sheet_memory_{tiling}.png"
        plot_shapes(sheet, [(f"order {out['orders'][g['orders'][0]]}", g["positions"],
                             np.isin(np.arange(sheet.n_cells), g["snapped"]))
                            for g in (a, b)], path)
        print(f"  wrote {path}: two shapes with cells {a['snapped']} snapped")
    return out


def coupling(order=(4, 0, 8), nodes=21):
    """The fast prediction (every snapped cell's sides bent as the released unit's,
    `units.sheet.predict_edge_curvatures`) against a 3 x 3 square sheet after each step."""
    from snapmorph.units.sheet import build_sheet, coupling_error, simulate_sheet
    from snapmorph.units.unit2d import SIDES, simulate_unit_2d

    g = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)
    unit = simulate_unit_2d(g, nodes=nodes)
    for state in ("released", "iii"):
        edges = unit.released["edges"] if state == "released" else unit.edges["iii"]
        k = np.array([edges[s]["curvature"] for s in SIDES])
        print(f"unit ({state}) side curvatures {np.round(k, 3).tolist()} 1/m", flush=True)
    k_rel = np.array([unit.released["edges"][s]["curvature"] for s in SIDES])
    k_iii = np.array([unit.edges["iii"][s]["curvature"] for s in SIDES])
    sheet = build_sheet(g, "square", (3, 3), nodes=nodes)
    r = simulate_sheet(sheet, list(order))
    for step in r.steps:
        for name, k in (("released unit", k_rel), ("unit (iii)", k_iii)):
            c = coupling_error(sheet, step, k)
            print(f"after cell {step.cell} (snapped {np.flatnonzero(step.snapped).tolist()}, "
                  f"stable {step.stable}, global mode {step.global_mode}) from the {name}: "
                  f"rms error {c['rms_error']:.3f} 1/m = {100 * c['relative']:.0f} % of the "
                  f"sheet's rms {np.sqrt(np.mean(c['simulated'] ** 2)):.3f} 1/m, max "
                  f"{c['max_error']:.3f} 1/m", flush=True)


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "polygons"
    if what == "polygons":
        polygons(tuple(int(s) for s in sys.argv[2].split(",")) if len(sys.argv) > 2
                 else (3, 4, 6))
    elif what == "convergence":
        convergence(tuple(int(s) for s in sys.argv[2].split(",")) if len(sys.argv) > 2
                    else (21, 31, 41))
    elif what == "memory":
        memory(sys.argv[2] if len(sys.argv) > 2 else "square",
               int(sys.argv[3]) if len(sys.argv) > 3 else 20,
               int(sys.argv[4]) if len(sys.argv) > 4 else 21,
               tuple(int(c) for c in sys.argv[5].split(",")) if len(sys.argv) > 5
               else (0, 2, 4, 6, 8))
    elif what == "coupling":
        coupling(tuple(int(c) for c in sys.argv[2].split(",")) if len(sys.argv) > 2
                 else (4, 0, 8), int(sys.argv[3]) if len(sys.argv) > 3 else 21)
    else:
        raise SystemExit(f"unknown study {what!r}: polygons, convergence, memory or coupling")
