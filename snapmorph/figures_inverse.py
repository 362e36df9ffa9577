"""Inverse-design figures: the paper's S by the paper's angle convention (theta_end, Table 3)
and by ours, both simulated as whole arrays, side by side (`make figures`). The M/S design
figures themselves are written with the forward-kinematics ones."""


def make(out, args=None):
    from pathlib import Path

    from snapmorph.design.lookup import load_map
    from snapmorph.design.paper import conventions, conventions_table, plot_conventions

    dm = load_map(getattr(args, "map", None) if args is not None else None)
    designs = conventions(dm)
    out = Path(out)
    paths = [plot_conventions(designs, out / "inverse_conventions.png")]
    table = out / "inverse_conventions.md"
    table.write_text("```\n" + conventions_table(designs) + "\n```\n")
    paths.append(table)
    return paths
