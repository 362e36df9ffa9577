"""`snapmorph tolerance`: fabrication tolerance of an array, Monte Carlo through the design map."""

from __future__ import annotations

import argparse

from snapmorph.commands._common import (add_target_options, add_unit_state_option, integer,
                                        number)

HELP = """Propagate fabrication errors of hand-made units (normal errors in L, h, t and w,
standard deviations in millimetres) through the design map: the envelope of the all-snapped
shape, the scatter of the free end (mm and degrees) and each unit's probability of staying
bistable. Units come from a units.csv (as `snapmorph design` writes it); an arch's b is its
b_mm column (b follows L in the samples), looked up at its own b/L on a map with a b/L axis."""

EPILOG = """Frame: the envelope is drawn with unit 1 starting at (0, 0) heading +x; --target
(the design's target: its target.csv, or the SVG, DXF or CSV it was designed from, with
--select and --target-units as for `snapmorph design`) is moved into that frame with the
units.csv placement line when there is one. The envelope's half-width is at least 0.05 mm.
--simulate K also simulates the nominal array and K randomly perturbed whole arrays
(design.arrays) and counts how many lie inside the envelope, widened at each point by how far
the simulated nominal array lies from the map's (the simulation's own accuracy; slow: seconds
per array)."""


def add_parser(sub):
    p = sub.add_parser("tolerance", help="fabrication tolerance of an array (Monte Carlo)",
                       description=HELP, epilog=EPILOG)
    p.add_argument("units", help="units.csv (unit, L_mm, h_mm, t_mm, w_mm, side[, b_mm])")
    for name, what, default in (("h", "the arch height h", 0.5), ("L", "the base length L", 0.3),
                                ("t", "the thickness t", 0.02), ("w", "the strip width w", 0.0)):
        p.add_argument(f"--sigma-{name}", type=number("mm", 0, 10, low_inclusive=True,
                                                      what=f"standard deviation of {name}"),
                       default=default, help=f"standard deviation of {what}, mm (default {default:g})")
    p.add_argument("--n", type=integer(10, 1000000, what="samples"), default=1000,
                   help="number of Monte Carlo samples (default 1000)")
    p.add_argument("--seed", type=integer(0, None, what="random seed"), default=0,
                   help="random seed (default 0; the same seed gives the same result)")
    add_unit_state_option(p, "units released from their actuators (default) or still actuated")
    p.add_argument("--map", metavar="FILE", help="design map (default maps/data/default.nc)")
    p.add_argument("--target", metavar="FILE",
                   help="target curve (.svg, .dxf or .csv) to draw under the envelope")
    add_target_options(p, "--target-units", what="the --target")
    p.add_argument("--simulate", type=integer(0, 1000, what="whole-array simulations"), default=0,
                   help="also simulate this many perturbed whole arrays and check them against "
                   "the envelope (default 0)")
    p.add_argument("--plot", metavar="PNG", help="write the envelope over the target")
    p.add_argument("--json", metavar="FILE", help="write the summary as JSON")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    import json
    import math

    import numpy as np

    from snapmorph.cli import CommandError
    from snapmorph.commands._common import input_file, output_file, plot_file, read_target_arg

    units_path = input_file(args.units, "units")
    if args.map:
        input_file(args.map, "--map")
    target = None
    if args.target:
        target = read_target_arg(args.target, "--target", select=args.select,
                                 units=args.target_units, units_option="--target-units").points
    plot_path = plot_file(args.plot, "--plot") if args.plot else None
    json_path = output_file(args.json, "--json") if args.json else None

    from snapmorph.design.lookup import load_map
    from snapmorph.design.fabrication_tolerance import plot_tolerance, tolerance
    from snapmorph.design.units import read_placement, read_units_csv

    dm = load_map(args.map)
    b_over_L = float(dm.attrs.get("b_over_L", 0.0))
    units = read_units_csv(units_path, b_over_L=b_over_L)
    sigma = {"L": args.sigma_L * 1e-3, "h": args.sigma_h * 1e-3, "t": args.sigma_t * 1e-3}
    if args.sigma_w:
        sigma["w"] = args.sigma_w * 1e-3
    try:
        r = tolerance(units, sigma=sigma, n=args.n, seed=args.seed, design_map=dm,
                      state=args.unit_state)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    print(f"{units_path}: {len(units)} units")
    print(r.summary())
    simulated, contained, accuracy = [], None, None
    if args.simulate:
        simulated, contained, accuracy = simulate_perturbed(units, sigma, args.simulate,
                                                            args.seed + 1, r)
        print(f"whole-array simulations: {sum(contained)} of {len(contained)} inside the envelope "
              f"({100.0 * sum(contained) / max(len(contained), 1):.0f} %), the band widened by "
              f"the simulated nominal array's distance from the map's (at most "
              f"{np.max(accuracy) * 1e3:.3g} mm)")
    if target is not None:
        placement = read_placement(units_path)
        if placement is not None:  # target frame -> array frame (unit 1 at (0, 0), +x)
            x0, y0, a = placement
            c, s = math.cos(-a), math.sin(-a)
            target = (np.asarray(target) - [x0, y0]) @ np.array([[c, s], [-s, c]])
    if plot_path:
        plot_tolerance(r, plot_path, target=target, simulated=simulated)
        print(f"wrote {plot_path}")
    if json_path:
        payload = {"n": r.n, "n_ok": r.n_ok, "outside_map": r.outside_map, "state": r.state,
                   "sigma_mm": {k: v * 1e3 for k, v in r.sigma.items()},
                   "free_end": r.free_end_summary(), "p_bistable": r.p_bistable.tolist(),
                   "held_out_coverage": r.held_out_coverage, "time_s": r.time_s}
        lo, hi = r.band()
        payload["envelope_half_width_mm"] = {"max": float(np.max(hi - lo) * 500),
                                             "min": float(np.min(hi - lo) * 500),
                                             "floor": r.floor * 1e3}
        if contained is not None:
            payload["simulated_inside"] = [bool(c) for c in contained]
            payload["simulation_accuracy_mm"] = float(np.max(accuracy) * 1e3)
        with open(json_path, "w") as fh:
            json.dump(payload, fh, indent=1)
        print(f"wrote {json_path}")
    return 0


def simulate_perturbed(units, sigma, k, seed, result):
    """Simulate the nominal array and ``k`` whole arrays (all snapped) with independently
    perturbed units: (list of (K, 2) bases, list of bool inside the envelope, the simulation's
    accuracy (n_units, m) m). The accuracy is how far the simulated nominal array lies from
    the map's nominal at each envelope station; a perturbed array is inside when it lies in
    the band widened by that much. Arrays that fail are skipped, with a line saying so."""
    import numpy as np

    from snapmorph.design.arrays import simulate_array
    from snapmorph.design.fabrication_tolerance import perturbed_units

    snapped = [not u.is_spacer for u in units]
    nominal = simulate_array(units, snapped)
    if nominal.status == "ok":
        accuracy = np.abs(result.normal_offsets(nominal.base))
    else:  # the band alone (its floor) then
        print(f"  the nominal array's simulation failed ({nominal.status}): the perturbed "
              "arrays are judged against the band alone")
        accuracy = np.zeros(result.stations.shape[:2])
    curves, inside = [], []
    for us in perturbed_units(units, sigma, k, seed):
        r = simulate_array(us, [not u.is_spacer for u in us])
        if r.status != "ok":
            print(f"  a perturbed array failed: {r.status}")
            continue
        curves.append(r.base)
        inside.append(result.envelope_contains(r.base, slack=accuracy))
    return curves, inside, accuracy
