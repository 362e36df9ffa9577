"""`snapmorph design T1 T2 [T3 ...]`: one array, one snap pattern per target (issue 24).

`snapmorph design` hands over to `run_multi` when it is given two or more targets; the options
are `design`'s (mm, N on the command line). Options of the paper's one-target procedure
(--controls, --refine, --min-turn, --theta-convention paper) are refused.

Exit status: 0 when every target meets --tol, 1 when some does not (the best design is still
written and marked in design.txt, units.csv and patterns.csv), 2 for bad input (one line).
"""

from __future__ import annotations

#: options of `snapmorph design` that belong to the paper's one-target procedure
ONE_TARGET_ONLY = (("controls", "--controls"), ("refine", "--refine"), ("min_turn", "--min-turn"))


def run_multi(args, *, L_range=None, hL_range=None, colours=None) -> int:
    """Design for args.target (a list of >= 2 files); args as parsed by `snapmorph design`
    (already checked there: --t, --w, --tol, --bed, --max-units, --min-barrier)."""
    import warnings
    from pathlib import Path

    from snapmorph.cli import CommandError
    from snapmorph.commands._common import input_file, output_dir

    for name, option in ONE_TARGET_ONLY:
        if getattr(args, name, None):
            raise CommandError(f"{option} belongs to the paper's one-target procedure; with "
                               f"{len(args.target)} targets leave it out")
    if getattr(args, "theta_convention", "ours") != "ours":
        raise CommandError("--theta-convention paper applies to one target; several targets "
                           "are designed with θ (the default, ours)")
    for k, path in enumerate(args.target, start=1):
        input_file(path, f"target {k}")
        if Path(path).suffix.lower() not in (".csv", ".svg", ".dxf"):
            raise CommandError(f"target {k} {path}: unknown target type "
                               f"{Path(path).suffix or '(no suffix)'!r}; use .csv, .svg or .dxf")
    if args.map is not None:
        input_file(args.map, "--map")
    state = getattr(args, "unit_state", None) or getattr(args, "state", None) or "released"

    from tqdm import tqdm

    from snapmorph.design.lookup import load_map
    from snapmorph.design.multishape import inverse_design_multi

    dm = load_map(args.map)
    output_dir(args.out)  # before the design: a folder that cannot be written fails at once
    bar = tqdm(desc="design", unit=" step", leave=False,
               disable=getattr(args, "no_progress", False) or None)

    def progress(stage):
        bar.set_description_str(stage)
        bar.update()

    with warnings.catch_warnings(), bar:
        warnings.simplefilter("ignore")  # the summary says it all, once
        md = inverse_design_multi(list(args.target), t=args.t * 1e-3, w=args.w * 1e-3,
                                  tol=args.tol, placement=args.placement, design_map=dm,
                                  L_range=L_range, hL_range=hL_range,
                                  min_barrier=args.min_barrier, state=state,
                                  max_units=args.max_units, verify=not args.no_verify,
                                  progress=progress)
    try:
        written = md.write(args.out, bed_length_mm=args.bed, colours=colours,
                           drawings=not args.no_drawings)
    except OSError as exc:
        raise CommandError(f"cannot write into {args.out}: {exc}") from None
    print(md.summary())
    print("wrote " + ", ".join(str(p) for p in written))
    return 0 if md.met_all else 1
