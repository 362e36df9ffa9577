"""`snapmorph design`: inverse design of an array from a target shape (issue 10).

The target is read as a drawing program wrote it (`design.target_io.read_target_file`:
`--select`, `--units`; its notes printed), refused with one line when its length cannot be an
array's (`design.targets_scale.check_scale`: the likely unit slip), designed, and written in
the drawing's own frame (target.csv, overlay.svg/.dxf) with the workshop's files
(`design.workshop`: `--bed`, `--kerf`, STL molds, assembly sheet).

Exit status: 0 when the design meets --tol (and --tol-mm) and its whole-array verification
confirms it, 1 when not (the best design found is still written, and marked TOLERANCE MISSED
or VERIFICATION FAILED in design.txt and units.csv), 2 for bad input (one line, in mm).
"""

from __future__ import annotations

import argparse

from snapmorph.commands._common import (add_target_options, add_unit_state_option, bed_size,
                                        integer, length_mm, number)

HELP = "design an array of units that snaps into a target shape; write units.csv, drawings, plots"


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "design", help=HELP, description=HELP + ".",
        epilog="target: the one open curve of an SVG (Inkscape: every transform and the "
               "document's units) or DXF file (lines, arcs, polylines, splines, ellipses, "
               "blocks; $INSUNITS), pieces whose ends meet joined, closed curves never; "
               "--select chooses among several; or a CSV of lines 'x_mm, y_mm' (any open "
               "curve, in any orientation) or 'x_mm, y_mm, tangent_deg' (control points with "
               "tangents: biarcs through them). Exit status 1 when --tol (--tol-mm) is missed "
               "or the whole-array verification fails.",
    )
    p.add_argument("target", nargs="+", help="target file: .svg, .dxf or .csv; two or more: "
                   "one array with one snap pattern per target (issue 24)")
    add_target_options(p, several=True)
    p.add_argument("--t", type=float, required=True, help="sheet thickness (mm)")
    p.add_argument("--w", type=float, required=True, help="strip width (mm)")
    p.add_argument("--b", type=length_mm(0.0, low_inclusive=True,
                                         what="extra flat length of the arch ends"),
                   default=None, help="extra flat length of every arch's ends, mm (the paper's "
                   "specimens: b = w; needs a map with a b/L axis, and units then are at least "
                   "b / (its largest b/L) long: 100 mm at b = 5 on the default map); default: "
                   "the map's own b/L")
    p.add_argument("--out", default="build/design", help="output directory (default %(default)s)")
    p.add_argument("--map", default=None, help="design map netCDF (default: the committed map)")
    p.add_argument("--tol", type=float, default=None,
                   help="largest deviation allowed, a fraction of the target's length "
                        "(default 0.01 = 1 %%; 0.02 with several targets)")
    p.add_argument("--tol-mm", type=length_mm(what="largest deviation allowed"), default=None,
                   metavar="MM", help="largest deviation allowed in mm (> 0); with --tol the "
                   "design meets both (the stricter governs)")
    p.add_argument("--placement", choices=("best", "clamped"), default="best",
                   help="the deviation --tol applies to: after the best rigid placement, or with "
                        "unit 1's start clamped on the target's start and tangent "
                        "(default %(default)s; both are printed)")
    p.add_argument("--L-range", default=None, metavar="MIN,MAX",
                   help="unit length range (mm; default: what the map covers at t, w)")
    p.add_argument("--hL-range", default=None, metavar="MIN,MAX",
                   help="h/L range (default: bistable in the map with --min-barrier)")
    p.add_argument("--min-barrier", type=float, default=0.5,
                   help="smallest energy barrier of a unit, E I_arch / L (default %(default)s)")
    p.add_argument("--max-units", type=int, default=40, help="at most this many arched units")
    add_unit_state_option(p, "unit state the map is entered with (default %(default)s: "
                             "actuator removed, as used)")
    p.add_argument("--theta-convention", choices=("ours", "paper"), default="ours",
                   help="'paper': the paper's procedure entering the map with theta_end "
                        "(reproduces its Table 3; such designs over-curve about twice)")
    p.add_argument("--no-verify", action="store_true",
                   help="skip the whole-array simulation of the design")
    p.add_argument("--controls", default=None,
                   help="the paper's procedure: x (mm) of interior control points, comma "
                        "separated (target x increasing)")
    p.add_argument("--max-controls", type=integer(3, what="control points, the two ends included"),
                   default=9,
                   help="paper's procedure, automatic control points: at most this many (>= 3, "
                        "the two ends included; default %(default)s)")
    p.add_argument("--min-turn", type=number("deg", 0, 180, low_inclusive=True,
                                             high_inclusive=False, what="smallest unit turning"),
                   default=None,
                   help="paper's procedure: arcs turning less (deg, 0 <= value < 180) become "
                        "straight spacers")
    p.add_argument("--refine", action="store_true",
                   help="paper's procedure: also refine (L, h) by least squares")
    p.add_argument("--bed", type=bed_size, default=None, metavar="WxH",
                   help="laser bed in mm, e.g. 600x400: every part nested on sheets of that "
                        "size (one DXF/SVG per sheet); one number: only the longest base piece "
                        "(mm). Without it, a warning for a part larger than 600x400 mm")
    p.add_argument("--kerf", type=length_mm(0, 2, low_inclusive=True, what="laser kerf width"),
                   default=0.0, metavar="MM",
                   help="laser kerf width in mm, 0 <= kerf <= 2: cuts offset by half of it "
                        "(default 0: none)")
    p.add_argument("--colours", default=None,
                   help="layer colours as AutoCAD indices, e.g. CUT=1,ENGRAVE=5,MARKS=3")
    p.add_argument("--no-drawings", action="store_true", help="skip DXF/SVG drawings")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (on stderr)")
    add_hold_options(p)
    p.set_defaults(run=run)
    return p


def _pair_mm(text, option, scale):
    from snapmorph.cli import CommandError

    if text is None:
        return None
    try:
        a, b = (float(v) for v in text.split(","))
    except ValueError:
        raise CommandError(f"{option} must be MIN,MAX (two numbers), got {text!r}") from None
    if not (0 < a < b < float("inf")):
        raise CommandError(f"{option} must be MIN,MAX with 0 < MIN < MAX, got {text!r}")
    return a * scale, b * scale


def run(args) -> int:
    import math
    import warnings
    from pathlib import Path

    import numpy as np

    from snapmorph.cli import CommandError
    from snapmorph.commands._common import format_value, per_target, read_target_arg

    if args.tol is None:
        args.tol = 0.02 if len(args.target) > 1 else 0.01
    for name, what in (("t", "sheet thickness"), ("w", "strip width")):
        value = getattr(args, name)
        if not (value > 0 and math.isfinite(value)):
            raise CommandError(f"--{name} must be a positive {what} in mm, got {value}")
    if not (0 < args.tol < 1):
        raise CommandError(f"--tol is a fraction of the target's length, 0 < tol < 1 "
                           f"(0.01 = 1 %), got {args.tol}")
    if args.max_units < 1:
        raise CommandError(f"--max-units must be >= 1, got {args.max_units}")
    if not (args.min_barrier >= 0 and math.isfinite(args.min_barrier)):
        raise CommandError(f"--min-barrier must be >= 0 (E I_arch / L), got {args.min_barrier}")
    L_range = _pair_mm(args.L_range, "--L-range (mm)", 1e-3)
    hL_range = _pair_mm(args.hL_range, "--hL-range", 1.0)
    colours = _colours(args.colours)
    controls = None
    if args.controls:
        try:
            controls = np.array([float(v) for v in args.controls.split(",") if v.strip()]) * 1e-3
        except ValueError:
            raise CommandError(f"--controls must be comma-separated numbers (mm), "
                               f"got {args.controls!r}") from None
    hold = hold_options(args)
    if len(args.target) > 1 and args.b is not None:
        raise CommandError("--b applies to the design of one target (several targets share "
                           "the map's own b/L)")
    if len(args.target) > 1:  # one array, several shapes (issue 24)
        if hold:
            raise CommandError("--material, --orientation, --max-strain and --min-backload "
                               "apply to one target")
        from snapmorph.commands.design_multi import run_multi

        return run_multi(args, L_range=L_range, hL_range=hL_range, colours=colours)
    args.target = args.target[0]
    select, units = per_target(args, 1)[0]
    if args.map is not None and not Path(args.map).is_file():
        raise CommandError(f"--map {args.map}: design map not found (no such file)")
    tf = read_target_arg(args.target, select=select, units=units)
    from tqdm import tqdm

    from snapmorph.design import inverse_design
    from snapmorph.design.lookup import load_map
    from snapmorph.design.targets_scale import check_points_scale
    from snapmorph.commands._common import output_dir

    dm = load_map(args.map)
    print(f"target {args.target}: {tf.source}, {format_value(tf.length_mm)} mm")
    for note in tf.notes:
        print(f"note: {note}")
    check_points_scale(tf.points, args.t * 1e-3, args.w * 1e-3, design_map=dm,
                       L_range=L_range, max_units=args.max_units)  # (before the progress bar)
    output_dir(args.out)  # before the design: a folder that cannot be written fails at once
    # one bar for the whole command: it counts the work done (layouts tried, least-squares
    # evaluations of --refine) and names the stage; the whole-array simulation is one step
    bar = tqdm(desc="design", unit=" step", leave=False, disable=args.no_progress or None)

    shown = ["design"]

    def progress(stage):
        if shown[0] != stage:  # (a disabled bar has no desc to compare with)
            shown[0] = stage
            bar.set_description_str(stage)
        bar.update()

    with warnings.catch_warnings(), bar:
        warnings.simplefilter("ignore")  # the summary says it all, once
        d = inverse_design(tf, t=args.t * 1e-3, w=args.w * 1e-3, controls=controls,
                           design_map=dm, tol=args.tol,
                           tol_abs=None if args.tol_mm is None else args.tol_mm * 1e-3,
                           max_controls=args.max_controls,
                           min_turn_deg=args.min_turn, refine=args.refine or None,
                           placement=args.placement, L_range=L_range, hL_range=hL_range,
                           min_barrier=args.min_barrier, state=args.unit_state,
                           max_units=args.max_units, theta_convention=args.theta_convention,
                           verify=not args.no_verify, progress=progress,
                           b=None if args.b is None else args.b * 1e-3, **hold)
    written, shop_warnings = write_design(d, args, colours)
    print(d.summary())
    print_hold(d)
    for msg in shop_warnings:
        print(f"warning: {msg}")
    print("wrote " + ", ".join(str(p) for p in written))
    return 0 if d.met else 1


def write_design(d, args, colours) -> tuple:
    """(paths, workshop warnings) of `Design.write` into --out with --bed, --kerf, --colours."""
    import warnings

    from snapmorph.cli import CommandError
    from snapmorph.design.drawings import BedWarning

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", BedWarning)
            written = d.write(args.out, colours=colours, drawings=not args.no_drawings,
                              bed=args.bed, kerf_mm=args.kerf)
    except OSError as exc:
        raise CommandError(f"cannot write into {args.out}: {exc}") from None
    return written, [str(w.message) for w in caught if issubclass(w.category, BedWarning)]


def _colours(text):
    from snapmorph.cli import CommandError

    if not text:
        return None
    out = {}
    for item in text.split(","):
        name, _, value = item.partition("=")
        name = name.strip().upper()
        if name not in ("CUT", "ENGRAVE", "MARKS") or not value.strip().isdigit():
            raise CommandError(f"--colours: expected LAYER=INDEX for CUT, ENGRAVE, MARKS "
                               f"(AutoCAD colour index 1-255), got {item!r}")
        index = int(value)
        if not 1 <= index <= 255:
            raise CommandError(f"--colours: colour index must be 1-255, got {index}")
        out[name] = index
    return out


# ------------------------------------------------------- does the design hold? (issue 23)
def add_hold_options(p) -> None:
    """--material, --orientation, --max-strain, --min-backload."""
    from snapmorph.commands.array import _material, _orientation

    p.add_argument("--material", default=None, type=_material,
                   help="check that the design holds under its own weight: petg, pla or paper "
                        "(density and allowable strain; any of these four options turns the "
                        "check on; exit 1 when it fails)")
    p.add_argument("--orientation", default=None, type=_orientation,
                   help="upright (default of the check), sideways or an angle in degrees "
                        "(-360 to 360): where gravity acts on the designed array")
    p.add_argument("--max-strain", type=number("", 0.0, 1.0, high_inclusive=False,
                                               what="largest surface strain allowed, a "
                                                    "fraction: 0.02 is 2 %"), default=None,
                   help="largest surface strain of any unit, 0 < strain < 1 (0.02 = 2 %%; "
                        "default the material's allowable strain)")
    p.add_argument("--min-backload", type=number("N", 0.0, 1e6, low_inclusive=True,
                                                 what="smallest snap-back load"), default=None,
                   help="smallest snap-back load of any unit, N (0 to 1e6)")


def hold_options(args) -> dict:
    """The inverse_design keywords of the hold check ({} when none was given)."""
    kw = dict(material=args.material, orientation=args.orientation,
              max_strain=args.max_strain, min_backload=args.min_backload)
    return {} if all(v is None for v in kw.values()) else kw


def print_hold(d) -> None:
    """The hold check's numbers (mm, N, %), when it ran."""
    check = getattr(d, "load_check", None)
    if not check:
        return
    ld, mat = check["loaded"], check["material"]
    if ld is not None:
        lim = ("none up to factor %g" % ld.max_factor if ld.limit_factor is None else
               f"unit {ld.limit_unit + 1} snaps back at {ld.limit_factor:.4g} x its weight")
        print(f"under its own weight ({mat.name}, {check['orientation']}): {ld.status}; free "
              f"end sag {ld.sag_m * 1e3:.2f} mm; {lim}")
    for m in check["margins"]:
        back = "" if m.F_back != m.F_back else f", snap-back load {m.F_back:.4g} N"
        print(f"  unit {m.unit + 1}: strain {100 * m.strain:.3f} % ({m.where}){back}")
    print(f"allowable strain {100 * check['allowable_strain']:.2f} %"
          + ("" if check["min_backload"] is None else
             f", smallest snap-back load {check['min_backload']:.4g} N"))
    if check["message"]:
        print(f"DOES NOT HOLD: {check['message']}")
    else:
        print("holds: every unit within its margins, no parts overlap")
