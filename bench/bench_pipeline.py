"""Pipeline figures: a build of the CI grid with the real unit solver (2 local workers), the
up-to-date check that makes `make maps` a no-op, a kill -9 of a build and its resume.

    .venv/bin/python bench/bench_pipeline.py

The kill -9 run starts `snapmorph maps build` in its own process group, kills the group with
SIGKILL once 4 batches are checkpointed, and runs the same command again; it reports the
points resumed and whether the resumed map's values equal the uninterrupted build's.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, REPO)


def _cli(out, *extra):
    return [sys.executable, "-m", "snapmorph", "maps", "build", "--grid", "ci", "--out", str(out),
            "--no-progress", *extra]


def main() -> None:
    import numpy as np
    import xarray as xr

    from snapmorph.pipeline.build import build_map
    from snapmorph.pipeline.checkpoint import checkpoint_dir
    from snapmorph.pipeline import preset

    grid = preset("ci")
    with tempfile.TemporaryDirectory(prefix="snapmorph-bench-") as tmp:
        out = Path(tmp) / "ci.nc"
        r = build_map(grid, out, workers=2, progress=False)
        print(f"CI grid ({r.points} points, real solver, 2 workers): wall {r.wall_time:.1f} s "
              f"(cluster start + warm-up {r.startup_time:.1f} s, fan-out {r.fanout_time:.1f} s, "
              f"sum of solve times {r.solve_time_sum:.1f} s; fan-out overhead {r.fanout_overhead:.2f})")
        t0 = time.perf_counter()
        r2 = build_map(grid, out, workers=2, progress=False)
        print(f"up-to-date check (the no-op `make maps`): {time.perf_counter() - t0:.2f} s in-process, "
              f"up_to_date={r2.up_to_date}")
        t0 = time.perf_counter()
        subprocess.run(_cli(out), cwd=REPO, capture_output=True, check=False)
        print(f"  the same from the shell (`snapmorph maps build ...`, imports included): "
              f"{time.perf_counter() - t0:.1f} s")

        killed = Path(tmp) / "killed.nc"
        t0 = time.perf_counter()
        proc = subprocess.Popen(_cli(killed, "--batch-size", "2"), cwd=REPO, start_new_session=True,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        ckpt = checkpoint_dir(killed)
        while len(list(ckpt.glob("batch-*.npz"))) < 4 and proc.poll() is None:
            time.sleep(0.1)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        t_kill = time.perf_counter() - t0
        n_done = len(list(ckpt.glob("batch-*.npz")))
        t0 = time.perf_counter()
        res = subprocess.run(_cli(killed), cwd=REPO, capture_output=True, text=True, check=False)
        t_resume = time.perf_counter() - t0
        line = next((ln for ln in res.stdout.splitlines() if ln.startswith("computed")), res.stdout.strip())
        with xr.open_dataset(out) as a, xr.open_dataset(killed) as b:
            same = same_values(a, b)
            same_bytes = out.read_bytes() == killed.read_bytes()
        print(f"kill -9 after {t_kill:.1f} s ({n_done} batches checkpointed), resume {t_resume:.1f} s "
              f"(exit {res.returncode}; {line}); values equal to the uninterrupted build: {same}; "
              f"same bytes: {same_bytes} (differ only if the solver source changed in between)")


def same_values(a, b) -> bool:
    """Do two maps (xarray datasets) hold the same values in every variable? NaN equals NaN
    in the numeric ones; the text ones (``strain_where``) are compared as they are."""
    import numpy as np

    return set(a.data_vars) == set(b.data_vars) and all(
        np.array_equal(a[v].values, b[v].values, equal_nan=a[v].values.dtype.kind in "fc")
        for v in a.data_vars)


def default_map_estimate(n: int = 40, seed: int = 0) -> None:
    """The default map (its b/L axis included): its size and a build-time estimate on two
    cores from n of its points drawn at random and solved here, one after another (the
    build's own figure, from `make maps`, is in pipeline/README.md)."""
    import numpy as np

    from snapmorph.pipeline import preset
    from snapmorph.pipeline.kinds.unit import solve_point

    grid = preset("default")
    axes = [np.asarray(a, dtype=float) for a in
            (grid.h_over_L, grid.t_over_L, grid.w_over_L, np.atleast_1d(grid.b_over_L))]
    total = int(np.prod([len(a) for a in axes]))
    rng = np.random.default_rng(seed)
    points = [tuple(float(a[rng.integers(len(a))]) for a in axes) for _ in range(n)]
    solve_point(*points[0], resolution=grid.resolution)  # kernels compiled or loaded
    t0, c0 = time.perf_counter(), time.process_time()
    for p in points:
        solve_point(*p, resolution=grid.resolution)
    wall, cpu = (time.perf_counter() - t0) / n, (time.process_time() - c0) / n
    print(f"default map: {' x '.join(str(len(a)) for a in axes)} = {total} points "
          f"(b/L {', '.join(f'{b:g}' for b in axes[3])}); {n} random points solved here: "
          f"{wall * 1e3:.0f} ms wall, {cpu * 1e3:.0f} ms CPU per point -> about "
          f"{total * cpu / 2 / 60:.1f} min of solving on two free cores")


if __name__ == "__main__":
    main()
    default_map_estimate()
