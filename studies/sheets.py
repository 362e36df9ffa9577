"""The studies of docs/sheets.md: polygon units' bistable ranges and mesh convergence, the
mesh convergence of a snapped 3 x 3 sheet's final shape, and the memory of sheets (many
orders of one set of cells).

    .venv/bin/python -m studies.sheets polygons [sides,...]      # h/L scans, F_cr at 21/41/81
    .venv/bin/python -m studies.sheets convergence [nodes,...]   # 3 x 3, order 4,0,8
    .venv/bin/python -m studies.sheets memory [square|hexagon] [orders] [nodes] [cells]
                     [shape RxC] [out.json] [figure.png] ["o1;o2" orders first]
                     # e.g. hexagon 20 21 1,2,3,4,5 2x3 hex.json hex.png 1,2,3,4,5
    .venv/bin/python -m studies.sheets coupling [order] [nodes]  # fast prediction vs sheet

SHEET_PROTOCOL=mgdc (environment) pushes the cells by the load-controlled protocol
(`units.push3d`) instead of the displacement-controlled rig (`units.sheet_rig`, the default).
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
    r = simulate_sheet(sheet, order, protocol=os.environ.get("SHEET_PROTOCOL", "rig"))
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
        print(f"nodes {nodes}: {time.perf_counter() - t0:.0f} s, "
              f"{'complete' if r.complete else 'NOT complete (no result)'}, pushes "
              f"{[s.push_status[:40] for s in r.steps]}, snapped "
              f"{np.flatnonzero(r.final.snapped).tolist()}, stable {r.final.stable}, "
              f"apex heights (mm) {np.round(1e3 * a, 2).tolist()}", flush=True)
    _, a_ref, k_ref = rows[-1]
    for nodes, a, k in rows[:-1]:
        da = float(np.max(np.abs(a - a_ref)) / np.max(np.abs(a_ref)))
        dk = float(np.max(np.abs(k - k_ref)) / np.max(np.abs(k_ref)))
        print(f"nodes {nodes} vs {rows[-1][0]}: apex heights {100 * da:.2f} % of the largest, "
              f"edge curvatures {100 * dk:.2f} % of the largest", flush=True)


def memory(tiling="square", n_orders=20, nodes=21, cells=(0, 2, 4, 6, 8), shape=(3, 3),
           out="", figure="", include=((0, 4, 8, 2, 6),)):
    """`explore_orders` on one set of ``cells`` of a ``shape`` sheet (square or hexagonal;
    L 100, h 40, t 0.5, w 5 mm; free): the final shapes grouped by shape distance (L / 100),
    written to ``out`` (JSON: orders, every final's snapped cells, stability, global modes,
    apex heights, the distance matrix, the groups) and a figure (``figure``, PNG): two
    stable shapes with the same snapped cells reached in different orders, or, when there
    are none, the finals of four orders with their distances in the titles."""
    import json

    from snapmorph.units.sheet import build_sheet, explore_orders

    g = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)
    sheet = build_sheet(g, tiling, tuple(shape), nodes=nodes)
    cells = list(cells)
    t0 = time.perf_counter()

    from snapmorph.units.sheet import shape_distance

    seen = []

    def progress(i, order, r):
        # the distance to every earlier final, so that a log cut short still groups them
        d = [shape_distance(p, r.final.positions) for p in seen]
        seen.append(r.final.positions)
        near = (f"; nearest earlier final: order {int(np.argmin(d))} at {1e3 * min(d):.3f} mm"
                if d else "")
        print(f"  order {i} {order}: {r.solve_time:.0f} s new{near}, per step "
              f"{[round(s.seconds) for s in r.steps]} s; snapped "
              f"{np.flatnonzero(r.final.snapped).tolist()} stable {r.final.stable} global "
              f"modes {[int(s.global_mode) for s in r.steps]} "
              f"{'; '.join(s.reason for s in r.steps if s.reason)}", flush=True)

    include = [o for o in include if sorted(o) == sorted(cells)]
    runs = branching_orders(cells, n_orders, include=include)
    protocol = os.environ.get("SHEET_PROTOCOL", "rig")
    print(f"{tiling} {shape[0]}x{shape[1]}, cells {cells}: pushes by protocol {protocol!r}",
          flush=True)
    res = explore_orders(sheet, cells, orders=runs, progress=progress, protocol=protocol)
    seconds = time.perf_counter() - t0
    print(f"{tiling} {shape[0]}x{shape[1]}, cells {cells}, {len(res['orders'])} orders, "
          f"{nodes} nodes: {seconds:.0f} s ({res['pushes']} pushes); {len(res['groups'])} "
          f"final shapes, {res['distinct']} distinct stable, {res['distinct_complete']} of them "
          f"reached by an order whose every push answered and every release was stable",
          flush=True)
    d = res["distances"]
    for grp in res["groups"]:
        orders = [res["orders"][i] for i in grp["orders"]]
        print(f"  shape: snapped {grp['snapped']} stable {grp['stable']} spread "
              f"{1e3 * grp['spread']:.3f} mm, {len(orders)} orders ({len(grp['complete'])} "
              f"complete), e.g. {orders[:3]}")
    print(f"  largest distance between finals {1e3 * d.max():.3f} mm", flush=True)
    finals = []
    for o, r in zip(res["orders"], res["results"]):
        f = r.final
        finals.append({"order": o, "snapped": np.flatnonzero(f.snapped).tolist(),
                       "stable": bool(f.stable), "negative_eigenvalues": f.negative_eigenvalues,
                       "global_modes": [bool(s.global_mode) for s in r.steps],
                       "reasons": [s.reason for s in r.steps],
                       "push_status": [s.push_status for s in r.steps],
                       "complete": r.complete,
                       "F_cr_N": [float(s.F_cr) for s in r.steps],
                       "apex_heights_mm": np.round(1e3 * f.apex_heights, 4).tolist()})
    record = {"tiling": tiling, "shape": list(shape), "nodes": nodes, "cells": cells,
              "protocol": protocol,
              "geometry_mm": {"L": 100, "h": 40, "t": 0.5, "w": 5}, "boundary": "free",
              "tolerance_mm": 1e3 * 0.01 * g.L, "seconds": seconds, "pushes": res["pushes"],
              "finals": finals, "distances_mm": np.round(1e3 * d, 4).tolist(),
              "groups": [{"orders": grp["orders"], "snapped": grp["snapped"],
                          "stable": grp["stable"], "spread_mm": 1e3 * grp["spread"],
                          "complete": grp["complete"]}
                         for grp in res["groups"]],
              "distinct_stable": res["distinct"],
              "distinct_stable_complete": res["distinct_complete"]}
    if out:
        with open(out, "w") as fh:
            json.dump(record, fh, indent=1)
        print(f"  wrote {out}")
    if figure:
        _memory_figure(sheet, res, figure)
    return res


def branching_orders(cells, n=20, firsts=2, per_pair=5, seed=0, include=()):
    """``n`` distinct orders of ``cells`` chosen to share prefixes (`explore_orders` pushes
    a shared prefix once): ``firsts`` different first cells, at most ``per_pair`` orders per
    first two cells, each next order the one that adds the fewest new pushes (ties broken by
    a shuffle with ``seed``); the orders ``include`` come first. 20 orders of 5 cells cost
    ~58 pushes instead of 100."""
    import itertools

    rng = np.random.default_rng(seed)
    perms = [list(p) for p in itertools.permutations(cells)]
    perms = [perms[i] for i in rng.permutation(len(perms))]
    chosen = [list(o) for o in include]
    middle = list(cells)[len(cells) // 2]  # e.g. the centre of 0, 2, 4, 6, 8
    heads = []
    for c in [o[0] for o in chosen] + [middle] + list(cells):
        if c not in heads:
            heads.append(c)
    heads = heads[:firsts]
    seen = {tuple(o[: k + 1]) for o in chosen for k in range(len(o))}
    while len(chosen) < n:
        best, cost = None, None
        head = heads[len(chosen) % len(heads)]  # the first cells take turns
        for p in perms:
            pair = sum(1 for o in chosen if o[:2] == p[:2])
            if p in chosen or p[0] != head or pair >= per_pair:
                continue
            new = sum(1 for k in range(len(p)) if tuple(p[: k + 1]) not in seen)
            if cost is None or new < cost:
                best, cost = p, new
        if best is None:
            break
        chosen.append(best)
        seen |= {tuple(best[: k + 1]) for k in range(len(best))}
    return chosen


def _memory_figure(sheet, res, path):
    """Two stable shapes with the same snapped set from different orders; else the finals
    of the orders farthest apart (four at most), their distances in the titles."""
    from snapmorph.figures_sheet import plot_shapes

    same = {}
    for grp in res["groups"]:
        if grp["stable"] and grp["complete"]:  # a shape let go of mid-push is no result
            same.setdefault(tuple(grp["snapped"]), []).append(grp)
    pairs = [grps for grps in same.values() if len(grps) > 1]
    d = res["distances"]
    if pairs:
        picks = [grp["complete"][0] for grp in pairs[0][:2]]
        what = "same snapped cells, different shapes"
    else:  # no memory: the first order and those farthest from it
        far = np.argsort(-d[0])
        picks = [0] + [int(i) for i in far if i != 0][:3]
        what = "one shape"
    states = []
    for i in picks:
        f = res["results"][i].final
        dist = ", ".join(f"{1e3 * d[i, j]:.2f}" for j in picks if j != i)
        states.append((f"order {res['orders'][i]}\nsnapped "
                       f"{np.flatnonzero(f.snapped).tolist()}; to the others {dist} mm",
                       f.positions, f.snapped))
    plot_shapes(sheet, states, path)
    print(f"  wrote {path} ({what})", flush=True)


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
                  f"{c['max_error']:.3f} 1/m; push {step.push_status[:40]!r}, complete "
                  f"{step.complete}", flush=True)


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "polygons"
    if what == "polygons":
        polygons(tuple(int(s) for s in sys.argv[2].split(",")) if len(sys.argv) > 2
                 else (3, 4, 6))
    elif what == "convergence":
        convergence(tuple(int(s) for s in sys.argv[2].split(",")) if len(sys.argv) > 2
                    else (21, 31, 41))
    elif what == "memory":
        a = sys.argv[2:] + [""] * 8
        memory(a[0] or "square", int(a[1] or 20), int(a[2] or 21),
               tuple(int(c) for c in (a[3] or "0,2,4,6,8").split(",")),
               tuple(int(c) for c in (a[4] or "3x3").split("x")), a[5], a[6],
               [tuple(int(c) for c in o.split(",")) for o in (a[7] or "0,4,8,2,6").split(";")])
    elif what == "coupling":
        coupling(tuple(int(c) for c in sys.argv[2].split(",")) if len(sys.argv) > 2
                 else (4, 0, 8), int(sys.argv[3]) if len(sys.argv) > 3 else 21)
    else:
        raise SystemExit(f"unknown study {what!r}: polygons, convergence, memory or coupling")
