"""`snapmorph fk`: forward kinematics of an array in one or every snap pattern (Section 3)."""

from __future__ import annotations

import argparse

HELP = "shape of an array of units in a snap pattern (forward kinematics)"
EPILOG = """Frame: when units.csv starts with a '# placement' line (written by `snapmorph
design`), shapes, printed joints and --csv are in the target's frame (where the design put unit
1); otherwise unit 1 starts at (0, 0) heading +x. --overlay draws a target (the design's
target.csv, or the SVG, DXF or CSV it was designed from: --select, --target-units as for
`snapmorph design`) in the same frame and prints the largest distance from its points to the
base."""


def add_parser(subparsers) -> argparse.ArgumentParser:
    from snapmorph.commands._common import (add_shape_options, add_snapped_option,
                                            add_target_options)

    p = subparsers.add_parser("fk", help=HELP, description=HELP + ".", epilog=EPILOG)
    p.add_argument("--units", required=True,
                   help="units.csv (unit, L_mm, h_mm, t_mm, w_mm, side[, b_mm])")
    add_snapped_option(p, ", '0' for spacers, e.g. 101 (default: every arched unit snapped)")
    p.add_argument("--all", action="store_true",
                   help="every snap pattern (2^n), plotted in one figure")
    add_shape_options(p, plot="write a figure (PNG/PDF/SVG)",
                      csv="write the base polyline (mm) of --snapped",
                      overlay="draw this target (.svg, .dxf or .csv) over the shapes, same "
                              "frame",
                      start="start at (0, 0) heading +x")
    p.add_argument("--nearest", default=None, metavar="TARGET",
                   help="the snap pattern closest to this target (.csv/.svg/.dxf, mm), by branch "
                        "and bound over the 2^n patterns; --plot and --csv show it")
    add_target_options(p, "--target-units", what="the --overlay or --nearest target")
    p.add_argument("--source", choices=("map", "simulate"), default="map",
                   help="unit shapes from the design map or a direct simulation "
                        "(default %(default)s)")
    p.add_argument("--map", default=None, help="design map netCDF (default: the committed map)")
    p.set_defaults(run=run)
    return p


MAX_ALL = 10  # --all: at most 2^10 snap patterns


def check_all(units, most, option):
    """Refuse `option` (every snap pattern) for more than `most` arched units."""
    from snapmorph.commands._common import CommandError

    n = sum(not u.is_spacer for u in units)
    if n > most:
        raise CommandError(f"{option} would draw 2^{n} states ({2 ** n}); it takes at most "
                           f"{most} arched units (give one --snapped instead)")


def check_snapped(text, units, option="--snapped"):
    """Booleans for a '0'/'1' snap pattern of `units`; None gives every arched unit snapped.
    A '1' on a spacer (h = 0) is refused: a spacer has one state only."""
    from snapmorph.commands._common import CommandError

    n = len(units)
    if text is None:
        return [not u.is_spacer for u in units]
    s = text.strip()
    if len(s) != n or any(ch not in "01" for ch in s):
        raise CommandError(f"{option} must be {n} characters 0/1, one per unit in units.csv "
                           f"(1 = snapped); got {text!r}")
    bad = [i + 1 for i, (ch, u) in enumerate(zip(s, units)) if ch == "1" and u.is_spacer]
    if bad:
        raise CommandError(f"{option} {text}: unit(s) {', '.join(map(str, bad))} are spacers "
                           f"(h_mm = 0, side = 0) with one state only; put 0 there")
    return [ch == "1" for ch in s]


def load_units(args):
    """(units, placement or None) from --units; the target from --overlay (m) or None."""
    from snapmorph.design.units import read_placement, read_units_csv
    from snapmorph.commands._common import input_file, read_target_arg

    path = input_file(args.units, "--units")
    b_over_L = getattr(args, "_b_over_L", 0.0)
    units = read_units_csv(path, b_over_L=b_over_L)
    placement = None if args.no_placement else read_placement(path)
    target = None
    if args.overlay:
        target = read_target_arg(args.overlay, "--overlay", select=args.select,
                                 units=args.target_units, units_option="--target-units").points
    return units, placement, target


def run(args) -> int:
    import math

    if args.nearest:  # the snap pattern closest to a target (issue 24)
        from snapmorph.commands.fk_nearest import run_nearest

        return run_nearest(args)

    from snapmorph.commands._common import input_file, output_file, plot_file, typed_name

    # Paths first: nothing long runs before a bad path is refused.
    input_file(args.units, "--units")
    if args.map:
        input_file(args.map, "--map")
    if args.overlay:
        input_file(args.overlay, "--overlay")
    plot_file(args.plot, "--plot")
    output_file(args.csv, "--csv")
    snapped_option = typed_name(args, "snapped", "--snapped")
    if args.all and (args.snapped or args.csv):
        from snapmorph.commands._common import CommandError

        raise CommandError(f"{snapped_option} and --csv apply to one snap pattern, not with "
                           "--all")

    import numpy as np

    from snapmorph.design import all_snap_patterns, chain
    from snapmorph.design.lookup import MapLookup, load_map
    from snapmorph.design.targets import distances_to_polyline
    from snapmorph.plotting.arrays import plot_fk_state, plot_fk_states

    # Read and check the files and the snap pattern before loading the map (the slow part).
    units, placement, target = load_units(args)
    if not args.all:
        check_snapped(args.snapped, units, snapped_option)
    else:
        check_all(units, MAX_ALL, "--all")
    lookup = MapLookup(load_map(args.map)) if args.source == "map" else None
    if lookup is not None and lookup.b_over_L:
        args._b_over_L = lookup.b_over_L
        units, placement, target = load_units(args)
    start, start_angle = ((placement[0], placement[1]), placement[2]) if placement else \
        ((0.0, 0.0), 0.0)
    frame = ("target's frame (units.csv placement: start "
             f"({start[0] * 1e3:.2f}, {start[1] * 1e3:.2f}) mm, "
             f"{math.degrees(start_angle):.2f} deg)") if placement else \
        "array frame (unit 1 starts at (0, 0) heading +x)"
    if args.all:
        states = all_snap_patterns(units, source=args.source,
                                   design_map=lookup.dm if lookup else None, chains=True,
                                   start=start, start_angle=start_angle)
        print(f"{len(units)} units, {len(states)} states, {frame}; end point and end direction:")
        for key, c in states.items():
            print(f"  {key}: ({c.xy[-1, 0] * 1e3:8.1f}, {c.xy[-1, 1] * 1e3:8.1f}) mm, "
                  f"{math.degrees(c.angles[-1]):7.1f} deg")
        if args.plot:
            figure = plot_fk_states({k: c.xy for k, c in states.items()}, args.plot,
                                    title=str(args.units), target=target, placement=placement)
            print(f"wrote {figure}")
        return 0
    snapped = check_snapped(args.snapped, units, snapped_option)
    key = "".join("1" if s else "0" for s in snapped)
    ch = chain(units, snapped, source=args.source, lookup=lookup, start=start,
               start_angle=start_angle)
    print(f"state {key}: {len(units)} units, {frame}")
    print(f"{'joint':>5} {'x_mm':>9} {'y_mm':>9} {'dir_deg':>8}")
    for i, (p, a) in enumerate(zip(ch.joints, ch.angles)):
        print(f"{i:>5} {p[0] * 1e3:9.2f} {p[1] * 1e3:9.2f} {math.degrees(a):8.2f}")
    if target is not None:
        dist = distances_to_polyline(target, ch.xy)
        print(f"overlay {args.overlay}: {len(target)} target points, largest distance to the "
              f"base {dist.max() * 1e3:.2f} mm (point {int(dist.argmax()) + 1})")
    if args.csv:
        np.savetxt(args.csv, ch.xy * 1e3, delimiter=",", fmt="%.4f", header="x_mm,y_mm",
                   comments="")
        print(f"wrote {args.csv}")
    if args.plot:
        figure = plot_fk_state(ch.xy, ch.joints, args.plot, title=f"state {key}: {args.units}",
                               target=target, placement=placement)
        print(f"wrote {figure}")
    return 0
