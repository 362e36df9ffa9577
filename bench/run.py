"""`make bench`: speed figures of the solver, the unit and (if present) the pipeline.

Every figure is a median of several warm runs in this process (numba kernels compiled or
loaded from the cache first); the JIT warm-up is measured in a fresh process with an empty
numba cache. The machine is whatever runs this: say which when you quote the numbers.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from bench.timing import median_time as _median_time  # noqa: E402

RUNS = int(os.environ.get("BENCH_RUNS", "7"))


def median_time(fn, runs=RUNS):
    return _median_time(fn, runs)


def jit_warmup():
    code = (
        "import time; t0=time.perf_counter();"
        "from bench.cases import clamped_arch_push; clamped_arch_push();"
        "print(time.perf_counter()-t0)"
    )
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=os.path.dirname(HERE))
        cold = float(subprocess.run([sys.executable, "-c", code], env=env, check=True,
                                    capture_output=True, text=True).stdout.strip())
        cached = float(subprocess.run([sys.executable, "-c", code], env=env, check=True,
                                      capture_output=True, text=True).stdout.strip())
    return cold, cached


def main():
    from bench.cases import clamped_arch_push, specimen_unit

    print(f"snapmorph benchmarks ({os.cpu_count()} cores visible, NUMBA_NUM_THREADS=1, "
          f"median of {RUNS} warm runs)")
    cold, cached = jit_warmup()
    print(f"JIT warm-up, first arch push in a fresh process: {cold:.2f} s cold (empty cache), "
          f"{cached:.2f} s with the on-disk cache")

    clamped_arch_push()
    med, best, path = median_time(clamped_arch_push)
    iters = int(path.info["total_iterations"]) + len(path) - 1
    print(f"clamped arch, 101 nodes, MGDC to 2.2 h: median {med*1e3:.1f} ms (best {best*1e3:.1f} ms; "
          f"target <= 20 ms), {len(path)} steps, {iters} Newton iterations, "
          f"{med / iters * 1e6:.0f} us per iteration (assemble + LDL^T + solve)")

    from bench.cases import cantilever_push

    per_iter = []
    for n in (101, 201, 401, 801):
        cantilever_push(n)
        med, _, path = median_time(lambda: cantilever_push(n), runs=3)
        iters = int(path.info["total_iterations"]) + len(path) - 1
        per_iter.append((n, med / iters * 1e6))
    print("scaling, cantilever MGDC (time per Newton iteration): " + ", ".join(
        f"{n} nodes {us:.0f} us" for n, us in per_iter)
        + f"  (x{per_iter[-1][1] / per_iter[0][1]:.1f} for x8 nodes: banded, linear in N)")

    specimen_unit()
    med, best, r = median_time(specimen_unit)
    print(f"unit (L=100, h=20, t=0.5, w=b=5 mm) at default resolution ({r.n_nodes} nodes), "
          f"d = 0 to state (iii) solved, self-standing check included: median {med*1e3:.1f} ms "
          f"(best {best*1e3:.1f} ms; target <= 50 ms)")
    med2, best2, _ = median_time(lambda: specimen_unit(check_self_standing=False))
    print(f"  the same without the self-standing check: median {med2*1e3:.1f} ms (best {best2*1e3:.1f} ms)")

    for extra in ("bench_unit_path", "against_reference", "bench_kernels", "bench_setup",
                  "bench_pipeline", "bench_stability",
                  "bench_units3d", "bench_inverse", "bench_tolerance", "bench_rods3d", "bench_paths",
                  "bench_multishape", "bench_loads", "bench_sparse", "bench_sheet"):
        path = os.path.join(HERE, extra + ".py")
        if os.path.exists(path):
            print(f"--- {extra}")
            sys.stdout.flush()
            # the reference comparison: alternating fresh processes, 5 rounds (a median of
            # three moved the specimen's ratio by +-3 % between runs on these machines)
            args = ["--rounds", "5"] if extra == "against_reference" else []
            subprocess.run([sys.executable, path, *args], check=False)


if __name__ == "__main__":
    main()
