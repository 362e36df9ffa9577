"""The paper's asymmetric M (Section 4, Fig. "inverse_experiment" a-f, Table 3), from five
equally spaced target points through a spline: x = 0, 100, 200, 300, 400 mm, y = 0, 40, 15,
50, 0 mm (the paper does not list its points; see design/paper.py), t = 0.5 mm, w = 5 mm.

Two designs: the paper's procedure with its control points (the ends, the centre, and the one
it added between the left-most and the centre point: x = 0, 100, 200, 400 mm), and the
tolerance-driven design (units, sides and spacers chosen automatically, least squares over all
of them until the deviation is below 1 % of the target length).

    python examples/design_M.py [--map PATH] [--out DIR] [--refine]
"""

from __future__ import annotations

from pathlib import Path

from snapmorph.design.lookup import load_map
from snapmorph.design.paper import compare_M, design_M, example_parser, written


def run(design_map=None, controls: str = "paper", refine: bool = False, out=None):
    """The M design; units.csv, design.png and the drawings into `out` when given."""
    return written(design_M(design_map, controls, refine), out)


def main(argv=None) -> None:
    p = example_parser(__doc__, "build/examples/M")
    p.add_argument("--refine", action="store_true", help="least-squares refinement too")
    args = p.parse_args(argv)
    dm = load_map(args.map)
    for controls in ("paper", "auto"):
        d = run(dm, controls, args.refine, Path(args.out) / controls)
        if len(d.control_points):
            xs = ", ".join(f"{x * 1e3:.0f}" for x in d.control_points[:, 0])
            print(f"== M, the paper's procedure, control points x = {xs} mm")
        else:
            print("== M, tolerance-driven design")
        print(d.summary())
        print(compare_M(d, dm))
        print()


if __name__ == "__main__":
    main()
