"""`snapmorph unit`: simulate one unit from its dimensions in millimetres."""

from __future__ import annotations

import argparse

HELP = """Simulate one bistable unit: push its apex down until it snaps, and report F_cr,
the equilibrium displacements, S, theta and the energies. Lengths on the command line are in
millimetres; E is in pascals. (The Python API, solver.unit, is SI throughout.)"""


def add_parser(sub):
    p = sub.add_parser("unit", help="simulate one unit (lengths in mm)", description=HELP)
    p.add_argument("--L", type=float, required=True, help="base length, mm")
    p.add_argument("--h", type=float, required=True, help="arch apex height, mm (0 = arch-less)")
    p.add_argument("--t", type=float, required=True, help="sheet thickness, mm")
    p.add_argument("--w", type=float, required=True, help="strip width, mm")
    p.add_argument("--b", type=float, default=0.0, help="extra flat length of the arch ends, mm (default 0; the paper's specimens use b = w)")
    p.add_argument("--E", type=float, default=2.2e9, help="Young's modulus, Pa (default 2.2e9, PETG)")
    p.add_argument("--nodes", type=int, default=None, help="resolution: about the number of base nodes (default: converged default)")
    p.add_argument("--method", choices=("mgdc", "displacement"), default="mgdc", help="path follower (default mgdc)")
    p.add_argument("--plot", metavar="PNG", help="write the force-displacement curve and the shapes (i)-(iii)")
    p.add_argument("--json", metavar="FILE", help="write the metrics and the curve as JSON")
    p.set_defaults(run=run)
    return p


def _fmt(value, scale=1.0, digits=4):
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if value != value:  # NaN
        return "n/a"
    return f"{value * scale:.{digits}g}"


def run(args: argparse.Namespace) -> int:
    import json
    import math

    from solver.unit import UnitGeometry, simulate_unit

    mm = 1e-3
    g = UnitGeometry(L=args.L * mm, h=args.h * mm, t=args.t * mm, w=args.w * mm, b=args.b * mm, E=args.E)
    if args.nodes is not None and args.nodes < 11:
        raise ValueError(f"--nodes must be >= 11; got {args.nodes}")
    r = simulate_unit(g, nodes=args.nodes, method=args.method)
    rows = [
        ("status", r.status, ""),
        ("bistable", _fmt(r.bistable), ""),
        ("F_cr", _fmt(r.F_cr), "N"),
        ("d_cr", _fmt(r.d_cr, 1e3), "mm"),
        ("d_unstable (ii)", _fmt(r.d_unstable, 1e3), "mm"),
        ("d_second (iii)", _fmt(r.d_second, 1e3), "mm"),
        ("S", _fmt(r.S, 1e3), "mm"),
        ("S/L", _fmt(r.S / g.L if r.S == r.S else math.nan), ""),
        ("theta", _fmt(r.theta_deg), "deg"),
        ("energy barrier", _fmt(r.energy_barrier, 1e3), "mJ"),
        ("energy stored (iii)", _fmt(r.energy_stored, 1e3), "mJ"),
        ("self-standing", _fmt(r.self_standing), ""),
        ("nodes", str(r.n_nodes), ""),
        ("solve time", _fmt(r.solve_time, 1e3, 3), "ms"),
    ]
    print(f"unit L={args.L:g} h={args.h:g} t={args.t:g} w={args.w:g} b={args.b:g} mm, E={args.E:g} Pa")
    for name, value, unit in rows:
        print(f"  {name:<20} {value:>12} {unit}")
    if args.json:
        payload = {k: (None if isinstance(v, float) and v != v else v) for k, v in r.summary().items()}
        payload["geometry_m"] = {k: getattr(g, k) for k in ("L", "h", "t", "w", "b", "E")}
        payload["curve"] = {"d_m": r.curve[0].tolist(), "F_N": r.curve[1].tolist()}
        with open(args.json, "w") as fh:
            json.dump(payload, fh, indent=1)
        print(f"wrote {args.json}")
    if args.plot:
        from snapmorph.plotting.unit import plot_unit

        plot_unit(r, args.plot)
        print(f"wrote {args.plot}")
    return 0 if r.status in ("ok", "monostable") else 1
