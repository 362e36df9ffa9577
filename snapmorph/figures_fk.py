"""Figures: forward kinematics of the paper's three units, and the inverse designs (M, S)."""


def make(out, args=None):
    from design.paper import write_figures

    dm = None
    if args is not None and getattr(args, "map", None):
        from maps import DesignMap

        dm = DesignMap.load(args.map)
    return [str(p) for p in write_figures(out, design_map=dm)]
