"""The planar unit's path: the specimen's states, Newton iterations and time, the cost of each
load-bearing metric, and the first command's wall time in a fresh process.

    .venv/bin/python bench/bench_unit_path.py

Warm figures are medians of several calls in this process (kernels compiled or loaded from
numba's on-disk cache first). The per-metric cost is the CPU time spent inside that metric's
function during one `simulate_unit` (wrapped with a timer; CPU time, so that a loaded machine
does not blur it). The first command is
`snapmorph unit --L 100 --h 20 --t 0.5 --w 5 --b 5` in a fresh process, as after `make venv`
(which warms the cache); a fresh clone without the warm-up pays numba's compilation once.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

RUNS = int(os.environ.get("BENCH_RUNS", "7"))
COMMAND = ["-m", "snapmorph", "unit", "--L", "100", "--h", "20", "--t", "0.5", "--w", "5",
           "--b", "5"]


def timed(module, name, spent):
    """Wrap ``module.name`` so that its calls add their CPU time (this process's, robust to
    a loaded machine) to spent[name]."""
    fn = getattr(module, name)

    def wrapper(*a, **k):
        t0 = time.process_time()
        try:
            return fn(*a, **k)
        finally:
            spent[name] = spent.get(name, 0.0) + time.process_time() - t0
    setattr(module, name, wrapper)
    return fn


def main():
    from snapmorph.units import UnitGeometry, simulate_unit
    import snapmorph.units.planar as planar

    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    simulate_unit(g)
    times, cpu, r = [], [], None
    for _ in range(RUNS):
        t0, c0 = time.perf_counter(), time.process_time()
        r = simulate_unit(g)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    path_iters = len(r.curve[0])  # the states of the path
    print(f"specimen (L 100, h 20, t 0.5, w = b = 5 mm), {r.n_nodes} nodes: median "
          f"{statistics.median(times) * 1e3:.1f} ms wall (best {min(times) * 1e3:.1f} ms), "
          f"{statistics.median(cpu) * 1e3:.1f} ms CPU, over {RUNS} warm calls; {path_iters} path "
          f"states; status {r.status}")
    spent = {}
    originals = {n: timed(planar, n, spent) for n in ("snap_back", "most_negative_force",
                                                      "largest_strain", "push_through")}
    reps = []
    for _ in range(RUNS):
        spent.clear()
        t0 = time.process_time()
        simulate_unit(g)
        reps.append((time.process_time() - t0, dict(spent)))
    for n, fn in originals.items():
        setattr(planar, n, fn)
    total = statistics.median(t for t, _ in reps)
    print(f"  per-metric CPU cost (median of {RUNS}; total {total * 1e3:.1f} ms CPU):")
    for name, what in (("push_through", "push, F_cr, states (ii)/(iii) and their stability"),
                       ("most_negative_force", "F_min, d_Fmin (displacement-controlled search)"),
                       ("largest_strain", "strain_max, strain_max_released"),
                       ("snap_back", "F_back, stiffness_released (the released unit pushed back)")):
        ms = statistics.median(s.get(name, 0.0) for _, s in reps) * 1e3
        print(f"    {what:<62} {ms:7.1f} ms ({ms / (total * 1e3) * 100:4.1f} %)")
    env = dict(os.environ, PYTHONPATH=ROOT)
    import resource

    walls, cpus = [], []
    for _ in range(3):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, *COMMAND], env=env, check=True, capture_output=True)
        walls.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    print(f"first command `snapmorph unit --L 100 --h 20 --t 0.5 --w 5 --b 5` in a fresh "
          f"process, numba cache warm (as after `make venv`): median {statistics.median(walls):.2f} s "
          f"wall, {statistics.median(cpus):.2f} s CPU (target <= 3 s)")


if __name__ == "__main__":
    main()
