"""`snapmorph design T1 T2 [T3 ...]`: one array, one snap pattern per target (issue 24).

`snapmorph design` hands over to `run_multi` when it is given two or more targets; the options
are `design`'s (mm, N on the command line). Each target is read as `design` reads one
(`--select` / `--units` once for all or once per target, its notes printed, the scale checked);
each gets target_k.csv and overlay_k.svg/.dxf in its drawing's frame. Options of the paper's
one-target procedure (--controls, --refine, --min-turn, --theta-convention paper) are refused.

Exit status: 0 when every target meets --tol (and --tol-mm) and its whole-array verification
confirms it, 1 when some does not (the best design is still written and marked in design.txt,
units.csv and patterns.csv), 2 for bad input (one line).
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
    from snapmorph.commands._common import format_value, per_target, read_target_arg

    files = []
    for k, (path, (select, units)) in enumerate(zip(args.target, per_target(args,
                                                                           len(args.target))),
                                              start=1):
        if Path(path).suffix.lower() not in (".csv", ".svg", ".dxf"):
            input_file(path, f"target {k}")
            raise CommandError(f"target {k} {path}: unknown target type "
                               f"{Path(path).suffix or '(no suffix)'!r}; use .csv, .svg or .dxf")
        files.append(read_target_arg(path, f"target {k}", select=select, units=units))
    if args.map is not None:
        input_file(args.map, "--map")
    state = getattr(args, "unit_state", None) or getattr(args, "state", None) or "released"

    from tqdm import tqdm

    from snapmorph.design.lookup import load_map
    from snapmorph.design.multishape import inverse_design_multi
    from snapmorph.design.targets_frame import write_in_drawing_frame, write_target_csv
    from snapmorph.design.targets_scale import check_points_scale
    from snapmorph.design.workshop import write_workshop

    dm = load_map(args.map)
    for k, (path, tf) in enumerate(zip(args.target, files), start=1):
        print(f"target {k} {path}: {tf.source}, {format_value(tf.length_mm)} mm")
        for note in tf.notes:
            print(f"note: {note}")
        try:
            check_points_scale(tf.points, args.t * 1e-3, args.w * 1e-3, design_map=dm,
                               L_range=L_range, max_units=args.max_units)
        except ValueError as exc:
            raise CommandError(f"target {k}: {exc}") from None
    tol = args.tol
    if args.tol_mm is not None:  # the design meets both: the stricter governs
        longest = max(tf.length_mm for tf in files)
        tol = min(args.tol, args.tol_mm / longest)
    output_dir(args.out)  # before the design: a folder that cannot be written fails at once
    bar = tqdm(desc="design", unit=" step", leave=False,
               disable=getattr(args, "no_progress", False) or None)

    def progress(stage):
        bar.set_description_str(stage)
        bar.update()

    with warnings.catch_warnings(), bar:
        warnings.simplefilter("ignore")  # the summary says it all, once
        md = inverse_design_multi(files, t=args.t * 1e-3, w=args.w * 1e-3, tol=tol,
                                  placement=args.placement, design_map=dm,
                                  L_range=L_range, hL_range=hL_range,
                                  min_barrier=args.min_barrier, state=state,
                                  max_units=args.max_units, verify=not args.no_verify,
                                  progress=progress)
    md.names = tuple(Path(p).name for p in args.target)
    if args.tol_mm is not None:
        md.notes.append(f"tolerance {100 * tol:.2f} % of each target's length: "
                        + (f"--tol-mm {args.tol_mm:g} mm governs (stricter than --tol "
                           f"{100 * args.tol:.2f} % on the longest target, {longest:.1f} mm)"
                           if tol < args.tol else
                           f"--tol {100 * args.tol:.2f} % governs (stricter than --tol-mm "
                           f"{args.tol_mm:g} mm)"))
    try:
        written = md.write(args.out, colours=colours, drawings=False)
        for k, tf in enumerate(files):
            sim = None if md.verification is None else md.verification[k]["xy"]
            written.append(write_target_csv(tf.points, Path(args.out) / f"target_{k + 1}.csv"))
            written += write_in_drawing_frame(tf.frame, {"target": tf.points,
                                                         "predicted": md.predicted[k],
                                                         "simulated": sim},
                                              args.out, stem=f"overlay_{k + 1}")
        ws = None if args.no_drawings else write_workshop(
            md.units, args.out, bed=args.bed, kerf_mm=args.kerf, colours=colours,
            shape_xy=md.predicted[0])
    except OSError as exc:
        raise CommandError(f"cannot write into {args.out}: {exc}") from None
    print(md.summary())
    for msg in ws.warnings if ws else ():
        print(f"warning: {msg}")
    print("wrote " + ", ".join(str(p) for p in written + (ws.paths if ws else [])))
    return 0 if md.met_all else 1
