"""`snapmorph unit`: simulate one unit from its dimensions in millimetres."""

from __future__ import annotations

import argparse

from snapmorph.commands._common import (add_result_files, add_unit_dimensions, format_value,
                                        integer, length_mm, number, print_why_not, push_rows,
                                        write_result_json)

HELP = """Simulate one bistable unit: push its apex down until it snaps, and report F_cr,
the equilibrium displacements, S, theta (actuated and released), F_min, the snap-back load
and stiffness of the released unit, the largest surface strain and the energies. Lengths on
the command line are in millimetres; E is in pascals. (The Python API, units.planar /
solver.unit, is SI throughout.)"""


def add_parser(sub):
    p = sub.add_parser("unit", help="simulate one unit (lengths in mm)", description=HELP)
    add_unit_dimensions(p, flat_ok=True)
    p.add_argument("--joint-length", type=length_mm(0, low_inclusive=True,
                                                    what="arch length held by the actuator"),
                   default=3.175, help="length of arch held straight by the actuator stem, mm "
                   "(default 3.175 = 1/8 in; 0 = a point clamp at the apex)")
    p.add_argument("--bond-length", type=length_mm(what="glued length at each end"), default=None,
                   help="glued length at each end, mm (default: the whole flat part b + w)")
    p.add_argument("--nodes", type=integer(11, 20001, what="mesh resolution"), default=None,
                   help="resolution: about the number of base nodes (default: converged default)")
    p.add_argument("--method", choices=("mgdc", "displacement"), default="mgdc",
                   help="path follower (default mgdc)")
    p.add_argument("--time-limit", type=number("s", 0, what="wall-time limit"), default=None,
                   help="stop after this many seconds with status timeout (default: no limit)")
    add_result_files(p, "write the force-displacement curve and the shapes (i)-(iii)")
    p.set_defaults(run=run)
    return p


# geometry_problem's messages start with the parameter(s) at fault: the options to name
_SUBJECT_OPTIONS = (("b + w", "--b, --w"), ("joint_length", "--joint-length"),
                    ("bond_length", "--bond-length"), ("L", "--L"), ("h", "--h"), ("t", "--t"),
                    ("w", "--w"), ("b", "--b"), ("E", "--E"))


def _domain_message(problem: str) -> str:
    """A `geometry_problem` message (quoting mm) as one line naming the option(s) at fault,
    argparse style: "argument --h: h must be <= ... mm; got ..."."""
    text = problem.replace("joint_length", "--joint-length").replace("bond_length", "--bond-length")
    for subject, options in _SUBJECT_OPTIONS:
        if problem == subject or problem.startswith(subject + " "):
            word = "arguments" if "," in options else "argument"
            return f"{word} {options}: {text}"
    return text


def run(args: argparse.Namespace) -> int:
    import math

    from snapmorph.cli import CommandError
    from snapmorph.commands._common import output_file, plot_file
    from snapmorph.units.geometry import geometry_problem

    mm = 1e-3
    dims = dict(L=args.L * mm, h=args.h * mm, t=args.t * mm, w=args.w * mm, b=args.b * mm,
                E=args.E, joint_length=args.joint_length * mm,
                bond_length=None if args.bond_length is None else args.bond_length * mm)
    # the model's valid domain, checked here so that the message quotes millimetres
    problem = geometry_problem(**dims, unit="mm", scale=1e3)
    if problem:
        raise CommandError(_domain_message(problem))
    json_path = output_file(args.json, "--json") if args.json else None
    plot_path = plot_file(args.plot, "--plot") if args.plot else None

    from snapmorph.units.geometry import UnitGeometry
    from snapmorph.units.planar import simulate_unit
    from snapmorph.units.status import exit_status

    g = UnitGeometry(**dims)
    r = simulate_unit(g, nodes=args.nodes, method=args.method, time_limit=args.time_limit)
    rel = r.released or {}
    rows = push_rows(r) + [
        ("S", format_value(r.S, 1e3), "mm"),
        ("S/L", format_value(r.S / g.L if r.S == r.S else math.nan), ""),
        ("theta", format_value(r.theta_deg), "deg"),
        ("theta_end", format_value(r.theta_end_deg), "deg"),
        ("self-standing", format_value(r.self_standing), ""),
        ("S released", format_value(rel.get("S", math.nan), 1e3), "mm"),
        ("theta released", format_value(rel.get("theta_deg", math.nan)), "deg"),
        ("F_min", format_value(r.F_min), "N"),
        ("d at F_min", format_value(r.d_Fmin, 1e3), "mm"),
        ("snap-back load", format_value(r.F_back), "N"),
        ("stiffness released", format_value(r.stiffness_released, 1e-3), "N/mm"),
        ("strain max", format_value(r.strain_max), ""),
        ("strain released", format_value(r.strain_max_released), ""),
        ("strain max at", r.strain_where or "-", ""),
        ("energy barrier", format_value(r.energy_barrier, 1e3), "mJ"),
        ("energy stored (iii)", format_value(r.energy_stored, 1e3), "mJ"),
        ("nodes", str(r.n_nodes), ""),
        ("solve time", format_value(r.solve_time, 1e3, 3), "ms"),
    ]
    print(f"unit L={args.L:g} h={args.h:g} t={args.t:g} w={args.w:g} b={args.b:g} mm, E={args.E:g} Pa, "
          f"joint {args.joint_length:g} mm, bond "
          + ("b + w" if args.bond_length is None else f"{args.bond_length:g} mm"))
    for name, value, unit in rows:
        print(f"  {name:<20} {value:>12} {unit}")
    print_why_not(r, self_standing=False)
    if json_path:
        write_result_json(json_path, r, g, ("L", "h", "t", "w", "b", "E", "joint_length",
                                             "bond_length"))
    if plot_path:
        from snapmorph.plotting.unit import plot_unit

        plot_unit(r, str(plot_path))
        print(f"wrote {plot_path}")
    if r.status.startswith("timeout"):
        raise CommandError(f"{r.status} (--time-limit {args.time_limit:g} s)")
    return exit_status(r.status)
