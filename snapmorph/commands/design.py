"""`snapmorph design`: inverse design of an array from a target shape (paper, Section 4)."""

from __future__ import annotations

import argparse

HELP = "design an array of units that snaps into a target shape; write units.csv, drawings, plots"


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "design", help=HELP, description=HELP + ".",
        epilog="target.csv: lines 'x_mm, y_mm' (x increasing; spline through them) or "
               "'x_mm, y_mm, tangent_deg' (control points with tangents, e.g. circular segments).",
    )
    p.add_argument("target", help="target CSV in mm")
    p.add_argument("--t", type=float, required=True, help="sheet thickness (mm)")
    p.add_argument("--w", type=float, required=True, help="strip width (mm)")
    p.add_argument("--out", default="build/design", help="output directory (default %(default)s)")
    p.add_argument("--map", default=None, help="design map netCDF (default: the committed map)")
    p.add_argument("--controls", default=None,
                   help="x (mm) of interior control points, comma separated (default: automatic)")
    p.add_argument("--tol", type=float, default=1.0,
                   help="automatic control points: target max deviation, %% of the target length "
                        "(default %(default)s)")
    p.add_argument("--max-controls", type=int, default=9,
                   help="automatic control points: at most this many (default %(default)s)")
    p.add_argument("--min-turn", type=float, default=None,
                   help="arcs turning less (deg) become straight spacers (default: the map's "
                        "smallest bistable θ)")
    p.add_argument("--refine", action="store_true",
                   help="adjust every unit's (L, h) by least squares on the deviation")
    p.add_argument("--bed", type=float, default=None,
                   help="laser bed length (mm): split the base strip into pieces no longer")
    p.add_argument("--colours", default=None,
                   help="layer colours as AutoCAD indices, e.g. CUT=1,ENGRAVE=5,MARKS=3")
    p.add_argument("--no-drawings", action="store_true", help="skip DXF/SVG drawings")
    p.set_defaults(run=run)
    return p


def run(args) -> int:
    from pathlib import Path

    import numpy as np

    from design import inverse_design
    from design.lookup import load_map

    for name in ("t", "w"):
        value = getattr(args, name)
        if not (value > 0 and np.isfinite(value)):
            raise ValueError(f"--{name} must be a positive thickness/width in mm, got {value}")
    if args.bed is not None and not args.bed > 0:
        raise ValueError(f"--bed must be a positive length in mm, got {args.bed}")
    colours = _colours(args.colours)
    controls = None
    if args.controls:
        try:
            controls = np.array([float(v) for v in args.controls.split(",") if v.strip()]) * 1e-3
        except ValueError:
            raise ValueError(f"--controls must be comma-separated numbers (mm), "
                             f"got {args.controls!r}") from None
    if not Path(args.target).is_file():
        raise ValueError(f"target file not found: {args.target}")
    dm = load_map(args.map)
    d = inverse_design(args.target, t=args.t * 1e-3, w=args.w * 1e-3, controls=controls,
                       design_map=dm, tol=args.tol / 100.0, max_controls=args.max_controls,
                       min_turn_deg=args.min_turn, refine=args.refine)
    try:
        written = d.write(args.out, bed_length_mm=args.bed, colours=colours,
                          drawings=not args.no_drawings)
    except OSError as exc:
        raise ValueError(f"cannot write into {args.out}: {exc}") from None
    print(d.summary())
    print("wrote " + ", ".join(str(p) for p in written))
    return 0


def _colours(text):
    if not text:
        return None
    out = {}
    for item in text.split(","):
        name, _, value = item.partition("=")
        name = name.strip().upper()
        if name not in ("CUT", "ENGRAVE", "MARKS") or not value.strip().isdigit():
            raise ValueError(f"--colours: expected LAYER=INDEX for CUT, ENGRAVE, MARKS "
                             f"(AutoCAD colour index 1-255), got {item!r}")
        index = int(value)
        if not 1 <= index <= 255:
            raise ValueError(f"--colours: colour index must be 1-255, got {index}")
        out[name] = index
    return out
