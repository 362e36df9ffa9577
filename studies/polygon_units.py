"""The studies behind docs/sheets.md ("Maps of the polygon units") and docs/unit3d.md ("The
3-D unit's mesh"), runnable from a clean process at the top of a checkout (one thread):

    .venv/bin/python -m studies.polygon_units triangle              # where is the triangle bistable
    .venv/bin/python -m studies.polygon_units convergence [nodes,...]   # 21,41,81 by default
    .venv/bin/python -m studies.polygon_units unit3d [plates] [nodes,...] [option=value ...]
        # theta vs mesh, CPU s; options of simulate_unit_3d, e.g. joints=node foot_refinement=4

Each prints CSV rows as it goes (SI lengths over L, N, degrees, CPU seconds).
"""

from __future__ import annotations

import itertools
import os
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from snapmorph.units.frame3d import UnitGeometry  # noqa: E402

L = 0.1
#: one bistable point of each footprint's small map (h/L, t/L; w/L = 0.05, b = 0)
BISTABLE = {3: (0.52, 0.0025), 4: (0.4, 0.005), 6: (0.5, 0.005)}


def _row(*values):
    print(*values, sep=",", flush=True)


def triangle(ws=(0.025, 0.05, 0.1), bs=(0.0, 0.05), ts=(0.0025, 0.005, 0.0075)):
    """The triangle over its whole declared domain h <= 2 (r - b - w/2): h/L every 0.05, then
    fractions 0.95-1 of the domain's edge, for each w/L, b/L, t/L."""
    from snapmorph.units.polygon import inradius
    from snapmorph.units.unit2d import simulate_unit_2d

    _row("h_over_L", "h_over_edge", "t_over_L", "w_over_L", "b_over_L", "status", "bistable",
         "self_standing", "F_cr_N", "cpu_s")
    for w, b, t in itertools.product(ws, bs, ts):
        edge = 2 * (inradius(1.0, 3) - b - w / 2)
        coarse = [round(0.05 * k, 2) for k in range(1, int(edge / 0.05) + 1)
                  if 0.05 * k < 0.95 * edge]
        fine = [round(f * edge, 5) for f in (0.95, 0.96, 0.97, 0.975, 0.98, 0.985, 0.99,
                                             0.995, 1.0)]
        for h in coarse + fine:
            t0 = time.process_time()
            r = simulate_unit_2d(UnitGeometry(L=L, h=h * L, t=t * L, w=w * L, b=b * L), sides=3)
            _row(h, round(h / edge, 4), t, w, b, r.status.split(":")[0], r.bistable,
                 r.self_standing, r.F_cr, round(time.process_time() - t0, 2))


def convergence(meshes=(21, 41, 81)):
    """F_cr and the released mean theta of each footprint at its bistable point (`BISTABLE`)
    at several meshes, and their change against the finest."""
    from snapmorph.units.unit2d import simulate_unit_2d

    _row("sides", "h_over_L", "t_over_L", "nodes", "status", "self_standing", "F_cr_N",
         "theta_deg", "theta_released_deg", "F_cr_vs_finest_pct", "theta_released_vs_finest_deg")
    for sides, (h, t) in BISTABLE.items():
        g = UnitGeometry(L=L, h=h * L, t=t * L, w=0.05 * L)
        rs = [simulate_unit_2d(g, sides=sides, nodes=n) for n in meshes]
        last = rs[-1]
        for n, r in zip(meshes, rs):
            _row(sides, h, t, n, r.status.split(":")[0], r.self_standing, r.F_cr, r.theta_deg,
                 r.theta_released_deg, 100 * (r.F_cr / last.F_cr - 1),
                 r.theta_released_deg - last.theta_released_deg)


def unit3d(plates=("elastic", "stiff"), meshes=(41, 81, 121, 161, 241), **options):
    """The 3-D unit at the Table 1 specimen h = 40.68 mm, t = 0.5, w = b = 5 mm: theta (state
    (iii) and released), F_cr and the CPU time of one call (warm, this process's CPU time)
    per mesh; ``options`` go to `simulate_unit_3d` (joints, foot_refinement)."""
    from snapmorph.units.unit3d import simulate_unit_3d

    g = UnitGeometry(L=L, h=0.04068, t=0.5e-3, w=5e-3, b=5e-3)
    simulate_unit_3d(g, nodes=21)  # warm: kernels compiled or loaded from the cache
    _row("end_plate", "nodes", "status", "theta_deg", "theta_released_deg", "F_cr_N", "cpu_s")
    for plate in plates:
        for n in meshes:
            t0 = time.process_time()
            r = simulate_unit_3d(g, nodes=n, end_plate=plate, **options)
            _row(plate, n, r.status, repr(r.theta_deg), repr(r.theta_released_deg),
                 repr(r.F_cr), round(time.process_time() - t0, 3))


def _ints(arg):
    return tuple(int(v) for v in arg.split(","))


if __name__ == "__main__":
    what, rest = sys.argv[1], sys.argv[2:]
    if what == "triangle":
        triangle()
    elif what == "convergence":
        convergence(*(_ints(a) for a in rest[:1]))
    elif what == "unit3d":
        plates = tuple(rest[0].split(",")) if rest else ("elastic", "stiff")
        options = dict(a.split("=", 1) for a in rest[2:])
        options = {k: int(v) if v.isdigit() else v for k, v in options.items()}
        unit3d(plates, *(_ints(a) for a in rest[1:2]), **options)
    else:
        raise SystemExit(f"unknown study {what!r}: triangle, convergence or unit3d")
