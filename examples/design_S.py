"""The paper's S (Section 4, Fig. "inverse_experiment" g-j, Table 3): two circular arms of
four equal segments, joined by a straight, given as control points with tangents (no spline).
The paper gives no radii; we take half-circle arms of radius 125 mm and a 100 mm straight
(see design/paper.py), t = 0.5 mm, w = 5 mm. Each arched unit then turns 45° over a 95.7 mm
chord; Table 3: every unit (106.7, 25.8) mm.

    python examples/design_S.py [--map PATH] [--out DIR]
"""

from __future__ import annotations

from snapmorph.design.lookup import load_map
from snapmorph.design.paper import compare_S, design_S, example_parser, written


def run(design_map=None, out=None):
    """The S design; units.csv, design.png and the drawings into `out` when given."""
    return written(design_S(design_map), out)


def main(argv=None) -> None:
    p = example_parser(__doc__, "build/examples/S")
    args = p.parse_args(argv)
    dm = load_map(args.map)
    d = run(dm, args.out)
    print(d.summary())
    print(compare_S(d, dm))
    print(f"wrote {args.out}/")


if __name__ == "__main__":
    main()
