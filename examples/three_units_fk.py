"""The paper's forward-kinematics experiment (Section 3, Fig. "fk"): three identical units,
t = 0.5 mm, h = 20 mm, w = 5 mm, L = 100 mm, have 2³ = 8 stable states.

    python examples/three_units_fk.py [--map PATH] [--simulate] [--out DIR]

Unit shapes come from the design map, read at b/L = 0 as the paper's parametric study (the
default map also holds b/L = 0.05, the specimens' b = w), or with --simulate from the unit
solver directly, with b = w as the paper's specimens.
"""

from __future__ import annotations

import math
from pathlib import Path

from snapmorph.design.lookup import load_map
from snapmorph.design.paper import example_parser, three_units


def run(design_map=None, source: str = "map", out=None) -> dict:
    """{state: Chain} (`.xy` base polyline in m, `.angles` joint directions in rad); the figure
    of all states into out/states.png when `out` is given."""
    states = three_units(design_map, source)
    if out is not None:
        from snapmorph.design.plots import plot_states

        plot_states({k: c.xy for k, c in states.items()}, Path(out) / "states.png",
                    title=f"three units t = 0.5, h = 20, w = 5, L = 100 mm ({source})")
    return states


def main(argv=None) -> None:
    p = example_parser(__doc__, "build/examples/three_units")
    p.add_argument("--simulate", action="store_true", help="direct simulation, b = w")
    args = p.parse_args(argv)
    source = "simulate" if args.simulate else "map"
    states = run(load_map(args.map) if source == "map" else None, source, args.out)
    print(f"{len(states)} states (1 = snapped): end point and end direction of the base")
    for key, c in states.items():
        print(f"  {key}: ({c.xy[-1, 0] * 1e3:7.1f}, {c.xy[-1, 1] * 1e3:7.1f}) mm  "
              f"{math.degrees(c.angles[-1]):6.1f} deg")
    print(f"wrote {Path(args.out) / 'states.png'}")


if __name__ == "__main__":
    main()
