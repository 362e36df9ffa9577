"""Speed of the 3-D unit and the 2-D unit (issue 14): a push from d = 0 to the second stable
state, states (ii) and (iii) solved, warm (numba kernels compiled or cached first); medians of
BENCH_RUNS runs in one process, one thread. Targets: 3-D unit <= 0.5 s, 2-D unit <= 2 s.

    .venv/bin/python bench/bench_units3d.py
"""

from __future__ import annotations

import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sys  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from bench.timing import median_time  # noqa: E402

RUNS = int(os.environ.get("BENCH_RUNS", "5"))


def _median(fn, runs=RUNS):
    return median_time(fn, runs, warm=True)


def main():
    try:
        from solver import Structure3D  # noqa: F401
    except ImportError:
        print("3-D unit / 2-D unit: solver.Structure3D is not available; nothing measured")
        return
    from units.frame3d import UnitGeometry
    from units.unit2d import simulate_unit_2d
    from units.unit3d import simulate_unit_3d

    for h in (0.02, 0.04):
        g = UnitGeometry(L=0.1, h=h, t=0.5e-3, w=5e-3, b=5e-3)
        med, best, r = _median(lambda: simulate_unit_3d(g, check_self_standing=False))
        print(f"3-D unit (L=100, h={h * 1e3:.0f}, t=0.5, w=b=5 mm), default mesh ({r.n_nodes} "
              f"nodes), d = 0 to state (iii) solved: median {med:.3f} s (best {best:.3f} s; "
              f"target <= 0.5 s); status {r.status}, {len(r.curve[0])} path steps")
        med, best, r = _median(lambda: simulate_unit_3d(g))
        print(f"  ... and the released state with its stability check: median {med:.3f} s "
              f"(best {best:.3f} s)")
    g2 = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)
    med, best, r = _median(lambda: simulate_unit_2d(g2, check_self_standing=False))
    print(f"2-D unit (L=100, h=40, t=0.5, w=5 mm), default mesh ({r.n_nodes} nodes), d = 0 to "
          f"state (iii) solved: median {med:.3f} s (best {best:.3f} s; target <= 2 s); "
          f"status {r.status}, {len(r.curve[0])} path steps")
    med, best, r = _median(lambda: simulate_unit_2d(g2))
    print(f"  ... and the released state with its stability check: median {med:.3f} s "
          f"(best {best:.3f} s)")

if __name__ == "__main__":
    main()
