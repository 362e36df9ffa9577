"""`snapmorph unit2d`: the paper's 2-D unit (square frame, two crossing arches), in mm."""

from __future__ import annotations

import argparse

from snapmorph.commands._common import (add_result_files, add_unit_dimensions, format_value,
                                        frame_unit_geometry, integer, print_why_not, push_rows,
                                        result_files, write_result_json)

HELP = """Simulate the paper's 2-D unit: a square frame base of side L made of strips of width w,
with two arches joining opposite midpoints of its sides and crossing (bonded) at the apex,
pushed down at the apex. Reports F_cr, the equilibrium displacements, bistability and, for
each side of the square in the second stable state, actuated and released (actuator and
supports removed), the chord S, the angle theta between its end tangents and its mean
curvature. Lengths in millimetres, E in pascals (the Python API,
units.unit2d, is SI)."""


def add_parser(sub):
    p = sub.add_parser("unit2d", help="simulate the 2-D unit (square frame, crossing arches; mm)",
                       description=HELP)
    p.set_defaults(run=run)
    add_unit_dimensions(p, L_what="side of the square", L_help="side of the square base, mm",
                        b_help="extra flat length of the arch ends beyond the frame strip, "
                        "mm (default 0)", nu=True)
    p.add_argument("--nodes", type=integer(11, 1001, what="nodes along a side"), default=None,
                   help="resolution: nodes along one side of the square (default 41)")
    add_result_files(p, "write the two stable states in perspective and the force-displacement "
                        "curve")
    return p


def run(args: argparse.Namespace) -> int:
    plot, js = result_files(args)
    from snapmorph.units.status import exit_status
    from snapmorph.units.unit2d import SIDES, simulate_unit_2d

    g = frame_unit_geometry(args)
    r = simulate_unit_2d(g, nodes=args.nodes, nu=args.nu)
    print(f"unit2d L={args.L:g} h={args.h:g} t={args.t:g} w={args.w:g} b={args.b:g} mm")
    rows = push_rows(r) + [
        ("S (mean)", format_value(r.S, 1e3), "mm"),
        ("theta (mean)", format_value(r.theta_deg), "deg"),
        ("self-standing", format_value(r.self_standing), ""),
        ("S released (mean)", format_value(r.S_released, 1e3), "mm"),
        ("theta released (mean)", format_value(r.theta_released_deg), "deg"),
        ("nodes", str(r.n_nodes), ""), ("solve time", format_value(r.solve_time, 1.0, 3), "s")]
    for name, value, unit in rows:
        print(f"  {name:<22} {value:>12} {unit}")
    print_why_not(r)
    for title, edges in (("state (iii)", r.edges.get("iii")),
                         ("the released state (iii)", r.released.get("edges"))):
        if not edges:
            continue
        print(f"  sides in {title}:")
        print("    side             S (mm)   theta (deg)   curvature (1/m)   sag (mm)")
        for side in SIDES:
            m = edges[side]
            print(f"    {side:<8} {format_value(m['S'], 1e3):>14} {format_value(m['theta_deg']):>13} "
                  f"{format_value(m['curvature']):>17} {format_value(m['sag'], 1e3):>10}")
    if js:
        write_result_json(js, r, g)
    if plot:
        from snapmorph.figures_unit3d import plot_unit2d_states

        plot_unit2d_states(r, plot)
        print(f"wrote {plot}")
    return exit_status(r.status)
