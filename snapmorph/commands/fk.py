"""`snapmorph fk`: forward kinematics of an array in one or every snapping state (Section 3)."""

from __future__ import annotations

import argparse

HELP = "shape of an array of units in a snapping state (forward kinematics)"


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser("fk", help=HELP, description=HELP + ".")
    p.add_argument("--units", required=True, help="units.csv (unit, L_mm, h_mm, t_mm, w_mm, side)")
    p.add_argument("--state", default=None,
                   help="one character per unit, '1' = snapped, e.g. 101 (default: all snapped)")
    p.add_argument("--all", action="store_true", help="every state (2^n), plotted in one figure")
    p.add_argument("--plot", default=None, help="write a figure (PNG/PDF/SVG)")
    p.add_argument("--csv", default=None, help="write the base polyline (mm) of --state")
    p.add_argument("--source", choices=("map", "simulate"), default="map",
                   help="unit shapes from the design map or a direct simulation "
                        "(default %(default)s)")
    p.add_argument("--map", default=None, help="design map netCDF (default: the committed map)")
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    import math

    import numpy as np

    from design import all_states, chain, parse_state, read_units_csv
    from design.lookup import MapLookup, load_map

    lookup = MapLookup(load_map(args.map)) if args.source == "map" else None
    units = read_units_csv(args.units, b_over_L=lookup.b_over_L if lookup else 0.0)
    if args.all:
        states = all_states(units, source=args.source,
                            design_map=lookup.dm if lookup else None, chains=True)
        print(f"{len(units)} units, {len(states)} states; end point and end direction:")
        for key, c in states.items():
            print(f"  {key}: ({c.xy[-1, 0] * 1e3:8.1f}, {c.xy[-1, 1] * 1e3:8.1f}) mm, "
                  f"{math.degrees(c.angles[-1]):7.1f} deg")
        if args.plot:
            from design.plots import plot_states

            figure = plot_states({k: c.xy for k, c in states.items()}, args.plot,
                                 title=str(args.units))
            print(f"wrote {figure}")
        return 0
    snapped = parse_state(args.state, len(units))
    key = "".join("1" if s else "0" for s in snapped)
    ch = chain(units, snapped, source=args.source, lookup=lookup)
    print(f"state {key}: {len(units)} units")
    print(f"{'joint':>5} {'x_mm':>9} {'y_mm':>9} {'dir_deg':>8}")
    for i, (p, a) in enumerate(zip(ch.joints, ch.angles)):
        print(f"{i:>5} {p[0] * 1e3:9.2f} {p[1] * 1e3:9.2f} {math.degrees(a):8.2f}")
    if args.csv:
        np.savetxt(args.csv, ch.xy * 1e3, delimiter=",", fmt="%.4f", header="x_mm,y_mm",
                   comments="")
        print(f"wrote {args.csv}")
    if args.plot:
        from design.plots import plot_state

        print(f"wrote {plot_state(ch.xy, args.plot, units, ch.joints, title=f'state {key}')}")
    return 0
