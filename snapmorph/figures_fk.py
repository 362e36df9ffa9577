"""Figures: forward kinematics of the paper's three units (8 states), and the inverse designs
(M, S) with their units.csv (with the placement line) and drawings."""

from pathlib import Path


def make(out, args=None):
    from snapmorph.design.drawings import write_drawings
    from snapmorph.design.lookup import load_map
    from snapmorph.design.paper import design_M, design_S, three_units
    from snapmorph.design.plots import plot_design
    from snapmorph.design.units import write_units_csv
    from snapmorph.plotting.arrays import plot_fk_states

    dm = load_map(getattr(args, "map", None) if args is not None else None)
    out = Path(out)
    states = {k: c.xy for k, c in three_units(dm).items()}
    paths = [plot_fk_states(states, out / "fk_states.png",
                            title="three units (L 100, h 20, t 0.5, w 5 mm; map, b = 0)")]
    for name, d in (("M", design_M(dm, "paper")), ("S", design_S(dm))):
        paths.append(plot_design(d, out / f"inverse_{name}.png"))
        paths.append(write_units_csv(d.units, out / f"inverse_{name}" / "units.csv",
                                     placement=getattr(d, "placement", None)))
        paths += write_drawings(d.units, out / f"inverse_{name}", bed_length_mm=600.0)
    return [str(p) for p in paths]
