"""`snapmorph maps`: build, check and describe design maps.

    snapmorph maps build --grid default --out maps/data/default.nc [--workers N] [--scheduler ADDR]
    snapmorph maps check --grid ci --against maps/data/ci.nc
    snapmorph maps info [FILE]

Exit status of `build`: 0 when the map is written (or already up to date) with no more failed
points than --max-failed allows; 1 when it has more (the map is still written, failed points
marked in its status); 2 for a usage error or an unreachable scheduler (one line, before any
work).
"""

from __future__ import annotations

import argparse
import math

GRIDS = ("default", "ci")
DEFAULT_SOLVER = "snapmorph.pipeline.kinds.unit:solve_point"
DEFAULT_KIND = "unit"
DEFAULT_TIME_LIMIT = 60.0  # s per point; pipeline.build.DEFAULT_TIME_LIMIT (not imported: --help stays light)
DEFAULT_CONNECT_TIMEOUT = 5.0
MAX_WORKERS = 256  # worker processes; pipeline.build.MAX_LOCAL_WORKERS bounds a local cluster further


def _positive_int(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {v}")
    return v


def _int_at_least(low, what, high=None):
    rng = f">= {low}" if high is None else f"in [{low}, {high}]"

    def parse(text):
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer {rng} ({what}); got {text!r}") from None
        if v < low or (high is not None and v > high):
            raise argparse.ArgumentTypeError(f"must be an integer {rng} ({what}); got {text!r}")
        return v
    parse.__name__ = "integer"
    return parse


def _nonneg_float(text):
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}") from None
    if not (math.isfinite(v) and v >= 0):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return v


def _seconds(high):
    def parse(text):
        msg = f"must be a number of seconds in (0, {high:g}]; got {text!r}"
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(msg) from None
        if not (math.isfinite(v) and 0 < v <= high):
            raise argparse.ArgumentTypeError(msg)
        return v
    parse.__name__ = "seconds"
    return parse


def _max_failed(text):
    t = text.strip()
    msg = (f"must be a count of points >= 0 (e.g. 3), a fraction in [0, 1) (e.g. 0.01) or a "
           f"percentage (e.g. 1%); got {text!r}")
    try:
        if t.endswith("%"):
            v = float(t[:-1])
            ok = math.isfinite(v) and 0 <= v <= 100
        elif t.isdigit():
            return int(t)
        else:
            v = float(t)
            ok = math.isfinite(v) and 0 <= v < 1
    except ValueError:
        raise argparse.ArgumentTypeError(msg) from None
    if not ok:
        raise argparse.ArgumentTypeError(msg)
    return t


def _module_function(text):
    if ":" not in text or text.startswith(":") or text.endswith(":") or text.count(":") != 1:
        raise argparse.ArgumentTypeError(f"must be MODULE:FUNCTION (importable on the workers); got {text!r}")
    return text


def _scheduler(text):
    t = text.strip()
    if not t:
        raise argparse.ArgumentTypeError("must be a dask scheduler address (tcp://HOST:PORT) or a "
                                         "scheduler-file path ending in .json; got ''")
    if t.endswith(".json"):
        return t
    rest = t.split("://", 1)[1] if "://" in t else t
    host, _, port = rest.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(
            f"must be a dask scheduler address such as tcp://127.0.0.1:8786 (port 1-65535) or a "
            f"scheduler-file path ending in .json; got {text!r}")
    return t


def _cluster_args(p):
    p.add_argument("--kind", default=DEFAULT_KIND, metavar="NAME",
                   help="kind of map from the registry in pipeline/solvers.py (default unit, the "
                        "planar unit; e.g. unit2d, the 2-D unit), or MODULE:ATTRIBUTE of a SolverSpec")
    p.add_argument("--scheduler", type=_scheduler, metavar="ADDRESS",
                   help="dask scheduler address or scheduler-file of an existing cluster "
                        "(default: $DASK_SCHEDULER_ADDRESS, else a local cluster)")
    p.add_argument("--connect-timeout", type=_seconds(600), default=DEFAULT_CONNECT_TIMEOUT, metavar="S",
                   help=f"seconds to wait for the scheduler to answer (default {DEFAULT_CONNECT_TIMEOUT:g})")
    p.add_argument("--workers", type=_int_at_least(1, "worker processes", MAX_WORKERS), metavar="N",
                   help="local worker processes (default: one per core); with --scheduler, "
                        "how many workers to wait for")
    p.add_argument("--resolution", type=_int_at_least(5, "solver nodes"), metavar="N",
                   help="solver resolution (nodes, >= 5) instead of the grid preset's")
    p.add_argument("--batch-size", type=_int_at_least(1, "points per task"), metavar="N",
                   help="points per dask task (default: up to 20)")
    p.add_argument("--solver", type=_module_function, default=None, metavar="MODULE:FUNCTION",
                   help=f"point solver, importable on the workers (default: the kind's; "
                        f"{DEFAULT_SOLVER} for unit)")
    p.add_argument("--time-limit", type=_seconds(1e6), default=DEFAULT_TIME_LIMIT, metavar="S",
                   help=f"wall-time limit per point in seconds (default {DEFAULT_TIME_LIMIT:g}); a "
                        f"point past it gets status timeout and the build goes on")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("maps", help="build, check and describe design maps",
                              description="Design maps: F_cr, S, theta, ... over (h/L, t/L, w/L).")
    sub = p.add_subparsers(dest="maps_command", metavar="SUBCOMMAND")
    p.set_defaults(run=run, _maps_parser=p)

    b = sub.add_parser("build", help="build a map (resumes an interrupted build of the same file)",
                       description="Fan the unit solver out over a grid with dask and write a "
                                   "netCDF design map. Finished points are checkpointed in "
                                   "OUT.partial/; running the same command again resumes. A map "
                                   "that exists with the same inputs (grid, model options, "
                                   "solver source, schema) is left alone unless --force. Exit "
                                   "status 1 when more points failed than --max-failed allows.")
    b.add_argument("--grid", default="default", metavar="NAME",
                   help="grid preset of the kind (unit: default, ci; default: default)")
    b.add_argument("--out", required=True, metavar="FILE", help="netCDF file to write")
    b.add_argument("--restart", action="store_true",
                   help="discard the checkpoint of an interrupted build and start afresh")
    b.add_argument("--force", action="store_true",
                   help="rebuild even if FILE exists with the same inputs")
    b.add_argument("--max-failed", type=_max_failed, default="0", metavar="N|F|P%",
                   help="failed points (not_converged, timeout, invalid_geometry) allowed before "
                        "the exit status is 1: a count (3), a fraction (0.01) or a percentage "
                        "(1%%); default 0")
    b.add_argument("--keep-solve-time", action="store_true",
                   help="store per-point wall times in solve_time (the file then differs between "
                        "rebuilds; default: NaN)")
    _cluster_args(b)

    c = sub.add_parser("check", help="recompute a grid and compare it with a map file",
                       description="Recompute the grid and compare every variable (except "
                                   "solve_time) with FILE; exit status 1 and a list of the "
                                   "differing variables and points when they differ.")
    c.add_argument("--grid", default="ci", metavar="NAME", help="grid preset (default: ci)")
    c.add_argument("--against", required=True, metavar="FILE", help="map file to compare with")
    c.add_argument("--rtol", type=_nonneg_float, default=1e-6, help="relative tolerance (default 1e-6)")
    c.add_argument("--atol", type=_nonneg_float, default=1e-9, help="absolute tolerance (default 1e-9)")
    _cluster_args(c)

    i = sub.add_parser("info", help="summarise a map file")
    i.add_argument("file", nargs="?", metavar="FILE", help="map file (default: the default map)")


def _spec_and_grid(args):
    from snapmorph.pipeline.solvers import get_spec

    try:
        spec = get_spec(args.kind)
    except ValueError as exc:
        raise ValueError(f"--kind: {exc}") from None
    if args.grid not in spec.presets:
        raise ValueError(f"--grid must be one of {', '.join(sorted(spec.presets))} for kind "
                         f"{spec.name}; got {args.grid!r}")
    grid = spec.preset(args.grid)
    if args.resolution is not None:
        if "resolution" not in spec.options:
            raise ValueError(f"--resolution: kind {spec.name} has no resolution option")
        grid = grid.with_options(resolution=args.resolution)
        try:
            spec.grid_options(grid)  # the kind's own bounds (the unit: nodes in [11, 20001])
        except ValueError as exc:
            raise ValueError(f"--resolution {args.resolution}: {exc}") from None
    return spec, grid


def _solver(args, spec):
    from snapmorph.pipeline.batch import resolve_solver

    solve = args.solver or spec.solve
    try:
        resolve_solver(solve)
    except ValueError as exc:
        raise ValueError(f"--solver: {exc}") from None
    return solve


def _build(args, out, restart, force=False, keep_solve_time=False):
    from snapmorph.pipeline.build import SchedulerConnectError, build_map
    from snapmorph.cli import CommandError

    spec, grid = _spec_and_grid(args)
    solve = _solver(args, spec)
    try:
        return build_map(grid, out, kind=spec, solve=solve, scheduler=args.scheduler,
                         workers=args.workers, batch_size=args.batch_size, restart=restart,
                         progress=not args.no_progress, time_limit=args.time_limit,
                         connect_timeout=args.connect_timeout, force=force,
                         keep_solve_time=keep_solve_time)
    except SchedulerConnectError as exc:
        raise CommandError(str(exc)) from None


def _run_build(args) -> int:
    from snapmorph.pipeline.build import allowed_failures
    from snapmorph.commands._common import output_file

    spec, _ = _spec_and_grid(args)  # option errors before anything touches the disk
    _solver(args, spec)
    out = output_file(args.out, "--out")
    report = _build(args, out, args.restart, force=args.force, keep_solve_time=args.keep_solve_time)
    print(report.summary())
    allowed = allowed_failures(args.max_failed, report.points)
    if report.failed > allowed:
        print(f"FAILED: {report.failed} of {report.points} points failed, more than --max-failed "
              f"{args.max_failed} allows ({allowed}); the map is written with their status")
        return 1
    return 0


def _run_check(args) -> int:
    import tempfile
    from pathlib import Path

    import xarray as xr

    from snapmorph.pipeline.compare import Difference, compare_maps
    from snapmorph.pipeline.dataset import check_file
    from snapmorph.commands._common import input_file

    spec, _ = _spec_and_grid(args)
    _solver(args, spec)
    against = input_file(args.against, "--against")
    check_file(spec, against)  # a finished map of the kind (the planar unit's: DesignMap.load)
    with xr.open_dataset(against, engine="netcdf4") as ds:
        expected = ds.load()
    with tempfile.TemporaryDirectory(prefix="snapmorph-check-") as tmp:
        out = Path(tmp) / f"{args.grid}.nc"
        report = _build(args, out, restart=True, force=True)
        print(report.summary())
        with xr.open_dataset(out, engine="netcdf4") as ds:
            actual = ds.load()
    if expected.attrs.get("inputs_sha256") and expected.attrs.get("inputs_sha256") != actual.attrs.get("inputs_sha256"):
        print(f"note: {args.against} was built from other inputs (fingerprint "
              f"{str(expected.attrs['inputs_sha256'])[:12]}, now {str(actual.attrs['inputs_sha256'])[:12]})")
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


def _info_other_kind(path, kind) -> int:
    """`maps info` of a map of a kind other than the planar unit (no DesignMap reader)."""
    import numpy as np
    import xarray as xr

    with xr.open_dataset(path, engine="netcdf4") as ds:
        ds = ds.load()
    print(f"map {path} (kind {kind})")
    for key in ("title", "schema_version", "grid", "sides", "model_options", "package_version",
                "git_commit", "created", "inputs_sha256"):
        if key in ds.attrs:
            print(f"  {key}: {ds.attrs[key]}")
    status = ds["status"]
    for dim in status.dims:
        v = ds[dim].values
        print(f"  {dim}: {v.min():g} .. {v.max():g} ({v.size} values)")
    names = dict(zip((int(c) for c in status.attrs.get("flag_values", [])),
                     str(status.attrs.get("flag_meanings", "")).split()))
    codes, counts = np.unique(status.values, return_counts=True)
    print(f"  points: {status.size} (" + ", ".join(f"{names.get(int(c), c)} {n}" for c, n in zip(codes, counts)) + ")")
    return 0


def _run_info(args) -> int:
    import numpy as np

    from snapmorph.maps.designmap import DesignMap

    if args.file:
        try:
            import netCDF4

            with netCDF4.Dataset(args.file) as nc:
                kind = getattr(nc, "kind", "unit")
        except Exception:
            kind = "unit"  # DesignMap.load says what is wrong with the file
        if kind != "unit":
            return _info_other_kind(args.file, kind)
    dm = DesignMap.load(args.file)
    ds = dm.dataset
    print(f"design map {dm.path}")
    for key in ("title", "schema_version", "grid", "b_over_L", "resolution", "package_version",
                "git_commit", "created", "normalisation", "inputs_sha256"):
        if key in ds.attrs:
            print(f"  {key}: {ds.attrs[key]}")
    for name, (lo, hi) in dm.ranges.items():
        print(f"  {name}: {lo:g} .. {hi:g} ({ds.sizes[name]} values)")
    print(f"  base-shape samples: {dm.samples}")
    status = ds["status"].values
    names = dm.status_names
    counts = ", ".join(f"{names[c]} {int(np.sum(status == c))}" for c in sorted(names)
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
    import warnings

    command = getattr(args, "maps_command", None)
    # warnings (refused checkpoint files, a rebuild and why) as one line each, no source line,
    # while the command runs
    plain = warnings.formatwarning
    warnings.formatwarning = lambda message, category, *rest, **kw: f"snapmorph maps: warning: {message}\n"
    try:
        return _dispatch(command, args)
    except FileNotFoundError as exc:
        from snapmorph.cli import CommandError

        raise CommandError(str(exc)) from None
    finally:
        warnings.formatwarning = plain


def _dispatch(command, args) -> int:
    if command == "build":
        return _run_build(args)
    if command == "check":
        return _run_check(args)
    if command == "info":
        return _run_info(args)
    args._maps_parser.print_help()
    return 2
