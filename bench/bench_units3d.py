"""Speed of the 3-D unit and the 2-D unit (issue 14): a push from d = 0 to the second stable
state, states (ii) and (iii) solved, warm (numba kernels compiled or cached first); medians of
BENCH_RUNS runs in one process, one thread. Targets: 3-D unit <= 0.5 s, 2-D unit <= 2 s.
Then one corrector iteration of the 3-D unit taken apart (assembly, LDL^T, solves).

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
        from snapmorph.solver import Structure3D  # noqa: F401
    except ImportError:
        print("3-D unit / 2-D unit: solver.Structure3D is not available; nothing measured")
        return
    from snapmorph.units.frame3d import UnitGeometry
    from snapmorph.units.unit2d import simulate_unit_2d
    from snapmorph.units.unit3d import simulate_unit_3d

    def report(label, simulate, target):
        """The push to (iii), then the same with the release and its stability check."""
        med, best, r = _median(lambda: simulate(check_self_standing=False))
        print(f"{label}, default mesh ({r.n_nodes} nodes), d = 0 to state (iii) solved: median "
              f"{med:.3f} s (best {best:.3f} s; target <= {target:g} s); status {r.status}, "
              f"{len(r.curve[0])} path steps")
        med, best, r = _median(lambda: simulate())
        print(f"  ... and the released state with its stability check: median {med:.3f} s "
              f"(best {best:.3f} s)")

    for h in (0.02, 0.04):
        g = UnitGeometry(L=0.1, h=h, t=0.5e-3, w=5e-3, b=5e-3)
        report(f"3-D unit (L=100, h={h * 1e3:.0f}, t=0.5, w=b=5 mm)",
               lambda g=g, **kw: simulate_unit_3d(g, **kw), 0.5)
    g2 = UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)
    report("2-D unit (L=100, h=40, t=0.5, w=5 mm)", lambda **kw: simulate_unit_2d(g2, **kw), 2)


def _best_us(fn, rounds=30, repeats=20):
    """Best round's time per call (us) of ``rounds`` rounds of ``repeats`` calls: the least
    disturbed round on a shared machine."""
    _, best, _ = median_time(lambda: [fn() for _ in range(repeats)], rounds, warm=True)
    return best / repeats * 1e6


def iteration_breakdown():
    """One corrector iteration of the 3-D unit taken apart: assembly, LDL^T, the solve of
    the two right-hand sides MGDC needs, and the fused iteration the driver calls (best of
    30 rounds of 20 calls, at a perturbed stress-free state)."""
    import numpy as np

    from snapmorph.solver.banded import ldlt_factor_envelope, ldlt_solve_envelope
    from snapmorph.solver.system import PIVOT_TOL
    from snapmorph.units.frame3d import UnitGeometry
    from snapmorph.units.unit3d import build_unit_3d

    for h in (0.02, 0.04):
        st = build_unit_3d(UnitGeometry(L=0.1, h=h, t=0.5e-3, w=5e-3, b=5e-3)).structure
        s = st.reduced_system()
        q0 = st.initial_state()
        q0[: 3 * st.n_nodes] += 1e-5 * np.random.default_rng(0).standard_normal(3 * st.n_nodes)
        assemble = _best_us(lambda: s.evaluate(q0))
        s.evaluate(q0)
        K = s.band.copy(order="F")

        def factor():
            s.band[:] = K
            ldlt_factor_envelope(s.band, s.heights, PIVOT_TOL)

        fac = _best_us(factor)
        rhs = np.random.default_rng(1).standard_normal((s.n, 2))
        solve = _best_us(lambda: ldlt_solve_envelope(s.band, s.heights, rhs.copy()))
        P = np.zeros(s.n)
        P[0] = 1.0
        q = q0.copy()

        def fused():
            q[:] = q0
            s.fused_mgdc(q, 0.0, P, np.ones(s.n), 0.0)

        it = _best_us(fused)
        print(f"3-D unit h = {h * 1e3:.0f} mm, one MGDC iteration ({s.n} DOFs, envelope "
              f"{int(s.heights.sum())} entries): assembly {assemble:.0f} us, LDL^T {fac:.0f} us, "
              f"two solves {solve:.0f} us, fused iteration {it:.0f} us (best of 30 x 20)")


if __name__ == "__main__":
    main()
    iteration_breakdown()
