"""`snapmorph array`: simulate a whole array, snapping units one at a time (issue 6)."""

from __future__ import annotations

import argparse

HELP = "simulate a whole array (one DER model), snapping units one at a time"
DESCRIPTION = """Simulate an array as one DER model: one end clamped, no gravity; each unit is
snapped by its own self-equilibrated actuator (apex pushed towards its base, reaction on its two
supports), which is then released. Compares the base with forward kinematics built from
directly simulated single units (source "simulate").

  snapmorph array --units units.csv --snapped 101 [--order 2,0] [--plot f.png] [--csv f.csv]
  snapmorph array --units units.csv --all --out DIR      every state, overlay plots, tables
  snapmorph array --paper-three [--out DIR]              the paper's three units, 8 states
  snapmorph array --paper-M [--out DIR]                  the paper's Table 3 M array, 16 states

Lengths in units.csv are millimetres; units.csv has no b column (--b-over-L sets b = b/L L)."""


def add_parser(sub) -> argparse.ArgumentParser:
    from snapmorph.commands._common import (add_shape_options, add_snapped_option, integer,
                                            length_mm, number)

    p = sub.add_parser("array", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--units", help="units.csv (unit, L_mm, h_mm, t_mm, w_mm, side)")
    what.add_argument("--paper-three", action="store_true",
                      help="every state of the paper's three units (t 0.5, h 20, w 5, L 100 mm)")
    what.add_argument("--paper-M", action="store_true",
                      help="every state of the paper's inverse-designed M (Table 3 units)")
    add_snapped_option(p, ", e.g. 101 (default: every arched unit snapped)")
    p.add_argument("--order", default=None,
                   help="snapping order, 0-based unit indices, e.g. 2,0 (default ascending; "
                        "units listed but not snapped in --snapped are skipped)")
    p.add_argument("--all", action="store_true", help="with --units: every state (a study)")
    p.add_argument("--b-over-L", type=number("", 0.0, 0.5, low_inclusive=True,
                                             high_inclusive=False, what="b / L"), default=0.0,
                   help="b / L of the arched units read from --units (default 0)")
    p.add_argument("--b", type=length_mm(0.0, low_inclusive=True, what="flat end length b"),
                   default=None,
                   help="with --paper-three: b in mm (default 5 = w, the specimens)")
    p.add_argument("--nodes", type=integer(11, 100000, what="base nodes per unit"), default=None,
                   help="resolution: base nodes per unit (default 161, as snapmorph unit)")
    p.add_argument("--E", type=number("Pa", 0.0, 1e13, what="Young's modulus"), default=2.2e9,
                   help="Young's modulus, Pa (default PETG)")
    add_shape_options(p, plot="single state: write a figure (PNG/PDF/SVG)",
                      csv="single state: write the base polyline (mm)",
                      overlay="with --units: draw this target (x_mm, y_mm) over the shapes",
                      start="clamp at (0, 0), heading +x")
    p.add_argument("--no-fk", action="store_true",
                   help="skip the comparison with forward kinematics")
    p.add_argument("--out", default=None,
                   help="study: folder for study.md, study.json, states.png "
                        "(default build/array/<name>)")
    p.set_defaults(run=run)
    return p


def _check(args):
    from snapmorph.cli import CommandError
    from snapmorph.commands._common import typed_name

    study = args.paper_three or args.paper_M or args.all
    if study and (args.snapped or args.order or args.plot or args.csv):
        raise CommandError(f"{typed_name(args, 'snapped', '--snapped')}, --order, --plot and "
                           "--csv apply to one snap pattern (not with --all, --paper-three, "
                           "--paper-M)")
    if args.all and not args.units:
        raise CommandError("--all needs --units")
    if args.b is not None and not args.paper_three:
        raise CommandError("--b applies to --paper-three (use --b-over-L with --units)")
    if not (0.0 <= args.b_over_L < 0.5):
        raise CommandError(f"--b-over-L must be in [0, 0.5); got {args.b_over_L}")
    if args.b is not None and args.b < 0:
        raise CommandError(f"--b must be >= 0 mm; got {args.b}")
    if args.overlay and not args.units:
        raise CommandError("--overlay needs --units")
    _check_paths(args, study)
    return study


def _check_paths(args, study):
    """Refuse unreadable inputs and unwritable outputs before simulating anything."""
    from snapmorph.commands._common import input_file, output_dir, output_file, plot_file

    if args.units:
        input_file(args.units, "--units")
    if args.overlay:
        input_file(args.overlay, "--overlay")
    if study:
        if args.out:
            output_dir(args.out, "--out")
    else:
        plot_file(args.plot, "--plot")
        output_file(args.csv, "--csv")


def run(args) -> int:
    import json
    from pathlib import Path

    study = _check(args)
    if study:
        from snapmorph.design.array_plots import plot_study
        from snapmorph.design.array_study import paper_three_units, run_study, table3_M_units
        if args.paper_three:
            b = None if args.b is None else args.b * 1e-3
            units = paper_three_units(b)
            name = f"paper three units (b = {units[0].b * 1e3:g} mm)"
            folder = "three_units"
        elif args.paper_M:
            units, name, folder = table3_M_units(), "paper Table 3 M (b = 0)", "M"
        placement = target = None
        if args.units:
            units, placement, target = _read_units(args)
            name, folder = str(args.units), Path(args.units).stem
        from snapmorph.commands._common import output_dir

        out = output_dir(Path(args.out) if args.out else Path("build/array") / folder, "--out")
        from snapmorph.commands.fk import check_all

        check_all(units, 8, "--all")
        n_arched = sum(not u.is_spacer for u in units)
        print(f"simulating {2 ** n_arched} states of {len(units)} units (a few seconds each) ...",
              flush=True)
        s = run_study(units, name=name, nodes=args.nodes, E=args.E, fk=not args.no_fk)
        print(s.table())
        (out / "study.md").write_text(s.table() + "\n")
        (out / "study.json").write_text(json.dumps(s.summary(), indent=1, default=float) + "\n")
        png = plot_study(s, out / "states.png", title=name, placement=placement, target=target)
        print(f"wrote {out / 'study.md'}, {out / 'study.json'}, {png}")
        return 0 if s.ok else 1
    return _one_state(args)


def _read_units(args):
    """(units, placement or None, overlay target in m or None) from --units / --overlay."""
    from snapmorph.design.targets import read_target_csv
    from snapmorph.design.units import read_placement, read_units_csv

    units = read_units_csv(args.units, b_over_L=args.b_over_L)
    placement = None if args.no_placement else read_placement(args.units)
    target = read_target_csv(args.overlay)[0] if args.overlay else None
    return units, placement, target


def _one_state(args) -> int:
    import math

    import numpy as np

    from snapmorph.design.array_study import curve_deviation
    from snapmorph.design.arrays import simulate_array
    from snapmorph.design.kinematics import chain
    from snapmorph.design.targets import distances_to_polyline
    from snapmorph.commands._common import typed_name
    from snapmorph.commands.fk import check_snapped
    from snapmorph.plotting.arrays import transform

    units, placement, target = _read_units(args)
    snapped = check_snapped(args.snapped, units, typed_name(args, "snapped", "--snapped"))
    if args.order is not None:
        from snapmorph.design.arrays import _order
        from snapmorph.commands._common import CommandError

        try:
            _order(args.order, snapped, len(units))
        except ValueError as exc:
            raise CommandError(f"--order {args.order}: {exc} (e.g. --order 2,0)") from None
    print(f"simulating {len(units)} units, snapping {sum(snapped)} of them one at a time ...",
          flush=True)
    r = simulate_array(units, snapped, order=args.order, nodes=args.nodes, E=args.E)
    key = "".join("1" if s else "0" for s in snapped)
    print(f"state {key}: {len(units)} units, snapped in the order "
          f"{', '.join(str(k) for k in r.order) or '-'} (0-based); status {r.status}; "
          f"{r.time:.2f} s")
    for k, s in enumerate(r.snaps, start=1):
        print(f"  snap {k}: unit index {s.unit} ({s.status}): F_cr {s.F_cr:.4g} N at "
              f"{s.d_cr * 1e3:.3g} mm, zero force at {s.d_zero * 1e3:.4g} mm, turned "
              f"{s.turn_deg:.3f} deg after release, {s.steps} steps, {s.time:.2f} s")
    fk = None
    if not args.no_fk and r.status == "ok":
        ch = chain(units, snapped, source="simulate", nodes=r.model.nodes, E=args.E)
        fk = ch.xy
        length = r.model.length
        print(f"forward kinematics (source simulate): max deviation "
              f"{100 * curve_deviation(r.base, fk, length):.3f} % of the array length, tip "
              f"{np.hypot(*(r.base[-1] - fk[-1])) * 1e3:.3f} mm, end direction "
              f"{math.degrees(r.angles[-1] - ch.angles[-1]):+.3f} deg")
    turn0 = placement[2] if placement else 0.0
    joints, base = transform(r.joints, placement), transform(r.base, placement)
    if placement:
        print(f"frame: the target's (units.csv placement: clamp at ({placement[0] * 1e3:.2f}, "
              f"{placement[1] * 1e3:.2f}) mm, heading {math.degrees(turn0):.2f} deg)")
    print(f"{'joint':>5} {'x_mm':>9} {'y_mm':>9} {'dir_deg':>8}")
    for i, (p, a) in enumerate(zip(joints, r.angles)):
        print(f"{i:>5} {p[0] * 1e3:9.2f} {p[1] * 1e3:9.2f} {math.degrees(a + turn0):8.2f}")
    if target is not None:
        dist = distances_to_polyline(target, base)
        print(f"overlay {args.overlay}: {len(target)} target points, largest distance to the "
              f"simulated base {dist.max() * 1e3:.2f} mm (point {int(dist.argmax()) + 1})")
    if args.csv:
        np.savetxt(args.csv, base * 1e3, delimiter=",", fmt="%.5f", header="x_mm,y_mm",
                   comments="")
        print(f"wrote {args.csv}")
    if args.plot:
        from snapmorph.design.array_plots import plot_result

        frame = ("target's frame (units.csv placement)" if placement else
                 "array frame: clamp at (0, 0), heading +x")
        figure = plot_result(r, args.plot, fk, title=f"state {key} (1 = snapped); {frame}",
                             placement=placement, target=target)
        print(f"wrote {figure}")
    return 0 if r.status == "ok" else 1
