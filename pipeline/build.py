"""Build a design map: fan the point solver out over a dask.distributed cluster, checkpoint
every finished batch, resume after any interruption, and write the schema-1 netCDF file.

    from pipeline import build_map, preset
    report = build_map(preset("ci"), "maps/data/ci.nc")          # LocalCluster, one worker/core
    report = build_map(grid, out, scheduler="tcp://host:8786")    # an existing cluster

Scripts that call `build_map` without `scheduler` start worker processes and need the
`if __name__ == "__main__":` guard.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.batch import empty_block, merge, put, resolve_solver, solve_batch, solver_name
from pipeline.checkpoint import Checkpoint
from pipeline.grid import Grid
from pipeline.point import default_resolution, empty_record, solve_point, warm_up
from pipeline.schema import NOT_CONVERGED, PENDING, STATUS_CODES

_DEFAULT = object()
MAX_BATCH = 20  # points per task: a few seconds of work, well above dask's ~2 ms per task
TASKS_PER_WORKER = 8  # at least this many tasks per worker, so the tail stays short


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
    failures: list = field(default_factory=list)  # (h/L, t/L, w/L, status, message), first few

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

    def summary(self) -> str:
        counts = ", ".join(f"{STATUS_CODES[k]} {v}" for k, v in sorted(self.status_counts.items()))
        lines = [
            f"wrote {self.out}: {self.points} points ({counts})",
            f"computed {self.computed}, resumed from checkpoint {self.resumed}; "
            f"{self.workers} workers, {self.batch_size} points per task",
            f"wall time {self.wall_time:.1f} s (fan-out {self.fanout_time:.1f} s, cluster start "
            f"and warm-up {self.startup_time:.1f} s); sum of solve times {self.solve_time_sum:.1f} s",
        ]
        if self.computed:
            lines.append(f"pipeline overhead: wall / (solve sum / workers) = {self.overhead:.3f} "
                         f"(fan-out only {self.fanout_overhead:.3f})")
        for h, t, w, status, msg in self.failures:
            lines.append(f"  {STATUS_CODES[status]} at h/L={h:g}, t/L={t:g}, w/L={w:g}: {msg}")
        n_failed = sum(v for k, v in self.status_counts.items() if k >= NOT_CONVERGED)
        if n_failed > len(self.failures):
            lines.append(f"  ... and {n_failed - len(self.failures)} more failed points (status in the map)")
        return "\n".join(lines)


def _available_cores() -> int:
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:
        return max(os.cpu_count() or 1, 1)


def _scheduler_address(scheduler):
    if scheduler:
        return str(scheduler)
    env = os.environ.get("DASK_SCHEDULER_ADDRESS")
    if env:
        return env
    import dask

    return dask.config.get("scheduler-address", None)


def _connect(scheduler, workers, timeout: float):
    """(client, cluster or None, number of workers)."""
    from distributed import Client, LocalCluster

    address = _scheduler_address(scheduler)
    if address:
        if address.endswith(".json") and Path(address).is_file():
            client = Client(scheduler_file=address, timeout=timeout)
        else:
            client = Client(address, timeout=timeout)
        try:
            client.wait_for_workers(workers or 1, timeout=timeout)
        except Exception:
            client.close()
            raise
        return client, None, len(client.scheduler_info()["workers"])
    import dask

    n = workers or _available_cores()
    # One task per single-threaded worker at a time (no prefetched second task): a point that
    # crashes its worker then takes no innocent batch down with it. Batches last seconds, so
    # the lost prefetch costs nothing measurable.
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


def open_checkpoint(out, grid: Grid, solve=solve_point, restart: bool = False) -> Checkpoint:
    """The checkpoint of a build of `grid` into `out` (created, or resumed), recording the
    start time, versions and the solver resolution actually used (the solver's default when
    grid.resolution is None)."""
    from pipeline.dataset import provenance

    resolution = grid.resolution if grid.resolution is not None else default_resolution()
    return Checkpoint.open(out, grid, solver_name(solve), {**provenance(), "resolution": resolution},
                           restart=restart)


def build_map(grid: Grid, out, *, solve=solve_point, warm=_DEFAULT, scheduler=None,
              workers: int | None = None, batch_size: int | None = None, restart: bool = False,
              progress: bool = True, timeout: float = 120.0) -> BuildReport:
    """Build the map of `grid` into the netCDF file `out`, resuming its checkpoint if any.

    solve: point solver (callable or "module:function", importable on the workers);
    warm: warm-up callable(resolution) run once in this process and once on every worker before
      the fan-out (default: the solver's warm-up when solve is `solve_point`, else none);
    scheduler: address or scheduler-file of an existing cluster (default: env
      DASK_SCHEDULER_ADDRESS, else a LocalCluster of `workers` single-threaded processes, one
      per core by default); with a scheduler, `workers` is how many workers to wait for;
    batch_size: points per task (default: up to 20, at least 8 tasks per worker);
    restart: discard an existing checkpoint instead of resuming it;
    timeout: seconds to wait for the cluster to connect.
    """
    from pipeline.dataset import assemble, global_attrs, write_netcdf

    t_start = time.perf_counter()
    if not isinstance(grid, Grid):
        raise ValueError(f"grid must be a pipeline.grid.Grid, got {type(grid).__name__}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if batch_size is not None and (isinstance(batch_size, bool) or not isinstance(batch_size, int)
                                   or batch_size < 1):
        raise ValueError(f"batch_size must be an integer >= 1, got {batch_size!r}")
    fn = resolve_solver(solve)  # fail now, not on the workers, if it does not resolve
    if warm is _DEFAULT:
        warm = warm_up if fn is solve_point else None
    out = Path(out)
    n_points, samples = grid.size, grid.samples
    coords = grid.points()

    ckpt = open_checkpoint(out, grid, solve, restart=restart)
    resolution = ckpt.meta["resolution"]
    try:
        total = empty_block(np.arange(n_points), samples)
        for block in ckpt.load(n_points, samples):
            merge(total, block)
        todo = np.flatnonzero(total["status"] == PENDING)
        resumed = n_points - todo.size
        stats = {"workers": 0, "batch_size": 0, "fanout": 0.0, "startup": 0.0, "solve": 0.0}
        if todo.size:
            _fan_out(grid, resolution, coords, todo, total, ckpt, solve, warm, scheduler, workers,
                     batch_size, progress, timeout, stats)
        attrs = global_attrs(grid, ckpt.meta)
        write_netcdf(assemble(grid, total, attrs), out)
    except BaseException:
        ckpt.close()
        raise
    ckpt.remove()

    status = total["status"]
    bad = np.flatnonzero(status >= NOT_CONVERGED)
    failures = [(*coords[i], int(status[i]), str(total["message"][i])) for i in bad[:10]]
    return BuildReport(
        out=out, points=n_points, computed=int(todo.size), resumed=int(resumed),
        workers=stats["workers"], batch_size=stats["batch_size"],
        wall_time=time.perf_counter() - t_start, fanout_time=stats["fanout"],
        startup_time=stats["startup"], solve_time_sum=stats["solve"],
        status_counts=dict(Counter(int(s) for s in status)), failures=failures,
    )


def _fan_out(grid, resolution, coords, todo, total, ckpt, solve, warm, scheduler, workers,
             batch_size, progress, timeout, stats):
    """Solve the points `todo` on a cluster; merge and checkpoint each batch as it arrives."""
    from distributed import as_completed
    from distributed.scheduler import KilledWorker
    from tqdm import tqdm

    local = not _scheduler_address(scheduler)
    t0 = time.perf_counter()
    if warm is not None and local:
        warm(resolution)  # compile once here so the workers load the numba cache
    client, cluster, n_workers = _connect(scheduler, workers, timeout)
    try:
        if warm is not None:
            client.run(warm, resolution)
        stats["startup"] = time.perf_counter() - t0
        if batch_size is None:
            batch_size = max(1, min(MAX_BATCH, math.ceil(todo.size / (n_workers * TASKS_PER_WORKER))))
        stats["workers"], stats["batch_size"] = n_workers, batch_size

        args = (grid.b_over_L, resolution, grid.samples, solve)
        t_fan = time.perf_counter()
        pending = {}
        for idx in _batches(todo, batch_size):
            fut = client.submit(solve_batch, idx, coords[idx], *args, pure=False)
            pending[fut] = idx
        bar = tqdm(total=grid.size, initial=grid.size - todo.size, unit="pt", desc="maps build",
                   disable=not progress, smoothing=0.1, dynamic_ncols=True)
        queue = as_completed(list(pending))
        try:
            for fut in queue:
                idx = pending.pop(fut)
                try:
                    block = fut.result()
                except KilledWorker:
                    # A point crashed its worker (several times). Isolate it: retry the batch
                    # point by point; a single point that still kills workers is recorded.
                    if idx.size > 1:
                        for i in idx:
                            one = np.array([i])
                            f1 = client.submit(solve_batch, one, coords[one], *args, pure=False)
                            pending[f1] = one
                            queue.add(f1)
                        continue
                    block = empty_block(idx, grid.samples)
                    put(block, 0, empty_record(grid.samples, NOT_CONVERGED,
                                               "the solver killed its worker process"), math.nan)
                ckpt.write(block)
                merge(total, block)
                stats["solve"] += float(np.nansum(block["solve_time"]))
                bar.update(block["index"].size)
        finally:
            bar.close()
        stats["fanout"] = time.perf_counter() - t_fan
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
