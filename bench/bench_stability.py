"""Cost of the stability checks (issue 7): a unit simulation with and without them.

``simulate_unit(g)`` detects and classifies critical points at every step and reports the
stability of states (i)-(iii); ``simulate_unit(g, critical=False)`` is the bare path. Runs
of the two alternate (A B A B ...) so that load from other processes on the machine hits
both alike; every figure is a median of warm runs in one process, one thread.

    .venv/bin/python bench/bench_stability.py        (BENCH_RUNS=n to change the count)
"""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from bench.timing import median_time  # noqa: E402

RUNS = int(os.environ.get("BENCH_RUNS", "9"))
MM = 1e-3
TABLE1 = [(9.11, 99.2, 0.50), (9.10, 99.0, 0.75), (19.24, 99.5, 0.50), (19.96, 99.7, 0.75),
          (40.68, 99.4, 0.50), (39.85, 99.5, 0.75)]


def alternate(fa, fb, runs=RUNS):
    """Median times (s) of fa and fb over interleaved warm runs; and their last results."""
    fa(), fb()
    ta, tb = [], []
    for _ in range(runs):
        for f, times in ((fa, ta), (fb, tb)):
            t0 = time.perf_counter()
            out = f()
            times.append(time.perf_counter() - t0)
        if f is fb:
            last_b = out
    return statistics.median(ta), statistics.median(tb), last_b


def unit_case(g, label):
    from snapmorph.units import simulate_unit

    with_checks = lambda: simulate_unit(g)  # noqa: E731
    bare = lambda: simulate_unit(g, critical=False)  # noqa: E731
    t_bare, t_checks, r = alternate(bare, with_checks)
    extra = 100.0 * (t_checks / t_bare - 1.0)
    print(f"{label}: bare {t_bare * 1e3:6.1f} ms, with stability {t_checks * 1e3:6.1f} ms "
          f"({extra:+.1f} %), {len(r.curve[0])} steps, {r.n_nodes} nodes, "
          f"bifurcation={r.bifurcation}")
    return t_bare, t_checks


def bifurcation_cases():
    """Paths that do meet bifurcations: what locating and switching cost."""
    from validation.arch import clamped_arch
    from validation.column import column

    def free_arch():
        h = 5e-3
        st, mid, _ = clamped_arch(h, centre_clamped=False)
        return st.push(mid, (0.0, -1.0), 2.2 * h, method="mgdc")

    cases = {
        "free-centre arch h/t=10, MGDC, follow": free_arch,
        "perfect column to 3 % shortening, MGDC, follow": lambda: column(imperfection=0.0).push(
            100, (-1.0, 0.0), 0.003, method="mgdc"),
        "perfect column, displacement control, follow": lambda: column(imperfection=0.0).push(
            100, (-1.0, 0.0), 0.003, method="displacement"),
    }
    for label, fn in cases.items():
        med, _, path = median_time(fn, RUNS, warm=True)
        located = sum(c.located for c in path.bifurcations)
        print(f"{label}: median {med * 1e3:.1f} ms, {len(path)} steps, {located} bifurcation(s) "
              f"located, {path.info['branch_switches']} switch(es), "
              f"{path.info['critical_seconds'] * 1e3:.1f} ms locating and switching")


def main():
    from snapmorph.units import UnitGeometry

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"stability checks: median of {RUNS} interleaved warm runs, one thread, "
          f"{os.cpu_count()} cores visible, load average {load:.1f} at start")
    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    unit_case(g, "unit L=100 h=20 t=0.5 w=b=5 mm")
    total_bare = total_checks = 0.0
    for h, L, t in TABLE1:
        gi = UnitGeometry(L=L * MM, h=h * MM, t=t * MM, w=5 * MM, b=5 * MM)
        tb, tc = unit_case(gi, f"  Table 1 h={h:5.2f} L={L:5.1f} t={t:.2f}")
        total_bare += tb
        total_checks += tc
    print(f"Table 1 total: bare {total_bare * 1e3:.1f} ms, with stability "
          f"{total_checks * 1e3:.1f} ms ({100 * (total_checks / total_bare - 1):+.1f} %; "
          "budget +30 %)")
    bifurcation_cases()


if __name__ == "__main__":
    main()
