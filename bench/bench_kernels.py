"""The compiled kernels of one fused Newton/MGDC iteration on the specimen's system
(L 100, h 20, t 0.5, w = b = 5 mm, 101 nodes: 377 reduced DOFs, 218 edges, 216 bending
nodes), per call, warm, and the specimen's `simulate_unit`.

    .venv/bin/python bench/bench_kernels.py

Each figure is the minimum over many calls from Python (BENCH_REPS, default 5000): the
machine is shared, and the minimum is what the code costs when nothing else runs. The
factor is timed with the copy of the assembled band it starts from (about 1.5 us of it);
the fused iterations start from the same state each call (a copy of q, 0.3 us).
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from bench.timing import best_time  # noqa: E402

REPS = int(os.environ.get("BENCH_REPS", "5000"))
UNIT_RUNS = int(os.environ.get("BENCH_UNIT_RUNS", "20"))


def best(fn, reps=REPS):
    """The fastest of ``reps`` calls of ``fn`` (s) (`bench.timing.best_time`)."""
    return best_time(fn, reps)


def specimen():
    """(system, a deformed state q) of the specimen."""
    from snapmorph.units import UnitGeometry
    from snapmorph.units.geometry import build_unit

    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    st = build_unit(g, nodes=101).structure
    s = st.reduced_system(normalized=True)
    q = st.reference_positions.ravel().copy()
    q[1::2] *= 0.97
    return s, q


def kernel_times():
    """{name: s per call} of the fused iteration's parts and the whole iterations."""
    from snapmorph.solver.assembly import assemble_banded, stiff_second_difference
    from snapmorph.solver.banded import ldlt_factor_envelope, ldlt_solve_envelope
    from snapmorph.solver.iteration import mgdc_iteration, newton_iteration
    from snapmorph.solver.system import PIVOT_TOL

    s, q = specimen()
    n, h = s.n, s.heights
    P = np.zeros(n)
    P[0] = 1.0
    uP1 = np.ones(n)
    out = {}
    out["assemble"] = best(lambda: assemble_banded(q, s.elements, s.dofs, s.slots, s.dof_map,
                                                   s.band, h, s.grad, s.grad_full))
    K = s.band.copy(order="F")
    work = np.empty_like(K, order="F")

    def factor():
        work[:, :] = K
        ldlt_factor_envelope(work, h, PIVOT_TOL)
    out["copy + factor"] = best(factor)
    factored = work.copy(order="F")
    rhs0 = np.random.default_rng(0).normal(size=(n, 3))
    rhs = rhs0.copy()
    for m in (1, 2):
        b = rhs[:, 1:1 + m]

        def solve():
            b[:, :] = rhs0[:, 1:1 + m]
            ldlt_solve_envelope(factored, h, b)
        out[f"solve, {m} rhs"] = best(solve)
    qq = q.copy()

    def newton():
        qq[:] = q
        newton_iteration(qq, 0.0, P, *s._kernel_args, 0.0)

    def mgdc():
        qq[:] = q
        mgdc_iteration(qq, 0.0, P, uP1, *s._kernel_args, 0.0)
    out["newton_iteration"] = best(newton)
    out["mgdc_iteration"] = best(mgdc)
    du = np.random.default_rng(1).normal(size=n) * 1e-5
    plus, minus = q.copy(), q.copy()
    s.increment(plus, du)
    s.increment(minus, du, -1.0)
    second = np.empty(n)
    out["stiff_second_difference"] = best(
        lambda: stiff_second_difference(q, plus, minus, s.elements, s.dofs, second))
    return out


def unit_time():
    """(min s of UNIT_RUNS warm calls, result) of the specimen's `simulate_unit`."""
    from snapmorph.units import UnitGeometry, simulate_unit

    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    r = simulate_unit(g)
    t = np.inf
    for _ in range(UNIT_RUNS):
        t0 = time.perf_counter()
        r = simulate_unit(g)
        t = min(t, time.perf_counter() - t0)
    return t, r


def main():
    for name, t in kernel_times().items():
        print(f"{name:26s} {t * 1e6:7.2f} us")
    t, r = unit_time()
    print(f"{'simulate_unit (specimen)':26s} {t * 1e3:7.2f} ms  (min of {UNIT_RUNS}; "
          f"{r.status}, F_cr {r.F_cr!r} N, theta {r.theta_deg!r} deg)")


if __name__ == "__main__":
    main()
