"""`snapmorph unit3d`: the unit in 3-D (frame base, imperfections), lengths in millimetres."""

from __future__ import annotations

import argparse

from snapmorph.commands._common import (add_result_files, add_unit_dimensions, format_value,
                                        frame_unit_geometry, integer, number, print_why_not,
                                        push_rows, result_files, write_result_json)

HELP = """Simulate one bistable unit in 3-D: a rectangular frame base (two side rails of width w,
solid end regions of width 4w), the arch through the frame's hole, rollers and actuator, on
3-D discrete elastic rods. Optional imperfections: the arch tilted about the base's axis, the
apex offset sideways, the actuator off centre. Reports the planar metrics (F_cr, d's, S,
theta, actuated and released: actuator and rollers removed) and the arch's tilt and the
rails' twist in states (i)-(iii) and released. Lengths in millimetres,
angles in degrees, E in pascals. (The Python API, units.unit3d, is SI throughout.)"""


def add_parser(sub):
    p = sub.add_parser("unit3d", help="simulate one unit in 3-D with imperfections (mm)",
                       description=HELP)
    add_unit_dimensions(p, nu=True)
    p.add_argument("--tilt", type=number("deg", -45.0, 45.0, low_inclusive=True,
                                         what="arch tilt about the base axis"), default=0.0,
                   help="arch tilt about the base's axis, degrees (default 0)")
    p.add_argument("--apex-offset", type=number("mm", what="sideways apex offset"), default=0.0,
                   help="sideways (y) offset of the apex, mm (default 0)")
    p.add_argument("--actuator-offset", type=number("mm", what="actuator offset along x"),
                   default=0.0, help="actuator position from mid-span along x, mm (default 0)")
    p.add_argument("--nodes", type=integer(21, 2001, what="nodes along a rail"), default=None,
                   help="resolution: nodes along a rail (default 41)")
    p.add_argument("--planar", action="store_true",
                   help="also run the planar model and print both side by side")
    add_result_files(p, "write the states (i)-(iii) in perspective and the force-displacement "
                        "curve")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    import math

    plot, js = result_files(args)
    from snapmorph.units.status import exit_status
    from snapmorph.units.unit3d import simulate_unit_3d

    from snapmorph.cli import CommandError

    if abs(args.apex_offset) > args.h:
        raise CommandError(f"--apex-offset must be within [-h, h] = [{-args.h:g}, {args.h:g}] mm "
                           f"(sideways apex offset); got {args.apex_offset:g}")
    quarter = 0.25 * (args.L - 2 * (args.b + args.w))
    if abs(args.actuator_offset) > quarter:
        raise CommandError(f"--actuator-offset must be within [{-quarter:g}, {quarter:g}] mm (a "
                           f"quarter of the arch span L - 2(b + w)); got {args.actuator_offset:g}")
    mm = 1e-3
    g = frame_unit_geometry(args)
    r = simulate_unit_3d(g, nodes=args.nodes, tilt_deg=args.tilt,
                         apex_offset=args.apex_offset * mm,
                         actuator_offset=args.actuator_offset * mm, nu=args.nu)
    planar = None
    if args.planar:
        from snapmorph.units import simulate_unit

        planar = simulate_unit(g)
    rows = push_rows(r) + [("S", format_value(r.S, 1e3), "mm"),
                           ("theta", format_value(r.theta_deg), "deg")]
    rel = r.released or {}
    rows += [("self-standing", format_value(r.self_standing), ""),
             ("S released", format_value(rel.get("S", math.nan), 1e3), "mm"),
             ("theta released", format_value(rel.get("theta_deg", math.nan)), "deg")]
    for state in ("i", "ii", "iii"):
        rows.append((f"arch tilt ({state})", format_value(r.arch_tilt_deg.get(state)), "deg"))
    rows.append(("arch tilt (released)", format_value(rel.get("arch_tilt_deg", math.nan)), "deg"))
    for state in ("i", "ii", "iii"):
        rows.append((f"rail twist ({state})", format_value(r.rail_twist_deg.get(state)), "deg"))
    rows.append(("rail twist (released)", format_value(rel.get("rail_twist_deg", math.nan)),
                 "deg"))
    rows += [("nodes", str(r.n_nodes), ""), ("solve time", format_value(r.solve_time, 1.0, 3), "s")]
    print(f"unit3d L={args.L:g} h={args.h:g} t={args.t:g} w={args.w:g} b={args.b:g} mm, "
          f"tilt={args.tilt:g} deg, apex offset={args.apex_offset:g} mm, actuator offset="
          f"{args.actuator_offset:g} mm")
    planar_rows = {"F_cr": (planar.F_cr, 1.0), "d_cr": (planar.d_cr, 1e3),
                   "d_unstable (ii)": (planar.d_unstable, 1e3),
                   "d_second (iii)": (planar.d_second, 1e3), "S": (planar.S, 1e3),
                   "theta": (planar.theta_deg, 1.0),
                   "self-standing": (planar.self_standing, None),
                   "S released": (planar.S_released, 1e3),
                   "theta released": (planar.theta_released_deg, 1.0)} if planar else {}
    for name, value, unit in rows:
        extra = ""
        if name in planar_rows:
            v, scale = planar_rows[name]
            shown = format_value(v) if scale is None else format_value(v, scale)
            extra = f"   planar {shown:>10}"
        print(f"  {name:<22} {value:>12} {unit:<4}{extra}")
    print_why_not(r)
    if js:
        write_result_json(js, r, g)
    if plot:
        from snapmorph.figures_unit3d import plot_unit3d_states

        plot_unit3d_states(r, plot, planar=planar)
        print(f"wrote {plot}")
    return exit_status(r.status)
