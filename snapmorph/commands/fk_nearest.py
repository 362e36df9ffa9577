"""`snapmorph fk --units units.csv --nearest target.svg`: the snap pattern of an array closest
to a target (issue 24), found by branch and bound over its 2ⁿ states
(`design.nearest.nearest_state`). `snapmorph fk` hands over to `run_nearest` when --nearest is
given; --plot draws the target and the nearest state, --csv writes its base (mm)."""

from __future__ import annotations


def run_nearest(args) -> int:
    """args as parsed by `snapmorph fk` (--units, --nearest, --plot, --csv, --map)."""
    import math

    from snapmorph.cli import CommandError
    from snapmorph.commands._common import input_file, output_file, plot_file, read_target_arg

    units_path = input_file(args.units, "--units")
    target_file = read_target_arg(args.nearest, "--nearest", select=getattr(args, "select", None),
                                  units=getattr(args, "target_units", None),
                                  units_option="--target-units")
    if getattr(args, "map", None):
        input_file(args.map, "--map")
    for option, given in (("--all", getattr(args, "all", False)),
                          ("--state", getattr(args, "state", None)),
                          ("--snapped", getattr(args, "snapped", None)),
                          ("--overlay", getattr(args, "overlay", None))):
        if given:
            raise CommandError(f"{option} does not go with --nearest (it finds the state; the "
                               "plot draws the target)")
    if getattr(args, "source", "map") != "map":
        raise CommandError("--nearest searches the design map's states: leave out --source "
                           "simulate")
    plot_file(args.plot, "--plot")
    output_file(args.csv, "--csv")

    import numpy as np

    from snapmorph.design.lookup import MapLookup, load_map
    from snapmorph.design.nearest import nearest_state
    from snapmorph.design.units import read_units_csv

    dm = load_map(getattr(args, "map", None))
    units = read_units_csv(units_path, b_over_L=MapLookup(dm).b_over_L)
    arched = sum(not u.is_spacer for u in units)
    for note in target_file.notes:
        print(f"note: {note}")
    r = nearest_state(units, target_file.target(what=f"--nearest {args.nearest}"), design_map=dm)
    x0, y0, a0 = r.placement
    L = r.target_length
    print(f"{args.units}: {len(units)} units ({arched} arched, 2^{arched} = {2 ** arched} "
          f"states), {r.array_length * 1e3:.1f} mm; target {args.nearest}: {L * 1e3:.1f} mm")
    print(f"nearest state {r.state} (1 = snapped, unit 1 first)")
    for mode, what in (("best", "best rigid placement"), ("clamped", "start clamped on the "
                                                                     "target's start")):
        mx, rms = r.deviations[mode]
        print(f"  deviation, {what:<36} max {100 * mx:6.2f} % ({mx * L * 1e3:.2f} mm), "
              f"RMS {100 * rms:5.2f} %")
    print(f"  placement of unit 1's start: ({x0 * 1e3:.2f}, {y0 * 1e3:.2f}) mm, "
          f"{math.degrees(a0):.2f} deg")
    print(f"  branch and bound: {r.nodes} tree nodes in {r.rounds} round(s), "
          f"{'exact' if r.exact else 'node budget reached'}, {r.time:.2f} s")
    for note in r.notes:
        print(f"note: {note}")
    if args.csv:
        np.savetxt(args.csv, r.predicted * 1e3, delimiter=",", fmt="%.4f", header="x_mm,y_mm",
                   comments="")
        print(f"wrote {args.csv}")
    if args.plot:
        from snapmorph.design.multishape_plots import plot_nearest

        title = f"{args.units}: nearest state to {args.nearest}"
        print(f"wrote {plot_nearest(r, args.plot, title=title)}")
    return 0
