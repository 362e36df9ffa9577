"""The studies behind docs/unit3d.md (issue 14), runnable from a clean process at the top of a
checkout:

    .venv/bin/python -m studies.studies3d table1   [nodes,...]   # 3-D vs planar, Table 1
    .venv/bin/python -m studies.studies3d tilt     [nodes]       # F_cr knock-down vs tilt
    .venv/bin/python -m studies.studies3d offsets  [nodes]       # apex / actuator offsets
    .venv/bin/python -m studies.studies3d unit2d   [nodes,...]   # 2-D unit, mesh convergence
    .venv/bin/python -m studies.studies3d map2d    [nodes]       # 2-D unit, bistability map
    .venv/bin/python -m studies.studies3d theta_residual [nodes,...] [all|decisive|table1]
        # where the stiff-plate residual against the planar model comes from
        # (studies/diagnostics3d.py; docs/unit3d.md, "Agreement with the planar model")

Each prints one line per run (SI converted to mm, N, degrees) as it goes.
"""

from __future__ import annotations

import sys
import time

#: Table 1 of the paper: (h, t, L) averages in mm, w = b = 5 mm
TABLE1 = [(9.11, 0.50, 99.2), (9.10, 0.75, 99.0), (19.24, 0.50, 99.5), (19.96, 0.75, 99.7),
          (40.68, 0.50, 99.4), (39.85, 0.75, 99.5)]
MM = 1e-3


def _geometry(h, t, L, w=5.0, b=5.0):
    from snapmorph.units.frame3d import UnitGeometry

    return UnitGeometry(L=L * MM, h=h * MM, t=t * MM, w=w * MM, b=b * MM)


def table1(nodes=(41, 81), plates=("elastic", "stiff")):
    from snapmorph.units import simulate_unit
    from snapmorph.units.unit3d import simulate_unit_3d

    rows = []
    for h, t, L in TABLE1:
        g = _geometry(h, t, L)
        p = simulate_unit(g, nodes=PLANAR_REFERENCE_NODES)
        print(f"h={h} t={t} L={L} planar ({PLANAR_REFERENCE_NODES} nodes): status {p.status} "
              f"F_cr {p.F_cr:.4f} N theta {p.theta_deg:.2f} deg S {p.S / MM:.2f} mm, released "
              f"theta {p.theta_released_deg:.2f} deg S {p.S_released / MM:.2f} mm", flush=True)
        for plate in plates:
            for n in nodes:
                t0 = time.perf_counter()
                r = simulate_unit_3d(g, nodes=n, end_plate=plate)
                dt = time.perf_counter() - t0
                rel = (r.F_cr / p.F_cr - 1) * 100
                dth = r.theta_deg - p.theta_deg
                print(f"   3-D {plate:<7} n={n:<4} status {r.status:<10} F_cr {r.F_cr:.4f} N "
                      f"({rel:+.2f} %) theta {r.theta_deg:.2f} deg ({dth:+.2f}) S "
                      f"{r.S / MM:.2f} mm d_cr {r.d_cr / MM:.2f} d_ii {r.d_unstable / MM:.2f} "
                      f"d_iii {r.d_second / MM:.2f} mm; released theta "
                      f"{r.theta_released_deg:.2f} ({r.theta_released_deg - p.theta_released_deg:+.2f})"
                      f" S {r.S_released / MM:.2f} mm, self-standing {r.self_standing}"
                      f"  [{dt:.1f} s]", flush=True)
                rows.append(dict(h=h, t=t, L=L, plate=plate, nodes=n, F_cr=r.F_cr,
                                 F_cr_planar=p.F_cr, theta=r.theta_deg,
                                 theta_planar=p.theta_deg, status=r.status,
                                 status_planar=p.status))
    return rows


def tilt(nodes=41, tilts=(0.0, 1.0, 2.0, 5.0), heights=(19.24, 40.68), t=0.5, plate="elastic"):
    from snapmorph.units.unit3d import simulate_unit_3d

    rows = []
    for h in heights:
        L = 99.5 if h < 30 else 99.4
        g = _geometry(h, t, L)
        base = None
        for a in tilts:
            t0 = time.perf_counter()
            r = simulate_unit_3d(g, nodes=nodes, tilt_deg=a, end_plate=plate)
            base = r.F_cr if a == 0.0 else base
            kd = r.F_cr / base if base else float("nan")
            print(f"h={h} tilt={a:g} deg n={nodes} {plate}: status {r.status} F_cr {r.F_cr:.4f} N "
                  f"(x{kd:.4f}) theta {r.theta_deg:.2f} deg S {r.S / MM:.2f} mm arch tilt "
                  f"(i) {r.arch_tilt_deg.get('i', float('nan')):.2f} (iii) "
                  f"{r.arch_tilt_deg.get('iii', float('nan')):.2f} deg rail twist (i) "
                  f"{r.rail_twist_deg.get('i', float('nan')):.3f} (iii) "
                  f"{r.rail_twist_deg.get('iii', float('nan')):.3f} deg  "
                  f"[{time.perf_counter() - t0:.1f} s]", flush=True)
            rows.append(dict(h=g.h, tilt_deg=a, F_cr=r.F_cr, theta_deg=r.theta_deg, S=r.S,
                             status=r.status, knockdown=kd))
    return rows


def offsets(nodes=41, heights=(19.24, 40.68), t=0.5, plate="elastic"):
    """F_cr and theta against the perfect unit for a sideways apex offset (1, 2 mm) and the
    actuator off centre (2, 5 mm): docs/unit3d.md, "Apex offset and actuator off centre"."""
    from snapmorph.units.unit3d import simulate_unit_3d

    cases = (("none", {}), ("apex offset 1 mm", {"apex_offset": 1 * MM}),
             ("apex offset 2 mm", {"apex_offset": 2 * MM}),
             ("actuator 2 mm off centre", {"actuator_offset": 2 * MM}),
             ("actuator 5 mm off centre", {"actuator_offset": 5 * MM}))
    for h in heights:
        g = _geometry(h, t, 99.5 if h < 30 else 99.4)
        base = None
        for name, options in cases:
            r = simulate_unit_3d(g, nodes=nodes, end_plate=plate, **options)
            base = base or r
            print(f"h={h} {name} n={nodes} {plate}: status {r.status} F_cr {r.F_cr:.4f} N "
                  f"({100 * (r.F_cr / base.F_cr - 1):+.2f} %) theta {r.theta_deg:.2f} deg "
                  f"({r.theta_deg - base.theta_deg:+.2f})", flush=True)


def unit2d(nodes=(21, 41, 81), h=40.0, t=0.5, L=100.0, w=5.0):
    from snapmorph.units.frame3d import UnitGeometry
    from snapmorph.units.unit2d import simulate_unit_2d

    g = UnitGeometry(L=L * MM, h=h * MM, t=t * MM, w=w * MM)
    out = []
    for n in nodes:
        t0 = time.perf_counter()
        r = simulate_unit_2d(g, nodes=n)
        e = r.edges.get("iii", {})
        th = [round(m["theta_deg"], 3) for m in e.values()]
        print(f"2-D unit L={L} h={h} t={t} w={w} n={n} ({r.n_nodes} nodes): {r.status} F_cr "
              f"{r.F_cr:.4f} N d_cr {r.d_cr / MM:.2f} d_ii {r.d_unstable / MM:.2f} d_iii "
              f"{r.d_second / MM:.2f} mm, sides' theta {th} deg, curvature "
              f"{r.curvature:.3f} 1/m, S {r.S / MM:.3f} mm  [{time.perf_counter() - t0:.1f} s]",
              flush=True)
        out.append(r)
    return out


def map2d(nodes=41, h_over_L=(0.2, 0.25, 0.3, 0.35, 0.4), t_over_L=(0.004, 0.005, 0.0075)):
    from snapmorph.pipeline.kinds.unit2d import solve_map_point

    for hl in h_over_L:
        for tl in t_over_L:
            t0 = time.perf_counter()
            rec = solve_map_point(hl, tl, resolution=nodes)
            print(f"h/L={hl} t/L={tl}: status {rec['status']} F_cr L^2/EI "
                  f"{rec.get('F_cr', float('nan')):.3f} theta {rec.get('theta', float('nan')):.2f} "
                  f"deg curvature*L {rec.get('curvature', float('nan')):.3f} "
                  f"[{time.perf_counter() - t0:.1f} s] {rec.get('message', '')}", flush=True)


#: the two specimens of the residual study (h, t, L in mm): Table 1's h = 20 and 40 mm, t = 0.5
RESIDUAL_SPECIMENS = [(19.24, 0.50, 99.5), (40.68, 0.50, 99.4)]
#: resolution of the planar reference: theta within 0.005 deg and F_cr within 0.02 % of
#: its limit (101 / 201 / 401 / 641 nodes: theta 79.106 / 79.144 / 79.154 / 79.156 deg)
PLANAR_REFERENCE_NODES = 641


def theta_residual(nodes=(41, 81), which="all"):
    """F_cr and theta of the 3-D unit's variants (`studies.diagnostics3d.VARIANTS`) against the
    converged planar model. ``which``: "all" (every variant at the two specimens),
    "decisive" (`studies.diagnostics3d.DECISIVE`: the mesh convergence), "table1" (the
    shipped stiff plates and the rigid bars over the six Table 1 specimens)."""
    from snapmorph.units import simulate_unit
    from studies.diagnostics3d import DECISIVE, VARIANTS, run_variant

    if which not in ("all", "decisive", "table1"):
        raise SystemExit(f"theta_residual: unknown set {which!r}: all, decisive or table1")
    names = {"all": list(VARIANTS), "decisive": list(DECISIVE),
             "table1": ["stiff (shipped: bars of 1e4 x E)",
                        "elastic (shipped: bars' torsion G b t^3/3)"]}[which]
    specimens = TABLE1 if which == "table1" else RESIDUAL_SPECIMENS
    rows = []
    for h, t, L in specimens:
        g = _geometry(h, t, L)
        p = simulate_unit(g, nodes=PLANAR_REFERENCE_NODES, critical=False,
                          check_self_standing=False)
        print(f"h={h} t={t} L={L} planar ({PLANAR_REFERENCE_NODES} nodes): F_cr "
              f"{p.F_cr:.5f} N theta {p.theta_deg:.3f} deg S {p.S / MM:.3f} mm", flush=True)
        for name in names:
            for n in nodes:
                if "rigid bar joints" in name and n > 161:
                    # 1000x joint pairs on 1e5 x E bars: ill-conditioned, > 10 min at 321
                    print(f"   {name:<40} n={n:<4} skipped (ill-conditioned above 161 nodes)")
                    continue
                r = run_variant(g, nodes=n, **VARIANTS[name])
                dF = (r["F_cr"] / p.F_cr - 1) * 100
                th = r.get("theta", float("nan"))
                extra = ""
                if "theta_centre" in r:
                    extra = (f" | centre-strip theta {r['theta_centre'] - th:+.4f}, rail twist "
                             f"{r['rail_twist']:.4f} deg")
                print(f"   {name:<40} n={n:<4} {r['status'][:12]:<12} F_cr {r['F_cr']:.5f} N "
                      f"({dF:+.2f} %) theta {th:.3f} deg ({th - p.theta_deg:+.3f})"
                      f"{extra}  [{r['time']:.1f} s]", flush=True)
                rows.append(dict(h=h, t=t, L=L, variant=name, nodes=n, F_cr=r["F_cr"],
                                 theta=th, dF_pct=dF, dtheta=th - p.theta_deg,
                                 F_cr_planar=p.F_cr, theta_planar=p.theta_deg,
                                 status=r["status"], time=r["time"]))
    return rows


if __name__ == "__main__":  # pragma: no cover
    what = sys.argv[1] if len(sys.argv) > 1 else "table1"
    arg = [int(x) for x in sys.argv[2].split(",")] if len(sys.argv) > 2 else None
    if what == "table1":
        table1(**({"nodes": arg} if arg else {}))
    elif what == "tilt":
        tilt(**({"nodes": arg[0]} if arg else {}))
    elif what == "offsets":
        offsets(**({"nodes": arg[0]} if arg else {}))
    elif what == "unit2d":
        unit2d(**({"nodes": arg} if arg else {}))
    elif what == "map2d":
        map2d(**({"nodes": arg[0]} if arg else {}))
    elif what == "theta_residual":
        theta_residual(**({"nodes": arg} if arg else {}),
                       **({"which": sys.argv[3]} if len(sys.argv) > 3 else {}))
    else:
        raise SystemExit(f"unknown study {what!r}: table1, tilt, offsets, unit2d, map2d or "
                         f"theta_residual")
