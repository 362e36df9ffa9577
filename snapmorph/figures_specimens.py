"""Figure: the Table 1 specimens (curves, states, shapes) and their metrics table."""

import os


def make(out, args=None):
    from snapmorph.plotting.specimens import plot_specimens, simulate_specimens, specimen_table

    nominal = simulate_specimens("nominal")
    average = simulate_specimens("average")
    png = plot_specimens(nominal, average, os.path.join(out, "specimens_forcedef.png"))
    md = os.path.join(out, "specimens_table.md")
    with open(md, "w") as fh:
        fh.write("## Table 1 specimens, measured-average dimensions (w = b = 5 mm)\n\n")
        fh.write(specimen_table(average) + "\n\n")
        fh.write("## Table 1 specimens, nominal dimensions (L = 100 mm)\n\n")
        fh.write(specimen_table(nominal) + "\n")
    return [png, md]
