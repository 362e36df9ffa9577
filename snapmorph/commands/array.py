"""`snapmorph array`: simulate a whole array, snapping units one at a time (issue 6)."""

from __future__ import annotations

import argparse
import math

HELP = "simulate a whole array (one DER model), snapping units one at a time"
DESCRIPTION = """Simulate an array as one DER model: one end clamped, no gravity; each unit is
snapped by its own self-equilibrated actuator (apex pushed towards its base, reaction on its two
supports), which is then released. Compares the base with forward kinematics built from
directly simulated single units (source "simulate").

  snapmorph array --units units.csv --snapped 101 [--order 2,0] [--plot f.png] [--csv f.csv]
  snapmorph array --units units.csv --all --out DIR      every state, overlay plots, tables
  snapmorph array --paper-three [--out DIR]              the paper's three units, 8 states
  snapmorph array --paper-M [--out DIR]                  the paper's Table 3 M array, 16 states
  snapmorph array --units units.csv --gravity --orientation upright --material petg
        [--load 2:apex:0,-0.05]     the morphed array under its weight and loads: sag (mm),
                                    states held, the load the first unit snaps back at, strain

Lengths in units.csv are millimetres. An arch's flat-end length b is its b_mm column (as
`snapmorph design --b` writes it); a units.csv without that column gets b = --b-over-L x L
(default 0)."""


def add_parser(sub) -> argparse.ArgumentParser:
    from snapmorph.commands._common import (add_shape_options, add_snapped_option, integer,
                                            length_mm, number)

    p = sub.add_parser("array", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--units", help="units.csv (unit, L_mm, h_mm, t_mm, w_mm, side[, b_mm])")
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
                   help="b / L of the arched units read from a --units file without a "
                        "b_mm column (default 0)")
    p.add_argument("--b", type=length_mm(0.0, low_inclusive=True, what="flat end length b"),
                   default=None,
                   help="with --paper-three: b in mm (default 5 = w, the specimens)")
    p.add_argument("--nodes", type=integer(11, 100000, what="base nodes per unit"), default=None,
                   help="resolution: base nodes per unit (default 161, as snapmorph unit)")
    p.add_argument("--E", type=number("Pa", 0.0, 1e13, what="Young's modulus"), default=None,
                   help="Young's modulus, Pa (default the paper's PETG, 2.2e9; with --gravity "
                        "the --material's)")
    add_shape_options(p, plot="single state: write a figure (PNG/PDF/SVG)",
                      csv="single state: write the base polyline (mm)",
                      overlay="with --units: draw this target (x_mm, y_mm) over the shapes",
                      start="clamp at (0, 0), heading +x")
    p.add_argument("--no-fk", action="store_true",
                   help="skip the comparison with forward kinematics")
    add_load_options(p)
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
    if study and (args.gravity is not None or args.load):
        raise CommandError("--gravity and --load apply to one snap pattern (--units, not with "
                           "--all, --paper-three, --paper-M)")
    _check_paths(args, study)
    return study


def _check_paths(args, study):
    """Refuse unreadable inputs and unwritable outputs before simulating anything."""
    from snapmorph.commands._common import input_file, output_dir, output_file, plot_file

    if args.units:
        input_file(args.units, "--units")
        _check_b_source(args)
    if args.overlay:
        input_file(args.overlay, "--overlay")
    if study:
        if args.out:
            output_dir(args.out, "--out")
    else:
        plot_file(args.plot, "--plot")
        output_file(args.csv, "--csv")


def _check_b_source(args):
    """--b-over-L and a units.csv with b_mm would give b twice: refuse rather than ignore one."""
    from snapmorph.cli import CommandError
    from snapmorph.design.units import has_b_column

    try:
        both = args.b_over_L > 0 and has_b_column(args.units)
    except (OSError, UnicodeDecodeError):
        return  # read_units_csv says what is wrong with the file
    if both:
        raise CommandError(f"--b-over-L {args.b_over_L:g}: {args.units} has a b_mm column, which "
                           "gives each arch's b; leave --b-over-L out (or drop the column)")


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
        s = run_study(units, name=name, nodes=args.nodes, E=2.2e9 if args.E is None else args.E,
                      fk=not args.no_fk)
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
    loads = _loads(args, units)
    dead = {} if args.gravity is None and not loads else dict(
        gravity=args.gravity, orientation=args.orientation, material=args.material,
        loads=loads, max_factor=args.max_factor)
    r = simulate_array(units, snapped, order=args.order, nodes=args.nodes, E=args.E, **dead)
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
        ch = chain(units, snapped, source="simulate", nodes=r.model.nodes, E=r.model.E)
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
    for overlap in r.interference:
        print(f"OVERLAP: {overlap}")
    if r.loaded is not None:
        print_loaded(r)
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
    return 0 if r.status == "ok" and (r.loaded is None or r.loaded.holds) else 1


# ------------------------------------------------------------------ dead loads (issue 23)
def add_load_options(p) -> None:
    """--gravity, --orientation, --material, --load, --max-factor."""
    from snapmorph.commands._common import number

    p.add_argument("--gravity", nargs="?", const=9.81, default=None,
                   type=number("m/s^2", 0.0, 1e4, low_inclusive=True, what="g"), metavar="G",
                   help="load the morphed array with its own weight (G m/s^2, default 9.81), "
                        "clamped at its start: prints the sag (mm), the states held, the "
                        "load the first unit snaps back at and the largest strain")
    p.add_argument("--orientation", default="upright", type=_orientation,
                   help="upright (gravity in the array's plane, -z of the array frame; "
                        "default), sideways (normal to it, as the paper's test: no in-plane "
                        "load) or an angle in degrees, -360 to 360 (gravity turned to "
                        "(sin a, -cos a): 90 hangs from the clamp, -90 stands on it)")
    p.add_argument("--material", default=None, type=_material,
                   help="petg, pla or paper (solver.materials presets: density, E, allowable "
                        "strain; default paper: E 2.2 GPa, 1300 kg/m^3)")
    p.add_argument("--load", action="append", default=[], metavar="UNIT:WHERE:FX,FZ",
                   help="a dead load in N on unit UNIT (0-based index) at its apex or end, "
                        "in the array frame, e.g. 2:apex:0,-0.05 (repeatable)")
    p.add_argument("--max-factor", type=number("", 1.0, 1e6, low_inclusive=True,
                                               what="load factor"), default=10.0,
                   help="look for the first snap-back up to this factor on the loads "
                        "(1 <= factor <= 1e6; default %(default)s)")


def _orientation(text):
    import argparse

    if text in ("upright", "sideways"):
        return text
    try:
        a = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be upright, sideways or an angle in degrees (-360 to 360); got {text!r}") from None
    if not (-360.0 <= a <= 360.0):
        raise argparse.ArgumentTypeError(
            f"must be an angle in degrees, -360 to 360 (or upright, sideways); got {text!r}")
    return a


def _material(text):
    import argparse

    from snapmorph.solver.materials import MATERIALS

    if text.lower() not in MATERIALS:
        raise argparse.ArgumentTypeError(
            f"must be one of {', '.join(sorted(MATERIALS))}; got {text!r}")
    return text.lower()


def _loads(args, units) -> list:
    """[ArrayLoad] from the --load texts; CommandError naming --load and the form."""
    from snapmorph.cli import CommandError
    from snapmorph.design.array_loads import ArrayLoad, check_loads
    out = []
    form = "UNIT:WHERE:FX,FZ (unit index 0-based, WHERE apex or end, forces in N)"
    for text in args.load:
        parts = text.split(":")
        try:
            unit, where, force = int(parts[0]), parts[1], [float(v) for v in parts[2].split(",")]
        except (IndexError, ValueError):
            raise CommandError(f"--load {text}: must be {form}, e.g. 2:apex:0,-0.05") from None
        if len(parts) != 3 or len(force) != 2:
            raise CommandError(f"--load {text}: must be {form}, e.g. 2:apex:0,-0.05")
        out.append(ArrayLoad(unit, where, tuple(force)))
    if out:
        try:
            check_loads(out, units)
        except ValueError as exc:
            raise CommandError(f"--load: {exc}") from None
    return out


def print_loaded(r) -> None:
    """The loaded array's sag, states, limit load and strains, in mm and N."""
    ld = r.loaded
    mat = ld.material
    what = []
    if ld.g > 0:
        what.append(f"its own weight ({mat.name}, {mat.density:g} kg/m^3, g {ld.g:g} m/s^2, "
                    f"{ld.orientation if isinstance(ld.orientation, str) else f'{ld.orientation:g} deg'})")
    if ld.loads:
        what.append(f"{len(ld.loads)} load(s)")
    print(f"under {' and '.join(what)}: {ld.status}; total dead load {ld.total_load:.4g} N")
    for note in ld.notes:
        print(f"note: {note}")
    dx, dz = ld.sag * 1e3
    print(f"free end sag: {ld.sag_m * 1e3:.3f} mm (dx {dx:+.3f}, dz {dz:+.3f} mm, array frame)")
    h0, h1 = ld.heights
    print(f"{'unit':>4} {'state':>7} {'apex/h before':>13} {'under load':>10} {'strain %':>8}  where"
          "  (unit: 0-based index; apex/h: apex above its support chord, < 0 snapped)")
    for i, u in enumerate(r.units):
        if u.is_spacer:
            print(f"{i:>4} {'spacer':>7}")
            continue
        state = "held" if ld.held[i] else "LOST"
        s, where = ld.strains[i]
        print(f"{i:>4} {state:>7} {h0[i]:13.3f} {h1[i]:10.3f} {100 * s:8.3f}  {where}")
    if ld.limit_factor is None:
        searched = "not looked for" if ld.max_factor <= 1 else f"none up to factor {ld.max_factor:g}"
        print(f"limit load: {searched} (no unit snaps back under {ld.max_factor:g} x the "
              f"loads, {ld.max_factor * ld.total_load:.4g} N)")
    else:
        print(f"limit load: unit index {ld.limit_unit} snaps back first, at load factor "
              f"{ld.limit_factor:.4g} ({ld.limit_load:.4g} N; {ld.limit_kind})")
    snap = max((s.strain_max for s in r.snaps), default=0.0)
    allow = "" if mat is None or not math.isfinite(mat.allowable_strain) else \
        f"; allowable {100 * mat.allowable_strain:.2f} % ({mat.name})"
    k = max(range(len(ld.strains)), key=lambda i: ld.strains[i][0])
    print(f"largest strain: {100 * ld.strain_max:.3f} % under the loads (unit index {k}, "
          f"{ld.strains[k][1]}), "
          f"{100 * snap:.3f} % while snapping{allow}")
