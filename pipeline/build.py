"""Build a design map: fan a point solver out over a dask.distributed cluster, checkpoint every
finished batch, resume after any interruption, and write the map's netCDF file.

    from snapmorph.pipeline import build_map, preset
    report = build_map(preset("ci"), "maps/data/ci.nc")          # LocalCluster, one worker/core
    report = build_map(grid, out, scheduler="tcp://host:8786")    # an existing cluster
    report = build_map(spec.preset("small"), out, kind="unit2d")  # any registered point solver

A map whose recorded inputs fingerprint equals this build's is left alone (`force=True`
rebuilds); a rebuild with unchanged inputs writes the same bytes. Every point gets a wall-time
limit (status "timeout"). Scripts that call `build_map` without `scheduler` start worker
processes and need the `if __name__ == "__main__":` guard.
"""

from __future__ import annotations

import json
import logging
import math
import os
import time
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from snapmorph.units import status as unit_status
from snapmorph.pipeline import dataset
from snapmorph.pipeline.batch import (check_block, merge, new_block, put, resolve_solver, solve_points,
                                      solver_name, timeout_record)
from snapmorph.pipeline.checkpoint import Checkpoint, checkpoint_dir
from snapmorph.pipeline.fingerprint import (build_inputs, canonical, differences, fingerprint,
                                            solver_modules, source_hash)
from snapmorph.pipeline.solvers import PENDING, get_spec

_DEFAULT = object()
MAX_BATCH = 20  # points per task: a few seconds of work, well above dask's ~2 ms per task
TASKS_PER_WORKER = 8  # at least this many tasks per worker, so the tail stays short
#: default wall-time limit per point (s); the planar unit needs ~0.1-1 s per point
DEFAULT_TIME_LIMIT = 60.0
#: the watchdog stops a batch after n * (WATCHDOG_FACTOR * time_limit + WATCHDOG_SLACK) s: a
#: backstop for point solvers that ignore time_limit, not the limit itself
WATCHDOG_FACTOR, WATCHDOG_SLACK = 1.5, 2.0
WATCHDOG_POLL = 0.5  # s between the watchdog's looks at the scheduler
#: seconds to wait for an existing scheduler to answer
DEFAULT_CONNECT_TIMEOUT = 5.0


class SchedulerConnectError(ConnectionError):
    """The dask scheduler could not be reached (the message is one line)."""


@dataclass
class BuildReport:
    """What a build did. Times in seconds."""

    out: Path
    points: int
    computed: int  # points solved in this run
    resumed: int  # points taken from the checkpoint
    workers: int
    batch_size: int
    wall_time: float  # whole call: checkpoint, cluster start, warm-up, fan-out, writing
    fanout_time: float  # first submit to last result
    startup_time: float  # cluster start and warm-up
    solve_time_sum: float  # sum of per-point solve times of the points computed in this run
    status_counts: dict = field(default_factory=dict)
    failures: list = field(default_factory=list)  # (*coords, status, message), first few
    up_to_date: bool = False  # the map existed with this build's inputs: nothing was done
    fingerprint: str = ""
    failed: int = 0  # points whose status is a failure of the kind (not_converged, timeout, ...)
    refused: list = field(default_factory=list)  # (checkpoint file, reason) refused on resume
    status_names: dict = field(default_factory=dict)  # code -> name of the kind's statuses
    dims: tuple = ()  # the grid's dimensions (the failures' coordinates)
    time_limit: float | None = None

    @property
    def overhead(self) -> float:
        """wall_time / (solve_time_sum / workers); 1 would be perfect parallel efficiency."""
        ideal = self.solve_time_sum / max(self.workers, 1)
        return self.wall_time / ideal if ideal > 0 else math.nan

    @property
    def fanout_overhead(self) -> float:
        """fanout_time / (solve_time_sum / workers): the fan-out alone, without start-up."""
        ideal = self.solve_time_sum / max(self.workers, 1)
        return self.fanout_time / ideal if ideal > 0 else math.nan

    def _counts(self) -> str:
        names = self.status_names or unit_status.NAME
        return ", ".join(f"{names.get(k, k)} {v}" for k, v in sorted(self.status_counts.items()))

    def summary(self) -> str:
        if self.up_to_date:
            return (f"{self.out} is up to date: {self.points} points ({self._counts()}); its recorded "
                    f"inputs (grid, model options, solver source, schema) match this build "
                    f"(fingerprint {self.fingerprint[:12]}); --force rebuilds it")
        lines = [
            f"wrote {self.out}: {self.points} points ({self._counts()})",
            f"computed {self.computed}, resumed from checkpoint {self.resumed}; "
            f"{self.workers} workers, {self.batch_size} points per task",
            f"wall time {self.wall_time:.1f} s (fan-out {self.fanout_time:.1f} s, cluster start "
            f"and warm-up {self.startup_time:.1f} s); sum of solve times {self.solve_time_sum:.1f} s",
        ]
        if self.computed:
            lines.append(f"pipeline overhead: wall / (solve sum / workers) = {self.overhead:.3f} "
                         f"(fan-out only {self.fanout_overhead:.3f})")
        if self.refused:
            lines.append(f"refused {len(self.refused)} checkpoint file(s) (points recomputed): "
                         + "; ".join(f"{n}: {r}" for n, r in self.refused[:5]))
        names = self.status_names or unit_status.NAME
        for *coords, status, msg in self.failures:
            where = ", ".join(f"{d.replace('_over_', '/')}={c:g}" for d, c in zip(self.dims, coords))
            lines.append(f"  {names.get(status, status)} at {where}: {msg}")
        if self.failed > len(self.failures):
            lines.append(f"  ... and {self.failed - len(self.failures)} more failed points (status in the map)")
        return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Inputs, output path, exit policy

def build_identity(grid, solve=None, spec=None):
    """(spec, resolved model options, inputs, fingerprint) of a build of `grid` with `solve`."""
    spec = get_spec(spec or "unit")
    fn = resolve_solver(solve if solve is not None else spec.solve)
    options = spec.grid_options(grid)
    name = solver_name(solve if solve is not None else spec.solve)
    inputs = build_inputs(spec, grid, options, name, source_hash(solver_modules(spec, fn)))
    return spec, options, inputs, fingerprint(inputs)


def check_output_path(out) -> Path:
    """Check that the map file `out` can be written, creating its missing parent folders (the
    rule of every snapmorph command); ValueError naming the problem otherwise."""
    if not isinstance(out, (str, os.PathLike)) or not str(out).strip():
        raise ValueError(f"--out must be a file path, got {out!r}")
    out = Path(out)
    if str(out).endswith(os.sep) or out.is_dir():
        raise ValueError(f"--out {out} is a folder; give a file name such as {out / 'map.nc'}")
    parent = out.parent
    existing = parent
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise ValueError(f"--out {out}: {existing} is a file, not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"--out {out}: cannot write in {existing} (permission denied)")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"--out {out}: cannot create folder {parent} ({exc.strerror or exc})") from None
    if out.exists() and not os.access(out, os.W_OK) and not os.access(parent, os.W_OK):
        raise ValueError(f"--out {out}: the file cannot be replaced (permission denied)")
    return out


def read_map_identity(path) -> dict | None:
    """{"fingerprint", "inputs", "status"} recorded in an existing map file, or None if the file
    holds none (an older map) or cannot be read."""
    try:
        import netCDF4

        with netCDF4.Dataset(path) as nc:
            attrs = {k: nc.getncattr(k) for k in nc.ncattrs()}
            status = np.asarray(nc["status"][...]) if "status" in nc.variables else None
    except Exception:
        return None
    fp = attrs.get("inputs_sha256")
    if not isinstance(fp, str):
        return None
    try:
        inputs = json.loads(attrs.get("build_inputs", "{}"))
    except ValueError:
        inputs = {}
    return {"fingerprint": fp, "inputs": inputs, "status": status}


def parse_max_failed(value):
    """A --max-failed value: an integer count >= 0, a fraction 0 <= f < 1 ("0.01") or a percentage
    ("1%"). Returns int (count) or float (fraction). ValueError names the option otherwise."""
    if isinstance(value, bool):
        raise ValueError(f"--max-failed must be a count >= 0, a fraction in [0, 1) or a percentage, got {value!r}")
    if isinstance(value, (int, np.integer)):
        if value < 0:
            raise ValueError(f"--max-failed must be >= 0 points, got {value}")
        return int(value)
    if isinstance(value, float):
        if not (0.0 <= value < 1.0):
            raise ValueError(f"--max-failed as a fraction must be in [0, 1), got {value!r}")
        return value
    text = str(value).strip()
    try:
        if text.endswith("%"):
            pct = float(text[:-1])
            if not (0.0 <= pct <= 100.0):
                raise ValueError
            return pct / 100.0
        if text.isdigit():
            return int(text)
        frac = float(text)
        if not (0.0 <= frac < 1.0):
            raise ValueError
        return frac
    except ValueError:
        raise ValueError(f"--max-failed must be a count of points >= 0 (e.g. 3), a fraction in [0, 1) "
                         f"(e.g. 0.01) or a percentage (e.g. 1%), got {value!r}") from None


def allowed_failures(max_failed, points: int) -> int:
    """How many failed points `max_failed` (count or fraction) allows in a map of `points`."""
    m = parse_max_failed(max_failed)
    return m if isinstance(m, int) else int(math.floor(m * points + 1e-9))


def _check_time_limit(time_limit):
    if time_limit is None:
        return None
    if isinstance(time_limit, bool) or not isinstance(time_limit, (int, float, np.floating, np.integer)) \
            or not math.isfinite(time_limit) or time_limit <= 0:
        raise ValueError(f"time_limit (--time-limit) must be a finite number of seconds > 0 per point, "
                         f"got {time_limit!r}")
    return float(time_limit)


# ---------------------------------------------------------------------------------------------
# Cluster

def _available_cores() -> int:
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:
        return max(os.cpu_count() or 1, 1)


def MAX_LOCAL_WORKERS() -> int:  # noqa: N802 - a bound, computed for this machine
    """The most worker processes a local cluster may start: 4 per core, at least 8."""
    return max(8, 4 * _available_cores())


def _scheduler_address(scheduler):
    if scheduler:
        return str(scheduler)
    env = os.environ.get("DASK_SCHEDULER_ADDRESS")
    if env:
        return env
    import dask

    return dask.config.get("scheduler-address", None)


def _connect(scheduler, workers, timeout: float, connect_timeout: float = DEFAULT_CONNECT_TIMEOUT):
    """(client, cluster or None, number of workers). An unreachable scheduler raises
    SchedulerConnectError after connect_timeout s."""
    from distributed import Client, LocalCluster

    address = _scheduler_address(scheduler)
    if address:
        try:
            if address.endswith(".json"):
                if not Path(address).is_file():
                    raise SchedulerConnectError(f"scheduler file {address} does not exist")
                client = Client(scheduler_file=address, timeout=connect_timeout)
            else:
                client = Client(address, timeout=connect_timeout)
        except SchedulerConnectError:
            raise
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise SchedulerConnectError(
                f"cannot connect to the dask scheduler at {address} within {connect_timeout:g} s "
                f"({first})") from None
        try:
            client.wait_for_workers(workers or 1, timeout=timeout)
        except (OSError, TimeoutError) as exc:
            client.close()
            raise SchedulerConnectError(
                f"the dask scheduler at {address} has fewer than {workers or 1} worker(s) after "
                f"{timeout:g} s ({type(exc).__name__})") from None
        except BaseException:
            client.close()
            raise
        return client, None, len(client.scheduler_info()["workers"])
    import dask

    n = workers or _available_cores()
    # One task per single-threaded worker at a time (no prefetched second task): a point that
    # crashes its worker then takes no innocent batch down with it, and the watchdog knows
    # which batch runs. Batches last seconds, so the lost prefetch costs nothing measurable.
    with dask.config.set({"distributed.scheduler.worker-saturation": 1.0}):
        # no dashboard; the scheduler's HTTP server on a free loopback port, not 8787 (which
        # another cluster on the machine may hold)
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
    try:
        client = Client(cluster, timeout=timeout)
    except Exception:
        cluster.close()
        raise
    return client, cluster, n


def _batches(todo: np.ndarray, batch_size: int):
    return [todo[i:i + batch_size] for i in range(0, todo.size, batch_size)]


def open_checkpoint(out, grid, solve=None, restart: bool = False, *, kind="unit",
                    identity=None) -> Checkpoint:
    """The checkpoint of a build of `grid` into `out` (created, or resumed), recording the
    build's inputs and fingerprint, and the provenance of the model source. solve: the point
    solver (default the kind's); identity: the build's (spec, options, inputs, fingerprint) if
    already computed."""
    spec, options, inputs, fp = identity or build_identity(grid, solve, kind)
    prov = {**dataset.provenance(), "resolution": options.get("resolution")}
    return Checkpoint.open(out, grid, inputs["solver"], prov, restart=restart, spec=spec,
                           inputs=inputs, fingerprint=fp)


# ---------------------------------------------------------------------------------------------
# The build

def build_map(grid, out, *, solve=_DEFAULT, kind="unit", warm=_DEFAULT, scheduler=None,
              workers: int | None = None, batch_size: int | None = None, restart: bool = False,
              progress: bool = True, timeout: float = 120.0,
              connect_timeout: float = DEFAULT_CONNECT_TIMEOUT,
              time_limit: float | None = DEFAULT_TIME_LIMIT, force: bool = False,
              keep_solve_time: bool = False) -> BuildReport:
    """Build the map of `grid` into the netCDF file `out`, resuming its checkpoint if any.

    kind: registered point-solver kind (`pipeline.solvers`; default "unit", the planar unit);
    solve: point solver (callable or "module:function", importable on the workers; default the
      kind's);
    warm: warm-up callable, given the resolved model options, run once in this process and once
      on every worker before the fan-out (default: the kind's warm-up when solve is the kind's
      solver, else none);
    scheduler: address or scheduler-file of an existing cluster (default: env
      DASK_SCHEDULER_ADDRESS, else a LocalCluster of `workers` single-threaded processes, one
      per core by default); with a scheduler, `workers` is how many workers to wait for;
    batch_size: points per task (default: up to 20, at least 8 tasks per worker);
    restart: discard an existing checkpoint instead of resuming it;
    timeout: seconds to wait for the cluster's workers; connect_timeout: seconds to wait for an
      existing scheduler to answer (SchedulerConnectError after);
    time_limit: wall-time limit per point (s; None = none), passed to point solvers that take
      it; a watchdog restarts a worker whose batch overruns it and records "timeout";
    force: rebuild even if `out` exists with this build's inputs (else nothing is done);
    keep_solve_time: store per-point wall times in `solve_time` (else NaN, so that a rebuild
      writes the same bytes; the report still gives their sum).

    Failed points do not raise: they are in the report (`failed`) and the map's status.
    """
    t_start = time.perf_counter()
    spec = get_spec(kind)
    spec.check_grid(grid)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if workers is not None and not _scheduler_address(scheduler) and workers > MAX_LOCAL_WORKERS():
        raise ValueError(f"workers (--workers) must be <= {MAX_LOCAL_WORKERS()} worker processes for a "
                         f"local cluster on this machine ({_available_cores()} cores), got {workers}")
    if batch_size is not None and (isinstance(batch_size, bool) or not isinstance(batch_size, int)
                                   or batch_size < 1):
        raise ValueError(f"batch_size must be an integer >= 1, got {batch_size!r}")
    for name, v in (("timeout", timeout), ("connect_timeout", connect_timeout)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise ValueError(f"{name} must be a finite number of seconds > 0, got {v!r}")
    time_limit = _check_time_limit(time_limit)
    if solve is _DEFAULT:
        solve = spec.solve
    fn = resolve_solver(solve)  # fail now, not on the workers, if it does not resolve
    own_solver = fn is resolve_solver(spec.solve)
    if warm is _DEFAULT:
        warm = spec.hook("warm") if own_solver else None
    out = check_output_path(out)
    address = _scheduler_address(scheduler)
    if address and address.endswith(".json") and not Path(address).is_file():
        raise SchedulerConnectError(f"scheduler file {address} does not exist")

    identity = build_identity(grid, solve, spec)
    _, options, inputs, fp = identity
    names = dict(spec.status_codes)
    n_points = grid.size
    if out.exists() and not force:
        recorded = read_map_identity(out)
        if recorded and recorded["fingerprint"] == fp and recorded["status"] is not None:
            status = recorded["status"].ravel()
            return _report(out, spec, grid, status, None, t_start, up_to_date=True, fingerprint=fp,
                           names=names, time_limit=time_limit)
        if recorded and recorded["inputs"]:
            changed = ", ".join(differences(recorded["inputs"], inputs)) or "fingerprint"
            warnings.warn(f"rebuilding {out}: its inputs differ from this build's ({changed})", stacklevel=2)
        elif not recorded:
            warnings.warn(f"rebuilding {out}: it records no build inputs (built by an older snapmorph, "
                          f"or not a map)", stacklevel=2)

    coords = grid.points()
    ckpt = open_checkpoint(out, grid, solve, restart=restart, kind=spec, identity=identity)
    stats = {"workers": 0, "batch_size": 0, "fanout": 0.0, "startup": 0.0, "solve": 0.0}
    try:
        total = new_block(spec, np.arange(n_points), options, coords)
        for block in ckpt.load(coords, options):
            merge(total, block)
        todo = np.flatnonzero(total["status"] == PENDING)
        resumed = n_points - todo.size
        if todo.size:
            _fan_out(spec, options, coords, todo, total, ckpt, solve, warm, scheduler, workers,
                     batch_size, progress, timeout, connect_timeout, time_limit, stats)
        _write_and_verify(spec, grid, options, inputs, fp, ckpt.meta, total, coords, out, keep_solve_time)
    except BaseException:
        if any(ckpt.dir.glob("batch-*.npz")) or any(ckpt.dir.glob("refused-*.npz")):
            ckpt.close()  # keep what was computed (and the refused files, as evidence)
        else:
            ckpt.remove()  # nothing worth resuming (e.g. the scheduler did not answer)
        raise
    ckpt.remove()
    report = _report(out, spec, grid, total["status"], total, t_start, fingerprint=fp, names=names,
                     time_limit=time_limit)
    report.computed, report.resumed = int(todo.size), int(resumed)
    report.workers, report.batch_size = stats["workers"], stats["batch_size"]
    report.fanout_time, report.startup_time, report.solve_time_sum = stats["fanout"], stats["startup"], stats["solve"]
    report.refused = list(ckpt.refused)
    return report


def _report(out, spec, grid, status, total, t_start, up_to_date=False, fingerprint="", names=None,
            time_limit=None) -> BuildReport:
    status = np.asarray(status).ravel()
    failed_mask = np.isin(status, spec.failed_codes)
    failures = []
    if total is not None:
        coords = grid.points()
        for i in np.flatnonzero(failed_mask)[:10]:
            failures.append((*coords[i], int(status[i]), str(total["message"][i])))
    return BuildReport(out=Path(out), points=int(status.size), computed=0, resumed=0, workers=0,
                       batch_size=0, wall_time=time.perf_counter() - t_start, fanout_time=0.0,
                       startup_time=0.0, solve_time_sum=0.0,
                       status_counts=dict(Counter(int(s) for s in status)), failures=failures,
                       up_to_date=up_to_date, fingerprint=fingerprint, failed=int(failed_mask.sum()),
                       status_names=names or {}, dims=spec.grid_dims(grid), time_limit=time_limit)


def _write_and_verify(spec, grid, options, inputs, fp, meta, total, coords, out, keep_solve_time):
    """Validate the assembled results, write the map atomically, read it back and check it
    before the caller deletes the checkpoint."""
    try:
        check_block(total, spec, options, coords)
    except ValueError as exc:
        raise RuntimeError(f"the assembled results are not a valid map ({exc}); the checkpoint "
                           f"{checkpoint_dir(out)} is kept") from None
    if not keep_solve_time:
        total = {**total, "solve_time": np.full(total["solve_time"].shape, np.nan)}
    prov = {k: meta.get(k, "unknown") for k in ("created", "package_version", "git_commit")}
    if spec.assemble:  # a kind's own Dataset (its hook's historical call)
        ds = spec.hook("assemble")(grid, total, {**prov, "model_options": options}, spec)
    else:
        ds = dataset.assemble(spec, grid, total, options, prov)
    ds.attrs.update({
        "kind": spec.name,
        "inputs_sha256": fp,
        "build_inputs": canonical(inputs),
        "solver": inputs["solver"],
        "solver_source_sha256": inputs["solver_source_sha256"],
    })
    if not keep_solve_time:
        ds["solve_time"].attrs["comment"] = (
            "not stored (NaN): wall times differ between runs and would make rebuilds differ; "
            "build with --keep-solve-time to store them")
    (spec.hook("write") or dataset.write_netcdf)(ds, out)
    _verify_written(spec, out, ds, fp)


def _verify_written(spec, out, ds, fp) -> None:
    import xarray as xr

    with xr.open_dataset(out, engine="netcdf4") as back:
        back = back.load()
    if back.attrs.get("inputs_sha256") != fp:
        raise RuntimeError(f"{out} was written but does not read back with this build's fingerprint")
    for name in ds.data_vars:
        if not np.array_equal(np.asarray(back[name].values), np.asarray(ds[name].values), equal_nan=True) \
                if np.asarray(ds[name].values).dtype.kind == "f" else \
                not np.array_equal(np.asarray(back[name].values), np.asarray(ds[name].values)):
            raise RuntimeError(f"{out} was written but its variable {name} does not read back as written")
    dataset.check_file(spec, out)


# ---------------------------------------------------------------------------------------------
# Fan-out with a watchdog

def _fan_out(spec, options, coords, todo, total, ckpt, solve, warm, scheduler, workers,
             batch_size, progress, timeout, connect_timeout, time_limit, stats):
    """Solve the points `todo` on a cluster; merge and checkpoint each batch as it arrives."""
    from distributed import wait
    from distributed.scheduler import KilledWorker
    from tqdm import tqdm

    local = not _scheduler_address(scheduler)
    t0 = time.perf_counter()
    if warm is not None and local:
        warm(options)  # compile once here so the workers load the numba cache
    client, cluster, n_workers = _connect(scheduler, workers, timeout, connect_timeout)
    try:
        if warm is not None:
            client.run(warm, options)
        stats["startup"] = time.perf_counter() - t0
        if batch_size is None:
            batch_size = max(1, min(MAX_BATCH, math.ceil(todo.size / (n_workers * TASKS_PER_WORKER))))
        stats["workers"], stats["batch_size"] = n_workers, batch_size

        t_fan = time.perf_counter()
        pending = {}

        def submit(idx):
            fut = client.submit(solve_points, idx, coords[idx], spec, options, solve, time_limit,
                                pure=False)
            pending[fut] = idx

        def record(block):
            ckpt.write(block)
            merge(total, block)
            stats["solve"] += float(np.nansum(block["solve_time"]))
            bar.update(block["index"].size)

        def single(idx, rec, elapsed):
            block = new_block(spec, idx, options, coords[idx])
            put(block, 0, rec, elapsed)
            record(block)

        for idx in _batches(todo, batch_size):
            submit(idx)
        bar = tqdm(total=len(coords), initial=len(coords) - todo.size, unit="pt",
                   desc=f"maps build ({spec.name})", disable=not progress, smoothing=0.1,
                   dynamic_ncols=True)
        watchdog = _Watchdog(client, time_limit) if time_limit is not None else None
        try:
            while pending:
                try:
                    done = wait(list(pending), timeout=WATCHDOG_POLL if watchdog else None,
                                return_when="FIRST_COMPLETED").done
                except TimeoutError:
                    done = ()
                for fut in done:
                    idx = pending.pop(fut)
                    try:
                        block = fut.result()
                    except KilledWorker:
                        # A point crashed its worker (several times). Isolate it: retry the batch
                        # point by point; a single point that still kills workers is recorded.
                        if idx.size > 1:
                            for i in idx:
                                submit(np.array([i]))
                            continue
                        single(idx, spec.empty_record(options, spec.code("not_converged"),
                                                      "the solver killed its worker process"), math.nan)
                        continue
                    record(block)
                if watchdog is not None:
                    for fut, elapsed in watchdog.overdue(pending):
                        idx = pending.pop(fut)
                        if idx.size > 1:  # which point hangs is unknown: retry them one by one
                            for i in idx:
                                submit(np.array([i]))
                        else:
                            single(idx, timeout_record(spec, options, time_limit,
                                                       f"the point solver ran {elapsed:.0f} s without "
                                                       f"returning; its worker was restarted"), elapsed)
        finally:
            bar.close()
        stats["fanout"] = time.perf_counter() - t_fan
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


class _Watchdog:
    """Finds batches that have run longer than n * (WATCHDOG_FACTOR * time_limit +
    WATCHDOG_SLACK) s, cancels them and restarts the worker running them (a point solver that
    ignores its time limit cannot be interrupted inside its process)."""

    def __init__(self, client, time_limit: float):
        self.client = client
        self.time_limit = time_limit
        self.started: dict = {}  # task key -> time it was first seen running
        self.seen: dict = {}  # task key -> time first seen on a worker
        self.nthreads: dict = {}

    def budget(self, n: int) -> float:
        return n * (WATCHDOG_FACTOR * self.time_limit + WATCHDOG_SLACK)

    def overdue(self, pending: dict):
        """[(future, seconds running)] of the overdue batches; their workers are restarted."""
        by_key = {f.key: f for f in pending}
        try:
            processing = self.client.processing()
        except Exception:
            return []
        now = time.monotonic()
        late, restart = [], set()
        for addr, keys in processing.items():
            ours = [k for k in keys if k in by_key]
            for k in ours:
                self.seen.setdefault(k, now)
            if addr not in self.nthreads:
                info = self.client.scheduler_info().get("workers", {})
                self.nthreads[addr] = int(info.get(addr, {}).get("nthreads", 1) or 1)
            # a worker runs at most nthreads tasks at once: the longest-known ones
            for k in sorted(ours, key=self.seen.get)[: self.nthreads[addr]]:
                self.started.setdefault(k, now)
                fut = by_key[k]
                elapsed = now - self.started[k]
                if elapsed > self.budget(pending[fut].size):
                    late.append((fut, elapsed))
                    restart.add(addr)
        for fut, _ in late:
            fut.cancel()
        if restart:
            try:
                self.client.restart_workers(sorted(restart), timeout=60, raise_for_error=False)
            except Exception as exc:  # no nanny (external cluster): the worker stays busy
                warnings.warn(f"could not restart worker(s) {sorted(restart)} running an overdue "
                              f"point: {exc}", stacklevel=2)
        return late
