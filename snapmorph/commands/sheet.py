"""`snapmorph sheet`: a sheet tiled from 2-D units, its cells snapped one at a time, in mm and N."""

from __future__ import annotations

import argparse

from snapmorph.commands._common import (add_unit_dimensions, format_value, frame_unit_geometry,
                                        integer, output_file, plot_file)

HELP = """Simulate a sheet tiled from 2-D units (each a frame of strips of width w on a
triangle, square or hexagon of side L, arches from its sides' midpoints to its apex; the
cells share their edge strips). The cells of --order are pushed at their apex one at a time
(actuator on, then released); after each snap: F_cr, which cells are snapped (neighbours
may snap along or back), whether the released sheet is stable, and whether it fell into a
global mode. Cells are numbered row after row from the bottom left (in a 3x3 square sheet
cell 4 is the centre). Lengths in millimetres, forces in newtons, E in pascals (the Python
API, units.sheet, is SI). Exit status 0 when every push answered and every release found a
stable sheet; 1 when a push was cut short (its step cap, a failed solve) or a release
failed: then the final shape is where the protocol let go, not a result."""


def cells_text(text: str):
    """--cells: ROWSxCOLS or a count."""
    try:
        if "x" in text.lower():
            rows, cols = (int(p) for p in text.lower().split("x"))
            return rows, cols
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be ROWSxCOLS (e.g. 3x3) or a number of cells; got {text!r}") from None


def order_text(text: str) -> list:
    """--order: comma-separated cell indices."""
    try:
        out = [int(p) for p in text.split(",") if p.strip() != ""]
    except ValueError:
        out = []
    if not out:
        raise argparse.ArgumentTypeError(
            f"must be comma-separated cell indices (e.g. 4,0,8); got {text!r}")
    return out


def add_parser(sub):
    p = sub.add_parser("sheet", help="snap the cells of a sheet of 2-D units one at a time (mm, N)",
                       description=HELP)
    p.set_defaults(run=run)
    p.add_argument("--tiling", choices=("square", "triangle", "hexagon"), default="square",
                   help="the cells' footprint (default square)")
    p.add_argument("--cells", type=cells_text, default=(3, 3),
                   help="ROWSxCOLS or a number of cells (default 3x3)")
    add_unit_dimensions(p, L_what="side of a cell", L_help="side of a cell, mm",
                        b_help="extra flat length of the arch ends beyond the frame strip, "
                        "mm (default 0)", nu=True)
    p.add_argument("--order", type=order_text, required=True,
                   help="the cells to push, in order, e.g. 4,0,8")
    p.add_argument("--boundary", choices=("free", "clamped-edge"), default="free",
                   help="free (rigid-body motion held by six components) or clamped-edge "
                   "(the bottom edge held); default free")
    p.add_argument("--protocol", choices=("mgdc", "rig"), default="rig",
                   help="how a cell is pushed: rig (default: a displacement-controlled rig that "
                   "settles into the stable state at every 2 mm and jumps where the path folds; "
                   "it answers pushes inside a curled sheet) or mgdc (the unit's "
                   "load-controlled path through the snap; it cuts some of those short)")
    p.add_argument("--nodes", type=integer(11, 201, what="nodes along a cell side"), default=21,
                   help="resolution: nodes along a cell side (default 21)")
    p.add_argument("--plot", metavar="PNG", help="3-D views of the sheet as made and after "
                   "every step")
    p.add_argument("--out", metavar="NC", help="write the states (node positions, snapped "
                   "cells, forces) as netCDF")
    return p


def run(args: argparse.Namespace) -> int:
    plot = plot_file(args.plot)
    out = output_file(args.out, "--out")
    from snapmorph.units.sheet import build_sheet, check_order, simulate_sheet
    from snapmorph.units.status import answered

    g = frame_unit_geometry(args)
    sheet = build_sheet(g, args.tiling, args.cells, nodes=args.nodes, nu=args.nu)
    order = check_order(sheet, args.order)
    rows, cols = sheet.shape
    print(f"sheet {args.tiling} {rows}x{cols} L={args.L:g} h={args.h:g} t={args.t:g} "
          f"w={args.w:g} b={args.b:g} mm, {args.boundary}, order {','.join(map(str, order))}, "
          f"protocol {args.protocol}")
    r = simulate_sheet(sheet, order, boundary=args.boundary, protocol=args.protocol)
    print("  step  cell   F_cr (N)   push          stable  global mode  snapped cells")
    for k, s in enumerate(r.steps):
        snapped = ",".join(str(c) for c in s.snapped.nonzero()[0]) or "-"
        print(f"  {k:4d}  {s.cell:4d} {format_value(s.F_cr):>10}   {s.push_status[:12]:<12}  "
              f"{format_value(s.stable):>6}  {format_value(s.global_mode):>11}  {snapped}")
        if s.reason:
            print(f"        released: {s.reason}")
        if not answered(s.push_status):  # the whole status: the table cuts it at 12
            print(f"        push cut short: {s.push_status}")
    print(f"  solve time {r.solve_time:.1f} s, {sheet.mesh.n_nodes} nodes")
    if not r.complete:
        print("NOT A RESULT: a push was cut short or a release found no stable state "
              "(the final shape is where the protocol let go)")
    if out:
        from snapmorph.units.sheet_io import write_states

        write_states(r, out)
        print(f"wrote {out}")
    if plot:
        from snapmorph.figures_sheet import plot_states

        plot_states(r, plot)
        print(f"wrote {plot}")
    return 0 if r.complete else 1
