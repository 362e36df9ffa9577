"""`snapmorph maps`: build, check and describe design maps.

    snapmorph maps build --grid default --out maps/data/default.nc [--workers N] [--scheduler ADDR]
    snapmorph maps check --grid ci --against maps/data/ci.nc
    snapmorph maps info [FILE]
"""

from __future__ import annotations

import argparse

GRIDS = ("default", "ci")
DEFAULT_SOLVER = "pipeline.point:solve_point"


def _positive_int(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {v}")
    return v


def _nonneg_float(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not v >= 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return v


def _cluster_args(p):
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="dask scheduler address or scheduler-file of an existing cluster "
                        "(default: $DASK_SCHEDULER_ADDRESS, else a local cluster)")
    p.add_argument("--workers", type=_positive_int, metavar="N",
                   help="local worker processes (default: one per core); with --scheduler, "
                        "how many workers to wait for")
    p.add_argument("--resolution", type=_positive_int, metavar="N",
                   help="solver resolution (nodes) instead of the grid preset's")
    p.add_argument("--batch-size", type=_positive_int, metavar="N",
                   help="points per dask task (default: up to 20)")
    p.add_argument("--solver", default=DEFAULT_SOLVER, metavar="MODULE:FUNCTION",
                   help=f"point solver, importable on the workers (default {DEFAULT_SOLVER})")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("maps", help="build, check and describe design maps",
                              description="Design maps: F_cr, S, theta, ... over (h/L, t/L, w/L).")
    sub = p.add_subparsers(dest="maps_command", metavar="SUBCOMMAND")
    p.set_defaults(run=run, _maps_parser=p)

    b = sub.add_parser("build", help="build a map (resumes an interrupted build of the same file)",
                       description="Fan the unit solver out over a grid with dask and write a "
                                   "netCDF design map. Finished points are checkpointed in "
                                   "OUT.partial/; running the same command again resumes.")
    b.add_argument("--grid", choices=GRIDS, default="default", help="grid preset (default: default)")
    b.add_argument("--out", required=True, metavar="FILE", help="netCDF file to write")
    b.add_argument("--restart", action="store_true",
                   help="discard the checkpoint of an interrupted build and start afresh")
    _cluster_args(b)

    c = sub.add_parser("check", help="recompute a grid and compare it with a map file",
                       description="Recompute the grid and compare every variable (except "
                                   "solve_time) with FILE; exit status 1 and a list of the "
                                   "differing variables and points when they differ.")
    c.add_argument("--grid", choices=GRIDS, default="ci", help="grid preset (default: ci)")
    c.add_argument("--against", required=True, metavar="FILE", help="map file to compare with")
    c.add_argument("--rtol", type=_nonneg_float, default=1e-6, help="relative tolerance (default 1e-6)")
    c.add_argument("--atol", type=_nonneg_float, default=1e-9, help="absolute tolerance (default 1e-9)")
    _cluster_args(c)

    i = sub.add_parser("info", help="summarise a map file")
    i.add_argument("file", nargs="?", metavar="FILE", help="map file (default: the default map)")


def _grid(args):
    from pipeline.grid import preset

    grid = preset(args.grid)
    if args.resolution is not None:
        grid = grid.with_resolution(args.resolution)
    return grid


def _build(args, out, restart):
    from pipeline.build import build_map

    return build_map(_grid(args), out, solve=args.solver, scheduler=args.scheduler,
                     workers=args.workers, batch_size=args.batch_size, restart=restart,
                     progress=not args.no_progress)


def _run_build(args) -> int:
    report = _build(args, args.out, args.restart)
    print(report.summary())
    return 0


def _run_check(args) -> int:
    import tempfile
    from pathlib import Path

    import xarray as xr

    from maps.designmap import DesignMap
    from pipeline.compare import Difference, compare_maps

    expected = DesignMap.load(args.against).dataset  # validates the schema
    with tempfile.TemporaryDirectory(prefix="snapmorph-check-") as tmp:
        out = Path(tmp) / f"{args.grid}.nc"
        report = _build(args, out, restart=True)
        print(report.summary())
        with xr.open_dataset(out, engine="netcdf4") as ds:
            actual = ds.load()
    problems = compare_maps(expected, actual, rtol=args.rtol, atol=args.atol)
    if not problems:
        print(f"OK: the recomputed {args.grid} grid matches {args.against} "
              f"(rtol {args.rtol:g}, atol {args.atol:g})")
        return 0
    print(f"FAIL: the recomputed {args.grid} grid differs from {args.against} "
          f"(rtol {args.rtol:g}, atol {args.atol:g}):")
    for p in problems:
        print(p.describe() if isinstance(p, Difference) else p)
    return 1


def _run_info(args) -> int:
    import numpy as np

    from maps.designmap import DesignMap
    from pipeline.schema import STATUS_CODES

    dm = DesignMap.load(args.file)
    ds = dm.dataset
    print(f"design map {dm.path}")
    for key in ("title", "schema_version", "grid", "b_over_L", "resolution", "package_version",
                "git_commit", "created", "normalisation"):
        if key in ds.attrs:
            print(f"  {key}: {ds.attrs[key]}")
    for name, (lo, hi) in dm.ranges.items():
        print(f"  {name}: {lo:g} .. {hi:g} ({ds.sizes[name]} values)")
    print(f"  base-shape samples: {dm.samples}")
    status = ds["status"].values
    counts = ", ".join(f"{STATUS_CODES[c]} {int(np.sum(status == c))}" for c in sorted(STATUS_CODES)
                       if np.any(status == c))
    print(f"  points: {status.size} ({counts})")
    ok = status == 0
    for name in ("F_cr", "S", "theta"):
        v = ds[name].values[ok]
        if v.size:
            print(f"  {name} ({ds[name].attrs.get('units', '')}): {np.min(v):.4g} .. {np.max(v):.4g} "
                  f"over the bistable points")
    t = ds["solve_time"].values
    if np.any(np.isfinite(t)):
        print(f"  solve time: total {np.nansum(t):.1f} s, mean {np.nanmean(t):.3f} s, "
              f"max {np.nanmax(t):.2f} s per point")
    return 0


def run(args) -> int:
    """Entry point of `snapmorph maps ...`."""
    command = getattr(args, "maps_command", None)
    try:
        return _dispatch(command, args)
    except FileNotFoundError as exc:
        from snapmorph.cli import CommandError

        raise CommandError(str(exc)) from None


def _dispatch(command, args) -> int:
    if command == "build":
        return _run_build(args)
    if command == "check":
        return _run_check(args)
    if command == "info":
        return _run_info(args)
    args._maps_parser.print_help()
    return 2
